#include "mmlio/sim/motion.hpp"

#include <algorithm>
#include <cmath>

namespace mmlio::sim {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;

Vec6 toVec(const Keyframe& k) {
  Vec6 v;
  v << k.p_world, k.yaw_rad, k.pitch_rad, k.roll_rad;
  return v;
}

Vec6 lerpKeyframes(const std::vector<Keyframe>& keys, double t) {
  if (t <= keys.front().t_s) return toVec(keys.front());
  if (t >= keys.back().t_s) return toVec(keys.back());
  const auto it = std::upper_bound(keys.begin(), keys.end(), t, [](double v, const Keyframe& k) { return v < k.t_s; });
  const Keyframe& b = *it;
  const Keyframe& a = *(it - 1);
  const double u = (t - a.t_s) / std::max(1e-12, b.t_s - a.t_s);
  return (1 - u) * toVec(a) + u * toVec(b);
}

struct Pose2 {
  double x, y, yaw;
};

double legTime(const Pose2& a, const Pose2& b, const WalkConfig& c) {
  const double dist = std::hypot(b.x - a.x, b.y - a.y);
  return std::max({dist / c.speed_m_s, std::abs(b.yaw - a.yaw) / c.yaw_rate_rad_s, 0.2});
}

}  // namespace

std::vector<Keyframe> walkKeyframes(const std::vector<Waypoint>& waypoints, const WalkConfig& config,
                                    double total_duration_s) {
  std::vector<Pose2> poses;
  for (const Waypoint& w : waypoints) poses.push_back({w.x_m, w.y_m, w.yaw_rad});
  std::vector<double> leg;
  double full_s = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    leg.push_back(legTime(poses[i - 1], poses[i], config));
    full_s += leg.back();
  }
  double rest_end_s = config.rest_end_s;
  if (total_duration_s > 0.0) {
    const double available_s = total_duration_s - config.rest_start_s - config.rest_end_s;
    if (available_s >= full_s) {
      rest_end_s += available_s - full_s;
    } else {
      // Out and back along a prefix: two half turns of pi at the far end and at the start.
      const double turn_s = M_PI / config.yaw_rate_rad_s;
      double prefix_s = 0.5 * (available_s - 2.0 * turn_s);
      std::vector<Pose2> out{poses.front()};
      std::vector<double> out_leg;
      for (size_t i = 0; i < leg.size() && prefix_s > 1e-6; ++i) {
        const double dt = std::min(prefix_s, leg[i]);
        const double u = dt / leg[i];
        out.push_back({poses[i].x + u * (poses[i + 1].x - poses[i].x), poses[i].y + u * (poses[i + 1].y - poses[i].y),
                       poses[i].yaw + u * (poses[i + 1].yaw - poses[i].yaw)});
        out_leg.push_back(dt);
        prefix_s -= dt;
      }
      std::vector<Pose2> walk = out;
      std::vector<double> walk_leg = out_leg;
      if (out.size() > 1) {
        Pose2 far = out.back();
        far.yaw += M_PI;
        walk.push_back(far);
        walk_leg.push_back(turn_s);
        for (size_t i = out.size() - 1; i-- > 0;) {
          walk.push_back({out[i].x, out[i].y, out[i].yaw + M_PI});
          walk_leg.push_back(out_leg[i]);
        }
        Pose2 home = walk.back();
        home.yaw += M_PI;
        walk.push_back(home);
        walk_leg.push_back(turn_s);
      }
      double used_s = 0.0;
      for (double dt : walk_leg) used_s += dt;
      rest_end_s = std::max(0.0, total_duration_s - config.rest_start_s - used_s);
      poses = walk;
      leg = walk_leg;
    }
  }

  // Coarse linear path, then dense samples with bobbing and sway while moving.
  std::vector<Keyframe> coarse;
  double t = config.rest_start_s;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) t += leg[i - 1];
    Keyframe k;
    k.t_s = t;
    k.p_world = Eigen::Vector3d(poses[i].x, poses[i].y, config.height_m);
    k.yaw_rad = poses[i].yaw;
    coarse.push_back(k);
  }
  const double move_start_s = config.rest_start_s, move_end_s = t;
  std::vector<Keyframe> keys;
  Keyframe first = coarse.front();
  first.t_s = 0.0;
  keys.push_back(first);
  const double step_s = 0.25;
  for (double s = move_start_s; s < move_end_s; s += step_s) {
    const Vec6 v = lerpKeyframes(coarse, s);
    const double envelope = std::clamp(std::min(s - move_start_s, move_end_s - s) / 1.0, 0.0, 1.0);
    const double phase = 2 * M_PI * (s - move_start_s) / config.bob_period_s;
    Keyframe k;
    k.t_s = s;
    k.p_world = v.head<3>();
    k.p_world.z() += envelope * config.bob_amplitude_m * std::sin(phase);
    k.yaw_rad = v[3];
    k.pitch_rad = envelope * config.sway_rad * std::sin(phase + 0.7);
    k.roll_rad = envelope * config.sway_rad * std::sin(0.5 * phase);
    keys.push_back(k);
  }
  Keyframe last = coarse.back();
  last.t_s = move_end_s;
  keys.push_back(last);
  last.t_s = move_end_s + rest_end_s;
  keys.push_back(last);
  return keys;
}

