#include "mmlio/eval/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace mmlio::eval {
namespace {

constexpr int kMaxLineVertices = 4000;
constexpr double kLeft = 62, kRight = 16, kTop = 34, kBottom = 46;  // axes margins, px

std::string num(double v, int decimals = 1) { return fixedText(v, decimals); }

// Tick labels with as many decimals as the step needs.
std::string tickLabel(double v, double step) {
  const int decimals = step >= 1.0 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  return num(std::abs(v) < step * 1e-6 ? 0.0 : v, decimals);
}

std::vector<Eigen::Vector2d> thinned(std::vector<Eigen::Vector2d> xy) {
  if (static_cast<int>(xy.size()) <= kMaxLineVertices) return xy;
  const double stride = static_cast<double>(xy.size() - 1) / (kMaxLineVertices - 1);
  std::vector<Eigen::Vector2d> out;
  out.reserve(kMaxLineVertices);
  for (int i = 0; i < kMaxLineVertices; ++i) out.push_back(xy[static_cast<std::size_t>(std::lround(i * stride))]);
  return out;
}

}  // namespace

std::vector<double> niceTicks(double lo, double hi, int target) {
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  const double raw = (hi - lo) / std::max(1, target);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = power;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw) {
      step = m * power;
      break;
    }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) ticks.push_back(t);
  return ticks;
}

std::string fixedText(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  char text[48];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string xmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  return out;
}

void SvgPlot::line(std::vector<Eigen::Vector2d> xy, const std::string& color, double width_px,
                   const std::string& label) {
  series_.push_back({Kind::kLine, thinned(std::move(xy)), color, width_px, label});
}

void SvgPlot::dots(std::vector<Eigen::Vector2d> xy, const std::string& color, double size_px,
                   const std::string& label) {
  series_.push_back({Kind::kDots, std::move(xy), color, size_px, label});
}

void SvgPlot::marker(const Eigen::Vector2d& xy, const std::string& color, const std::string& label) {
  series_.push_back({Kind::kMarker, {xy}, color, 5.0, label});
}

void SvgPlot::span(double x0, double x1, const std::string& color, const std::string& label) {
  series_.push_back({Kind::kSpan, {{x0, 0.0}, {x1, 0.0}}, color, 0.0, label});
}

