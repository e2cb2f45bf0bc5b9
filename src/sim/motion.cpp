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

// A pose of the walk: x, y, floor z, yaw, pitch, roll.
Vec6 poseOf(const Waypoint& w) {
  Vec6 v;
  v << w.x_m, w.y_m, w.z_m, w.yaw_rad, w.pitch_rad, w.roll_rad;
  return v;
}

double legTime(const Vec6& a, const Vec6& b, const WalkConfig& c) {
  const Vec6 d = (b - a).cwiseAbs();
  return std::max({std::hypot(std::hypot(d[0], d[1]), d[2]) / c.speed_m_s, d[2] / c.climb_rate_m_s,
                   d[3] / c.yaw_rate_rad_s, std::max(d[4], d[5]) / c.look_rate_rad_s, 0.2});
}

Vec6 turnedAround(Vec6 v) {
  v[3] += M_PI;
  return v;
}

// The walk's piecewise-linear path (rest, legs, rest) and when it moves.
struct PlannedWalk {
  std::vector<Keyframe> coarse;  // at the waypoints, starting at move_start_s
  double move_start_s = 0.0, move_end_s = 0.0, end_s = 0.0;
};

PlannedWalk planWalk(const std::vector<Waypoint>& waypoints, const WalkConfig& config, double total_duration_s) {
  std::vector<Vec6> poses;
  poses.reserve(waypoints.size());
  for (const Waypoint& w : waypoints) poses.push_back(poseOf(w));
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
      std::vector<Vec6> out{poses.front()};
      std::vector<double> out_leg;
      for (size_t i = 0; i < leg.size() && prefix_s > 1e-6; ++i) {
        const double dt = std::min(prefix_s, leg[i]);
        const double u = dt / leg[i];
        out.emplace_back(poses[i] + u * (poses[i + 1] - poses[i]));
        out_leg.push_back(dt);
        prefix_s -= dt;
      }
      std::vector<Vec6> walk = out;
      std::vector<double> walk_leg = out_leg;
      if (out.size() > 1) {
        walk.push_back(turnedAround(out.back()));
        walk_leg.push_back(turn_s);
        for (size_t i = out.size() - 1; i-- > 0;) {
          walk.push_back(turnedAround(out[i]));
          walk_leg.push_back(out_leg[i]);
        }
        walk.push_back(turnedAround(walk.back()));
        walk_leg.push_back(turn_s);
      }
      double used_s = 0.0;
      for (double dt : walk_leg) used_s += dt;
      rest_end_s = std::max(0.0, total_duration_s - config.rest_start_s - used_s);
      poses = walk;
      leg = walk_leg;
    }
  }
  PlannedWalk plan;
  double t = config.rest_start_s;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) t += leg[i - 1];
    Keyframe k;
    k.t_s = t;
    k.p_world = Eigen::Vector3d(poses[i][0], poses[i][1], poses[i][2] + config.height_m);
    k.yaw_rad = poses[i][3];
    k.pitch_rad = poses[i][4];
    k.roll_rad = poses[i][5];
    plan.coarse.push_back(k);
  }
  plan.move_start_s = config.rest_start_s;
  plan.move_end_s = t;
  plan.end_s = t + rest_end_s;
  return plan;
}

// The gait on top of the path at time s: bobbing, nod, sway, wobble, faded in and out over a second
// at the walk's start and end.
Vec6 withGait(Vec6 v, double s, const PlannedWalk& plan, const WalkConfig& c) {
  const double envelope = std::clamp(std::min(s - plan.move_start_s, plan.move_end_s - s) / 1.0, 0.0, 1.0);
  const double phase = 2 * M_PI * (s - plan.move_start_s) / c.bob_period_s;
  v[2] += envelope * c.bob_amplitude_m * std::sin(phase);
  v[3] += envelope * c.yaw_wobble_rad * std::sin(0.5 * phase + 1.3);
  v[4] += envelope * c.nod_rad * std::sin(phase + 0.7);
  v[5] += envelope * c.sway_rad * std::sin(0.5 * phase);
  return v;
}

Keyframe keyframeOf(double t_s, const Vec6& v) {
  Keyframe k;
  k.t_s = t_s;
  k.p_world = v.head<3>();
  k.yaw_rad = v[3];
  k.pitch_rad = v[4];
  k.roll_rad = v[5];
  return k;
}

std::vector<Keyframe> restingEnds(std::vector<Keyframe> keys, const PlannedWalk& plan) {
  Keyframe first = plan.coarse.front();
  first.t_s = 0.0;
  keys.insert(keys.begin(), first);
  Keyframe last = plan.coarse.back();
  last.t_s = plan.move_end_s;
  keys.push_back(last);
  last.t_s = plan.end_s;
  keys.push_back(last);
  return keys;
}

constexpr double kPathKnotS = 0.25;

