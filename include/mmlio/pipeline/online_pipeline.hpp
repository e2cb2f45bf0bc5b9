#pragma once
// The streaming core shared by `mmlio run` (bag) and the ROS node (live topics): IMU samples
// and LiDAR scans in, in any interleaving; fused, de-skewed, estimated sweeps out once the IMU
// covers their end.
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/estimator/odometry.hpp"
#include "mmlio/lidar/sweep_aligner.hpp"
#include "mmlio/pipeline/imu_gate.hpp"
#include "mmlio/pipeline/stream_tally.hpp"
#include "mmlio/pipeline/stamp_jump_guard.hpp"

namespace mmlio::pipeline {

class OnlinePipeline {
 public:
  using SweepCallback = std::function<void(estimator::SweepResult)>;  // the callee may keep it

  /// Throws mmlio::Error on a bad mode or a config with no active LiDAR.
  OnlinePipeline(const config::RigConfig& cfg, const std::string& mode, SweepCallback on_sweep);

  void addImu(const ImuSample& sample);
  /// scan.sensor names a configured LiDAR; others are ignored. Its clock offset is applied here.
  void addScan(LidarScan scan);
  /// At the end of a stream: processes the sweeps still waiting (IMU permitting).
  void flush();

  const estimator::Odometry& odometry() const { return odometry_; }
  /// What the IMU check dropped before the estimator.
  const ImuGate& imuGate() const { return imu_gate_; }
  /// LiDAR scans dropped before the sweep aligner: not after the same LiDAR's previous scan, or a
  /// lone stamp more than 2 s after it (a corrupt stamp would otherwise hold every later sweep
  /// back; a LiDAR that resumes after a real gap is accepted again after three scans), or more
  /// than 2 s before it (let in only when the whole time base went back: TimeBaseJump).
  struct ScanDrops {
    std::size_t out_of_order = 0, jumped = 0;
    Stamp first_at_ns = 0, last_at_ns = 0;  // the LiDAR's last accepted scan at the first and last drop
  };
  const ScanDrops& scanDrops() const { return scan_drops_; }
  std::size_t sweepsProcessed() const { return processed_; }
  /// Every LiDAR stream's scans received and missing as of the stream's end, in the stream's time.
  std::map<std::string, StreamTally::Stream> lidarStreams(Stamp stream_end_ns) const;
  /// The same for the IMU's accepted samples.
  StreamTally::Stream imuStream(Stamp stream_end_ns) const;
  /// Most sweeps that waited at once for the IMU to cover them (bounded: see kMaxImuWaitNs).
  std::size_t waitingHighWater() const { return waiting_high_water_; }

  /// A sweep waits for the IMU to cover its end, but only until the LiDARs are this far past it:
  /// then it goes on without (registered by the LiDARs alone, counted as degraded). An IMU that
  /// stopped would otherwise keep every later sweep in memory until the end of the stream.
  static constexpr Stamp kMaxImuWaitNs = 2000000000LL;

  /// A jump of the whole stream's time base: the IMU and every LiDAR resumed together `jump_s`
  /// after their last data (a clock re-sync, bags joined, a paused recording) or before it (a bag
  /// played again from its start, `rosbag play -l`, a clock set back). The pipeline then
  /// continues as if no time had passed (stamps shifted back) instead of extrapolating the motion
  /// over the gap; the estimator's stamps stay shifted, externalStamp() maps them back.
  struct TimeBaseJump {
    Stamp at_ns = 0;     // first shifted stamp, in the stream's (external) time
    Stamp shift_ns = 0;  // subtracted from every later stamp
  };
  const std::vector<TimeBaseJump>& timeBaseJumps() const { return time_jumps_; }
  /// An estimator stamp in the stream's own time (the bag's stamps).
  Stamp externalStamp(Stamp internal_ns) const;
  /// The reverse, for a stream stamp after the latest jump (the stream's end).
  Stamp internalStamp(Stamp external_ns) const { return external_ns - shift_ns_; }

 private:
  void drain(bool all);
  /// A tallied stream's stamps (the estimator's) in the stream's own time.
  void inputTime(StreamTally::Stream* st) const;

  std::map<std::string, double> offset_s_;
  lidar::SweepAligner aligner_;
  estimator::Odometry odometry_;
  ImuGate imu_gate_;
  ScanDrops scan_drops_;
  StreamTally streams_;     // in the estimator's stamps
  StreamTally imu_stream_;  // the same, one stream named "imu"
  std::map<std::string, Stamp> last_scan_ns_;
  std::map<std::string, StampJumpGuard> scan_jumps_;  // per LiDAR
  bool timeBaseJumped(Stamp imu_jump_ns) const;
  /// Records a jump of the time base by gap_ns (either way) at the input's stamp at_ns; returns
  /// the shift it adds to shift_ns_.
  Stamp shiftTimeBase(Stamp at_ns, Stamp gap_ns);
  StampJumpGuard& scanJumpGuard(const std::string& sensor);
  Stamp shift_ns_ = 0;       // subtracted from every incoming stamp
  Stamp imu_period_ns_ = 0;  // latest spacing of accepted IMU samples
  std::vector<TimeBaseJump> time_jumps_;
  std::deque<lidar::AlignedSweep> pending_;
  SweepCallback on_sweep_;
  std::size_t processed_ = 0;
  std::size_t waiting_high_water_ = 0;
};

}  // namespace mmlio::pipeline
