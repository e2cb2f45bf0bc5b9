#include "mmlio/calib/time_offset.hpp"

#include <algorithm>
#include <iterator>
#include <cstdio>
#include <cmath>
#include <limits>
#include <optional>

#include "mmlio/core/so3.hpp"
#include "mmlio/imu/imu_integrator.hpp"
#include "mmlio/lidar/deskew.hpp"

namespace mmlio::calib {
namespace {

/// Gyro-integrated rotation R_imu(t0)^T R_imu(t1) as a rotation vector (bias removed).
Eigen::Vector3d gyroRotation(const std::vector<ImuSample>& imu, Stamp t0, Stamp t1, const Eigen::Vector3d& bias) {
  const std::vector<ImuSample> s = imu::imuBetween(imu, t0, t1);
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double dt = toSec(s[i].stamp_ns - s[i - 1].stamp_ns);
    q = q * so3::exp((0.5 * (s[i - 1].gyro_rad_s + s[i].gyro_rad_s) - bias) * dt);
  }
  return so3::log(q.normalized());
}

Stamp midStamp(const LidarScan& scan) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (const Point& p : scan.points) {
    lo = std::min(lo, p.time_s);
    hi = std::max(hi, p.time_s);
  }
  return scan.start_ns + fromSec(0.5 * (static_cast<double>(lo) + static_cast<double>(hi)));
}

Stamp endStamp(const LidarScan& scan) {
  float hi = std::numeric_limits<float>::lowest();
  for (const Point& p : scan.points) hi = std::max(hi, p.time_s);
  return scan.start_ns + fromSec(hi);
}

/// The sweep rotated to its end with the gyroscope (d.imu: smoothed), moved by its velocity when known.
LidarScan gyroDeskewed(const LidarScan& scan, const GyroDeskew& d) {
  LidarScan out = scan;
  const Stamp shift = fromSec(d.offset_s), end = endStamp(scan);
  const double end_s = toSec(end - scan.start_ns);
  std::vector<double> times;
  std::vector<Eigen::Isometry3d> T_end_t;
  for (int i = 0; i <= 10; ++i) {
    const double t = end_s * i / 10.0;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    // R_imu(end)^T R_imu(t) = (R_imu(t)^T R_imu(end))^T, from the gyro over [t, end] in IMU time.
    T.linear() = so3::exp(gyroRotation(*d.imu, scan.start_ns + fromSec(t) + shift, end + shift, d.gyro_bias))
                     .toRotationMatrix()
                     .transpose();
    if (d.velocity) {
      const auto it = d.velocity->find(scan.start_ns);
      if (it != d.velocity->end()) T.translation() = -(d.T_imu_sensor.linear() * it->second) * (end_s - t);
    }
    times.push_back(t);
    T_end_t.push_back(T);
  }
  lidar::deskewToEnd(out, d.T_imu_sensor, lidar::SweepMotion(times, T_end_t), end_s);
  return out;
}

/// The gyroscope's readings averaged over +-half_window_s (centred: no lag).
std::vector<ImuSample> smoothedGyro(const std::vector<ImuSample>& imu, double half_window_s) {
  std::vector<ImuSample> out = imu;
  const Stamp half = fromSec(half_window_s);
  std::size_t lo = 0, hi = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < imu.size(); ++i) {
    while (hi < imu.size() && imu[hi].stamp_ns <= imu[i].stamp_ns + half) sum += imu[hi++].gyro_rad_s;
    while (imu[lo].stamp_ns < imu[i].stamp_ns - half) sum -= imu[lo++].gyro_rad_s;
    out[i].gyro_rad_s = sum / static_cast<double>(hi - lo);
  }
  return out;
}

}  // namespace

