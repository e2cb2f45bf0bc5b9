#include "mmlio/eval/plot2d.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace mmlio::eval {
namespace {

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo <= hi; }
  double span() const { return hi - lo; }
};

/// Widens an empty or degenerate range and pads it by `fraction` on each side.
Range padded(Range r, double fraction) {
  if (!r.valid()) return {0.0, 1.0};
  if (r.span() <= 0.0) {
    const double half = std::max(1.0, std::abs(r.lo) * 0.05);
    return {r.lo - half, r.hi + half};
  }
  const double pad = fraction * r.span();
  return {r.lo - pad, r.hi + pad};
}

}  // namespace

std::vector<double> niceTicks(double lo, double hi, int target_count) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
  const double raw = (hi - lo) / std::max(1, target_count);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double fraction = raw / magnitude;
  const double mantissa = fraction < 1.5 ? 1.0 : fraction < 3.5 ? 2.0 : fraction < 7.5 ? 5.0 : 10.0;
  const double step = mantissa * magnitude;
  // Dividing by an exact power of ten (rather than multiplying by 0.1...) gives the double
  // nearest the decimal, so a tick prints and compares as "0.3", not 0.30000000000000004.
  const double inverse_magnitude = magnitude < 1.0 ? std::round(1.0 / magnitude) : 0.0;
  for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0) {
    const double v = inverse_magnitude > 0.0 ? (k * mantissa) / inverse_magnitude : k * step;
    ticks.push_back(v == 0.0 ? 0.0 : v);  // no "-0"
  }
  return ticks;
}

std::string formatTick(double value, double step) {
  const int decimals = step > 0.0 ? std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9))) : 0;
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f", std::min(decimals, 9), value);
  std::string s = text;
  if (s == "-0" || s.rfind("-0.", 0) == 0) {  // "-0.00" after rounding a tiny negative
    bool all_zero = s.find_first_not_of("-0.") == std::string::npos;
    if (all_zero) s.erase(0, 1);
  }
  return s;
}

void Plot2D::addLine(std::vector<Eigen::Vector2d> xy, Rgb color, double width_px, std::string label) {
  series_.push_back({Kind::kLine, std::move(xy), {color}, width_px, std::move(label)});
}

void Plot2D::addScatter(std::vector<Eigen::Vector2d> xy, std::vector<Rgb> colors, double radius_px, std::string label) {
  if (colors.size() != xy.size()) colors.resize(xy.size(), colors.empty() ? colors::kBlack : colors.front());
  series_.push_back({Kind::kScatter, std::move(xy), std::move(colors), radius_px, std::move(label)});
}

void Plot2D::addScatter(std::vector<Eigen::Vector2d> xy, Rgb color, double radius_px, std::string label) {
  std::vector<Rgb> colors(xy.size(), color);
  addScatter(std::move(xy), std::move(colors), radius_px, std::move(label));
}

void Plot2D::addMarker(const Eigen::Vector2d& xy, Rgb color, double radius_px, std::string label) {
  series_.push_back({Kind::kMarker, {xy}, {color}, radius_px, std::move(label)});
}