Eigen::Vector3d MotionState::specificForce() const {
  return q_world_body.conjugate() * (a_world + Eigen::Vector3d(0, 0, kGravityM_s2));
}

Eigen::Isometry3d MotionState::pose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q_world_body.toRotationMatrix();
  T.translation() = p_world;
  return T;
}

SplineMotion::SplineMotion(const std::vector<Keyframe>& keyframes, double knot_interval_s)
    : h_(knot_interval_s), duration_s_(keyframes.empty() ? 0.0 : keyframes.back().t_s) {
  if (keyframes.empty()) return;
  // Control point j sits at time (j - 1) h: at s = 0 of segment i the curve is near c_{i+1}.
  const int segments = static_cast<int>(std::ceil(duration_s_ / h_)) + 1;
  control_.resize(segments + 3);
  for (int j = 0; j < segments + 3; ++j) control_[j] = lerpKeyframes(keyframes, (j - 1) * h_);
}

MotionState SplineMotion::at(double t_s) const {
  MotionState m;
  if (control_.empty()) return m;
  const double t = std::clamp(t_s, 0.0, duration_s_);
  const int i = std::min(static_cast<int>(std::floor(t / h_)), static_cast<int>(control_.size()) - 4);
  const double s = t / h_ - i;
  const double s2 = s * s, s3 = s2 * s, r = 1 - s;
  const double b[4] = {r * r * r / 6, (3 * s3 - 6 * s2 + 4) / 6, (-3 * s3 + 3 * s2 + 3 * s + 1) / 6, s3 / 6};
  const double db[4] = {-0.5 * r * r, 1.5 * s2 - 2 * s, -1.5 * s2 + s + 0.5, 0.5 * s2};
  const double ddb[4] = {r, 3 * s - 2, -3 * s + 1, s};
  Vec6 x = Vec6::Zero(), dx = Vec6::Zero(), ddx = Vec6::Zero();
  for (int k = 0; k < 4; ++k) {
    x += b[k] * control_[i + k];
    dx += db[k] * control_[i + k];
    ddx += ddb[k] * control_[i + k];
  }
  dx /= h_;
  ddx /= h_ * h_;
  m.p_world = x.head<3>();
  m.v_world = dx.head<3>();
  m.a_world = ddx.head<3>();
  const double yaw = x[3], pitch = x[4], roll = x[5];
  m.q_world_body = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  const double dyaw = dx[3], dpitch = dx[4], droll = dx[5];
  const double sp = std::sin(pitch), cp = std::cos(pitch), sr = std::sin(roll), cr = std::cos(roll);
  m.omega_body = Eigen::Vector3d(droll - dyaw * sp, dpitch * cr + dyaw * sr * cp, -dpitch * sr + dyaw * cr * cp);
  return m;
}

}  // namespace mmlio::sim
