#include "mmlio/eval/canvas.hpp"

#include <algorithm>
#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/eval/font5x7.hpp"

namespace mmlio::eval {

Rgb colors::greyscale(double value01) {
  const double v = std::clamp(value01, 0.0, 1.0);
  const auto level = static_cast<std::uint8_t>(std::lround(230.0 * (1.0 - v)));
  return {level, level, level};
}

Canvas::Canvas(int width, int height, Rgb background)
    : width_(width), height_(height), clip_x1_(width), clip_y1_(height) {
  if (width <= 0 || height <= 0 || width > 20000 || height > 20000)
    throw Error("Canvas: size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range");
  rgb_.resize(static_cast<size_t>(width) * static_cast<size_t>(height) * 3);
  for (size_t i = 0; i < rgb_.size(); i += 3) {
    rgb_[i] = background.r;
    rgb_[i + 1] = background.g;
    rgb_[i + 2] = background.b;
  }
}

Rgb Canvas::pixel(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return colors::kBlack;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)) * 3;
  return {rgb_[i], rgb_[i + 1], rgb_[i + 2]};
}

void Canvas::setPixel(int x, int y, Rgb color) {
  if (!inClip(x, y)) return;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)) * 3;
  rgb_[i] = color.r;
  rgb_[i + 1] = color.g;
  rgb_[i + 2] = color.b;
}

void Canvas::setClip(int x0, int y0, int x1, int y1) {
  clip_x0_ = std::clamp(x0, 0, width_);
  clip_y0_ = std::clamp(y0, 0, height_);
  clip_x1_ = std::clamp(x1, clip_x0_, width_);
  clip_y1_ = std::clamp(y1, clip_y0_, height_);
}

void Canvas::resetClip() { setClip(0, 0, width_, height_); }

void Canvas::line(double x0, double y0, double x1, double y1, Rgb color, double width_px) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  // Keep absurd coordinates (a zoomed-in plot of a far outlier) from looping for ages.
  const double limit = 4.0 * std::max(width_, height_);
  if (std::max({std::abs(x0), std::abs(y0), std::abs(x1), std::abs(y1)}) > limit) {
    // Clip the segment parametrically to the enlarged box (Liang-Barsky).
    double t0 = 0.0, t1 = 1.0;
    const double dx = x1 - x0, dy = y1 - y0;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {x0 + limit, limit - x0, y0 + limit, limit - y0};
    for (int k = 0; k < 4; ++k) {
      if (p[k] == 0.0) {
        if (q[k] < 0.0) return;
        continue;
      }
      const double t = q[k] / p[k];
      if (p[k] < 0.0)
        t0 = std::max(t0, t);
      else
        t1 = std::min(t1, t);
    }
    if (t0 > t1) return;
    const double nx0 = x0 + t0 * dx, ny0 = y0 + t0 * dy;
    x1 = x0 + t1 * dx;
    y1 = y0 + t1 * dy;
    x0 = nx0;
    y0 = ny0;
  }
  const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))));
  for (int i = 0; i <= steps; ++i) {
    const double u = static_cast<double>(i) / steps;
    const double x = x0 + u * (x1 - x0), y = y0 + u * (y1 - y0);
    if (width_px <= 1.5)
      setPixel(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)), color);
    else
      circle(x, y, 0.5 * width_px, color, true);
  }
}

void Canvas::polyline(const std::vector<Eigen::Vector2d>& points_px, Rgb color, double width_px) {
  if (points_px.size() == 1) circle(points_px[0].x(), points_px[0].y(), 0.5 * std::max(width_px, 1.0), color);
  for (size_t i = 1; i < points_px.size(); ++i)
    line(points_px[i - 1].x(), points_px[i - 1].y(), points_px[i].x(), points_px[i].y(), color, width_px);
}

void Canvas::circle(double cx, double cy, double radius_px, Rgb color, bool filled) {
  if (!std::isfinite(cx) || !std::isfinite(cy) || !(radius_px >= 0.0)) return;
  const int x_lo = static_cast<int>(std::floor(cx - radius_px)), x_hi = static_cast<int>(std::ceil(cx + radius_px));
  const int y_lo = static_cast<int>(std::floor(cy - radius_px)), y_hi = static_cast<int>(std::ceil(cy + radius_px));
  if (x_hi < clip_x0_ || x_lo >= clip_x1_ || y_hi < clip_y0_ || y_lo >= clip_y1_) return;
  const double r2 = radius_px * radius_px + 0.25;  // +0.25 px^2 keeps tiny circles from vanishing
  const double inner2 = std::max(0.0, radius_px - 1.0) * std::max(0.0, radius_px - 1.0);
  for (int y = y_lo; y <= y_hi; ++y)
    for (int x = x_lo; x <= x_hi; ++x) {
      const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
      if (d2 <= r2 && (filled || d2 >= inner2)) setPixel(x, y, color);
    }
}

void Canvas::fillRect(int x, int y, int w, int h, Rgb color) {
  for (int yy = std::max(y, clip_y0_); yy < std::min(y + h, clip_y1_); ++yy)
    for (int xx = std::max(x, clip_x0_); xx < std::min(x + w, clip_x1_); ++xx) setPixel(xx, yy, color);
}

void Canvas::rect(int x, int y, int w, int h, Rgb color) {
  fillRect(x, y, w, 1, color);
  fillRect(x, y + h - 1, w, 1, color);
  fillRect(x, y, 1, h, color);
  fillRect(x + w - 1, y, 1, h, color);
}

int Canvas::textWidth(const std::string& s, int scale) {
  return s.empty() ? 0 : (static_cast<int>(s.size()) * kGlyphAdvance - 1) * scale;
}

int Canvas::textHeight(int scale) { return kGlyphHeight * scale; }

void Canvas::text(int x, int y, const std::string& s, Rgb color, int scale) {
  for (size_t k = 0; k < s.size(); ++k) {
    const auto& rows = glyph(s[k]);
    const int gx = x + static_cast<int>(k) * kGlyphAdvance * scale;
    const int gy = y + glyphDrop(s[k]) * scale;
    for (int r = 0; r < kGlyphHeight; ++r)
      for (int c = 0; c < kGlyphWidth; ++c)
        if (rows[r] & (1u << (kGlyphWidth - 1 - c))) fillRect(gx + c * scale, gy + r * scale, scale, scale, color);
  }
}

void Canvas::textVertical(int x, int y, const std::string& s, Rgb color, int scale) {
  // Rotating CCW maps glyph column c to height above the baseline point and row r to x.
  for (size_t k = 0; k < s.size(); ++k) {
    const auto& rows = glyph(s[k]);
    const int gy = y - static_cast<int>(k) * kGlyphAdvance * scale;
    const int gx = x + glyphDrop(s[k]) * scale;
    for (int r = 0; r < kGlyphHeight; ++r)
      for (int c = 0; c < kGlyphWidth; ++c)
        if (rows[r] & (1u << (kGlyphWidth - 1 - c)))
          fillRect(gx + r * scale, gy - (c + 1) * scale, scale, scale, color);
  }
}

}  // namespace mmlio::eval
