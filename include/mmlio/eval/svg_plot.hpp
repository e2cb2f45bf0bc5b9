#pragma once
// Plots as SVG text: axes with "nice" ticks, grid, labels, a legend and several series (lines,
// dots, markers, shaded time spans), and horizontal bar charts. The browser draws the text with
// real fonts, so a figure stays sharp at any zoom; pages (report.html) inline them as they are.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mmlio::eval {

/// Colours shared by every figure (CSS colour strings).
namespace colors {
inline constexpr const char* kEstimate = "#d62728";
inline constexpr const char* kGroundTruth = "#1f77b4";
inline constexpr const char* kStart = "#2ca02c";
inline constexpr const char* kMap = "#9aa0a6";
inline constexpr const char* kReference = "#7f7f7f";
inline constexpr const char* kSpan = "#ff7f0e";
}  // namespace colors

/// Round tick values covering [lo, hi], about `target` of them (1, 2, 5 times a power of ten).
std::vector<double> niceTicks(double lo, double hi, int target = 6);

class SvgPlot {
 public:
  struct Config {
    std::string id = "plot";  // unique within a page (names the clip path)
    std::string title, x_label, y_label;
    int width_px = 640, height_px = 360;
    bool equal_aspect = false;  // same metres per pixel on both axes (top views)
  };

  explicit SvgPlot(Config config) : config_(std::move(config)) {}

  /// A connected line through `xy` (data units); long series are thinned to about 4000 vertices.
  void line(std::vector<Eigen::Vector2d> xy, const std::string& color, double width_px = 1.5,
            const std::string& label = "");
  /// Dots of one colour drawn as one path (tens of thousands stay light).
  void dots(std::vector<Eigen::Vector2d> xy, const std::string& color, double size_px = 1.0,
            const std::string& label = "");
  /// A filled circle with a dark outline, e.g. a trajectory's start.
  void marker(const Eigen::Vector2d& xy, const std::string& color, const std::string& label = "");
  /// A shaded span of x (e.g. a degenerate spell), behind the series.
  void span(double x0, double x1, const std::string& color, const std::string& label = "");

  void xRange(double lo, double hi) { x_range_ = std::make_pair(lo, hi); }
  void yRange(double lo, double hi) { y_range_ = std::make_pair(lo, hi); }

  /// The whole figure: <svg ...>...</svg>.
  std::string render() const;

 private:
  enum class Kind { kLine, kDots, kMarker, kSpan };
  struct Series {
    Kind kind;
    std::vector<Eigen::Vector2d> xy;
    std::string color;
    double size_px;
    std::string label;
  };
  Config config_;
  std::vector<Series> series_;
  std::optional<std::pair<double, double>> x_range_, y_range_;
};

/// Horizontal bars, one row per label, one bar per value set (e.g. mean and p95 per stage).
struct BarChart {
  std::string title, unit;
  std::vector<std::string> labels;
  std::vector<std::pair<std::string, std::vector<double>>> sets;  // legend name, one value per label
  std::vector<std::string> set_colors;
  int width_px = 640;
  std::string render() const;
};

/// Escapes &, <, >, " and ' for XML/HTML text and attributes.
std::string xmlEscape(const std::string& text);

/// `value` with `decimals` digits after the point ("0.72"), "n/a" when it is not finite.
std::string fixedText(double value, int decimals);

}  // namespace mmlio::eval
