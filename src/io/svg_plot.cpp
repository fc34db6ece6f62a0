#include "rgbl/io/svg_plot.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

namespace rgbl {
namespace {

std::string escape_xml(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// A "nice" grid step (1, 2 or 5 times a power of ten) giving roughly `target` lines over `span`.
double grid_step(double span, int target) {
  const double raw = span / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * magnitude) return m * magnitude;
  }
  return 10.0 * magnitude;
}

}  // namespace

std::string trajectory_svg(const std::vector<PlotSeries>& series, const std::string& title,
                           const std::vector<PlotLink>& links, const std::string& links_label) {
  constexpr double kWidth = 800.0, kHeight = 800.0, kMargin = 60.0;
  double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x;
  double min_z = min_x, max_z = -min_x;
  for (const auto& s : series) {
    for (const auto& p : s.positions) {
      if (!p.allFinite()) continue;
      min_x = std::min(min_x, p.x());
      max_x = std::max(max_x, p.x());
      min_z = std::min(min_z, p.z());
      max_z = std::max(max_z, p.z());
    }
  }
  if (!std::isfinite(min_x)) min_x = max_x = min_z = max_z = 0.0;
  // equal scale: fit the larger extent, centre the other
  const double span = std::max({max_x - min_x, max_z - min_z, 1.0}) * 1.05;
  const double cx = 0.5 * (min_x + max_x), cz = 0.5 * (min_z + max_z);
  const double scale = (kWidth - 2.0 * kMargin) / span;
  const auto to_px = [&](double x, double z) {
    return std::pair{kMargin + (x - cx) * scale + 0.5 * (kWidth - 2.0 * kMargin),
                     kHeight - kMargin - ((z - cz) * scale + 0.5 * (kHeight - 2.0 * kMargin))};
  };

  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      kWidth, kHeight);
  const double step = grid_step(span, 8);
  const double x0 = cx - 0.5 * span, z0 = cz - 0.5 * span;
  for (double g = std::ceil(x0 / step) * step; g <= x0 + span; g += step) {
    const auto [px, py0] = to_px(g, z0);
    const auto [px1, py1] = to_px(g, z0 + span);
    svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\" fill=\"#666\">{:g}</text>\n",
                       px, py0, px1, py1, px, kHeight - kMargin + 18.0, g + 0.0);  // + 0.0: no "-0"
  }
  for (double g = std::ceil(z0 / step) * step; g <= z0 + span; g += step) {
    const auto [px0, py] = to_px(x0, g);
    const auto [px1, py1] = to_px(x0 + span, g);
    svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\" fill=\"#666\">{:g}</text>\n",
                       px0, py, px1, py1, kMargin - 6.0, py + 4.0, g + 0.0);
  }
  svg += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">x [m]</text>\n", kWidth / 2.0,
                     kHeight - 15.0);
  svg += fmt::format("<text x=\"15\" y=\"{:.1f}\" transform=\"rotate(-90 15 {:.1f})\" "
                     "text-anchor=\"middle\">z [m]</text>\n",
                     kHeight / 2.0, kHeight / 2.0);
  svg += fmt::format("<text x=\"{:.1f}\" y=\"30\" text-anchor=\"middle\" font-size=\"16\">{}</text>\n",
                     kWidth / 2.0, escape_xml(title));

  for (std::size_t k = 0; k < series.size(); ++k) {
    const auto& s = series[k];
    const std::string color = escape_xml(s.color);
    // one polyline per run of finite positions
    std::string points;
    const auto flush = [&] {
      if (!points.empty()) {
        svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\"{} points=\"{}\"/>\n", color,
                           s.dashed ? " stroke-dasharray=\"6 4\"" : "", points);
      }
      points.clear();
    };
    const Eigen::Vector3d* first = nullptr;
    const Eigen::Vector3d* last = nullptr;
    for (const auto& p : s.positions) {
      if (!p.allFinite()) {
        flush();
        continue;
      }
      if (first == nullptr) first = &p;
      last = &p;
      const auto [px, py] = to_px(p.x(), p.z());
      points += fmt::format("{:.1f},{:.1f} ", px, py);
    }
    flush();
    if (first != nullptr) {
      const auto [sx, sy] = to_px(first->x(), first->z());
      const auto [ex, ey] = to_px(last->x(), last->z());
      svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"5\" fill=\"{}\"/>"
                         "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"9\" height=\"9\" fill=\"{}\"/>\n",
                         sx, sy, color, ex - 4.5, ey - 4.5, color);
    }
    const double ly = 55.0 + 18.0 * static_cast<double>(k);
    svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" "
                       "stroke-width=\"3\"{}/><text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n",
                       kMargin, ly, kMargin + 25.0, ly, color, s.dashed ? " stroke-dasharray=\"6 4\"" : "",
                       kMargin + 32.0, ly + 4.0, escape_xml(s.label));
  }
  constexpr const char* kLinkColor = "#2ca02c";
  for (const PlotLink& link : links) {
    if (!link.from.allFinite() || !link.to.allFinite()) continue;
    const auto [fx, fy] = to_px(link.from.x(), link.from.z());
    const auto [tx, ty] = to_px(link.to.x(), link.to.z());
    svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" stroke-width=\"2\"/>"
                       "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"4\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>"
                       "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"{}\">{}</text>\n",
                       fx, fy, tx, ty, kLinkColor, fx, fy, kLinkColor, fx + 7.0, fy - 7.0, kLinkColor,
                       escape_xml(link.label));
  }
  if (!links.empty()) {
    const double ly = 55.0 + 18.0 * static_cast<double>(series.size());
    svg += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"{}\" "
                       "stroke-width=\"3\"/><text x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n",
                       kMargin, ly, kMargin + 25.0, ly, kLinkColor, kMargin + 32.0, ly + 4.0, escape_xml(links_label));
  }
  svg += "</svg>\n";
  return svg;
}

void write_trajectory_svg(const std::filesystem::path& path, const std::vector<PlotSeries>& series,
                          const std::string& title, const std::vector<PlotLink>& links,
                          const std::string& links_label) {
  const std::string svg = trajectory_svg(series, title, links, links_label);
  write_atomically(path, [&](std::ofstream& out) { out << svg; });
}

}  // namespace rgbl
