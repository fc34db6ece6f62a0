// ORB extraction: keypoints as a structured array, descriptors as N x 32 uint8, both without copies.

#include "common.hpp"

#include "rgbl/features/orb.hpp"

#include <algorithm>
#include <memory>
#include <optional>
#include <mutex>
#include <string>

namespace rgbl::python {
namespace {

static_assert(sizeof(Descriptor) == 32);

struct PyOrbExtractor {
  std::unique_ptr<OrbExtractor> extractor;
  std::mutex mutex;  // one extractor's scratch serves one call at a time
};

}  // namespace

void bind_features(py::module_& m) {
  PYBIND11_NUMPY_DTYPE(Keypoint, x, y, angle, response, size, level);

  py::class_<OrbOptions>(m, "OrbOptions", "ORB extraction settings (ORB-SLAM semantics).")
      .def(py::init<>())
      .def_readwrite("num_features", &OrbOptions::num_features, "Total over all levels.")
      .def_readwrite("num_levels", &OrbOptions::num_levels)
      .def_readwrite("scale_factor", &OrbOptions::scale_factor, "Between consecutive levels.")
      .def_readwrite("fast_threshold", &OrbOptions::fast_threshold)
      .def_readwrite("fast_min_threshold", &OrbOptions::fast_min_threshold, "Fallback for cells with no corner.")
      .def_readwrite("cell_size", &OrbOptions::cell_size)
      .def_readwrite("features_per_node", &OrbOptions::features_per_node)
      .def_readwrite("spread_fraction", &OrbOptions::spread_fraction,
                     "Share of each level's budget placed by the quadtree; the rest are the strongest corners.")
      .def_readwrite("edge_threshold", &OrbOptions::edge_threshold)
      .def_readwrite("patch_size", &OrbOptions::patch_size)
      .def_readwrite("orientation_radius", &OrbOptions::orientation_radius)
      .def_readwrite("blur_size", &OrbOptions::blur_size)
      .def_readwrite("blur_sigma", &OrbOptions::blur_sigma)
      .def("validate", &OrbOptions::validate, "Raises ConfigError naming a bad option.");

  py::class_<PyOrbExtractor>(m, "OrbExtractor",
                             "The ORB extractor rgbl tracks with: pyramid, FAST with a per-cell fallback, quadtree "
                             "distribution, rotated BRIEF. Deterministic.")
      .def(py::init([](const std::optional<OrbOptions>& options) {
             auto e = std::make_unique<PyOrbExtractor>();
             e->extractor = std::make_unique<OrbExtractor>(options.value_or(OrbOptions{}));
             return e;
           }),
           py::arg("options") = py::none())
      .def_property_readonly("options", [](const PyOrbExtractor& e) { return e.extractor->options(); })
      .def(
          "extract",
          [](PyOrbExtractor& e, const ImageArg& image) {
            const MatView gray = mat_view(image, "image");
            if (gray.mat.type() != CV_8UC1) throw py::type_error("image: expected a uint8 H x W grey image");
            std::vector<Keypoint> keypoints;
            std::vector<Descriptor> descriptors;
            {
              const py::gil_scoped_release release;
              const std::lock_guard lock(e.mutex);
              e.extractor->extract(gray.mat, keypoints, descriptors);
            }
            const auto n = static_cast<py::ssize_t>(keypoints.size());
            std::vector<Keypoint>* k = nullptr;
            std::vector<Descriptor>* d = nullptr;
            const py::capsule k_base = owning_capsule(k, std::move(keypoints));
            const py::capsule d_base = owning_capsule(d, std::move(descriptors));
            auto k_array = py::array_t<Keypoint>(n, k->data(), k_base);
            auto d_array = py::array_t<std::uint8_t>({n, py::ssize_t{32}},
                                                      reinterpret_cast<const std::uint8_t*>(d->data()), d_base);
            return py::make_tuple(k_array, d_array);
          },
          py::arg("image"),
          "Keypoints and descriptors of a grey uint8 H x W image: (keypoints, descriptors), keypoints a structured "
          "array with fields x, y (level-0 pixels), angle (degrees), response, size, level; descriptors uint8 "
          "N x 32 (256-bit rotated BRIEF), row i for keypoint i.");

  m.def(
      "hamming_distance",
      [](const py::array_t<std::uint8_t, py::array::c_style>& a, const py::array_t<std::uint8_t, py::array::c_style>& b) {
        if (a.size() != 32 || b.size() != 32) throw py::type_error("expected two 32-byte descriptors");
        Descriptor da{}, db{};
        std::copy_n(a.data(), 32, da.begin());
        std::copy_n(b.data(), 32, db.begin());
        return hamming_distance(da, db);
      },
      py::arg("a"), py::arg("b"), "Differing bits of two descriptors.");
}

}  // namespace rgbl::python
