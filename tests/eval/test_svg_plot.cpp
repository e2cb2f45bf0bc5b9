#include <gtest/gtest.h>

#include <regex>

#include "mmlio/eval/plot_evaluation.hpp"
#include "mmlio/eval/svg_plot.hpp"

namespace mmlio::eval {
namespace {

TEST(SvgPlot, NiceTicksAreRoundAndCoverTheRange) {
  EXPECT_EQ(niceTicks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const std::vector<double> t = niceTicks(-0.013, 0.047, 6);
  ASSERT_GE(t.size(), 4u);
  EXPECT_NEAR(t[1] - t[0], 0.01, 1e-12);
  EXPECT_GE(t.front(), -0.013);
  EXPECT_LE(t.back(), 0.047 + 1e-12);
}

TEST(SvgPlot, PlacesDataInsideTheAxesWithYUp) {
  SvgPlot::Config c;
  c.width_px = 400, c.height_px = 300;
  SvgPlot plot(c);
  plot.xRange(0, 10);
  plot.yRange(0, 10);
  plot.line({{0, 0}, {10, 10}}, "#f00", 1.0, "rising");
  const std::string svg = plot.render();
  // Axes span x 62..384, y 34..254: (0,0) is the bottom-left corner, (10,10) the top-right.
  EXPECT_NE(svg.find("points=\"62.0,254.0 384.0,34.0 \""), std::string::npos) << svg;
  EXPECT_NE(svg.find(">rising</text>"), std::string::npos);
}

TEST(SvgPlot, EqualAspectKeepsMetresSquare) {
  SvgPlot::Config c;
  c.width_px = 662, c.height_px = 380;  // axes 584 x 300 px
  c.equal_aspect = true;
  SvgPlot plot(c);
  plot.xRange(0, 1);
  plot.yRange(0, 1);
  plot.line({{0, 0}, {1, 1}}, "#f00");
  const std::regex pts("points=\"([0-9.]+),([0-9.]+) ([0-9.]+),([0-9.]+) \"");
  std::smatch m;
  const std::string svg = plot.render();
  ASSERT_TRUE(std::regex_search(svg, m, pts));
  const double dx = std::stod(m[3]) - std::stod(m[1]), dy = std::stod(m[2]) - std::stod(m[4]);
  EXPECT_NEAR(dx, dy, 0.2);
  EXPECT_NEAR(dy, 300.0, 0.2);
}

TEST(SvgPlot, DotsAreSmallSquaresInOnePath) {
  SvgPlot::Config c;
  c.width_px = 400, c.height_px = 300;
  SvgPlot plot(c);
  plot.xRange(0, 10);
  plot.yRange(0, 10);
  plot.dots({{0, 0}, {10, 10}}, "#999", 1.5);
  EXPECT_NE(plot.render().find("d=\"M62.0 254.0h1.5v1.5h-1.5zM384.0 34.0h1.5v1.5h-1.5z\""), std::string::npos);
}

TEST(SvgPlot, TextIsEscaped) {
  SvgPlot::Config c;
  c.title = "a < b & \"c\"";
  EXPECT_NE(SvgPlot(c).render().find("a &lt; b &amp; &quot;c&quot;"), std::string::npos);
}

TEST(SvgPlot, BarsScaleToTheLargestValue) {
  BarChart bars;
  bars.labels = {"features", "registration"};
  bars.sets = {{"mean", {1.0, 4.0}}};
  bars.width_px = 640;  // bar area 640 - 150 - 70 = 420 px
  const std::string svg = bars.render();
  EXPECT_NE(svg.find("width=\"105.0\""), std::string::npos);
  EXPECT_NE(svg.find("width=\"420.0\""), std::string::npos);
}

TEST(PlotEvaluation, HtmlPageAndSvgHoldBothFigures) {
  EvalResult r;
  r.ate_rmse_m = 0.012;
  r.path_length_m = 10.0;
  r.times_s = {0.0, 1.0};
  r.errors_m = {0.01, 0.014};
  r.gt_xyz = {{0, 0, 0}, {1, 0, 0}};
  r.est_xyz_aligned = {{0, 0.01, 0}, {1, 0.01, 0}};
  const std::string html = evaluationFigure(r, true), svg = evaluationFigure(r, false);
  EXPECT_NE(html.find("<h1>ATE 1.20 cm over 10.0 m</h1>"), std::string::npos);
  for (const std::string& s : {html, svg}) {
    EXPECT_NE(s.find("Top view: ATE RMSE 1.20 cm"), std::string::npos);
    EXPECT_NE(s.find("Position error after alignment"), std::string::npos);
  }
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
}

}  // namespace
}  // namespace mmlio::eval
