// Odometry stage: keyframes. A keyframe joins the sliding window, which is optimised and
// marginalised; its features go into the local map, its view carves what moved out of it.
#include "mmlio/core/so3.hpp"
#include "odometry_impl.hpp"

namespace mmlio::estimator {

bool Odometry::Impl::isKeyframe(const NavState& s) const {
  if (window.empty()) return true;
  const NavState k = fromBlocks(window.back().x, window.back().stamp);
  const double angle_deg = Eigen::AngleAxisd(k.q_world_body.inverse() * s.q_world_body).angle() * 180.0 / M_PI;
  return angle_deg > cfg.keyframe_rotation_deg || (s.p_world - k.p_world).norm() > cfg.keyframe_translation_m ||
         toSec(s.stamp_ns - k.stamp_ns) > cfg.keyframe_interval_s;
}

bool Odometry::Impl::addKeyframe(Features features, const Prediction& p, bool tracked, NavState* state,
                                 Stopwatch* watch, SweepResult* out) {
  const bool keyframe = isKeyframe(*state) || plane_map.empty();
  if (!keyframe || !tracked || (!p.imu_ok && !window.empty())) {
    out->times_ms.emplace_back("window", 0.0);
    out->times_ms.emplace_back("marginalize", 0.0);
    return false;
  }
  WindowKeyframe kf;
  kf.stamp = state->stamp_ns;
  kf.x = toBlocks(*state);
  kf.features = std::move(features);
  kf.pre = pre_since_keyframe;
  if (!window.empty() && !kf.pre) kf.pre = p.pre;
  kf.max_match_residual_m = matchGate(p.imu_ok, p.prev_velocity_guessed);
  window.push(std::move(kf));
  window.optimize(edge_map, plane_map);
  out->times_ms.emplace_back("window", watch->lapMs());
  window.marginalizeOldest(edge_map, plane_map);
  out->times_ms.emplace_back("marginalize", watch->lapMs());
  addToMap(window.back());
  calibration.addAnchorKeyframe(calibration_features, poseOf(window.back().x.pose));
  *state = fromBlocks(window.back().x, state->stamp_ns);
  if (view) view->place(state->pose());
  // What the keyframe sees through in the local map was left by a mover: where none was found
  // lately, only the odd mixed pixel, which would cost static points.
  if (view && mover_watch.moversLately(state->stamp_ns))
    out->carved_points = carveMap(state->p_world, &out->moved_world);
  plane_map.refitPlanes();  // once, after this keyframe's additions, trim and carving
  pre_since_keyframe = std::make_shared<imu::Preintegration>(state->bias, cfg.imu_noise);
  ++keyframes;
  return true;
}

void Odometry::Impl::finishSweep(const NavState& state, const Prediction& p, bool tracked, SweepResult* out) {
  const NavState& prev = p.prev;
  if (view && tracked) {
    view->place(state.pose());
    if (p.imu_ok) free_space.remember(view);  // a sweep without IMU is de-skewed and placed by a guess
    out->view = view;
  }
  if (tracked && state.stamp_ns > prev.stamp_ns)  // the body's turn rate, for sweeps without IMU
    omega_body = so3::log(prev.q_world_body.inverse() * state.q_world_body) / toSec(state.stamp_ns - prev.stamp_ns);
  last = state;
  trimImu();
  out->state = state;
  out->status = tracked && p.imu_ok ? SweepResult::Status::kTracking : SweepResult::Status::kDegraded;
}

// The map keeps the features' resolution: denser map clouds (0.1-0.2 m) were measured to fit
// noisier local planes (office HVI ATE 1.2 -> 1.8-2.0 cm) although they are faster to search.
void Odometry::Impl::addToMap(const WindowKeyframe& kf) {
  const Eigen::Isometry3d T = poseOf(kf.x.pose);
  std::vector<Eigen::Vector3d> e, p;
  e.reserve(kf.features.edges.size());
  p.reserve(kf.features.planes.size());
  for (const auto& v : kf.features.edges) e.push_back(T * v);
  for (const auto& v : kf.features.planes) p.push_back(T * v);
  edge_map.add(e);
  plane_map.add(p);
  edge_map.removeFarFrom(T.translation(), cfg.local_map_radius_m);
  plane_map.removeFarFrom(T.translation(), cfg.local_map_radius_m);
}

void Odometry::Impl::trimImu() {
  while (imu.size() > 2 && imu[1].stamp_ns < last.stamp_ns - fromSec(1.0)) imu.pop_front();
}

}  // namespace mmlio::estimator
