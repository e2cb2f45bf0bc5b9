#include "mmlio/pipeline/report_html.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

#include "mmlio/eval/svg_plot.hpp"
#include "mmlio/report_page.hpp"

namespace mmlio::pipeline {
namespace {

using eval::xmlEscape;
const auto fixed = eval::fixedText;

double pathLength(const Trajectory& trajectory) {
  double length = 0.0;
  for (std::size_t i = 1; i < trajectory.size(); ++i)
    length += (trajectory[i].T_world_body.translation() - trajectory[i - 1].T_world_body.translation()).norm();
  return length;
}

// The pose nearest in time to `stamp_ns` (the trajectory is in time order).
const StampedPose* poseAt(const Trajectory& trajectory, Stamp stamp_ns) {
  if (trajectory.empty()) return nullptr;
  const auto it = std::lower_bound(trajectory.begin(), trajectory.end(), stamp_ns,
                                   [](const StampedPose& p, Stamp t) { return p.stamp_ns < t; });
  if (it == trajectory.end()) return &trajectory.back();
  if (it != trajectory.begin() && stamp_ns - std::prev(it)->stamp_ns < it->stamp_ns - stamp_ns) return &*std::prev(it);
  return &*it;
}

// ---- the answer first ----

struct Card {
  std::string key, label, value, note;
};

std::string cardsHtml(const std::vector<Card>& cards) {
  std::string html = "<div class=\"cards\">\n";
  for (const Card& c : cards)
    html += "<div class=\"card\" data-figure=\"" + c.key + "\"><div class=\"k\">" + xmlEscape(c.label) +
            "</div><div class=\"v\">" + xmlEscape(c.value) + "</div><div class=\"n\">" + xmlEscape(c.note) +
            "</div></div>\n";
  return html + "</div>\n";
}

std::vector<Card> summaryCards(const RunReport& r, const Trajectory& trajectory) {
  std::vector<Card> cards;
  const double duration = r.input.duration_s;
  cards.push_back({"duration_s", "duration", fixed(duration, 1) + " s", r.input.mode + " mode"});
  cards.push_back(
      {"path_m", "path length", fixed(pathLength(trajectory), 1) + " m", std::to_string(trajectory.size()) + " poses"});
  cards.push_back(
      {"realtime_factor", "speed", fixed(r.realtime_factor, 1) + "x real time", fixed(r.wall_time_s, 1) + " s wall"});
  if (r.evaluation) {
    const eval::EvalResult& e = *r.evaluation;
    cards.push_back({"ate_cm", "ATE RMSE", fixed(100.0 * e.ate_rmse_m, 2) + " cm",
                     "max " + fixed(100.0 * e.ate_max_m, 1) + " cm, " + fixed(e.ate_rot_rmse_deg, 2) + " deg"});
    const double pct = e.path_length_m > 0 ? 100.0 * e.end_to_end_m / e.path_length_m : NAN;
    cards.push_back(
        {"end_to_end_cm", "end to end", fixed(100.0 * e.end_to_end_m, 1) + " cm", fixed(pct, 2) + " % of the path"});
  }
  cards.push_back({"loops", "loops closed", std::to_string(r.mapping.accepted),
                   r.mapping.enabled ? std::to_string(r.mapping.attempts) + " tried" : "loop closure off"});
  const double degenerate_pct =
      r.sweeps.tracked > 0 ? 100.0 * static_cast<double>(r.sweeps.degenerate) / r.sweeps.tracked : 0.0;
  cards.push_back({"degenerate", "degenerate sweeps", std::to_string(r.sweeps.degenerate),
                   fixed(degenerate_pct, 1) + " % rode partly on the IMU"});
  cards.push_back(
      {"degraded", "degraded sweeps", std::to_string(r.sweeps.degraded),
       fixed(100.0 * r.sweeps.degraded_fraction, 1) + " %, coverage " + fixed(100.0 * r.sweeps.coverage, 0) + " %"});
  cards.push_back({"input", "input", r.inputDegraded() ? "degraded" : "complete", r.inputStatus()});
  cards.push_back({"map_points", "map", std::to_string(r.outputs.map_points) + " points",
                   fixed(100.0 * r.outputs.map_voxel_m, 0) + " cm voxels"});
  cards.push_back({"peak_rss_mb", "peak memory", fixed(r.memory.peak_rss_mb, 0) + " MB", ""});
  return cards;
}

std::string headerHtml(const RunReport& r, const std::string& title) {
  const bool complete = r.status == "complete";
  const bool trusted = r.untrusted.empty();
  std::string html = "<header><h1>" + xmlEscape(title) + "</h1><div class=\"sub\">";
  html += "<span class=\"badge " + std::string(complete ? "ok" : "warn") + "\" id=\"status\">" + xmlEscape(r.status) +
          "</span>";
  html += "<span class=\"badge " + std::string(trusted ? "ok" : "bad") + "\" id=\"trust\">" +
          (trusted ? "trusted" : "untrusted") + "</span>";
  html += "mmlio " + xmlEscape(r.run.mmlio_version) + " (" + xmlEscape(r.run.commit) + "), extrinsics from " +
          xmlEscape(r.run.calibration) + "</div>";
  if (!trusted) html += "<p class=\"reasons\">" + xmlEscape(r.untrusted) + "</p>";
  if (!r.mapping_error.empty()) html += "<p class=\"reasons\">mapping: " + xmlEscape(r.mapping_error) + "</p>";
  return html + "</header>\n";
}

// ---- the 3D view ----

template <typename T> void append(std::vector<std::uint8_t>* out, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out->insert(out->end(), p, p + sizeof(T));
}

/// The map section, its points streamed as base64 (the largest part of the page: written as it is
/// encoded, never held as text).
void writeView3d(std::ostream& os, const RunReport& r, const Trajectory& trajectory,
                 const std::vector<Point>& map_world, const HtmlScripts& scripts, const HtmlReportLimits& limits) {
  std::string html = "<section><h2>Map</h2><div id=\"view3d\">";
  if (!scripts.available()) {
    os << html
       << "<div class=\"missing\">The 3D view needs three.js: <code>apt-get install libjs-three</code> (or point "
          "MMLIO_JS_DIR at a folder holding three/three.min.js), then run again.</div></div></section>\n";
    return;
  }
  const std::size_t stride = std::max<std::size_t>(
      1, (map_world.size() + limits.max_map_points - 1) / std::max<std::size_t>(1, limits.max_map_points));
  // Coordinates relative to the trajectory's start: float32 keeps millimetres within kilometres.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  if (!trajectory.empty()) origin = trajectory.front().T_world_body.translation();
  std::vector<Eigen::Vector3f> points, poses, keyframes, loops;
  std::vector<std::uint8_t> intensity;
  for (std::size_t i = 0; i < map_world.size(); i += stride) {
    points.emplace_back((map_world[i].xyz.cast<double>() - origin).cast<float>());
    intensity.push_back(static_cast<std::uint8_t>(std::clamp(map_world[i].intensity, 0.f, 255.f)));
  }
  const std::size_t pose_stride = std::max<std::size_t>(1, trajectory.size() / 20000 + 1);
  for (std::size_t i = 0; i < trajectory.size(); i += pose_stride)
    poses.emplace_back((trajectory[i].T_world_body.translation() - origin).cast<float>());
  Stamp first_keyframe_ns = -1;
  for (const RunReport::SweepSample& s : r.timeline) {
    if (!s.keyframe) continue;
    if (first_keyframe_ns < 0) first_keyframe_ns = s.stamp_ns;
    if (const StampedPose* p = poseAt(trajectory, s.stamp_ns))
      keyframes.emplace_back((p->T_world_body.translation() - origin).cast<float>());
  }
  if (first_keyframe_ns < 0 && !trajectory.empty()) first_keyframe_ns = trajectory.front().stamp_ns;
  for (const backend::ClosedLoop& loop : r.mapping.loops) {
    const StampedPose* a = poseAt(trajectory, first_keyframe_ns + fromSec(loop.query_s));
    const StampedPose* b = poseAt(trajectory, first_keyframe_ns + fromSec(loop.match_s));
    if (!a || !b) continue;
    loops.emplace_back((a->T_world_body.translation() - origin).cast<float>());
    loops.emplace_back((b->T_world_body.translation() - origin).cast<float>());
  }
  std::vector<std::uint8_t> data;
  data.reserve(12 * (points.size() + poses.size() + keyframes.size() + loops.size()) + intensity.size());
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), high = -low;
  for (const auto* set : {&points, &poses, &keyframes, &loops})
    for (const Eigen::Vector3f& p : *set) {
      for (int c = 0; c < 3; ++c) append(&data, p(c));
      if (set == &points) low = low.cwiseMin(p), high = high.cwiseMax(p);
    }
  data.insert(data.end(), intensity.begin(), intensity.end());
  if (points.empty()) low = high = Eigen::Vector3f::Zero();
  // Height colours span the 2nd to 98th percentile, so a few stray points do not wash them out.
  std::vector<float> z;
  z.reserve(points.size());
  for (const Eigen::Vector3f& p : points) z.push_back(p.z());
  float z_low = low.z(), z_high = high.z();
  if (z.size() > 50) {
    std::nth_element(z.begin(), z.begin() + z.size() / 50, z.end());
    z_low = z[z.size() / 50];
    std::nth_element(z.begin(), z.begin() + z.size() * 49 / 50, z.end());
    z_high = z[z.size() * 49 / 50];
  }
  double mean_z = 0.0;  // of the trajectory, relative to its start like the points
  for (const Eigen::Vector3f& p : poses) mean_z += p.z() / poses.size();
  char meta[512];
  std::snprintf(meta, sizeof(meta),
                "{\"points\":%zu,\"poses\":%zu,\"keyframes\":%zu,\"loops\":%zu,\"x_low\":%.3f,\"x_high\":%.3f,"
                "\"y_low\":%.3f,\"y_high\":%.3f,\"z_low\":%.3f,\"z_high\":%.3f,\"z_max\":%.3f,\"cut_z\":%.3f}",
                points.size(), poses.size(), keyframes.size(), loops.size() / 2, low.x(), high.x(), low.y(), high.y(),
                z_low, z_high, high.z(), std::min<double>(high.z() + 0.01, mean_z + 1.0));
  html +=
      "<canvas id=\"view3d-canvas\"></canvas><div class=\"tools\">colour <select id=\"view3d-colour\">"
      "<option value=\"height\">height</option><option value=\"intensity\">intensity</option></select> "
      "point size <input id=\"view3d-size\" type=\"range\" min=\"1\" max=\"6\" step=\"0.5\" value=\"2\"> "
      "cut above <input id=\"view3d-cut\" type=\"range\" step=\"0.05\"> "
      "<label><input type=\"checkbox\" data-layer=\"trajectory\" checked> trajectory</label>"
      "<label><input type=\"checkbox\" data-layer=\"keyframes\" checked> keyframes</label>"
      "<label><input type=\"checkbox\" data-layer=\"loops\" checked> loops</label></div>"
      "<div class=\"hint\">drag: orbit, right-drag: pan, wheel: zoom &middot; " +
      std::to_string(points.size()) + " of " + std::to_string(map_world.size()) + " map points</div></div>";
  html += "<script type=\"application/json\" id=\"view3d-meta\">" + std::string(meta) + "</script>\n";
  os << html << "<script type=\"application/octet-stream\" id=\"view3d-data\">";
  constexpr std::size_t kChunk = std::size_t{3} * 16384;  // a multiple of 3: no padding inside the stream
  for (std::size_t i = 0; i < data.size(); i += kChunk)
    os << base64(data.data() + i, std::min(kChunk, data.size() - i));
  os << "</script>\n</section>\n";
}

// ---- plots ----

std::vector<std::pair<double, double>> degenerateSpans(const RunReport& r, Stamp t0_ns) {
  std::vector<std::pair<double, double>> spans;
  for (const RunReport::SweepSample& s : r.timeline) {
    const double t = toSec(s.stamp_ns - t0_ns);
    if (!s.degenerate) continue;
    if (!spans.empty() && t - spans.back().second < 0.25)
      spans.back().second = t;
    else
      spans.emplace_back(t - 0.05, t);
  }
  return spans;
}

std::string plotsHtml(const RunReport& r, const Trajectory& trajectory, const std::vector<Point>& map_world,
                      const HtmlReportLimits& limits) {
  std::string html = "<section><h2>Plots</h2><div class=\"plots\">\n";
  const auto figure = [&html](const std::string& svg) { html += "<figure>" + svg + "</figure>\n"; };
  const Stamp t0_ns = trajectory.empty() ? 0 : trajectory.front().stamp_ns;
  const auto spans = degenerateSpans(r, t0_ns);
  const auto shade = [&spans](eval::SvgPlot& plot) {
    for (std::size_t i = 0; i < spans.size(); ++i)
      plot.span(spans[i].first, spans[i].second, eval::colors::kSpan, i == 0 ? "degenerate" : "");
  };

  // Top view: a slice of the map around the trajectory's height, the estimate, and the ground truth
  // brought into the map's frame.
  {
    eval::SvgPlot::Config c;
    c.id = "topview";
    c.title = "Top view";
    c.x_label = "x [m]";
    c.y_label = "y [m]";
    c.width_px = 640, c.height_px = 520;
    c.equal_aspect = true;
    eval::SvgPlot plot(c);
    double mean_z = 0.0;
    for (const StampedPose& p : trajectory) mean_z += p.T_world_body.translation().z() / trajectory.size();
    std::vector<Eigen::Vector2d> slice;
    const std::size_t stride = std::max<std::size_t>(1, map_world.size() / 60000);
    for (std::size_t i = 0; i < map_world.size(); i += stride)
      if (std::abs(map_world[i].xyz.z() - mean_z) < limits.slice_half_height_m)
        slice.emplace_back(map_world[i].xyz.x(), map_world[i].xyz.y());
    plot.dots(std::move(slice), "#b9bec5", 1.0, "map slice");
    if (r.evaluation) {
      std::vector<Eigen::Vector2d> gt;
      const Eigen::Isometry3d T_est_gt = r.evaluation->T_gt_est.inverse();
      for (const Eigen::Vector3d& p : r.evaluation->gt_xyz) gt.emplace_back((T_est_gt * p).head<2>());
      plot.line(std::move(gt), eval::colors::kGroundTruth, 2.5, "ground truth");
    }
    std::vector<Eigen::Vector2d> est;
    for (const StampedPose& p : trajectory) est.emplace_back(p.T_world_body.translation().head<2>());
    if (!est.empty()) plot.marker(est.front(), eval::colors::kStart, "start");
    plot.line(std::move(est), eval::colors::kEstimate, 1.5, "estimate");
    figure(plot.render());
  }
  if (r.evaluation) {
    const eval::EvalResult& e = *r.evaluation;
    eval::SvgPlot::Config c;
    c.id = "error";
    c.title = "Position error after alignment (ATE " + fixed(100.0 * e.ate_rmse_m, 2) + " cm)";
    c.x_label = "time [s]";
    c.y_label = "error [cm]";
    eval::SvgPlot plot(c);
    shade(plot);
    std::vector<Eigen::Vector2d> err;
    const double offset = e.gt_start_s - toSec(t0_ns);
    double t_low = 0, t_high = 1, e_high = 0;
    for (std::size_t i = 0; i < e.times_s.size() && i < e.errors_m.size(); ++i) {
      err.emplace_back(e.times_s[i] + offset, 100.0 * e.errors_m[i]);
      e_high = std::max(e_high, 100.0 * e.errors_m[i]);
    }
    if (!err.empty()) t_low = err.front().x(), t_high = err.back().x();
    plot.xRange(t_low, t_high);
    plot.yRange(0.0, e_high > 0 ? 1.15 * e_high : 1.0);
    plot.line({{t_low, 100.0 * e.ate_rmse_m}, {t_high, 100.0 * e.ate_rmse_m}}, eval::colors::kReference, 1.0, "RMSE");
    plot.line(std::move(err), eval::colors::kEstimate, 1.5, "error");
    figure(plot.render());
  }
  if (!r.timeline.empty()) {
    std::vector<Eigen::Vector2d> edges, planes, weakest, ms;
    for (const RunReport::SweepSample& s : r.timeline) {
      const double t = toSec(s.stamp_ns - t0_ns);
      edges.emplace_back(t, s.edges);
      planes.emplace_back(t, s.planes);
      weakest.emplace_back(t, s.weakest_points);
      ms.emplace_back(t, s.total_ms);
    }
    const auto timePlot = [&](const std::string& id, const std::string& title, const std::string& y_label) {
      eval::SvgPlot::Config c;
      c.id = id, c.title = title, c.x_label = "time [s]", c.y_label = y_label;
      return eval::SvgPlot(c);
    };
    eval::SvgPlot features = timePlot("features", "Features per sweep", "features");
    shade(features);
    features.line(std::move(planes), "#1f77b4", 1.2, "planes");
    features.line(std::move(edges), "#9467bd", 1.2, "edges");
    figure(features.render());
    eval::SvgPlot degeneracy =
        timePlot("degeneracy", "Weakest translation direction (effective points)", "effective points");
    shade(degeneracy);
    double high = 0.0;
    for (const Eigen::Vector2d& p : weakest) high = std::max(high, p.y());
    degeneracy.yRange(0.0, std::min(high, 400.0) * 1.05 + 1.0);  // a wide-open sweep would flatten the rest
    degeneracy.line(std::move(weakest), "#17becf", 1.2, "weakest direction");
    figure(degeneracy.render());
    eval::SvgPlot time = timePlot("sweep-time", "Processing time per sweep", "ms");
    time.line(std::move(ms), "#8c564b", 1.0, "odometry");
    figure(time.render());
  }
  if (r.timing.sweeps() > 0) {
    eval::BarChart bars;
    bars.title = "Time per stage";
    bars.unit = "ms";
    bars.set_colors = {"#4e79a7", "#f28e2b"};
    std::vector<double> mean, p95;
    for (const std::string& stage : r.timing.stages()) {
      bars.labels.push_back(stage);
      mean.push_back(r.timing.meanMs(stage));
      p95.push_back(r.timing.p95Ms(stage));
    }
    bars.sets = {{"mean", mean}, {"p95", p95}};
    figure(bars.render());
  }
  return html + "</div></section>\n";
}

// ---- how the run started, per LiDAR ----

std::string startupHtml(const RunReport& r) {
  std::string html = "<section><h2>Start-up and sensors</h2><table id=\"startup\">";
  const auto row = [&html](const std::string& k, const std::string& v) {
    html += "<tr><th>" + xmlEscape(k) + "</th><td>" + xmlEscape(v) + "</td></tr>";
  };
  row("IMU initialisation",
      std::string(r.imu_init.ok ? "" : "FAILED: ") + (r.imu_init.forced ? "forced: " : "") + r.imu_init.message);
  row("gravity",
      fixed(r.imu_init.gravity_norm_m_s2, 3) + " m/s^2, accelerometer scale " + fixed(r.input.imu_acc_scale, 5));
  row("gyroscope bias", fixed(r.imu_init.gyro_bias.x(), 4) + ", " + fixed(r.imu_init.gyro_bias.y(), 4) + ", " +
                            fixed(r.imu_init.gyro_bias.z(), 4) + " rad/s");
  row("IMU biases estimated while running",
      "accelerometer " + fixed(r.imu_bias.acc_end_m_s2.norm(), 3) + " m/s^2 at the end (at most " +
          fixed(r.imu_bias.max_acc_m_s2, 3) + " at " + fixed(r.imu_bias.max_acc_at_s, 0) + " s), gyroscope " +
          fixed(r.imu_bias.gyro_end_rad_s.norm(), 4) + " rad/s (at most " + fixed(r.imu_bias.max_gyro_rad_s, 4) +
          " at " + fixed(r.imu_bias.max_gyro_at_s, 0) + " s)");
  row("extrinsics", r.run.calibration + " (config_used.yaml holds them as run)");
  if (!r.mount_check.lidar.empty())
    row("mount check",
        std::string(r.mount_check.checked && !r.mount_check.agrees ? "CONTRADICTED: " : "") + r.mount_check.message);
  row("mode", r.input.mode + ", config " + (r.input.config.empty() ? "built-in defaults" : r.input.config));
  html +=
      "</table><table id=\"lidars\"><tr><th>LiDAR</th><th>sweeps</th><th>points / sweep</th>"
      "<th>edges / sweep</th><th>planes / sweep</th><th>bad frames</th></tr>";
  for (const auto& [name, f] : r.features) {
    const double n = static_cast<double>(std::max<std::size_t>(1, f.sweeps));
    html += "<tr><td>" + xmlEscape(name) + "</td><td>" + std::to_string(f.sweeps) + "</td><td>" +
            fixed(f.points / n, 0) + "</td><td>" + fixed(f.edges / n, 0) + "</td><td>" + fixed(f.planes / n, 0) +
            "</td><td>" + std::to_string(f.bad_frames) + "</td></tr>";
  }
  return html + "</table></section>\n";
}

// ---- every field, collapsed ----

std::string scalarText(const Json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return fixed(v.get<double>(), 4);
  return v.dump();
}

void jsonHtml(std::string& html, const Json& v) {
  if (v.is_object()) {
    html += "<table>";
    for (const auto& [k, item] : v.items()) {
      html += "<tr><th>" + xmlEscape(k) + "</th><td>";
      if (item.is_structured() && item.dump().size() > 200) {
        html += "<details><summary>" + std::to_string(item.size()) + " entries</summary>";
        jsonHtml(html, item);
        html += "</details>";
      } else {
        jsonHtml(html, item);
      }
      html += "</td></tr>";
    }
    html += "</table>";
  } else if (v.is_array()) {
    bool scalars = true;
    for (const Json& item : v) scalars &= !item.is_structured();
    if (scalars) {
      std::string text;
      for (const Json& item : v) text += (text.empty() ? "" : ", ") + scalarText(item);
      html += xmlEscape(text);
      return;
    }
    for (const Json& item : v) jsonHtml(html, item);
  } else {
    html += xmlEscape(scalarText(v));
  }
}

std::string detailsHtml(const Json& report) {
  std::string html = "<section><h2>Details</h2>\n";
  for (const auto& [section, value] : report.items()) {
    html += "<details><summary>" + xmlEscape(section) + "</summary>";
    if (section == "run" && value.contains("config_yaml")) {
      Json run = value;
      const std::string yaml = run["config_yaml"].get<std::string>();
      run.erase("config_yaml");
      jsonHtml(html, run);
      html += "<details><summary>config_yaml</summary><pre>" + xmlEscape(yaml) + "</pre></details>";
    } else {
      jsonHtml(html, value);
    }
    html += "</details>\n";
  }
  return html + "</section>\n";
}

}  // namespace