std::string SvgPlot::render() const {
  const double W = config_.width_px, H = config_.height_px;
  const double aw = W - kLeft - kRight, ah = H - kTop - kBottom;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const Series& s : series_)
    for (const Eigen::Vector2d& p : s.xy) {
      if (!p.allFinite()) continue;
      x0 = std::min(x0, p.x());
      x1 = std::max(x1, p.x());
      if (s.kind == Kind::kSpan) continue;
      y0 = std::min(y0, p.y());
      y1 = std::max(y1, p.y());
    }
  if (!(x1 >= x0)) x0 = 0, x1 = 1;
  if (!(y1 >= y0)) y0 = 0, y1 = 1;
  if (x_range_) std::tie(x0, x1) = *x_range_;
  if (y_range_) std::tie(y0, y1) = *y_range_;
  if (x1 - x0 < 1e-9) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-9) y0 -= 0.5, y1 += 0.5;
  if (!x_range_) {
    const double pad = 0.03 * (x1 - x0);
    x0 -= pad, x1 += pad;
  }
  if (!y_range_) {
    const double pad = 0.05 * (y1 - y0);
    y0 -= pad, y1 += pad;
  }
  if (config_.equal_aspect) {  // widen the tighter axis about its centre
    const double scale = std::max((x1 - x0) / aw, (y1 - y0) / ah);
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    x0 = cx - 0.5 * aw * scale, x1 = cx + 0.5 * aw * scale;
    y0 = cy - 0.5 * ah * scale, y1 = cy + 0.5 * ah * scale;
  }
  const auto px = [&](double x) { return kLeft + (x - x0) / (x1 - x0) * aw; };
  const auto py = [&](double y) { return kTop + (y1 - y) / (y1 - y0) * ah; };

  std::ostringstream os;
  os << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" viewBox=\"0 0 " << W << ' ' << H << "\" width=\"" << W
     << "\" height=\"" << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  os << "<text x=\"" << kLeft << "\" y=\"20\" font-size=\"14\" font-weight=\"600\">" << xmlEscape(config_.title)
     << "</text>\n";
  os << "<defs><clipPath id=\"" << config_.id << "-clip\"><rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\""
     << aw << "\" height=\"" << ah << "\"/></clipPath></defs>\n";
  // grid and tick labels
  os << "<g stroke=\"#e3e3e3\" stroke-width=\"1\">";
  const std::vector<double> xt = niceTicks(x0, x1, static_cast<int>(aw / 90)), yt = niceTicks(y0, y1, 6);
  for (double t : xt)
    os << "<line x1=\"" << num(px(t)) << "\" x2=\"" << num(px(t)) << "\" y1=\"" << kTop << "\" y2=\"" << kTop + ah
       << "\"/>";
  for (double t : yt)
    os << "<line x1=\"" << kLeft << "\" x2=\"" << kLeft + aw << "\" y1=\"" << num(py(t)) << "\" y2=\"" << num(py(t))
       << "\"/>";
  os << "</g>\n<g fill=\"#444\">";
  const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0, ystep = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double t : xt)
    os << "<text x=\"" << num(px(t)) << "\" y=\"" << kTop + ah + 16 << "\" text-anchor=\"middle\">"
       << tickLabel(t, xstep) << "</text>";
  for (double t : yt)
    os << "<text x=\"" << kLeft - 6 << "\" y=\"" << num(py(t) + 4) << "\" text-anchor=\"end\">" << tickLabel(t, ystep)
       << "</text>";
  os << "<text x=\"" << kLeft + aw / 2 << "\" y=\"" << H - 8 << "\" text-anchor=\"middle\">"
     << xmlEscape(config_.x_label) << "</text>";
  os << "<text transform=\"translate(14," << kTop + ah / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
     << xmlEscape(config_.y_label) << "</text></g>\n";
  os << "<rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << aw << "\" height=\"" << ah
     << "\" fill=\"none\" stroke=\"#999\"/>\n";

  os << "<g clip-path=\"url(#" << config_.id << "-clip)\">\n";
  for (const Series& s : series_) {
    if (s.kind == Kind::kSpan) {
      const double a = px(s.xy[0].x()), b = px(s.xy[1].x());
      os << "<rect x=\"" << num(a) << "\" y=\"" << kTop << "\" width=\"" << num(std::max(1.0, b - a)) << "\" height=\""
         << ah << "\" fill=\"" << s.color << "\" fill-opacity=\"0.18\"/>";
    }
  }
  for (const Series& s : series_) {
    if (s.kind == Kind::kLine) {
      os << "<polyline fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\"" << s.size_px
         << "\" stroke-linejoin=\"round\" points=\"";
      for (const Eigen::Vector2d& p : s.xy)
        if (p.allFinite()) os << num(px(p.x())) << ',' << num(py(p.y())) << ' ';
      os << "\"/>\n";
    } else if (s.kind == Kind::kDots) {
      os << "<path fill=\"" << s.color << "\" d=\"";
      const std::string side = num(s.size_px);
      for (const Eigen::Vector2d& p : s.xy)
        if (p.allFinite())
          os << 'M' << num(px(p.x())) << ' ' << num(py(p.y())) << 'h' << side << 'v' << side << "h-" << side << 'z';
      os << "\"/>\n";
    } else if (s.kind == Kind::kMarker) {
      os << "<circle cx=\"" << num(px(s.xy[0].x())) << "\" cy=\"" << num(py(s.xy[0].y())) << "\" r=\"" << s.size_px
         << "\" fill=\"" << s.color << "\" stroke=\"#222\"/>\n";
    }
  }
  os << "</g>\n";
  // legend, top right inside the axes
  int row = 0;
  for (const Series& s : series_) {
    if (s.label.empty()) continue;
    const double y = kTop + 14 + 17 * row++, x = kLeft + aw - 150;
    os << "<g><rect x=\"" << x - 6 << "\" y=\"" << y - 11 << "\" width=\"152\" height=\"17\" fill=\"#fff\" "
       << "fill-opacity=\"0.8\"/>";
    if (s.kind == Kind::kLine)
      os << "<line x1=\"" << x << "\" x2=\"" << x + 18 << "\" y1=\"" << y - 4 << "\" y2=\"" << y - 4 << "\" stroke=\""
         << s.color << "\" stroke-width=\"" << std::max(2.0, s.size_px) << "\"/>";
    else if (s.kind == Kind::kSpan)
      os << "<rect x=\"" << x << "\" y=\"" << y - 10 << "\" width=\"18\" height=\"12\" fill=\"" << s.color
         << "\" fill-opacity=\"0.3\"/>";
    else
      os << "<circle cx=\"" << x + 9 << "\" cy=\"" << y - 4 << "\" r=\"4\" fill=\"" << s.color << "\"/>";
    os << "<text x=\"" << x + 24 << "\" y=\"" << y << "\">" << xmlEscape(s.label) << "</text></g>\n";
  }
  os << "</svg>\n";
  return os.str();
}

