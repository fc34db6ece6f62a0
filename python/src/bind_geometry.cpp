// Cameras, calibration and the LiDAR projection.

#include "common.hpp"

#include "rgbl/geometry/calibration.hpp"
#include "rgbl/geometry/camera.hpp"
#include "rgbl/geometry/projection.hpp"

#include <cmath>
#include <limits>

namespace rgbl::python {
namespace {

py::array matrix34_array(const Matrix34d& P) {
  py::array_t<double> out({3, 4});
  auto w = out.mutable_unchecked<2>();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) w(r, c) = P(r, c);
  }
  return out;
}

Matrix34d to_matrix34(const py::handle& object) {
  auto a = py::array_t<double, py::array::forcecast>::ensure(object);
  if (!a || a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 4) throw py::type_error("P: expected a 3 x 4 matrix");
  const auto r = a.unchecked<2>();
  Matrix34d P;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) P(row, col) = r(row, col);
  }
  return P;
}

// Points N x 3 (or one point, 3) in the camera frame -> pixels N x 2, NaN where project() gives none.
py::array project_points(const PinholeCamera& camera, const py::array_t<double, py::array::forcecast>& points) {
  const bool single = points.ndim() == 1;
  if (!((single && points.shape(0) == 3) || (points.ndim() == 2 && points.shape(1) == 3))) {
    throw py::type_error("points: expected 3 or N x 3 coordinates in the camera frame");
  }
  const py::ssize_t n = single ? 1 : points.shape(0);
  py::array_t<double> out({n, py::ssize_t{2}});
  auto w = out.mutable_unchecked<2>();
  const double* p = points.data();
  const auto stride = single ? 0 : points.strides(0) / static_cast<py::ssize_t>(sizeof(double));
  const auto step = (single ? points.strides(0) : points.strides(1)) / static_cast<py::ssize_t>(sizeof(double));
  for (py::ssize_t i = 0; i < n; ++i) {
    const double* q = p + i * stride;
    const auto px = camera.project({q[0], q[step], q[2 * step]});
    w(i, 0) = px ? px->x() : std::numeric_limits<double>::quiet_NaN();
    w(i, 1) = px ? px->y() : std::numeric_limits<double>::quiet_NaN();
  }
  if (single) return out.reshape({2});
  return out;
}

}  // namespace

