#include "mmlio/pipeline/online_pipeline.hpp"

#include "mmlio/core/log.hpp"

#include "mmlio/pipeline/odometry_setup.hpp"

namespace mmlio::pipeline {
namespace {

constexpr double kMaxScanJumpS = 2.0;       // a scan further after its LiDAR's previous one ...
constexpr int kScanJumpConfirmations = 3;   // ... is dropped unless this many in a row agree

lidar::SweepAligner::Config alignerConfig(const io::RigConfig& cfg, const std::string& mode) {
  lidar::SweepAligner::Config c;
  c.reference = io::referenceLidar(cfg, mode).name;
  return c;
}

}  // namespace

OnlinePipeline::OnlinePipeline(const io::RigConfig& cfg, const std::string& mode, SweepCallback on_sweep)
    : aligner_(alignerConfig(cfg, mode)),
      odometry_(cfg.estimator, lidarSetups(cfg, mode)),
      on_sweep_(std::move(on_sweep)) {
  for (const auto& s : lidarSetups(cfg, mode)) offset_s_[s.extrinsic.name] = s.extrinsic.time_offset_s;
}

void OnlinePipeline::addImu(const ImuSample& sample) {
  if (!imu_gate_.accept(sample)) return;
  odometry_.addImu(sample);
  drain(false);
}

void OnlinePipeline::addScan(LidarScan scan) {
  const auto it = offset_s_.find(scan.sensor);
  if (it == offset_s_.end()) return;
  scan.start_ns += fromSec(it->second);  // t_imu = t_stamp + offset
  const auto drop = [&](std::size_t* count, const std::string& why) {
    if ((*count)++ == 0) log::warn(scan.sensor, " scan dropped: ", why, " (further ones are counted in the report)");
  };
  const auto last = last_scan_ns_.find(scan.sensor);
  if (last != last_scan_ns_.end()) {
    if (scan.start_ns <= last->second) return drop(&scan_drops_.out_of_order, "not after the previous scan of this LiDAR");
    if (scan.start_ns - last->second > fromSec(kMaxScanJumpS)) {
      // A lone stamp far ahead is corrupt; a LiDAR that stays there had a real gap.
      Jump& jump = scan_jumps_[scan.sensor];
      const bool continues = jump.run > 0 && scan.start_ns > jump.last_ns && scan.start_ns - jump.last_ns < fromSec(1.0);
      jump.run = continues ? jump.run + 1 : 1;
      jump.last_ns = scan.start_ns;
      if (jump.run < kScanJumpConfirmations)
        return drop(&scan_drops_.jumped, "it starts " + std::to_string(toSec(scan.start_ns - last->second)) +
                                             " s after this LiDAR's previous scan");
    }
  }
  scan_jumps_[scan.sensor].run = 0;
  last_scan_ns_[scan.sensor] = scan.start_ns;
  aligner_.add(scan);
  drain(false);
}

void OnlinePipeline::flush() { drain(true); }

void OnlinePipeline::drain(bool all) {
  lidar::AlignedSweep sweep;
  while (aligner_.pop(&sweep)) pending_.push_back(std::move(sweep));
  if (all) {
    for (auto& s : aligner_.flush()) pending_.push_back(std::move(s));
  }
  while (!pending_.empty() && (all || pending_.front().end_ns <= odometry_.lastImuNs())) {
    const estimator::SweepResult r = odometry_.process(pending_.front());
    pending_.pop_front();
    ++processed_;
    on_sweep_(r);
  }
}

}  // namespace mmlio::pipeline
