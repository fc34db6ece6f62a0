// The simulator, for data without a dataset: a synthetic street written in KITTI odometry layout.

#include "common.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/sim/scenarios.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <string>

namespace rgbl::python {

void bind_sim(py::module_& m) {
  py::class_<KittiLayout>(m, "KittiLayout", "Where a written synthetic sequence is.")
      .def_readonly("root", &KittiLayout::root, "The dataset root holding sequences/ and poses/.")
      .def_readonly("sequence_dir", &KittiLayout::sequence_dir, "root/sequences/NN: what open_sequence and Pipeline take.")
      .def_readonly("poses_file", &KittiLayout::poses_file);

  m.def(
      "write_synthetic_kitti",
      [](const std::filesystem::path& root, int frames, std::uint64_t seed, const std::string& path, int width,
         int height, const std::string& scenario, int sequence) {
        SyntheticOptions o = scenario.empty() ? SyntheticOptions{} : scenario_options(scenario, seed, frames);
        o.seed = seed;
        o.frames = frames;
        o.width = width;
        o.height = height;
        if (scenario.empty()) {
          const auto kind = parse_path_kind(path);
          if (!kind) throw ConfigError("path", "straight, curve, loop or turn");
          o.path.kind = *kind;
        }
        const SyntheticGenerator generator(o);
        const py::gil_scoped_release release;
        return write_kitti(generator, root, sequence);
      },
      py::arg("root"), py::kw_only(), py::arg("frames") = 20, py::arg("seed") = 1, py::arg("path") = "straight",
      py::arg("width") = 613, py::arg("height") = 185, py::arg("scenario") = "", py::arg("sequence") = 0,
      "Renders a synthetic street with exact ground truth (rgbl::sim) into root in KITTI odometry layout "
      "(sequences/NN with images, scans, calib.txt, times.txt; poses/NN.txt) and returns where. 613 x 185 is "
      "half of KITTI 04's resolution. scenario: one of `rgbl demo --scenario list` instead of the plain street.");
}

}  // namespace rgbl::python
