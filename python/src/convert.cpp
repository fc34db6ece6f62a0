// numpy <-> rgbl conversions (common.hpp).

#include "common.hpp"

#include <cstdint>
#include <string>

namespace rgbl::python {
namespace {

static_assert(sizeof(Eigen::Isometry3d) == 16 * sizeof(double), "Isometry3d must be a bare 4x4 matrix");
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));

[[noreturn]] void type_error(const char* name, const std::string& expected, const py::handle& got) {
  throw py::type_error(std::string(name) + ": expected " + expected + ", got " +
                       py::str(py::repr(got)).cast<std::string>().substr(0, 120));
}

int cv_depth(const py::dtype& dtype) {
  if (dtype.is(py::dtype::of<std::uint8_t>())) return CV_8U;
  if (dtype.is(py::dtype::of<std::uint16_t>())) return CV_16U;
  if (dtype.is(py::dtype::of<float>())) return CV_32F;
  // dtype objects compare equal without being the same object
  if (dtype.equal(py::dtype::of<std::uint8_t>())) return CV_8U;
  if (dtype.equal(py::dtype::of<std::uint16_t>())) return CV_16U;
  if (dtype.equal(py::dtype::of<float>())) return CV_32F;
  return -1;
}

py::dtype numpy_dtype(int depth) {
  switch (depth) {
    case CV_8U: return py::dtype::of<std::uint8_t>();
    case CV_16U: return py::dtype::of<std::uint16_t>();
    case CV_32F: return py::dtype::of<float>();
    case CV_64F: return py::dtype::of<double>();
    default: throw py::type_error("an image of OpenCV depth " + std::to_string(depth) + " has no numpy counterpart here");
  }
}

// Pixels packed (each row's pixels adjacent), rows at any positive stride: what a cv::Mat header can view.
bool packed_pixels(const py::array& a, int channels) {
  const auto item = a.itemsize();
  if (a.ndim() == 3 && a.strides(2) != item) return false;
  return a.strides(1) == item * channels && a.strides(0) >= a.shape(1) * item * channels;
}

// The pixel buffer of an array as OpenCV's (non-const) data pointer: the Mats are only read.
void* pixel_data(const py::array& a) { return const_cast<void*>(a.data()); }

}  // namespace

MatView mat_view(const py::handle& object, const char* name) {
  py::array a = py::array::ensure(object);
  if (!a) type_error(name, "a numpy array", object);
  const int depth = cv_depth(a.dtype());
  const bool shape_ok = a.ndim() == 2 || (a.ndim() == 3 && (a.shape(2) == 1 || a.shape(2) == 3));
  if (depth < 0 || !shape_ok || (a.ndim() == 3 && a.shape(2) == 3 && depth != CV_8U)) {
    type_error(name, "an image: uint8 H x W or H x W x 3, or float32 / uint16 H x W", object);
  }
  const int channels = a.ndim() == 3 ? static_cast<int>(a.shape(2)) : 1;
  if (!packed_pixels(a, channels)) a = py::array::ensure(a, py::array::c_style);
  MatView view;
  view.mat = cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), CV_MAKETYPE(depth, channels),
                     pixel_data(a), static_cast<std::size_t>(a.strides(0)));
  view.array = std::move(a);
  return view;
}

MatView optional_mat_view(const OptionalImageArg& array, const char* name) {
  if (!array) return {};
  return mat_view(*array, name);
}

ScanView scan_view(const py::handle& object, const char* name) {
  if (object.is_none()) return {};
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(object);
  if (!a || a.ndim() != 2 || a.shape(1) != 4) type_error(name, "a float32 N x 4 scan (x, y, z, reflectance)", object);
  ScanView view;
  view.points = PointCloudView(reinterpret_cast<const LidarPoint*>(a.data()), static_cast<std::size_t>(a.shape(0)));
  view.array = std::move(a);
  return view;
}

ScanView scan_view(const OptionalScanArg& array, const char* name) {
  if (!array) return {};
  return scan_view(*array, name);
}