std::vector<SensorRotation> sweepRotations(const std::vector<LidarScan>& sweeps, const backend::IcpConfig& icp,
                                           const GyroDeskew* deskew, const std::vector<int>& strides) {
  std::vector<SensorRotation> out;
  const auto toVec = [](const LidarScan& s) {
    std::vector<Eigen::Vector3d> v;
    v.reserve(s.points.size());
    for (const Point& p : s.points)
      if (p.xyz.allFinite() && p.xyz.norm() > 1.0) v.emplace_back(p.xyz.cast<double>());
    return v;
  };
  const auto stamp = [&](const LidarScan& s) { return deskew ? endStamp(s) : midStamp(s); };
  // Sweeps k..k+m follow each other without a gap in the selection.
  const auto contiguous = [&](std::size_t k, std::size_t m) {
    return toSec(sweeps[k + m].start_ns - sweeps[k].start_ns) <= 0.1 * static_cast<double>(m) + 0.05;
  };
  // Consecutive pairs first, each starting from the previous pair's motion; longer pairs then start
  // from the consecutive ones composed, not from the gyroscope: no gyro sample enters, through an
  // alignment's start, a LiDAR rotation it is then compared with.
  std::vector<std::optional<Eigen::Isometry3d>> step(sweeps.size());
  const auto pass = [&](const std::vector<int>& pass_strides) {
    const int longest = *std::max_element(pass_strides.begin(), pass_strides.end());
    std::vector<std::vector<Eigen::Vector3d>> points(sweeps.size());
    std::vector<Stamp> stamps(sweeps.size(), 0);
    std::size_t prepared_until = 0;  // each sweep is prepared (de-skewed) once a pass
    const auto prepare = [&](std::size_t k) {
      for (; prepared_until <= k && prepared_until < sweeps.size(); ++prepared_until) {
        const LidarScan& s = sweeps[prepared_until];
        if (s.points.empty()) continue;
        const LidarScan ready = deskew ? gyroDeskewed(s, *deskew) : s;
        points[prepared_until] = toVec(ready);
        stamps[prepared_until] = stamp(ready);
      }
    };
    Eigen::Isometry3d prior = Eigen::Isometry3d::Identity();
    for (std::size_t k = 0; k + 1 < sweeps.size(); ++k) {
      prepare(k + static_cast<std::size_t>(longest));
      if (points[k].empty()) continue;
      std::optional<backend::IcpTarget> target;
      for (const int stride : pass_strides) {
        const auto m = static_cast<std::size_t>(stride);
        if (k + m >= sweeps.size() || points[k + m].empty() || !contiguous(k, m)) continue;
        Eigen::Isometry3d start = prior;
        if (m > 1) {
          const auto from = step.begin() + static_cast<std::ptrdiff_t>(k);
          if (!std::all_of(from, from + static_cast<std::ptrdiff_t>(m), [](const auto& t) { return t.has_value(); }))
            continue;
          start.setIdentity();
          for (auto t = from; t != from + static_cast<std::ptrdiff_t>(m); ++t) start = start * **t;
        }
        if (!target) target.emplace(map::voxelCentroids(points[k], icp.voxel_fine_m));
        const backend::IcpResult r = backend::alignPointToPlane(points[k + m], *target, start, icp);
        if (m == 1) {
          prior = r.converged ? r.T_target_source : Eigen::Isometry3d::Identity();
          if (r.converged) step[k] = r.T_target_source;
        }
        if (!r.converged) continue;
        out.push_back({stamps[k], stamps[k + m],
                       so3::log(Eigen::Quaterniond(r.T_target_source.rotation()).normalized()),
                       r.T_target_source.translation(), stride});
      }
      points[k].clear();
      points[k].shrink_to_fit();
    }
  };
  pass({1});
  std::vector<int> longer;
  for (const int stride : strides)
    if (stride > 1) longer.push_back(stride);
  if (!longer.empty()) pass(longer);
  return out;
}

