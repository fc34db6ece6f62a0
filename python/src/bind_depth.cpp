// Depth kernels (inverse dilation, IP-Basic), depth sources by name and depth metrics.

#include "common.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/depth/completion.hpp"
#include "rgbl/depth/evaluation.hpp"
#include "rgbl/depth/ip_basic.hpp"
#include "rgbl/depth/registry.hpp"
#include "rgbl/depth/sources.hpp"

#include <memory>
#include <string>

namespace rgbl::python {
namespace {

static_assert(sizeof(KeypointDepth) == 4 * sizeof(float), "KeypointDepth is returned as N x 4 float32");

cv::Mat_<float> depth_view(const py::handle& object, const char* name, MatView& keep) {
  keep = mat_view(object, name);
  if (keep.mat.type() != CV_32FC1) throw py::type_error(std::string(name) + ": expected a float32 H x W depth map");
  return keep.mat;  // a header over the array's buffer
}

// A depth source with the arrays of the frame it prepared: some sources keep views of the images
// (stereo_sparse reads them again in dense_depth()), so the arrays live as long as that frame.
struct PyDepthSource {
  std::unique_ptr<DepthSource> source;
  py::tuple frame;
};

IpBasicOptions ip_basic_options(float max_depth, bool extrapolate, const std::string& blur) {
  IpBasicOptions o;
  o.max_depth = max_depth;
  o.extrapolate = extrapolate;
  if (blur == "bilateral") o.blur = IpBasicBlur::bilateral;
  else if (blur == "gaussian") o.blur = IpBasicBlur::gaussian;
  else throw ConfigError("ip_basic.blur", "bilateral or gaussian");
  o.validate();
  return o;
}

}  // namespace

void bind_depth(py::module_& m) {
  m.def(
      "dilate_depth",
      [](const ImageArg& sparse, const std::string& kernel, int size, float max_depth) {
        MatView keep;
        const cv::Mat_<float> in = depth_view(sparse, "sparse", keep);
        DilationOptions o;
        o.shape = parse_kernel_shape(kernel, "kernel");
        o.size = size;
        o.max_depth = max_depth;
        o.validate();
        cv::Mat_<float> dense;
        {
          const py::gil_scoped_release release;
          dilate_depth(in, o, dense);
        }
        return mat_array(dense);
      },
      py::arg("sparse"), py::arg("kernel") = "diamond", py::arg("size") = 5, py::arg("max_depth") = 200.0F,
      "Inverse dilation (RGB-L): every pixel takes the nearest valid depth under the kernel ('diamond', "
      "'rectangle' or 'cross', odd size) centred on it. float32 H x W in and out, 0 = none; depths must lie "
      "in (0, max_depth).");
  m.def(
      "ip_basic",
      [](const ImageArg& sparse, const std::string& mode, float max_depth, bool extrapolate, const std::string& blur) {
        MatView keep;
        const cv::Mat_<float> in = depth_view(sparse, "sparse", keep);
        const IpBasicOptions o = ip_basic_options(max_depth, extrapolate, blur);
        if (mode != "fast" && mode != "multiscale") throw ConfigError("mode", "fast or multiscale");
        cv::Mat_<float> dense;
        {
          const py::gil_scoped_release release;
          dense = mode == "fast" ? ip_basic_fast(in, o) : ip_basic_multiscale(in, o);
        }
        return mat_array(dense);
      },
      py::arg("sparse"), py::arg("mode") = "fast", py::arg("max_depth") = 100.0F, py::arg("extrapolate") = false,
      py::arg("blur") = "bilateral",
      "IP-Basic depth completion (Ku et al. 2018), 'fast' or 'multiscale'. float32 H x W in and out.");
  m.def(
      "remove_occluded_samples",
      [](const ImageArg& sparse, int radius, float ratio) {
        MatView keep;
        cv::Mat_<float> out = depth_view(sparse, "sparse", keep).clone();
        {
          const py::gil_scoped_release release;
          remove_occluded_samples(out, radius, ratio);
        }
        return mat_array(out);
      },
      py::arg("sparse"), py::arg("radius"), py::arg("ratio") = 1.25F,
      "A copy of the sparse depth without the samples the camera cannot see: those with a sample nearer by "
      "more than the factor `ratio` within `radius` px (what the lidar source does before completion).");
  m.def("occlusion_radius_px", &occlusion_radius_px, py::arg("fx"), py::arg("window_deg") = 0.3,
        "The occlusion filter's half-width in px for a window of window_deg at focal length fx px.");
  m.def(
      "depth_density", [](const ImageArg& depth) {
        MatView keep;
        return depth_density(depth_view(depth, "depth", keep));
      },
      py::arg("depth"), "Share of pixels with depth (> 0).");

  py::class_<DepthSourceNeeds>(m, "DepthSourceNeeds", "What a depth source reads from a frame besides the image.")
      .def_readonly("scan", &DepthSourceNeeds::scan)
      .def_readonly("right_image", &DepthSourceNeeds::right_image)
      .def_readonly("depth_image", &DepthSourceNeeds::depth_image);

  m.def("depth_source_names", [] { return builtin_depth_sources().names(); },
        "The registered depth sources: lidar, precomputed, rgbd, stereo, stereo_sparse.");
  m.def("depth_source_usage", [] { return builtin_depth_sources().usage(); },
        "Every source's spec grammar, e.g. 'lidar[:dilated|ipbasic|...|<shape><size>]'.");
  m.def("depth_source_needs", [](const std::string& spec) { return builtin_depth_sources().entry(spec).needs; },
        py::arg("spec"));

  py::class_<PyDepthSource>(m, "DepthSource",
                            "A depth source: one frame's sensor data in, metric depth at keypoints and a dense "
                            "depth map out. Create with make_depth_source(spec, calibration).")
      .def_property_readonly("name", [](const PyDepthSource& s) { return std::string(s.source->name()); })
      .def(
          "prepare",
          [](PyDepthSource& s, const ImageArg& image, const OptionalScanArg& scan, const OptionalImageArg& image_right,
             const OptionalImageArg& depth_image, std::size_t index, double timestamp) {
            const MatView left = mat_view(image, "image");
            const MatView right = optional_mat_view(image_right, "image_right");
            const MatView depth = optional_mat_view(depth_image, "depth_image");
            const ScanView points = scan_view(scan, "scan");
            SensorFrame frame;
            frame.index = index;
            frame.timestamp = timestamp;
            frame.image = left.mat;
            frame.image_right = right.mat;
            frame.depth_image = depth.mat;
            frame.scan = points.points;
            s.frame = py::make_tuple(left.array, right.array, depth.array, points.array);
            const py::gil_scoped_release release;
            s.source->prepare(frame);
          },
          py::arg("image"), py::arg("scan") = py::none(), py::arg("image_right") = py::none(),
          py::arg("depth_image") = py::none(), py::arg("index") = 0, py::arg("timestamp") = 0.0,
          "Per-frame work (e.g. projecting the scan). Raises ConfigError when the frame lacks what the source needs.")
      .def(
          "sample",
          [](const PyDepthSource& s, const py::array_t<float, py::array::c_style | py::array::forcecast>& pixels) {
            if (pixels.ndim() != 2 || pixels.shape(1) != 2) throw py::type_error("pixels: expected float32 N x 2 (u, v)");
            const auto n = static_cast<std::size_t>(pixels.shape(0));
            const std::span<const Eigen::Vector2f> px(reinterpret_cast<const Eigen::Vector2f*>(pixels.data()), n);
            std::vector<KeypointDepth> depths(n);
            s.source->sample(px, depths);
            std::vector<KeypointDepth>* held = nullptr;
            const py::capsule base = owning_capsule(held, std::move(depths));
            return py::array_t<float>({static_cast<py::ssize_t>(n), py::ssize_t{4}},
                                      reinterpret_cast<const float*>(held->data()), base);
          },
          py::arg("pixels"),
          "Depth at pixels (float32 N x 2) after prepare(): float32 N x 4 of (z, distance in px to the measurement "
          "it came from, depth spread under the kernel, depth gradient in m/px or 0 = unknown); z = 0: no depth.")
      .def("dense_depth", [](const PyDepthSource& s) { return mat_array(s.source->dense_depth()); },
           "The completed depth map of the prepared frame (float32 H x W, 0 = none).");

  m.def(
      "make_depth_source",
      [](const std::string& spec, const CameraCalibration& calibration, double stereo_baseline) {
        DepthSourceContext context;
        context.calibration = calibration;
        context.stereo_baseline = stereo_baseline;
        return PyDepthSource{builtin_depth_sources().create(spec, context), py::tuple()};
      },
      py::arg("spec"), py::arg("calibration"), py::arg("stereo_baseline") = 0.0,
      "A registered depth source by spec name[:argument], e.g. 'lidar', 'lidar:ipbasic', 'lidar:cross7', "
      "'stereo', 'precomputed:<folder>'. Raises ConfigError naming a bad spec.");

  m.def(
      "make_lidar_source",
      [](const CameraCalibration& calibration, double surface_fit_window_deg, double occlusion_window_deg,
         float surface_tolerance, int surface_step_px, bool kernel_from_ring_spacing) {
        LidarSourceOptions options;
        options.surface_fit_window_deg = surface_fit_window_deg;
        options.occlusion_window_deg = occlusion_window_deg;
        options.surface_tolerance = surface_tolerance;
        options.surface_step_px = surface_step_px;
        options.kernel_from_ring_spacing = kernel_from_ring_spacing;
        DepthSourceContext context;
        context.calibration = calibration;
        return PyDepthSource{make_lidar_source(options, context), py::tuple()};
      },
      // the defaults are the C++ options' own, so the two cannot drift apart
      py::arg("calibration"), py::arg("surface_fit_window_deg") = LidarSourceOptions{}.surface_fit_window_deg,
      py::arg("occlusion_window_deg") = LidarSourceOptions{}.occlusion_window_deg,
      py::arg("surface_tolerance") = LidarSourceOptions{}.surface_tolerance,
      py::arg("surface_step_px") = LidarSourceOptions{}.surface_step_px,
      py::arg("kernel_from_ring_spacing") = LidarSourceOptions{}.kernel_from_ring_spacing,
      "The 'lidar' source (5x5 diamond, surface-mean keypoint depth) with its options: the settings keys "
      "LiDAR.SurfaceFitWindowDeg, LiDAR.OcclusionWindowDeg, the surface's relative depth step, "
      "LiDAR.SurfaceStepPx and LiDAR.KernelFromRingSpacing. Raises ConfigError naming an option out of range.");
  m.def("read_depth_png", [](const std::filesystem::path& file) { return mat_array(read_depth_png(file)); },
        py::arg("file"), "A depth PNG (uint16, depth x 256) in metres, float32 H x W.");
  m.def(
      "write_depth_png",
      [](const std::filesystem::path& file, const ImageArg& depth) {
        MatView keep;
        write_depth_png(file, depth_view(depth, "depth", keep));
      },
      py::arg("file"), py::arg("depth"));

  py::class_<DepthErrors>(m, "DepthErrors", "Depth errors over pixels where prediction and ground truth both have depth.")
      .def_readonly("count", &DepthErrors::count)
      .def_readonly("coverage", &DepthErrors::coverage, "Compared pixels / ground-truth pixels.")
      .def_readonly("mae", &DepthErrors::mae, "m")
      .def_readonly("rmse", &DepthErrors::rmse, "m")
      .def_readonly("imae", &DepthErrors::imae, "1/km")
      .def_readonly("irmse", &DepthErrors::irmse, "1/km")
      .def("__repr__", [](const DepthErrors& e) {
        return py::str("DepthErrors(count={}, coverage={:.4f}, mae={:.4f}, rmse={:.4f}, imae={:.4f}, irmse={:.4f})")
            .format(e.count, e.coverage, e.mae, e.rmse, e.imae, e.irmse);
      });
  m.def(
      "evaluate_depth",
      [](const ImageArg& prediction, const ImageArg& ground_truth) {
        MatView keep_p, keep_g;
        return evaluate_depth(depth_view(prediction, "prediction", keep_p), depth_view(ground_truth, "ground_truth", keep_g));
      },
      py::arg("prediction"), py::arg("ground_truth"), "Depth metrics of one float32 H x W map against another.");
  py::class_<DepthErrorAccumulator>(m, "DepthErrorAccumulator", "Depth metrics pooled over many frames.")
      .def(py::init<>())
      .def(
          "add",
          [](DepthErrorAccumulator& a, const ImageArg& prediction, const ImageArg& ground_truth) {
            MatView keep_p, keep_g;
            a.add(depth_view(prediction, "prediction", keep_p), depth_view(ground_truth, "ground_truth", keep_g));
          },
          py::arg("prediction"), py::arg("ground_truth"))
      .def("result", &DepthErrorAccumulator::result);
}

}  // namespace rgbl::python
