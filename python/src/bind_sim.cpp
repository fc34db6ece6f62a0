// The simulator, for data without a dataset: a synthetic street written in KITTI odometry layout.

#include "common.hpp"

#include "rgbl/pipeline/demo.hpp"
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
         int height, const std::string& scenario, int sequence, int laps) {
        DemoOptions demo;  // the street of `rgbl demo`, with every sensor rendered
        demo.scenario = scenario;
        demo.path = path;
        demo.frames = frames;
        demo.seed = seed;
        demo.laps = laps;
        SyntheticOptions o = demo_simulation(demo);
        o.cameras = SyntheticOptions{}.cameras;
        o.render_depth = SyntheticOptions{}.render_depth;
        o.width = width;
        o.height = height;
        o.validate();
        const SyntheticGenerator generator(o);
        const py::gil_scoped_release release;
        return write_kitti(generator, root, sequence);
      },
      py::arg("root"), py::kw_only(), py::arg("frames") = 20, py::arg("seed") = 1, py::arg("path") = "straight",
      py::arg("width") = 613, py::arg("height") = 185, py::arg("scenario") = "", py::arg("sequence") = 0,
      py::arg("laps") = 1,
      "Renders a synthetic street with exact ground truth (rgbl::sim) into root in KITTI odometry layout "
      "(sequences/NN with images, scans, calib.txt, times.txt; poses/NN.txt) and returns where. 613 x 185 is "
      "half of KITTI 04's resolution. scenario: one of `rgbl demo --scenario list` instead of the street of `path` "
      "(straight, curve, loop or turn; laps: of a loop). Every camera, the scans and the exact depth are written.");
}

}  // namespace rgbl::python