namespace {

/// Sums over a set of increments at one trial offset from which the mismatch cost follows with a
/// residual gyro bias fitted out: the bias adds bias * dt to every increment, the clock offset
/// (rate at t1 - rate at t0) * offset, so the two separate.
struct CostSums {
  double rr = 0, tt = 0;
  Eigen::Vector3d rt = Eigen::Vector3d::Zero();
  void add(const Eigen::Vector3d& r, double dt) {
    rr += r.squaredNorm();
    tt += dt * dt;
    rt += r * dt;
  }
  CostSums& operator+=(const CostSums& o) {
    rr += o.rr;
    tt += o.tt;
    rt += o.rt;
    return *this;
  }
  CostSums operator-(const CostSums& o) const {
    CostSums d = *this;
    d.rr -= o.rr;
    d.tt -= o.tt;
    d.rt -= o.rt;
    return d;
  }
  /// The residual bias that fits the increments best (rad/s).
  Eigen::Vector3d bias() const { return tt > 0 ? Eigen::Vector3d(rt / tt) : Eigen::Vector3d::Zero(); }
  double cost() const { return tt > 0 ? rr - rt.squaredNorm() / tt : rr; }
};

struct GridMinimum {
  bool ok = false;  // an interior minimum with positive curvature
  double offset_s = 0, cost = 0, curvature = 0;
};

/// The minimum of costs sampled every step_s from first_s, refined by a parabola.
GridMinimum gridMinimum(const std::vector<double>& costs, double first_s, double step_s) {
  GridMinimum m;
  const auto best = static_cast<std::size_t>(std::min_element(costs.begin(), costs.end()) - costs.begin());
  if (best == 0 || best + 1 >= costs.size()) return m;
  const double cm = costs[best - 1], c0 = costs[best], cp = costs[best + 1];
  m.curvature = (cm - 2 * c0 + cp) / (step_s * step_s);
  if (!(m.curvature > 0)) return m;
  const double shift = std::clamp(0.5 * (cm - cp) / (cm - 2 * c0 + cp), -0.5, 0.5);
  m.offset_s = first_s + (static_cast<double>(best) + shift) * step_s;
  m.cost = c0 - 0.25 * (cm - cp) * shift;
  m.ok = true;
  return m;
}

/// One estimate from every increment given.
TimeOffsetResult estimateOnce(const std::vector<SensorRotation>& rotations, const Eigen::Matrix3d& R_imu_sensor,
                              const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                              const TimeOffsetConfig& cfg, double center_s) {
  TimeOffsetResult res;
  if (imu.size() < 2) {
    res.message = "no IMU data to compare the LiDAR's rotation with";
    return res;
  }
  std::vector<SensorRotation> moving;
  const Stamp margin = fromSec(std::abs(center_s) + cfg.max_offset_s + 0.01);
  for (const SensorRotation& r : rotations) {
    const double dt = toSec(r.t1_ns - r.t0_ns);
    if (dt <= 0 || r.rotvec.norm() / dt < cfg.min_rate_rad_s) continue;
    if (r.t0_ns - margin < imu.front().stamp_ns || r.t1_ns + margin > imu.back().stamp_ns) continue;
    moving.push_back(r);
  }
  std::sort(moving.begin(), moving.end(),
            [](const SensorRotation& a, const SensorRotation& b) { return a.t0_ns < b.t0_ns; });
  res.increments = static_cast<int>(moving.size());
  if (res.increments < cfg.min_increments) {
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%.2g", cfg.min_rate_rad_s);
    res.message = "only " + std::to_string(moving.size()) + " sweep pairs turn faster than " + rate + " rad/s (need " +
                  std::to_string(cfg.min_increments) +
                  "): record a few turns after the stationary start to calibrate "
                  "the clock offset";
    return res;
  }
  // Sums per block of increments (consecutive in time) and trial offset: the whole estimate, and
  // the estimate without each block (the jackknife), come from them.
  const int n = static_cast<int>(std::round(cfg.max_offset_s / cfg.step_s));
  const double first_s = center_s - n * cfg.step_s;
  const int blocks = std::clamp(res.increments / 4, 2, cfg.jackknife_blocks);
  std::vector<std::vector<CostSums>> sums(static_cast<std::size_t>(blocks), std::vector<CostSums>(2 * n + 1));
  for (std::size_t i = 0; i < moving.size(); ++i) {
    const SensorRotation& r = moving[i];
    const std::size_t block = i * static_cast<std::size_t>(blocks) / moving.size();
    const Eigen::Vector3d seen = R_imu_sensor * r.rotvec;
    const double dt = toSec(r.t1_ns - r.t0_ns);
    for (int g = 0; g <= 2 * n; ++g) {
      const Stamp shift = fromSec(first_s + g * cfg.step_s);
      sums[block][static_cast<std::size_t>(g)].add(
          seen - gyroRotation(imu, r.t0_ns + shift, r.t1_ns + shift, gyro_bias), dt);
    }
  }
  std::vector<CostSums> total(2 * n + 1);
  for (const auto& b : sums)
    for (std::size_t g = 0; g < total.size(); ++g) total[g] += b[g];
  const auto costsOf = [&](const std::vector<CostSums>& s, const std::vector<CostSums>* minus) {
    std::vector<double> c(s.size());
    for (std::size_t g = 0; g < s.size(); ++g) c[g] = (minus ? s[g] - (*minus)[g] : s[g]).cost();
    return c;
  };
  const GridMinimum all = gridMinimum(costsOf(total, nullptr), first_s, cfg.step_s);
  if (!all.ok) {
    char range[32];
    std::snprintf(range, sizeof(range), "%.2g", cfg.max_offset_s);
    res.message = std::string("no clear minimum of the rotation mismatch within +-") + range +
                  " s: the offset is larger, or the LiDAR's rotations do not match the gyroscope";
    return res;
  }
  res.offset_s = all.offset_s;
  const int dof = 3 * res.increments - 4;
  res.rms_rad = std::sqrt(std::max(0.0, all.cost) / res.increments);
  // cost ~ sum r^2 with residual variance s2 per component: var(offset) = 2 s2 / curvature, if
  // the increments' errors were independent. They are not (sweeps shared by pairs, one scene's
  // registration bias over a turn): the spread of the estimates leaving out one block each says how
  // far the answer depends on which turns were seen. The larger of the two is stated.
  const double white_sigma = std::sqrt(2.0 * (std::max(0.0, all.cost) / dof) / all.curvature);
  double jack = 0;
  int jack_n = 0;
  std::vector<double> left_out;
  for (const auto& b : sums) {
    const GridMinimum m = gridMinimum(costsOf(total, &b), first_s, cfg.step_s);
    left_out.push_back(m.ok ? m.offset_s : std::numeric_limits<double>::infinity());
  }
  double mean = 0;
  for (double v : left_out) mean += v;
  mean /= static_cast<double>(left_out.size());
  for (double v : left_out) {
    jack += (v - mean) * (v - mean);
    ++jack_n;
  }
  const double jack_sigma = std::sqrt(jack * (jack_n - 1) / std::max(jack_n, 1));
  res.sigma_s = std::isfinite(jack_sigma) ? std::max(white_sigma, jack_sigma) : std::numeric_limits<double>::infinity();
  res.ok = std::isfinite(res.sigma_s);
  res.message = res.ok ? "clock offset from " + std::to_string(res.increments) + " turning sweep pairs"
                       : "the clock offset depends on which turns are used: its minimum vanishes without some";
  return res;
}

}  // namespace

