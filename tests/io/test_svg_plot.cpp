// The trajectory plot: positions land where the equal-scale mapping puts them, gaps break the line,
// and links (loop closures) are drawn between the two positions they join.

#include "rgbl/io/svg_plot.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>
#include <string>

using Catch::Matchers::Contains;

namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("trajectory plot: exact pixel positions, gaps, start and end marks, loop closure links", "[io][svg]") {
  // a 10 m square in x-z with a gap in the middle; the plot spans 10 * 1.05 m over 680 px
  rgbl::PlotSeries s{"estimate", "#d62728", {}, false};
  s.positions = {{0, 0, 0}, {10, 0, 0}, {10, 0, 10}, Eigen::Vector3d::Constant(std::nan("")), {0, 0, 10}, {0, 0, 0}};
  const double scale = 680.0 / 10.5;
  const auto px = [&](double x) { return 60.0 + (x - 5.0) * scale + 340.0; };
  const auto py = [&](double z) { return 800.0 - 60.0 - ((z - 5.0) * scale + 340.0); };

  const std::string plain = rgbl::trajectory_svg({s}, "a <title> & more");
  CHECK(count(plain, "<polyline") == 2);  // the gap splits the line
  CHECK_THAT(plain, Contains("a &lt;title&gt; &amp; more"));
  CHECK_THAT(plain, Contains(fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"5\"", px(0.0), py(0.0))));
  CHECK_THAT(plain, Contains(fmt::format("{:.1f},{:.1f} ", px(10.0), py(10.0))));
  CHECK_FALSE(plain.find("loop closure") != std::string::npos);

  const std::string linked =
      rgbl::trajectory_svg({s}, "t", {{{0, 0, 10}, {10, 0, 0}, "470-71"}, {{std::nan(""), 0, 0}, {0, 0, 0}, "bad"}});
  CHECK(count(linked, "r=\"4\" fill=\"none\"") == 1);  // one link mark: the non-finite link is left out
  CHECK_THAT(linked, Contains(fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#2ca02c\"",
                                          px(0.0), py(10.0), px(10.0), py(0.0))));
  CHECK_THAT(linked, Contains(">470-71</text>"));
  CHECK_FALSE(linked.find(">bad</text>") != std::string::npos);
  CHECK_THAT(linked, Contains(">loop closure</text>"));  // the legend
}
