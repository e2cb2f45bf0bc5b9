#include "mmlio/pipeline/online_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mmlio/core/log.hpp"

#include "mmlio/pipeline/odometry_setup.hpp"

namespace mmlio::pipeline {
namespace {

constexpr double kMaxScanJumpS = 2.0;        // a scan further after its LiDAR's previous one ...
constexpr int kScanJumpConfirmations = 3;    // ... is dropped unless this many in a row agree,
constexpr double kScanRunSpacingS = 1.0;     // ... each within this of the one before
constexpr double kTimeBaseJumpS = 1.0;       // the IMU resuming this much later, every LiDAR alike ...
constexpr double kTimeBaseAgreementS = 0.3;  // ... within this: the stream's time base jumped

lidar::SweepAligner::Config alignerConfig(const config::RigConfig& cfg, const std::string& mode) {
  lidar::SweepAligner::Config c;
  c.reference = config::referenceLidar(cfg, mode).name;
  return c;
}

}  // namespace

OnlinePipeline::OnlinePipeline(const config::RigConfig& cfg, const std::string& mode, SweepCallback on_sweep)
    : aligner_(alignerConfig(cfg, mode)),
      odometry_(cfg.estimator, lidarSetups(cfg, mode)),
      on_sweep_(std::move(on_sweep)) {
  for (const auto& s : lidarSetups(cfg, mode)) {
    offset_s_[s.extrinsic.name] = s.extrinsic.time_offset_s;
    streams_.expect(s.extrinsic.name);
  }
}

void OnlinePipeline::addImu(const ImuSample& sample) {
  ImuSample s = sample;
  s.stamp_ns -= shift_ns_;
  const Stamp last_ns = imu_gate_.lastNs();
  if (!imu_gate_.accept(s)) {
    // Gone back with every LiDAR alike (a bag played again, a clock set back): go on from here.
    if (!imu_gate_.wentBack() || !timeBaseJumped(s.stamp_ns - last_ns)) return;
    s.stamp_ns -= shiftTimeBase(sample.stamp_ns, s.stamp_ns - last_ns);
    if (!imu_gate_.accept(s)) return;
  } else if (last_ns != std::numeric_limits<Stamp>::min()) {
    const Stamp gap_ns = s.stamp_ns - last_ns;
    if (gap_ns > fromSec(kTimeBaseJumpS) && timeBaseJumped(gap_ns)) {
      const Stamp shift = shiftTimeBase(sample.stamp_ns, gap_ns);
      s.stamp_ns -= shift;
      imu_gate_.shiftBack(shift);
    } else if (gap_ns <= fromSec(kTimeBaseJumpS)) {
      imu_period_ns_ = gap_ns;
    }
  }
  imu_stream_.add("imu", s.stamp_ns);
  odometry_.addImu(s);
  drain(false);
}

Stamp OnlinePipeline::shiftTimeBase(Stamp at_ns, Stamp gap_ns) {
  // The gate confirmed the IMU's jump on this sample: continue the stream as if only the samples
  // the gate held back had passed.
  const int held_back = imu_gate_.config().jump_confirmations;
  const Stamp shift = gap_ns - held_back * std::max<Stamp>(imu_period_ns_, 1);
  time_jumps_.push_back({at_ns, shift_ns_ + shift});
  log::warn("time base jumped ", gap_ns > 0 ? "ahead" : "back", " by ", toSec(gap_ns > 0 ? gap_ns : -gap_ns), " s at ",
            log::stampText(at_ns),
            " s (IMU and every LiDAR together): continuing as if no time passed; outputs keep the input's stamps");
  shift_ns_ += shift;
  for (auto& [sensor, jump] : scan_jumps_) jump.accepted();
  return shift;
}

bool OnlinePipeline::timeBaseJumped(Stamp imu_jump_ns) const {
  // Every LiDAR's latest scans were held back for jumping by about as much as the IMU did.
  for (const auto& [sensor, offset] : offset_s_) {
    const auto j = scan_jumps_.find(sensor);
    if (j == scan_jumps_.end() || !j->second.pending()) return false;
    if (std::abs(toSec(j->second.pendingJumpNs() - imu_jump_ns)) > kTimeBaseAgreementS) return false;
  }
  return !offset_s_.empty();
}

StampJumpGuard& OnlinePipeline::scanJumpGuard(const std::string& sensor) {
  return scan_jumps_.try_emplace(sensor, kMaxScanJumpS, kScanJumpConfirmations, kScanRunSpacingS).first->second;
}

Stamp OnlinePipeline::externalStamp(Stamp internal_ns) const {
  Stamp shift = 0;
  for (const TimeBaseJump& j : time_jumps_)
    if (internal_ns >= j.at_ns - j.shift_ns) shift = j.shift_ns;
  return internal_ns + shift;
}

void OnlinePipeline::addScan(LidarScan scan) {
  const auto it = offset_s_.find(scan.sensor);
  if (it == offset_s_.end()) return;
  scan.start_ns += fromSec(it->second) - shift_ns_;  // t_imu = t_stamp + offset
  const auto last = last_scan_ns_.find(scan.sensor);
  const auto drop = [&](std::size_t* count, const std::string& why) {
    const Stamp at = last != last_scan_ns_.end() ? last->second : scan.start_ns;
    if (scan_drops_.out_of_order + scan_drops_.jumped == 0) scan_drops_.first_at_ns = at;
    scan_drops_.last_at_ns = at;
    if ((*count)++ == 0) log::warn(scan.sensor, " scan dropped: ", why, " (further ones are counted in the report)");
  };
  if (last != last_scan_ns_.end()) {
    // Far back: kept out unless the IMU goes back alike (then addImu shifts the time base).
    StampJumpGuard& jump = scanJumpGuard(scan.sensor);
    if (jump.jumpedBack(last->second, scan.start_ns)) {
      jump.holdBack(last->second, scan.start_ns);
      return drop(&scan_drops_.jumped, "it starts " + std::to_string(toSec(last->second - scan.start_ns)) +
                                           " s before this LiDAR's previous scan");
    }
    if (scan.start_ns <= last->second)
      return drop(&scan_drops_.out_of_order, "not after the previous scan of this LiDAR");
    // A lone stamp far ahead is corrupt; a LiDAR that stays there had a real gap.
    if (jump.jumped(last->second, scan.start_ns) && jump.holdBack(last->second, scan.start_ns))
      return drop(&scan_drops_.jumped, "it starts " + std::to_string(toSec(scan.start_ns - last->second)) +
                                           " s after this LiDAR's previous scan");
  }
  scanJumpGuard(scan.sensor).accepted();
  last_scan_ns_[scan.sensor] = scan.start_ns;
  streams_.add(scan.sensor, scan.start_ns);
  aligner_.add(scan);
  drain(false);
}

void OnlinePipeline::flush() { drain(true); }

std::map<std::string, StreamTally::Stream> OnlinePipeline::lidarStreams(Stamp stream_end_ns) const {
  std::map<std::string, StreamTally::Stream> out = streams_.streamsUntil(stream_end_ns - shift_ns_);
  for (auto& [sensor, st] : out) inputTime(&st);
  return out;
}

StreamTally::Stream OnlinePipeline::imuStream(Stamp stream_end_ns) const {
  std::map<std::string, StreamTally::Stream> out = imu_stream_.streamsUntil(stream_end_ns - shift_ns_);
  StreamTally::Stream st = out.empty() ? StreamTally::Stream() : out.begin()->second;
  inputTime(&st);
  return st;
}

void OnlinePipeline::inputTime(StreamTally::Stream* st) const {
  st->first_ns = externalStamp(st->first_ns);
  st->last_ns = externalStamp(st->last_ns);
  for (StreamTally::Gap& g : st->gaps) g.after_ns = externalStamp(g.after_ns);
}

void OnlinePipeline::drain(bool all) {
  lidar::AlignedSweep sweep;
  while (aligner_.pop(&sweep)) pending_.push_back(std::move(sweep));
  if (all) {
    for (auto& s : aligner_.flush()) pending_.push_back(std::move(s));
  }
  waiting_high_water_ = std::max(waiting_high_water_, pending_.size());
  const auto ready = [&](const lidar::AlignedSweep& front) {
    return all || front.end_ns <= odometry_.lastImuNs() || pending_.back().end_ns - front.end_ns > kMaxImuWaitNs;
  };
  while (!pending_.empty() && ready(pending_.front())) {
    estimator::SweepResult r = odometry_.process(std::move(pending_.front()));
    pending_.pop_front();
    ++processed_;
    on_sweep_(std::move(r));
  }
}

}  // namespace mmlio::pipeline
