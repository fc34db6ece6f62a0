#pragma once
// Shared by every binding file: pybind11 with the same type casters everywhere (STL containers, paths,
// numpy), the numpy conversions and the functions that bind each part of the library.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "rgbl/geometry/point_cloud.hpp"

#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace rgbl {
class System;
}

namespace rgbl::python {

namespace py = pybind11;

// Parameter types, as help() and the signatures show them: ndarrays (lists are converted for scans and poses).
using ImageArg = py::array;
using OptionalImageArg = std::optional<py::array>;
using ScanArg = py::array_t<float>;
using OptionalScanArg = std::optional<py::array_t<float>>;
using PosesArg = py::array_t<double>;

// --- numpy in -------------------------------------------------------------------------------------
// Arrays from Python are viewed in place when their layout allows; otherwise a packed copy is made
// and held by `array`, which the caller keeps for as long as the view is used.

// Images: uint8 H x W or H x W x 3 (BGR, as OpenCV), float32 H x W (depth), uint16 H x W. Rows may be
// strided (a crop), pixels must be packed. `name` is the argument's name for error messages.
struct MatView {
  cv::Mat mat;
  py::array array;
};
MatView mat_view(const py::handle& object, const char* name);
// The same for an optional argument (None -> an empty Mat).
MatView optional_mat_view(const OptionalImageArg& array, const char* name);

// LiDAR scans: float32 N x 4 (x, y, z, reflectance), the KITTI .bin layout LidarPoint has.
struct ScanView {
  PointCloudView points;
  py::array array;
};
ScanView scan_view(const py::handle& object, const char* name);
ScanView scan_view(const OptionalScanArg& array, const char* name);  // None -> no points

// Poses: float64 N x 4 x 4 (T[i] a 4 x 4 matrix). Viewed in place when the array has Eigen's layout
// (the column-major views this module returns do), else copied.
struct PosesView {
  std::span<const Eigen::Isometry3d> poses;
  std::vector<Eigen::Isometry3d> storage;
  py::array array;
};
PosesView poses_view(const py::handle& object, const char* name);
Eigen::Isometry3d to_pose(const py::handle& object, const char* name);  // float64 4 x 4

// --- numpy out ------------------------------------------------------------------------------------
// Arrays share the C++ buffer: `owner` (a Python object holding it) or a moved-in container is the
// array's base.

// None for an empty Mat.
py::object mat_array(const cv::Mat& mat);                           // shares the Mat's refcounted buffer
py::object mat_array(const cv::Mat& mat, const py::handle& owner);  // a buffer owner keeps alive
py::array scan_array(std::vector<LidarPoint> scan);
py::array scan_array(std::span<const LidarPoint> scan, const py::handle& owner);
py::array poses_array(std::vector<Eigen::Isometry3d> poses);
py::array poses_array(std::span<const Eigen::Isometry3d> poses, const py::handle& owner);
py::array pose_array(const Eigen::Isometry3d& pose);  // a 4 x 4 copy
py::array points_array(std::span<const Eigen::Vector3d> points, const py::handle& owner);  // N x 3
py::array doubles_array(std::vector<double> values);

// Moves `value` to the heap and returns a capsule that deletes it: the base of arrays over its buffer.
template <typename T>
py::capsule owning_capsule(T*& out, T&& value) {
  out = new T(std::move(value));
  return py::capsule(out, [](void* p) { delete static_cast<T*>(p); });
}

// System is bound with the frame count and period track() defaults to (bind_tracking.cpp).
py::object wrap_system(std::unique_ptr<System> system, double frame_period);
System& unwrap_system(const py::handle& object);

// --- the parts of the module ----------------------------------------------------------------------
void bind_errors(py::module_& m);
void bind_geometry(py::module_& m);
void bind_depth(py::module_& m);
void bind_features(py::module_& m);
void bind_io(py::module_& m);
void bind_tracking(py::module_& m);
void bind_pipeline(py::module_& m);
void bind_eval(py::module_& m);
void bind_sim(py::module_& m);

}  // namespace rgbl::python