void bind_geometry(py::module_& m) {
  py::class_<PinholeCamera>(m, "PinholeCamera",
                            "A rectified pinhole camera (optionally with radial-tangential distortion). Pixel "
                            "coordinates are integer at pixel centres, as in KITTI and OpenCV.")
      .def(py::init([](double fx, double fy, double cx, double cy, int width, int height) {
             PinholeCamera c;
             c.fx = fx;
             c.fy = fy;
             c.cx = cx;
             c.cy = cy;
             c.width = width;
             c.height = height;
             c.validate();
             return c;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width"), py::arg("height"))
      .def_readwrite("fx", &PinholeCamera::fx)
      .def_readwrite("fy", &PinholeCamera::fy)
      .def_readwrite("cx", &PinholeCamera::cx)
      .def_readwrite("cy", &PinholeCamera::cy)
      .def_readwrite("width", &PinholeCamera::width)
      .def_readwrite("height", &PinholeCamera::height)
      .def_property(
          "distortion",
          [](const PinholeCamera& c) {
            const auto& d = c.distortion;
            return py::make_tuple(d.k1, d.k2, d.p1, d.p2, d.k3);
          },
          [](PinholeCamera& c, const std::array<double, 5>& d) { c.distortion = {d[0], d[1], d[2], d[3], d[4]}; },
          "(k1, k2, p1, p2, k3), OpenCV's order; all zero without distortion.")
      .def_property_readonly("K", [](const PinholeCamera& c) {
        Eigen::Matrix3d K = c.K();
        return py::array_t<double>({3, 3}, {8, 24}, K.data());  // column-major Eigen, copied into the array
      }, "The 3 x 3 intrinsic matrix.")
      .def("project", &project_points, py::arg("points"),
           "Pixels of points (3 or N x 3, camera frame): N x 2 (or 2), NaN where a point is behind the camera or "
           "outside the image.")
      .def("unproject", [](const PinholeCamera& c, const std::array<double, 2>& px, double z) {
        const Eigen::Vector3d p = c.unproject({px[0], px[1]}, z);
        return py::make_tuple(p.x(), p.y(), p.z());
      }, py::arg("pixel"), py::arg("z"), "The point at camera depth z seen at pixel (u, v).")
      .def("__repr__", [](const PinholeCamera& c) {
        return py::str("PinholeCamera(fx={}, fy={}, cx={}, cy={}, width={}, height={})")
            .format(c.fx, c.fy, c.cx, c.cy, c.width, c.height);
      });

  py::class_<CameraCalibration>(m, "CameraCalibration",
                                "One rectified camera of a rig with a LiDAR: the camera, its pose relative to cam0 "
                                "(the rig's reference) and the LiDAR's pose in it.")
      .def(py::init([](const PinholeCamera& camera, const py::object& T_cam_cam0, const py::object& T_cam_lidar) {
             CameraCalibration c;
             c.camera = camera;
             if (!T_cam_cam0.is_none()) c.T_cam_cam0 = to_pose(T_cam_cam0, "T_cam_cam0");
             if (!T_cam_lidar.is_none()) c.T_cam_lidar = to_pose(T_cam_lidar, "T_cam_lidar");
             return c;
           }),
           py::arg("camera"), py::arg("T_cam_cam0") = py::none(), py::arg("T_cam_lidar") = py::none(),
           "Poses are float64 4 x 4 matrices; None is the identity.")
      .def_readwrite("camera", &CameraCalibration::camera)
      .def_property(
          "T_cam_cam0", [](const CameraCalibration& c) { return pose_array(c.T_cam_cam0); },
          [](CameraCalibration& c, const py::object& T) { c.T_cam_cam0 = to_pose(T, "T_cam_cam0"); })
      .def_property(
          "T_cam_lidar", [](const CameraCalibration& c) { return pose_array(c.T_cam_lidar); },
          [](CameraCalibration& c, const py::object& T) { c.T_cam_lidar = to_pose(T, "T_cam_lidar"); })
      .def_property_readonly("P_img_lidar", [](const CameraCalibration& c) { return matrix34_array(c.P_img_lidar()); },
                             "3 x 4: homogeneous LiDAR points to homogeneous pixels (K [R | t] of T_cam_lidar).");

  py::class_<KittiCalibration>(m, "KittiCalibration",
                               "A KITTI rig: the rectified projections P0..P3, T_cam0_lidar (KITTI's Tr) and the "
                               "image size of each camera.")
      .def_property_readonly("P", [](const KittiCalibration& k) {
        py::list out;
        for (const auto& P : k.P) out.append(matrix34_array(P));
        return out;
      }, "The four 3 x 4 rectified projection matrices.")
      .def_property_readonly("T_cam0_lidar", [](const KittiCalibration& k) { return pose_array(k.T_cam0_lidar); })
      .def_readonly("width", &KittiCalibration::width)
      .def_readonly("height", &KittiCalibration::height)
      .def("camera", &KittiCalibration::camera, py::arg("index"), "Camera 0..3 with its offset from cam0.")
      .def("baseline", &KittiCalibration::baseline, py::arg("a"), py::arg("b"),
           "Distance between the optical centres of cameras a and b, metres.");

  m.def("read_kitti_calibration", &read_kitti_odometry_calibration, py::arg("calib_txt"), py::arg("width") = 0,
        py::arg("height") = 0,
        "Reads a KITTI odometry calib.txt (the file has no image size: pass it, or 0). Raises ParseError naming "
        "the file and line.");

  m.def(
      "project_to_depth",
      [](const ScanArg& scan, const CameraCalibration& calibration, float min_depth, float max_depth) {
        const ScanView points = scan_view(scan, "scan");
        ProjectionOptions options;
        options.min_depth = min_depth;
        options.max_depth = max_depth;
        options.validate();
        const Matrix34d P = calibration.P_img_lidar();
        cv::Mat_<float> depth;
        {
          const py::gil_scoped_release release;
          depth = project_to_depth(points.points, P, calibration.camera.width, calibration.camera.height, options);
        }
        return mat_array(depth);
      },
      py::arg("scan"), py::arg("calibration"), py::arg("min_depth") = 5.0F, py::arg("max_depth") = 200.0F,
      "The sparse depth image (float32 H x W, camera z in metres, 0 = none) of a scan (float32 N x 4 in the "
      "LiDAR frame) in a camera: z-buffered, nearest point wins, min_depth < z < max_depth.");
  m.def(
      "project_to_depth",
      [](const ScanArg& scan, const py::array_t<double>& P_img_lidar, int width, int height, float min_depth,
         float max_depth) {
        const ScanView points = scan_view(scan, "scan");
        ProjectionOptions options;
        options.min_depth = min_depth;
        options.max_depth = max_depth;
        options.validate();
        const Matrix34d P = to_matrix34(P_img_lidar);
        cv::Mat_<float> depth;
        {
          const py::gil_scoped_release release;
          depth = project_to_depth(points.points, P, width, height, options);
        }
        return mat_array(depth);
      },
      py::arg("scan"), py::arg("P_img_lidar"), py::arg("width"), py::arg("height"), py::arg("min_depth") = 5.0F,
      py::arg("max_depth") = 200.0F, "The same with a 3 x 4 projection matrix and an image size.");
}

}  // namespace rgbl::python