TimeOffsetResult estimateTimeOffset(const std::vector<SensorRotation>& rotations, const Eigen::Matrix3d& R_imu_sensor,
                                    const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                    const TimeOffsetConfig& cfg, double center_s) {
  TimeOffsetResult first = estimateOnce(rotations, R_imu_sensor, imu, gyro_bias, cfg, center_s);
  if (!first.ok) return first;
  // An alignment that converged to the wrong pose (a long pair across a U-turn matched to the
  // other wall) is an error of degrees where the rest err by a fraction of a milliradian: such
  // increments are dropped by their mismatch at the first estimate (the residual bias fitted out)
  // and the estimate repeated.
  const Stamp shift = fromSec(first.offset_s);
  std::vector<Eigen::Vector3d> residual;
  std::vector<double> dts;
  CostSums sums;
  for (const SensorRotation& r : rotations) {
    dts.push_back(toSec(r.t1_ns - r.t0_ns));
    residual.emplace_back(R_imu_sensor * r.rotvec - gyroRotation(imu, r.t0_ns + shift, r.t1_ns + shift, gyro_bias));
    sums.add(residual.back(), dts.back());
  }
  const Eigen::Vector3d bias = sums.bias();
  std::vector<double> norms;
  for (std::size_t i = 0; i < residual.size(); ++i) norms.push_back((residual[i] - bias * dts[i]).norm());
  std::vector<double> sorted = norms;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double gate = std::max(cfg.outlier_floor_rad, cfg.outlier_medians * sorted[sorted.size() / 2]);
  std::vector<SensorRotation> kept;
  for (std::size_t i = 0; i < rotations.size(); ++i)
    if (norms[i] <= gate) kept.push_back(rotations[i]);
  if (kept.size() == rotations.size()) return first;
  return estimateOnce(kept, R_imu_sensor, imu, gyro_bias, cfg, center_s);
}

namespace {

/// The standard deviation of the offsets estimated from each stride's increments alone (strides
/// that give no estimate are left out; 0 with fewer than two).
double strideSpread(const std::vector<SensorRotation>& rotations, const Eigen::Matrix3d& R_imu_sensor,
                    const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias, const TimeOffsetConfig& cfg,
                    double center_s) {
  std::vector<double> offsets;
  for (const int stride : cfg.strides) {
    std::vector<SensorRotation> of_stride;
    std::copy_if(rotations.begin(), rotations.end(), std::back_inserter(of_stride),
                 [stride](const SensorRotation& r) { return r.stride == stride; });
    const TimeOffsetResult r = estimateTimeOffset(of_stride, R_imu_sensor, imu, gyro_bias, cfg, center_s);
    if (r.ok) offsets.push_back(r.offset_s);
  }
  if (offsets.size() < 2) return 0.0;
  double mean = 0, sq = 0;
  for (const double o : offsets) mean += o / static_cast<double>(offsets.size());
  for (const double o : offsets) sq += (o - mean) * (o - mean);
  return std::sqrt(sq / static_cast<double>(offsets.size() - 1));
}

}  // namespace