PosesView poses_view(const py::handle& object, const char* name) {
  auto a = py::array_t<double, py::array::forcecast>::ensure(object);
  if (!a || a.ndim() != 3 || a.shape(1) != 4 || a.shape(2) != 4) type_error(name, "float64 N x 4 x 4 poses", object);
  const auto n = static_cast<std::size_t>(a.shape(0));
  PosesView view;
  const bool eigen_layout = a.strides(0) == 16 * 8 && a.strides(1) == 8 && a.strides(2) == 4 * 8 &&
                            reinterpret_cast<std::uintptr_t>(a.data()) % alignof(Eigen::Isometry3d) == 0;
  if (eigen_layout || n == 0) {
    view.poses = {reinterpret_cast<const Eigen::Isometry3d*>(a.data()), n};
  } else {
    const auto r = a.unchecked<3>();
    view.storage.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Matrix4d& m = view.storage[i].matrix();
      for (int row = 0; row < 4; ++row) {
        for (int col = 0; col < 4; ++col) m(row, col) = r(static_cast<py::ssize_t>(i), row, col);
      }
    }
    view.poses = view.storage;
  }
  view.array = std::move(a);
  return view;
}

Eigen::Isometry3d to_pose(const py::handle& object, const char* name) {
  auto a = py::array_t<double, py::array::forcecast>::ensure(object);
  if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) type_error(name, "a float64 4 x 4 pose", object);
  const auto r = a.unchecked<2>();
  Eigen::Isometry3d pose;
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) pose.matrix()(row, col) = r(row, col);
  }
  return pose;
}

py::object mat_array(const cv::Mat& mat, const py::handle& owner) {
  if (mat.empty()) return py::none();
  std::vector<py::ssize_t> shape{mat.rows, mat.cols};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(mat.step[0]), static_cast<py::ssize_t>(mat.elemSize())};
  if (mat.channels() > 1) {
    shape.push_back(mat.channels());
    strides.push_back(static_cast<py::ssize_t>(mat.elemSize1()));
  }
  return py::array(numpy_dtype(mat.depth()), shape, strides, mat.data, owner);
}

py::object mat_array(const cv::Mat& mat) {
  if (mat.empty()) return py::none();
  cv::Mat* header = nullptr;
  // a copy of the header holds a reference to OpenCV's buffer (or, for a header over foreign data,
  // the data stays the caller's responsibility, as with any cv::Mat)
  const py::capsule base = owning_capsule(header, cv::Mat(mat));
  return mat_array(*header, base);
}

py::array scan_array(std::span<const LidarPoint> scan, const py::handle& owner) {
  if (scan.empty()) return py::array_t<float>(std::vector<py::ssize_t>{0, 4});
  return py::array_t<float>({static_cast<py::ssize_t>(scan.size()), py::ssize_t{4}},
                            reinterpret_cast<const float*>(scan.data()), owner);
}

py::array scan_array(std::vector<LidarPoint> scan) {
  if (scan.empty()) return py::array_t<float>(std::vector<py::ssize_t>{0, 4});
  std::vector<LidarPoint>* held = nullptr;
  const py::capsule base = owning_capsule(held, std::move(scan));
  return scan_array(*held, base);
}

py::array poses_array(std::span<const Eigen::Isometry3d> poses, const py::handle& owner) {
  if (poses.empty()) return py::array_t<double>(std::vector<py::ssize_t>{0, 4, 4});
  // Eigen stores each 4 x 4 column-major: element (r, c) of pose i at i * 16 + c * 4 + r doubles
  const std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(poses.size()), 4, 4};
  const std::vector<py::ssize_t> strides{16 * 8, 8, 4 * 8};
  return py::array_t<double>(shape, strides, poses.data()->data(), owner);
}

py::array poses_array(std::vector<Eigen::Isometry3d> poses) {
  if (poses.empty()) return py::array_t<double>(std::vector<py::ssize_t>{0, 4, 4});
  std::vector<Eigen::Isometry3d>* held = nullptr;
  const py::capsule base = owning_capsule(held, std::move(poses));
  return poses_array(*held, base);
}

py::array pose_array(const Eigen::Isometry3d& pose) {
  py::array_t<double> out({4, 4});
  auto w = out.mutable_unchecked<2>();
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) w(row, col) = pose.matrix()(row, col);
  }
  return out;
}

py::array points_array(std::span<const Eigen::Vector3d> points, const py::handle& owner) {
  if (points.empty()) return py::array_t<double>(std::vector<py::ssize_t>{0, 3});
  return py::array_t<double>({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}}, points.data()->data(), owner);
}

py::array doubles_array(std::vector<double> values) {
  if (values.empty()) return py::array_t<double>(0);
  std::vector<double>* held = nullptr;
  const py::capsule base = owning_capsule(held, std::move(values));
  return py::array_t<double>(static_cast<py::ssize_t>(held->size()), held->data(), base);
}

}  // namespace rgbl::python
