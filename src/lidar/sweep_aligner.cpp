#include "mmlio/lidar/sweep_aligner.hpp"

#include <algorithm>

#include "mmlio/core/log.hpp"

namespace mmlio::lidar {

SweepAligner::SweepAligner(Config cfg) : cfg_(std::move(cfg)) {}

void SweepAligner::pushWindow(Stamp start_ns, Stamp end_ns) {
  // Contiguity: the gap to the previous window (the reference's inter-sweep gap, or a dropped
  // sweep shorter than the timeout) is absorbed so the points in it are not lost. After a longer
  // silence with no fallback sensor the window starts afresh.
  if (have_window_ && start_ns - last_window_end_ns_ <= fromSec(cfg_.reference_timeout_s))
    start_ns = last_window_end_ns_;
  if (have_window_) start_ns = std::max(start_ns, last_window_end_ns_);
  if (end_ns <= start_ns) return;
  windows_.push_back({start_ns, end_ns});
  have_window_ = true;
  last_window_end_ns_ = end_ns;
}

void SweepAligner::add(const LidarScan& scan) {
  if (scan.points.empty()) return;
  auto [it, inserted] = sensors_.try_emplace(scan.sensor);
  SensorQueue& q = it->second;
  if (inserted) {
    q.order = sensors_.size() - 1;
    if (fallback_sensor_.empty() && scan.sensor != cfg_.reference) fallback_sensor_ = scan.sensor;
  }
  // Cut points are dropped once they are half the queue: erasing them at every cut moved the
  // queued sweeps (max_wait_s of points) to the front each time.
  if (2 * q.head > q.points.size()) {
    q.points.erase(q.points.begin(), q.points.begin() + static_cast<std::ptrdiff_t>(q.head));
    q.head = 0;
  }
  // Append, keeping the queue sorted even if this scan overlaps the previous one.
  const std::size_t old_size = q.points.size();
  for (const Point& p : scan.points) q.points.push_back({scan.start_ns + fromSec(p.time_s), p});
  const auto by_time = [](const TimedPoint& a, const TimedPoint& b) { return a.t_ns < b.t_ns; };
  if (!std::is_sorted(q.points.begin() + static_cast<std::ptrdiff_t>(old_size), q.points.end(), by_time))
    std::stable_sort(q.points.begin() + static_cast<std::ptrdiff_t>(old_size), q.points.end(), by_time);
  if (old_size > q.head && q.points[old_size].t_ns < q.points[old_size - 1].t_ns)
    std::inplace_merge(q.points.begin() + static_cast<std::ptrdiff_t>(q.head),
                       q.points.begin() + static_cast<std::ptrdiff_t>(old_size), q.points.end(), by_time);
  const Stamp first_ns = scan.start_ns + fromSec(scan.points.front().time_s);
  const Stamp end_ns = scan.endNs();
  q.latest_ns = std::max(q.latest_ns, end_ns);
  if (!have_data_) {
    have_data_ = true;
    reference_mark_ns_ = first_ns;
    first_data_ns_ = first_ns;
  }
  newest_ns_ = std::max(newest_ns_, end_ns);

  if (scan.sensor == cfg_.reference) {
    reference_mark_ns_ = std::max(reference_mark_ns_, end_ns);
    if (fallback_) {
      const std::string msg =
          "sweep aligner: reference LiDAR '" + cfg_.reference + "' is back, its sweeps define the windows again";
      if (!resume_logged_)
        log::info(msg);
      else
        log::debug(msg);  // a flapping reference must not flood the log
      resume_logged_ = true;
      fallback_ = false;
    }
    pushWindow(scan.start_ns, end_ns + 1);  // +1 ns: the last point belongs to this window
  } else {
    q.frames.emplace_back(scan.start_ns, end_ns + 1);
  }
  updateFallback();
  if (fallback_) windowsFromFallbackFrames();
  // Frames older than the windows are no longer needed.
  for (auto& [name, s] : sensors_)
    while (!s.frames.empty() && have_window_ && s.frames.front().second <= last_window_end_ns_) s.frames.pop_front();
}

void SweepAligner::updateFallback() {
  if (fallback_ || fallback_sensor_.empty()) return;
  if (toSec(newest_ns_ - reference_mark_ns_) <= cfg_.reference_timeout_s) return;
  fallback_ = true;
  const bool first = !fallback_logged_;
  fallback_logged_ = true;
  if (first) {
    log::warn("sweep aligner: no data from reference LiDAR '", cfg_.reference, "' for more than ",
              cfg_.reference_timeout_s, " s; windows now come from '", fallback_sensor_, "' frames");
  } else {
    log::debug("sweep aligner: reference '", cfg_.reference, "' silent again; windows from '", fallback_sensor_, "'");
  }
}

void SweepAligner::windowsFromFallbackFrames() {
  auto it = sensors_.find(fallback_sensor_);
  if (it == sensors_.end()) return;
  for (const auto& [start, end] : it->second.frames)
    if (!have_window_ || end > last_window_end_ns_) pushWindow(start, end);
}

bool SweepAligner::complete(const Window& w) const {
  const Stamp max_wait_ns = fromSec(cfg_.max_wait_s);
  if (newest_ns_ >= w.end_ns + max_wait_ns) return true;
  // Start-up: give every LiDAR max_wait_s to show up before releasing anything.
  if (newest_ns_ < first_data_ns_ + max_wait_ns) return false;
  const Stamp silent_ns = fromSec(cfg_.reference_timeout_s);
  for (const auto& [name, s] : sensors_)
    if (s.latest_ns < w.end_ns && newest_ns_ - s.latest_ns <= silent_ns) return false;  // still expected
  return true;
}

AlignedSweep SweepAligner::cut(const Window& w) {
  AlignedSweep out;
  out.start_ns = w.start_ns;
  out.end_ns = w.end_ns;
  std::vector<std::pair<std::size_t, const std::string*>> order;  // reference first, then first-seen
  for (const auto& [name, s] : sensors_) order.emplace_back(name == cfg_.reference ? 0 : s.order + 1, &name);
  std::sort(order.begin(), order.end());
  for (const auto& [rank, name] : order) {
    SensorQueue& q = sensors_[*name];
    const auto front = q.points.begin() + static_cast<std::ptrdiff_t>(q.head);
    const auto before =
        std::partition_point(front, q.points.end(), [&](const TimedPoint& t) { return t.t_ns < w.start_ns; });
    dropped_points_ += static_cast<std::size_t>(before - front);
    LidarScan scan;
    scan.sensor = *name;
    scan.start_ns = w.start_ns;
    // The queue is in time order: the window's points are its front, up to the first at its end.
    const auto end =
        std::partition_point(before, q.points.end(), [&](const TimedPoint& t) { return t.t_ns < w.end_ns; });
    scan.points.reserve(static_cast<std::size_t>(end - before));
    for (auto it = before; it != end; ++it) {
      Point p = it->p;
      p.time_s = static_cast<float>(toSec(it->t_ns - w.start_ns));
      scan.points.push_back(p);
    }
    q.head = static_cast<std::size_t>(end - q.points.begin());
    if (!scan.points.empty()) out.scans.push_back(std::move(scan));
  }
  return out;
}

bool SweepAligner::pop(AlignedSweep* out) {
  if (windows_.empty() || !complete(windows_.front())) return false;
  *out = cut(windows_.front());
  windows_.pop_front();
  return true;
}

std::vector<AlignedSweep> SweepAligner::flush() {
  // A stream shorter than the timeout without any reference sweep still yields windows.
  if (!have_window_ && !fallback_sensor_.empty()) {
    fallback_ = true;
    windowsFromFallbackFrames();
  }
  std::vector<AlignedSweep> out;
  while (!windows_.empty()) {
    out.push_back(cut(windows_.front()));
    windows_.pop_front();
  }
  for (auto& [name, s] : sensors_) s.frames.clear();
  return out;
}

}  // namespace mmlio::lidar