TimeOffsetResult calibrateTimeOffset(const std::vector<LidarScan>& sweeps, const Eigen::Isometry3d& T_imu_sensor,
                                     const std::vector<ImuSample>& imu, const Eigen::Vector3d& gyro_bias,
                                     const TimeOffsetConfig& cfg, int max_rounds) {
  const Eigen::Matrix3d R = T_imu_sensor.linear();
  const std::vector<SensorRotation> raw = sweepRotations(sweeps);
  TimeOffsetResult res = estimateTimeOffset(raw, R, imu, gyro_bias, cfg);
  if (!res.ok) return res;
  // Each sweep's velocity from the raw registration of the pair it starts (mid stamps are
  // within the sweep, so match a pair to the sweep whose start precedes its t0 most closely).
  std::map<Stamp, Eigen::Vector3d> velocity;
  for (const SensorRotation& r : raw) {
    const double dt = toSec(r.t1_ns - r.t0_ns);
    if (dt <= 0) continue;
    const auto after = std::upper_bound(sweeps.begin(), sweeps.end(), r.t0_ns,
                                        [](Stamp t, const LidarScan& s) { return t < s.start_ns; });
    if (after == sweeps.begin()) continue;
    const Eigen::Vector3d v = r.translation / dt;
    velocity[(after - 1)->start_ns] = v;
    if (after != sweeps.end()) velocity.emplace(after->start_ns, v);  // the pair's second sweep, if unset
  }
  // The de-skew's gyroscope is smoothed: its white noise, rotated into the sweeps, correlates the
  // LiDAR's rotations with the very samples they are compared with.
  const std::vector<ImuSample> smoothed = smoothedGyro(imu, cfg.deskew_smoothing_s);
  // Only the turning sweeps (and their successors) carry timing information: re-register those.
  std::vector<LidarScan> turning;
  for (std::size_t k = 0; k + 1 < sweeps.size(); ++k) {
    if (sweeps[k].points.empty()) continue;
    const double dt = toSec(sweeps[k + 1].start_ns - sweeps[k].start_ns);
    const Eigen::Vector3d w = gyroRotation(imu, sweeps[k].start_ns + fromSec(res.offset_s),
                                           sweeps[k + 1].start_ns + fromSec(res.offset_s), gyro_bias);
    if (dt > 0 && w.norm() / dt >= 0.5 * cfg.min_rate_rad_s) {
      if (turning.empty() || turning.back().start_ns != sweeps[k].start_ns) turning.push_back(sweeps[k]);
      turning.push_back(sweeps[k + 1]);
    }
  }
  std::vector<SensorRotation> refined;  // the last round's increments, and the config they were compared with
  TimeOffsetConfig refined_config = cfg;
  for (int round = 1; round < max_rounds; ++round) {
    GyroDeskew d{&smoothed, gyro_bias, T_imu_sensor, res.offset_s, &velocity};
    // Finer than the first pass (whose job is only a start): measured on the simulated corridor
    // 73.8 -> 70.9 ms for a true 70 ms, office 70.7 -> 71.4 ms.
    backend::IcpConfig fine;
    fine.voxel_fine_m = 0.05;
    fine.max_corr_fine_m = 0.15;
    TimeOffsetConfig near = cfg;
    near.max_offset_s = cfg.refine_range_s;
    std::vector<SensorRotation> rotations = sweepRotations(turning, fine, &d, cfg.strides);
    const TimeOffsetResult next = estimateTimeOffset(rotations, R, imu, gyro_bias, near, res.offset_s);
    if (!next.ok) break;
    const double moved = std::abs(next.offset_s - res.offset_s);
    res = next;
    refined = std::move(rotations);
    refined_config = near;
    if (moved < cfg.step_s) break;
  }
  // The strides disagree where a sweep's own error (its de-skew, its registration) follows the
  // motion: on a hand-held walk consecutive sweeps say 10 ms less than sweeps 0.8 s apart.
  if (!refined.empty()) {
    res.stride_spread_s = strideSpread(refined, R, imu, gyro_bias, refined_config, res.offset_s);
    res.sigma_s = std::max(res.sigma_s, res.stride_spread_s);
  }
  if (res.ok && res.sigma_s > cfg.max_sigma_s) {
    char what[256];
    std::snprintf(what, sizeof what,
                  "the turns at the start determine the clock offset only to +-%.1f ms: record turns that start and "
                  "stop briskly (to 1 rad/s within half a second), in both directions; `mmlio run` refines it",
                  1e3 * res.sigma_s);
    res.advice = what;
  }
  return res;
}

}  // namespace mmlio::calib
