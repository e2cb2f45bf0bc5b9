// Odometry stage: the IMU prediction over a sweep and the motion that de-skews it; without IMU
// over the sweep, the last motion carried on.
#include <algorithm>

#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/imu/imu_integrator.hpp"
#include "odometry_impl.hpp"

namespace mmlio::estimator {
namespace {

constexpr Stamp kMaxImuGapNs = 50000000;  // 50 ms: ten samples of a 200 Hz IMU

/// The de-skew motion of a sweep: `start` propagated through the IMU `samples` to 11 times from
/// max(from, sweep start) to the sweep end, as poses relative to the end pose; the end state into
/// *end if given.
lidar::SweepMotion imuMotion(const NavState& start, const std::vector<ImuSample>& samples, Stamp from,
                             const lidar::AlignedSweep& sweep, const Eigen::Vector3d& g_world,
                             NavState* end = nullptr) {
  std::vector<Stamp> query;
  const int n = 10;
  for (int k = 0; k <= n; ++k)
    query.push_back(std::max(from, sweep.start_ns + (sweep.end_ns - sweep.start_ns) * k / n));
  const std::vector<NavState> states = imu::propagate(start, samples, query, g_world);
  const Eigen::Isometry3d T_end_inv = states.back().pose().inverse();
  std::vector<double> times;
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t k = 0; k < states.size(); ++k) {
    times.push_back(toSec(query[k] - sweep.start_ns));
    poses.push_back(T_end_inv * states[k].pose());
  }
  if (end) *end = states.back();
  return lidar::SweepMotion(times, poses);
}

Stamp widestGap(const std::vector<ImuSample>& samples) {
  Stamp widest = 0;
  for (std::size_t k = 1; k < samples.size(); ++k)
    widest = std::max(widest, samples[k].stamp_ns - samples[k - 1].stamp_ns);
  return widest;
}

}  // namespace

Prediction Odometry::Impl::predict(const lidar::AlignedSweep& sweep, SweepResult* out) {
  Prediction p;
  p.prev = last;
  const NavState& prev = p.prev;
  const Stamp t0 = std::max(prev.stamp_ns, sweep.start_ns - fromSec(0.2));
  const std::vector<ImuSample> samples = imu::imuBetween(imuBuffer(), prev.stamp_ns, sweep.end_ns);
  p.predicted = prev;
  p.predicted.stamp_ns = sweep.end_ns;
  p.pre = std::make_shared<imu::Preintegration>(prev.bias, cfg.imu_noise);
  // A gap in the IMU stream must not be bridged by interpolating across it (a straight line through
  // two seconds of walking): the sweeps it spans are registered by their LiDARs alone.
  Stamp widest_gap = 0;
  for (std::size_t k = 1; k < imu.size(); ++k)
    if (imu[k].stamp_ns > prev.stamp_ns && imu[k - 1].stamp_ns < sweep.end_ns)
      widest_gap = std::max(widest_gap, imu[k].stamp_ns - imu[k - 1].stamp_ns);
  p.imu_ok = samples.size() >= 2 && samples.front().stamp_ns <= prev.stamp_ns + fromSec(0.02) &&
             samples.back().stamp_ns >= sweep.end_ns - fromSec(0.02) && widest_gap <= kMaxImuGapNs;
  if (p.imu_ok) {
    p.pre->integrate(samples);
    if (!pre_since_keyframe) pre_since_keyframe = std::make_shared<imu::Preintegration>(prev.bias, cfg.imu_noise);
    pre_since_keyframe->integrate(samples);
    p.predicted = p.pre->predict(prev, g_world);
    p.predicted.stamp_ns = sweep.end_ns;
    p.motion = imuMotion(prev, samples, t0, sweep, g_world);
  } else {
    predictAcrossImuGap(sweep, &p, out);
  }
  p.prev_velocity_guessed = in_imu_gap;
  in_imu_gap = !p.imu_ok;
  return p;
}

void Odometry::Impl::predictAcrossImuGap(const lidar::AlignedSweep& sweep, Prediction* p, SweepResult* out) {
  // No IMU across this sweep (gap or IMU stopped): the last motion goes on (velocity and turn
  // rate), for the prediction and the de-skew, logged.
  const NavState& prev = p->prev;
  const double dt = toSec(sweep.end_ns - prev.stamp_ns);
  p->unobserved_s = dt;
  p->predicted.p_world += prev.v_world * dt;
  p->predicted.q_world_body = (prev.q_world_body * so3::exp(omega_body * dt)).normalized();
  p->motion = lidar::SweepMotion::constantTwist(prev.q_world_body.inverse() * prev.v_world, omega_body,
                                                toSec(sweep.end_ns - sweep.start_ns));
  // The IMU may be back within this sweep (a gap of all data just ended): its gyroscope then
  // de-skews the sweep instead of the turn rate from before the gap (a walker who stopped turning
  // during the gap would be de-skewed by a turn that did not happen).
  const std::vector<ImuSample> within = imu::imuBetween(imuBuffer(), sweep.start_ns, sweep.end_ns);
  if (within.size() >= 2 && within.front().stamp_ns <= sweep.start_ns + fromSec(0.005) &&
      within.back().stamp_ns >= sweep.end_ns - fromSec(0.005) && widestGap(within) <= kMaxImuGapNs) {
    const double to_start_s = toSec(sweep.start_ns - prev.stamp_ns);
    NavState start = prev;
    start.stamp_ns = sweep.start_ns;
    start.p_world = prev.p_world + prev.v_world * to_start_s;
    start.q_world_body = (prev.q_world_body * so3::exp(omega_body * to_start_s)).normalized();
    NavState end;
    p->motion = imuMotion(start, within, sweep.start_ns, sweep, g_world, &end);
    p->unobserved_s = to_start_s;
    p->predicted.q_world_body = end.q_world_body;
    p->predicted.p_world = end.p_world;
  }
  out->note = "no IMU over the sweep: constant-velocity prediction, LiDAR-only registration";
  // The keyframe preintegration now misses an interval: restart the window (the map stays).
  window.clear();
  pre_since_keyframe.reset();
  // Moved-in tests place points at predictions that may be centimetres off after a gap: static
  // surfaces then seem to stand where earlier views saw through, and whole walls are rejected as
  // movers (measured: 40 % of the features), so the LiDARs cannot pull the pose back. The views
  // restart with the data.
  free_space.clear();
  if (!in_imu_gap)
    log::emit(log::Level::kWarn, "no IMU data over the sweep ending at ", log::stampText(sweep.end_ns),
              " s: LiDAR-only registration until it returns (the report counts degraded sweeps)");
}

}  // namespace mmlio::estimator