std::string base64(const std::uint8_t* data, std::size_t size) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t a = data[i], b = i + 1 < size ? data[i + 1] : 0, c = i + 2 < size ? data[i + 2] : 0;
    const std::uint32_t triple = (a << 16) | (b << 8) | c;
    out += kAlphabet[(triple >> 18) & 63];
    out += kAlphabet[(triple >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < size ? kAlphabet[triple & 63] : '=';
  }
  return out;
}

void writeHtml(std::ostream& os, const RunReport& report, const Trajectory& trajectory,
               const std::vector<Point>& map_world, const HtmlScripts& scripts, const std::string& title,
               const HtmlReportLimits& limits) {
  // Written section by section: an autosaving node's page is tens of MB, and held whole (plus the
  // copies its concatenation makes) it was the run's peak memory.
  os << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
        // Nothing outside this file may load: the page works offline and leaks nothing.
        "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; script-src 'unsafe-inline'; "
        "style-src 'unsafe-inline'; img-src data:\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>mmlio: "
     << xmlEscape(title) << "</title>\n<style>" << kReportCss
     << "</style>\n<script>window.mmlioBlocked = 0; document.addEventListener('securitypolicyviolation', function () {"
        " window.mmlioBlocked += 1; document.body.dataset.blocked = String(window.mmlioBlocked); });</script>\n"
        "</head><body><main>\n";
  os << headerHtml(report, title);
  os << cardsHtml(summaryCards(report, trajectory));
  writeView3d(os, report, trajectory, map_world, scripts, limits);
  os << plotsHtml(report, trajectory, map_world, limits);
  os << startupHtml(report);
  os << detailsHtml(toJson(report));
  os << "<footer>Written by mmlio " << xmlEscape(report.run.mmlio_version)
     << ". Self-contained: the map, plots and scripts are inside this file.</footer>\n</main>\n";
  if (scripts.available()) {
    os << "<script>" << scripts.three << "</script>\n<script>" << scripts.orbit_controls << "</script>\n";
    os << "<script>" << kView3dJs << "</script>\n";
  }
  os << "</body></html>\n";
}

std::string toHtml(const RunReport& report, const Trajectory& trajectory, const std::vector<Point>& map_world,
                   const HtmlScripts& scripts, const std::string& title, const HtmlReportLimits& limits) {
  std::ostringstream os;
  writeHtml(os, report, trajectory, map_world, scripts, title, limits);
  return os.str();
}

}  // namespace mmlio::pipeline