void Plot2D::draw(Canvas& canvas, int x, int y, int width, int height) const {
  const int s = std::max(1, config_.text_scale);
  const int th = Canvas::textHeight(s);
  const int gap = 3 * s;

  // Data ranges.
  Range xr, yr;
  for (const Series& series : series_)
    for (const Eigen::Vector2d& p : series.xy) {
      xr.add(p.x());
      yr.add(p.y());
    }
  xr = x_range_ ? Range{x_range_->first, x_range_->second} : padded(xr, config_.margin_fraction);
  yr = y_range_ ? Range{y_range_->first, y_range_->second} : padded(yr, config_.margin_fraction);
  if (!(xr.span() > 0.0)) xr = padded(xr, 0.0);
  if (!(yr.span() > 0.0)) yr = padded(yr, 0.0);

  // Layout: title on top, y label and tick labels on the left, tick labels and x label below.
  const int top = y + (config_.title.empty() ? gap : th + 3 * gap);
  const int bottom_margin = th + 2 * gap + (config_.x_label.empty() ? 0 : th + 2 * gap);
  const int right = x + width - 4 * gap;
  const int bottom = y + height - bottom_margin;
  // Y tick labels decide the left margin; estimate with the widest label of a first tick pass.
  int plot_h = std::max(10, bottom - top);
  std::vector<double> y_ticks = niceTicks(yr.lo, yr.hi, std::max(2, plot_h / (5 * th)));
  const double y_step_guess = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : yr.span();
  int label_w = 0;
  for (double t : y_ticks) label_w = std::max(label_w, Canvas::textWidth(formatTick(t, y_step_guess), s));
  const int left = x + gap + (config_.y_label.empty() ? 0 : th + 2 * gap) + label_w + 2 * gap;
  int plot_w = std::max(10, right - left);

  // Equal aspect: widen the axis that has fewer metres per pixel.
  if (config_.equal_aspect) {
    const double mx = xr.span() / plot_w, my = yr.span() / plot_h;
    if (mx > my) {
      const double c = 0.5 * (yr.lo + yr.hi), half = 0.5 * mx * plot_h;
      yr = {c - half, c + half};
    } else {
      const double c = 0.5 * (xr.lo + xr.hi), half = 0.5 * my * plot_w;
      xr = {c - half, c + half};
    }
    y_ticks = niceTicks(yr.lo, yr.hi, std::max(2, plot_h / (5 * th)));
  }
  const std::vector<double> x_ticks =
      niceTicks(xr.lo, xr.hi, std::max(2, plot_w / (Canvas::textWidth("-000.0", s) * 2)));
  const double x_step = x_ticks.size() > 1 ? x_ticks[1] - x_ticks[0] : xr.span();
  const double y_step = y_ticks.size() > 1 ? y_ticks[1] - y_ticks[0] : yr.span();

  const auto to_px = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(left + (p.x() - xr.lo) / xr.span() * (plot_w - 1),
                           top + (yr.hi - p.y()) / yr.span() * (plot_h - 1));
  };

  // Title, grid and ticks.
  if (!config_.title.empty())
    canvas.text(x + (width - Canvas::textWidth(config_.title, s)) / 2, y + gap, config_.title, colors::kBlack, s);
  for (double t : x_ticks) {
    const int px = static_cast<int>(std::lround(to_px({t, yr.lo}).x()));
    canvas.fillRect(px, top, 1, plot_h, colors::kGrid);
    canvas.fillRect(px, top + plot_h, 1, gap, colors::kBlack);
    const std::string label = formatTick(t, x_step);
    canvas.text(px - Canvas::textWidth(label, s) / 2, top + plot_h + gap + s, label, colors::kBlack, s);
  }
  for (double t : y_ticks) {
    const int py = static_cast<int>(std::lround(to_px({xr.lo, t}).y()));
    canvas.fillRect(left, py, plot_w, 1, colors::kGrid);
    canvas.fillRect(left - gap, py, gap, 1, colors::kBlack);
    const std::string label = formatTick(t, y_step);
    canvas.text(left - gap - s - Canvas::textWidth(label, s), py - th / 2, label, colors::kBlack, s);
  }
  if (!config_.x_label.empty())
    canvas.text(left + (plot_w - Canvas::textWidth(config_.x_label, s)) / 2, top + plot_h + 2 * gap + th + gap,
                config_.x_label, colors::kBlack, s);
  if (!config_.y_label.empty())
    canvas.textVertical(x + gap, top + (plot_h + Canvas::textWidth(config_.y_label, s)) / 2, config_.y_label,
                        colors::kBlack, s);

  // Series, clipped to the plot area, in insertion order (later ones on top).
  canvas.setClip(left, top, left + plot_w, top + plot_h);
  for (const Series& series : series_) {
    switch (series.kind) {
      case Kind::kLine: {
        std::vector<Eigen::Vector2d> px;
        px.reserve(series.xy.size());
        for (const Eigen::Vector2d& p : series.xy) px.push_back(to_px(p));
        canvas.polyline(px, series.colors.front(), series.size_px);
        break;
      }
      case Kind::kScatter:
        for (size_t i = 0; i < series.xy.size(); ++i) {
          const Eigen::Vector2d p = to_px(series.xy[i]);
          if (series.size_px <= 0.5)
            canvas.setPixel(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())),
                            series.colors[i]);
          else
            canvas.circle(p.x(), p.y(), series.size_px, series.colors[i]);
        }
        break;
      case Kind::kMarker: {
        const Eigen::Vector2d p = to_px(series.xy.front());
        canvas.circle(p.x(), p.y(), series.size_px + 1.5, colors::kBlack);
        canvas.circle(p.x(), p.y(), series.size_px, series.colors.front());
        break;
      }
    }
  }

  // Legend inside the plot area, in the configured corner.
  std::vector<const Series*> labelled;
  for (const Series& series : series_)
    if (!series.label.empty()) labelled.push_back(&series);
  if (config_.legend && !labelled.empty()) {
    const int swatch = 6 * s, row_h = th + 2 * gap;
    int text_w = 0;
    for (const Series* series : labelled) text_w = std::max(text_w, Canvas::textWidth(series->label, s));
    const int box_w = swatch + text_w + 4 * gap, box_h = static_cast<int>(labelled.size()) * row_h + gap;
    using Corner = Config::Corner;
    const Corner corner = config_.legend_corner;
    const bool at_right = corner == Corner::kTopRight || corner == Corner::kBottomRight;
    const bool at_top = corner == Corner::kTopRight || corner == Corner::kTopLeft;
    const int bx = at_right ? left + plot_w - box_w - gap : left + gap;
    const int by = at_top ? top + gap : top + plot_h - box_h - gap;
    canvas.fillRect(bx, by, box_w, box_h, colors::kWhite);
    canvas.rect(bx, by, box_w, box_h, colors::kGrey);
    for (size_t k = 0; k < labelled.size(); ++k) {
      const Series& series = *labelled[k];
      const int cy = by + gap + static_cast<int>(k) * row_h + th / 2;
      const Rgb color = series.colors.front();
      if (series.kind == Kind::kLine)
        canvas.line(bx + gap, cy, bx + gap + swatch, cy, color, std::max(2.0, series.size_px));
      else
        canvas.circle(bx + gap + swatch / 2.0, cy, std::max(2.0, std::min(series.size_px, th / 2.0)), color);
      canvas.text(bx + 2 * gap + swatch + gap, cy - th / 2, series.label, colors::kBlack, s);
    }
  }
  canvas.resetClip();
  canvas.rect(left - 1, top - 1, plot_w + 2, plot_h + 2, colors::kBlack);
}

}  // namespace mmlio::eval
