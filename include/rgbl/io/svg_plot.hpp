#pragma once
// A dependency-free top view of trajectories as SVG: what `rgbl run` writes next to its trajectory files.

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace rgbl {

struct PlotSeries {
  std::string label;
  std::string color = "#1f77b4";          // any SVG colour
  std::vector<Eigen::Vector3d> positions;  // camera centres in the cam0 world frame; non-finite = gap
  bool dashed = false;
};

// Two positions joined on the plot, e.g. a loop closure's frame and the frame it matched.
struct PlotLink {
  Eigen::Vector3d from = Eigen::Vector3d::Zero(), to = Eigen::Vector3d::Zero();
  std::string label;  // written next to `from`
};

// Bird's-eye view of the x-z plane (KITTI cameras: x right, z forward, y down), equal scale on both
// axes, with a grid in metres, a legend, and start (circle) and end (square) markers. Links are drawn
// in green over the series, with `links_label` in the legend.
std::string trajectory_svg(const std::vector<PlotSeries>& series, const std::string& title,
                           const std::vector<PlotLink>& links = {}, const std::string& links_label = "loop closure");

// Writes trajectory_svg() to `path` whole (write_atomically); throws rgbl::Error naming the file when it
// cannot be written.
void write_trajectory_svg(const std::filesystem::path& path, const std::vector<PlotSeries>& series,
                          const std::string& title, const std::vector<PlotLink>& links = {},
                          const std::string& links_label = "loop closure");

}  // namespace rgbl