// The plan sampled every kPathKnotS with the gait on top, resting at both ends.
std::vector<Keyframe> gaitKeyframes(const PlannedWalk& plan, const WalkConfig& config) {
  std::vector<Keyframe> keys;
  for (double s = plan.move_start_s; s < plan.move_end_s; s += kPathKnotS)
    keys.push_back(keyframeOf(s, withGait(lerpKeyframes(plan.coarse, s), s, plan, config)));
  return restingEnds(std::move(keys), plan);
}

// The plan's motion: the path smoothed on 0.25 s knots, the gait on top on the config's knots.
SplineMotion motionOf(const PlannedWalk& plan, const WalkConfig& config) {
  if (config.knot_interval_s >= kPathKnotS) return SplineMotion(gaitKeyframes(plan, config), kPathKnotS);
  const SplineMotion path(restingEnds(plan.coarse, plan), kPathKnotS);
  std::vector<Keyframe> keys;
  const double h = config.knot_interval_s;
  for (int j = 0; j * h <= plan.end_s + 1e-9; ++j)
    keys.push_back(keyframeOf(j * h, withGait(path.coordinates(j * h), j * h, plan, config)));
  return SplineMotion(keys, h);
}

// A recorded path timed as recorded: rest, the path (cut at the budget, if any), rest.
PlannedWalk planRecorded(const std::vector<Keyframe>& recorded, const WalkConfig& config, double total_duration_s) {
  PlannedWalk plan;
  plan.move_start_s = config.rest_start_s;
  const double t0 = recorded.front().t_s;
  const double budget_s =
      total_duration_s > 0.0 ? total_duration_s - config.rest_start_s - config.rest_end_s : recorded.back().t_s - t0;
  for (Keyframe k : recorded) {
    if (!plan.coarse.empty() && k.t_s - t0 > budget_s + 1e-9) break;
    k.t_s += plan.move_start_s - t0;
    k.p_world.z() += config.height_m;
    plan.coarse.push_back(k);
  }
  plan.move_end_s = plan.coarse.back().t_s;
  plan.end_s = std::max(plan.move_end_s + config.rest_end_s, total_duration_s);
  return plan;
}

}  // namespace

std::vector<Keyframe> walkKeyframes(const std::vector<Waypoint>& waypoints, const WalkConfig& config,
                                    double total_duration_s) {
  return gaitKeyframes(planWalk(waypoints, config, total_duration_s), config);
}

SplineMotion walkMotion(const std::vector<Waypoint>& waypoints, const WalkConfig& config, double total_duration_s) {
  return motionOf(planWalk(waypoints, config, total_duration_s), config);
}

SplineMotion recordedMotion(const std::vector<Keyframe>& recorded, const WalkConfig& config, double total_duration_s) {
  if (recorded.empty()) return SplineMotion();
  return motionOf(planRecorded(recorded, config, total_duration_s), config);
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

SplineMotion::Jet SplineMotion::evaluate(double t_s) const {
  Jet j{Vec6::Zero(), Vec6::Zero(), Vec6::Zero()};
  const double t = std::clamp(t_s, 0.0, duration_s_);
  const int i = std::min(static_cast<int>(std::floor(t / h_)), static_cast<int>(control_.size()) - 4);
  const double s = t / h_ - i;
  const double s2 = s * s, s3 = s2 * s, r = 1 - s;
  const double b[4] = {r * r * r / 6, (3 * s3 - 6 * s2 + 4) / 6, (-3 * s3 + 3 * s2 + 3 * s + 1) / 6, s3 / 6};
  const double db[4] = {-0.5 * r * r, 1.5 * s2 - 2 * s, -1.5 * s2 + s + 0.5, 0.5 * s2};
  const double ddb[4] = {r, 3 * s - 2, -3 * s + 1, s};
  for (int k = 0; k < 4; ++k) {
    j.x += b[k] * control_[i + k];
    j.dx += db[k] * control_[i + k];
    j.ddx += ddb[k] * control_[i + k];
  }
  j.dx /= h_;
  j.ddx /= h_ * h_;
  return j;
}

Vec6 SplineMotion::coordinates(double t_s) const { return control_.empty() ? Vec6::Zero() : evaluate(t_s).x; }

MotionState SplineMotion::at(double t_s) const {
  MotionState m;
  if (control_.empty()) return m;
  const Jet j = evaluate(t_s);
  const Vec6 &x = j.x, &dx = j.dx, &ddx = j.ddx;
  m.p_world = x.head<3>();
  m.v_world = dx.head<3>();
  m.a_world = ddx.head<3>();
  const double yaw = x[3], pitch = x[4], roll = x[5];
  m.q_world_body = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  const double dyaw = dx[3], dpitch = dx[4], droll = dx[5];
  const double sp = std::sin(pitch), cp = std::cos(pitch), sr = std::sin(roll), cr = std::cos(roll);
  m.omega_body = Eigen::Vector3d(droll - dyaw * sp, dpitch * cr + dyaw * sr * cp, -dpitch * sr + dyaw * cr * cp);
  return m;
}

}  // namespace mmlio::sim
