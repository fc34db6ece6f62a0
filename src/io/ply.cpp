#include "rgbl/io/ply.hpp"

#include "rgbl/core/error.hpp"
#include "text.hpp"

#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <string>

namespace rgbl {

void PlyOptions::validate() const {
  require(camera_size > 0.0, "camera_size", "a positive size in metres");
}

void write_ply(const std::filesystem::path& file, std::span<const Eigen::Vector3d> points,
               std::span<const std::array<std::uint8_t, 3>> colours_rgb,
               std::span<const Eigen::Isometry3d> T_world_cams, const PlyOptions& options) {
  options.validate();
  if (!colours_rgb.empty() && colours_rgb.size() != points.size()) {
    throw Error(fmt::format("{}: {} colours for {} points", file.string(), colours_rgb.size(), points.size()));
  }
  // A pyramid per camera: apex (centre) and 4 base corners, 4 side triangles.
  const double s = options.camera_size;
  const Eigen::Vector3d corners[4] = {{-s / 2, -s / 3, s}, {s / 2, -s / 3, s}, {s / 2, s / 3, s}, {-s / 2, s / 3, s}};
  const std::size_t vertex_count = points.size() + 5 * T_world_cams.size();
  write_atomically(file, [&](std::ofstream& out) {
    out << "ply\nformat ascii 1.0\ncomment rgbl map: points then camera pyramids\n";
    out << fmt::format("element vertex {}\n", vertex_count);
    out << "property double x\nproperty double y\nproperty double z\n";
    out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out << fmt::format("element face {}\n", 4 * T_world_cams.size());
    out << "property list uchar int vertex_indices\nend_header\n";
    std::string buffer;
    const auto vertex = [&](const Eigen::Vector3d& p, const std::array<std::uint8_t, 3>& c) {
      buffer += fmt::format("{} {} {} {} {} {}\n", p.x(), p.y(), p.z(), c[0], c[1], c[2]);
      if (buffer.size() > (1U << 16)) {
        out << buffer;
        buffer.clear();
      }
    };
    for (std::size_t i = 0; i < points.size(); ++i) {
      vertex(points[i], colours_rgb.empty() ? options.point_rgb : colours_rgb[i]);
    }
    for (const auto& T : T_world_cams) {
      vertex(T.translation(), options.camera_rgb);
      for (const auto& c : corners) vertex(T * c, options.camera_rgb);
    }
    for (std::size_t k = 0; k < T_world_cams.size(); ++k) {
      const std::size_t apex = points.size() + 5 * k;
      for (std::size_t e = 0; e < 4; ++e) {
        buffer += fmt::format("3 {} {} {}\n", apex, apex + 1 + e, apex + 1 + (e + 1) % 4);
      }
    }
    out << buffer;
  });
}

}  // namespace rgbl
