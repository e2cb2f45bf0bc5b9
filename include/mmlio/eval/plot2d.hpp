#pragma once
// A small 2D plot: axes with "nice" ticks, grid, labels, a legend and several series (lines,
// scatters with per-point colours, markers), drawn into a rectangle of a Canvas. Used for the
// trajectory top view, the error-over-time panel and the run report's map top view.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mmlio/eval/canvas.hpp"

namespace mmlio::eval {

class Plot2D {
 public:
  struct Config {
    std::string title;          // drawn above the axes (may be empty)
    std::string x_label;        // e.g. "x [m]"
    std::string y_label;        // drawn vertically left of the y ticks
    bool equal_aspect = false;  // same metres per pixel on both axes (top views)
    bool legend = true;         // legend box for labelled series
    enum class Corner { kTopRight, kTopLeft, kBottomRight, kBottomLeft };
    Corner legend_corner = Corner::kTopRight;  // where the legend sits inside the axes
    int text_scale = 2;                        // font pixel size of ticks and labels
    double margin_fraction = 0.04;             // data-range padding on each side when ranges are automatic
  };

  explicit Plot2D(Config config) : config_(std::move(config)) {}

  /// A connected line through `xy` (data units).
  void addLine(std::vector<Eigen::Vector2d> xy, Rgb color, double width_px = 2.0, std::string label = "");
  /// Points, one colour each (`colors` same size as `xy`); radius 0 draws single pixels.
  void addScatter(std::vector<Eigen::Vector2d> xy, std::vector<Rgb> colors, double radius_px = 0.0,
                  std::string label = "");
  void addScatter(std::vector<Eigen::Vector2d> xy, Rgb color, double radius_px = 0.0, std::string label = "");
  /// One marker (filled circle with a dark outline), e.g. a trajectory's start.
  void addMarker(const Eigen::Vector2d& xy, Rgb color, double radius_px = 5.0, std::string label = "");

  /// Fixes an axis range instead of fitting the data (equal_aspect may still widen one axis).
  void setXRange(double lo, double hi) { x_range_ = std::make_pair(lo, hi); }
  void setYRange(double lo, double hi) { y_range_ = std::make_pair(lo, hi); }

  /// Draws the whole plot (title, axes, series, legend) inside [x, x+width) x [y, y+height).
  void draw(Canvas& canvas, int x, int y, int width, int height) const;

 private:
  enum class Kind { kLine, kScatter, kMarker };
  struct Series {
    Kind kind;
    std::vector<Eigen::Vector2d> xy;
    std::vector<Rgb> colors;  // one per point (scatter) or one for the series
    double size_px;
    std::string label;
  };

  Config config_;
  std::vector<Series> series_;
  std::optional<std::pair<double, double>> x_range_, y_range_;
};

/// Tick positions covering [lo, hi] with a 1-2-5 x 10^k step and about `target_count` ticks.
std::vector<double> niceTicks(double lo, double hi, int target_count);
/// Formats a tick value with just enough decimals for `step` ("0.25", "-10", "1200").
std::string formatTick(double value, double step);

}  // namespace mmlio::eval
