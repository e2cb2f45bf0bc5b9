// Plots: the PNG decodes to the right size and shows both trajectories in their colours.
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mmlio/core/error.hpp"
#include "mmlio/eval/canvas.hpp"
#include "mmlio/eval/font5x7.hpp"
#include "mmlio/eval/plot2d.hpp"
#include "mmlio/eval/plot_evaluation.hpp"

namespace mmlio::eval {
namespace {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  bool has(Rgb c) const {
    for (size_t i = 0; i + 2 < rgb.size(); i += 3)
      if (rgb[i] == c.r && rgb[i + 1] == c.g && rgb[i + 2] == c.b) return true;
    return false;
  }
};

Image readPng(const std::string& path) {
  Image image;
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) return image;
  png.format = PNG_FORMAT_RGB;
  image.rgb.resize(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, image.rgb.data(), 0, nullptr)) return Image{};
  image.width = static_cast<int>(png.width);
  image.height = static_cast<int>(png.height);
  return image;
}

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "mmlio_eval_" + std::to_string(::getpid()) + "_" + name;
}

EvalResult loopResult() {
  Trajectory gt, est;
  for (int i = 0; i <= 1200; ++i) {
    const double t = i * 0.05, a = 2.0 * M_PI * t / 60.0;
    StampedPose p;
    p.stamp_ns = fromSec(100.0 + t);
    p.T_world_body.translation() = Eigen::Vector3d(20.0 * std::cos(a), 12.0 * std::sin(a), 0.0);
    gt.push_back(p);
    if (i % 2 == 0) {
      p.T_world_body.translation() += Eigen::Vector3d(0.5 * std::sin(3 * a), 0.02 * t, 0.0);
      est.push_back(p);
    }
  }
  return evaluate(gt, est, {});
}

TEST(Plot, EvaluationFigureIsAPngOfTheStatedSizeShowingBothTrajectoryColours) {
  const std::string path = tempPath("evaluation.png");
  plotEvaluation(loopResult(), path);
  const Image image = readPng(path);
  EXPECT_EQ(image.width, 1000);
  EXPECT_EQ(image.height, 1180);
  EXPECT_TRUE(image.has(colors::kGroundTruth));
  EXPECT_TRUE(image.has(colors::kEstimate));
  EXPECT_TRUE(image.has(colors::kBlack));  // axes and labels
  std::remove(path.c_str());
}

TEST(Plot, TrajectoryTopViewPngHasBothSeriesColours) {
  const EvalResult r = loopResult();
  const std::string path = tempPath("top.png");
  plotTrajectories(path, r.gt_xyz, r.est_xyz_aligned, "loop");
  const Image image = readPng(path);
  EXPECT_EQ(image.width, 1000);
  EXPECT_GT(image.height, 0);
  EXPECT_TRUE(image.has(colors::kGroundTruth));
  EXPECT_TRUE(image.has(colors::kEstimate));
  std::remove(path.c_str());
}

TEST(Plot, SavingIntoAMissingDirectoryThrowsNamingThePath) {
  Canvas canvas(4, 4);
  try {
    canvas.savePng("/nonexistent-dir/plot.png");
    FAIL() << "expected mmlio::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/plot.png"), std::string::npos);
  }
}

TEST(Canvas, HorizontalLineCoversExactlyItsPixels) {
  Canvas canvas(20, 10);
  canvas.line(2, 5, 12, 5, colors::kBlack);
  int count = 0;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) count += canvas.pixel(x, y) == colors::kBlack;
  EXPECT_EQ(count, 11);
  EXPECT_EQ(canvas.pixel(2, 5), colors::kBlack);
  EXPECT_EQ(canvas.pixel(12, 5), colors::kBlack);
}

TEST(Canvas, DrawingIsClippedToTheClipRectangle) {
  Canvas canvas(20, 20);
  canvas.setClip(5, 5, 10, 10);
  canvas.fillRect(0, 0, 20, 20, colors::kBlack);
  EXPECT_EQ(canvas.pixel(4, 4), colors::kWhite);
  EXPECT_EQ(canvas.pixel(5, 5), colors::kBlack);
  EXPECT_EQ(canvas.pixel(9, 9), colors::kBlack);
  EXPECT_EQ(canvas.pixel(10, 10), colors::kWhite);
}

