#include "mmlio/imu/imu_integrator.hpp"

#include <algorithm>

#include "mmlio/core/so3.hpp"

namespace mmlio::imu {
namespace {

ImuSample interpolate(const ImuSample& a, const ImuSample& b, Stamp t) {
  const double s = b.stamp_ns == a.stamp_ns ? 0.0 : double(t - a.stamp_ns) / double(b.stamp_ns - a.stamp_ns);
  ImuSample out;
  out.stamp_ns = t;
  out.acc_m_s2 = (1 - s) * a.acc_m_s2 + s * b.acc_m_s2;
  out.gyro_rad_s = (1 - s) * a.gyro_rad_s + s * b.gyro_rad_s;
  return out;
}

/// Advances `x` by dt with measurements m0 at the start and m1 at the end of the step.
void step(NavState& x, const ImuSample& m0, const ImuSample& m1, double dt, const Eigen::Vector3d& g) {
  const Eigen::Vector3d w = 0.5 * (m0.gyro_rad_s + m1.gyro_rad_s) - x.bias.gyro_rad_s;
  const Eigen::Quaterniond q1 = (x.q_world_body * so3::exp(w * dt)).normalized();
  const Eigen::Vector3d a =
      0.5 * (x.q_world_body * (m0.acc_m_s2 - x.bias.acc_m_s2) + q1 * (m1.acc_m_s2 - x.bias.acc_m_s2)) + g;
  x.p_world += x.v_world * dt + 0.5 * a * dt * dt;
  x.v_world += a * dt;
  x.q_world_body = q1;
  x.stamp_ns += fromSec(dt);
}

}  // namespace

std::vector<ImuSample> imuBetween(const std::vector<ImuSample>& sorted, Stamp t0, Stamp t1) {
  std::vector<ImuSample> out;
  if (sorted.empty() || t1 < t0) return out;
  auto byStamp = [](const ImuSample& s, Stamp t) { return s.stamp_ns < t; };
  auto first = std::lower_bound(sorted.begin(), sorted.end(), t0, byStamp);  // first >= t0
  if (first != sorted.begin() && (first == sorted.end() || first->stamp_ns > t0)) {
    out.push_back(first == sorted.end() ? *(first - 1) : interpolate(*(first - 1), *first, t0));
    out.back().stamp_ns = std::max(out.back().stamp_ns, t0);
  }
  auto it = first;
  for (; it != sorted.end() && it->stamp_ns < t1; ++it) out.push_back(*it);
  if (it != sorted.end()) {
    out.push_back(it->stamp_ns == t1 || it == sorted.begin() ? *it : interpolate(*(it - 1), *it, t1));
  }
  return out;
}

std::vector<NavState> propagate(const NavState& start, const std::vector<ImuSample>& samples,
                                const std::vector<Stamp>& query_times, const Eigen::Vector3d& g_world) {
  std::vector<NavState> out;
  out.reserve(query_times.size());
  NavState x = start;
  const std::size_t n = samples.size();
  std::size_t k = 0;  // samples[k] is the latest sample at or before x (or the first one)
  while (k + 1 < n && samples[k + 1].stamp_ns <= x.stamp_ns) ++k;
  // Measurement at t between samples k and k+1 (held constant outside the samples).
  auto at = [&](Stamp t) {
    if (k + 1 >= n) return samples[k];
    ImuSample m = interpolate(samples[k], samples[k + 1], std::clamp(t, samples[k].stamp_ns, samples[k + 1].stamp_ns));
    m.stamp_ns = t;
    return m;
  };
  for (const Stamp t : query_times) {
    while (n > 0 && x.stamp_ns < t) {
      const Stamp next = k + 1 < n ? std::min(t, std::max(samples[k + 1].stamp_ns, x.stamp_ns + 1)) : t;
      step(x, at(x.stamp_ns), at(next), toSec(next - x.stamp_ns), g_world);
      x.stamp_ns = next;
      while (k + 1 < n && samples[k + 1].stamp_ns <= x.stamp_ns) ++k;
    }
    NavState s = x;
    s.stamp_ns = t;
    out.push_back(s);
  }
  return out;
}

}  // namespace mmlio::imu
