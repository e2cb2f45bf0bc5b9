#pragma once
// A tiny RGB raster canvas for plots: lines, polylines, circles, rectangles and 5x7 bitmap
// text, saved as PNG. Pixel coordinates: x to the right, y down, (0, 0) the top-left pixel.
// Every drawing call is clipped to the canvas and to the current clip rectangle.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace mmlio::eval {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

namespace colors {
constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kGrey{128, 128, 128};
constexpr Rgb kGroundTruth{0, 114, 189};  // blue
constexpr Rgb kEstimate{217, 83, 25};     // orange-red
constexpr Rgb kGreen{40, 160, 60};
constexpr Rgb kPurple{126, 47, 142};
/// Grey level for a value in [0, 1] (0 light, 1 dark), e.g. map intensity on a white background.
Rgb greyscale(double value01);
}  // namespace colors

class Canvas {
 public:
  Canvas(int width, int height, Rgb background = colors::kWhite);

  int width() const { return width_; }
  int height() const { return height_; }
  Rgb pixel(int x, int y) const;  // black outside the canvas
  void setPixel(int x, int y, Rgb color);

  /// Restricts drawing to [x0, x1) x [y0, y1) (intersected with the canvas).
  void setClip(int x0, int y0, int x1, int y1);
  void resetClip();

  /// Straight line; widths above 1 px are drawn as a chain of discs (round caps).
  void line(double x0, double y0, double x1, double y1, Rgb color, double width_px = 1.0);
  void polyline(const std::vector<Eigen::Vector2d>& points_px, Rgb color, double width_px = 1.0);
  void circle(double cx, double cy, double radius_px, Rgb color, bool filled = true);
  void fillRect(int x, int y, int w, int h, Rgb color);
  void rect(int x, int y, int w, int h, Rgb color);  // 1 px outline

  /// Text with its top-left corner at (x, y); each font pixel becomes scale x scale pixels.
  void text(int x, int y, const std::string& s, Rgb color, int scale = 1);
  /// Text rotated 90 degrees counter-clockwise (reads bottom to top), its bottom-left at (x, y).
  void textVertical(int x, int y, const std::string& s, Rgb color, int scale = 1);
  static int textWidth(const std::string& s, int scale = 1);
  static int textHeight(int scale = 1);  // cap height; g p q y hang 2 * scale below it

  /// Row-major RGB bytes, 3 per pixel.
  const std::vector<std::uint8_t>& rgb() const { return rgb_; }

  /// Writes an 8-bit RGB PNG (via libpng). Throws mmlio::Error naming the path on failure.
  void savePng(const std::string& path) const;

 private:
  bool inClip(int x, int y) const { return x >= clip_x0_ && x < clip_x1_ && y >= clip_y0_ && y < clip_y1_; }

  int width_, height_;
  int clip_x0_ = 0, clip_y0_ = 0, clip_x1_, clip_y1_;
  std::vector<std::uint8_t> rgb_;
};

}  // namespace mmlio::eval