TEST(Canvas, TextDrawsTheGlyphBitmapAtTheRequestedScale) {
  Canvas canvas(20, 20);
  canvas.text(1, 1, "1", colors::kBlack, 2);
  // Glyph '1' row 0 is "  #  ": column 2 inked, column 0 not.
  EXPECT_EQ(canvas.pixel(1 + 4, 1), colors::kBlack);
  EXPECT_EQ(canvas.pixel(1 + 5, 2), colors::kBlack);
  EXPECT_EQ(canvas.pixel(1, 1), colors::kWhite);
  EXPECT_EQ(Canvas::textWidth("12", 2), (2 * kGlyphAdvance - 1) * 2);
  for (char c : std::string("0123456789.-:% abcxyzABCXYZ[]()/")) EXPECT_TRUE(hasGlyph(c)) << c;
}

TEST(Plot2D, NiceTicksUseOneTwoFiveStepsCoveringTheRange) {
  EXPECT_EQ(niceTicks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(niceTicks(-0.3, 0.35, 6), (std::vector<double>{-0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3}));
  EXPECT_EQ(formatTick(0.25, 0.05), "0.25");
  EXPECT_EQ(formatTick(-10.0, 5.0), "-10");
}

TEST(Plot2D, ScatterPointsKeepTheirOwnColours) {
  Plot2D::Config config;
  config.legend = false;
  Plot2D plot(config);
  const Rgb dark = colors::greyscale(1.0), light = colors::greyscale(0.3);
  plot.addScatter({{0, 0}, {10, 10}}, {dark, light}, 3.0);
  Canvas canvas(400, 300);
  plot.draw(canvas, 0, 0, 400, 300);
  Image image{canvas.width(), canvas.height(), canvas.rgb()};
  EXPECT_TRUE(image.has(dark));
  EXPECT_TRUE(image.has(light));
}

}  // namespace
}  // namespace mmlio::eval

namespace mmlio::eval {
namespace {
// Not a check: leaves a figure for a human to look at when MMLIO_KEEP_PLOT is set.
TEST(Plot, WritesAFigureForInspectionWhenAsked) {
  if (const char* keep = std::getenv("MMLIO_KEEP_PLOT")) plotEvaluation(loopResult(), keep);
}

// Map-style top view: many grey points by intensity, the trajectory on top. Checks that the
// trajectory stays visible over the scatter and the darkest map pixels are present.
TEST(Plot2D, MapScatterUnderATrajectoryKeepsBothVisible) {
  Plot2D::Config config;
  config.title = "map top view";
  config.x_label = "x [m]";
  config.y_label = "y [m]";
  config.equal_aspect = true;
  Plot2D plot(config);
  std::vector<Eigen::Vector2d> points;
  std::vector<Rgb> shades;
  for (int i = 0; i < 60000; ++i) {  // a noisy rectangular "building" outline, intensity by side
    const double u = (i % 1000) / 1000.0, side = (i / 1000) % 4;
    const double jitter = 0.3 * std::sin(i * 12.9898);
    const Eigen::Vector2d corner[5] = {{-40, -25}, {40, -25}, {40, 25}, {-40, 25}, {-40, -25}};
    const int k = static_cast<int>(side);
    points.push_back(corner[k] + u * (corner[k + 1] - corner[k]) + Eigen::Vector2d(jitter, -jitter));
    shades.push_back(colors::greyscale(0.25 * (side + 1)));
  }
  plot.addScatter(points, shades, 0.0, "");
  std::vector<Eigen::Vector2d> path;
  for (int i = 0; i <= 400; ++i) {
    const double a = 2 * M_PI * i / 400.0;
    path.emplace_back(30 * std::cos(a), 15 * std::sin(a));
  }
  plot.addLine(path, colors::kEstimate, 2.0, "trajectory");
  Canvas canvas(900, 700);
  plot.draw(canvas, 0, 0, 900, 700);
  Image image{canvas.width(), canvas.height(), canvas.rgb()};
  EXPECT_TRUE(image.has(colors::kEstimate));
  EXPECT_TRUE(image.has(colors::greyscale(1.0)));
  EXPECT_TRUE(image.has(colors::greyscale(0.25)));
  if (const char* keep = std::getenv("MMLIO_KEEP_MAP_PLOT")) canvas.savePng(keep);
}
}  // namespace
}  // namespace mmlio::eval