std::string BarChart::render() const {
  constexpr double kRow = 22, kLabelW = 150, kTop = 34, kRight = 70;
  const double bar_h = (kRow - 6) / std::max<std::size_t>(1, sets.size());
  const double H = kTop + kRow * labels.size() + 30, aw = width_px - kLabelW - kRight;
  double hi = 0.0;
  for (const auto& set : sets)
    for (double v : set.second)
      if (std::isfinite(v)) hi = std::max(hi, v);
  if (hi <= 0) hi = 1;
  std::ostringstream os;
  os << "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" viewBox=\"0 0 " << width_px << ' ' << H
     << "\" width=\"" << width_px << "\" height=\"" << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  os << "<text x=\"8\" y=\"20\" font-size=\"14\" font-weight=\"600\">" << xmlEscape(title) << "</text>\n";
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const double y = kTop + kRow * i;
    os << "<text x=\"" << kLabelW - 8 << "\" y=\"" << y + kRow / 2 + 3 << "\" text-anchor=\"end\" fill=\"#333\">"
       << xmlEscape(labels[i]) << "</text>";
    for (std::size_t k = 0; k < sets.size(); ++k) {
      const double v = i < sets[k].second.size() ? sets[k].second[i] : 0.0;
      if (!std::isfinite(v)) continue;
      const std::string color = k < set_colors.size() ? set_colors[k] : "#888";
      const double w = std::max(1.0, v / hi * aw), yb = y + 3 + bar_h * k;
      os << "<rect x=\"" << kLabelW << "\" y=\"" << num(yb) << "\" width=\"" << num(w) << "\" height=\""
         << num(bar_h - 1) << "\" fill=\"" << color << "\"><title>" << xmlEscape(sets[k].first) << ": " << num(v, 2)
         << ' ' << xmlEscape(unit) << "</title></rect>";
      os << "<text x=\"" << num(kLabelW + w + 4) << "\" y=\"" << num(yb + bar_h - 2) << "\" font-size=\"10\" "
         << "fill=\"#555\">" << num(v, v < 10 ? 2 : 1) << "</text>";
    }
    os << '\n';
  }
  double lx = kLabelW;
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const std::string color = k < set_colors.size() ? set_colors[k] : "#888";
    os << "<rect x=\"" << lx << "\" y=\"" << H - 20 << "\" width=\"12\" height=\"12\" fill=\"" << color << "\"/>"
       << "<text x=\"" << lx + 16 << "\" y=\"" << H - 10 << "\">" << xmlEscape(sets[k].first) << " (" << xmlEscape(unit)
       << ")</text>";
    lx += 140;
  }
  os << "</svg>\n";
  return os.str();
}

}  // namespace mmlio::eval
