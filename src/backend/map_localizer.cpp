#include "mmlio/backend/map_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mmlio/core/log.hpp"

namespace mmlio::backend {
namespace {

std::vector<Eigen::Vector3d> mapPoints(const Session& session, double voxel_m) {
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(session.map.size());
  for (const Point& p : session.map) pts.emplace_back(p.xyz.cast<double>());
  return map::voxelCentroids(pts, voxel_m);
}

}  // namespace

MapLocalizer::MapLocalizer(const Session& session, MapLocalizerConfig cfg,
                           std::optional<Eigen::Isometry3d> initial_pose)
    : session_(&session),
      cfg_(std::move(cfg)),
      pending_hint_(std::move(initial_pose)),
      relocalizer_(session, cfg_.relocalization),
      map_(mapPoints(session, cfg_.map_voxel_m)) {}

void MapLocalizer::addKeyframe(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body,
                               const std::vector<Eigen::Vector3d>& cloud_body) {
  if (status_.keyframes++ > 0) walked_since_update_m_ += (T_odom_body.translation() - last_keyframe_odom_).norm();
  last_keyframe_odom_ = T_odom_body.translation();
  recent_.push_back({T_odom_body, cloud_body});
  while (static_cast<int>(recent_.size()) > std::max(1, cfg_.relocalize_keyframes)) recent_.pop_front();
  if (pending_hint_) {
    T_map_odom_hint_ = *pending_hint_ * T_odom_body.inverse();
    pending_hint_.reset();
    const bool was_localized = status_.localized;
    if (relocalize(stamp_ns, T_odom_body, cloud_body) || !was_localized) return;
    ++status_.pose_hints_refuted;
    T_map_odom_hint_.reset();  // tracking goes on in the map <- odom it had
    status_.last_reason = "a pose hint did not fit the map there (" + status_.last_reason + "): tracking went on";
    log::warn(status_.last_reason);
  }
  if (status_.localized)
    track(stamp_ns, T_odom_body, cloud_body);
  else if (since_attempt_++ % std::max(1, cfg_.relocalize_every) == 0)
    relocalize(stamp_ns, T_odom_body, cloud_body);
}

void MapLocalizer::hint(const Eigen::Isometry3d& T_map_body, bool with_height) {
  pending_hint_ = T_map_body;
  ++status_.pose_hints;
  if (with_height) return;
  double nearest = std::numeric_limits<double>::infinity();
  for (const SessionKeyframe& k : session_->keyframes) {
    const double d = (k.T_map_body.translation() - T_map_body.translation()).head<2>().norm();
    if (d >= nearest) continue;
    nearest = d;
    pending_hint_->translation().z() = k.T_map_body.translation().z();
  }
}

bool MapLocalizer::relocalize(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body,
                              const std::vector<Eigen::Vector3d>& cloud) {
  ++status_.relocalization_attempts;
  // A hint until the rig is found (once lost, the old map <- odom is what went wrong: no hint).
  std::optional<Eigen::Isometry3d> hint;
  if (T_map_odom_hint_) hint = *T_map_odom_hint_ * T_odom_body;
  std::vector<Eigen::Vector3d> walked;  // the latest keyframes in this one's frame
  const Eigen::Isometry3d T_body_odom = T_odom_body.inverse();
  for (const Recent& k : recent_) {
    const Eigen::Isometry3d T_body_k = T_body_odom * k.T_odom_body;
    for (const Eigen::Vector3d& p : k.cloud_body) walked.push_back(T_body_k * p);
  }
  const Relocalization r =
      relocalizer_.locate(cloud, map::voxelCentroids(walked, cfg_.relocalization.checks.submap_voxel_m), hint);
  status_.last_reason = r.reason;
  if (!r.localized) {
    log::debug("relocalization: ", r.reason);
    return false;
  }
  corrections_.emplace_back(stamp_ns, r.T_map_body * T_odom_body.inverse());
  walked_since_update_m_ = 0.0;
  T_map_odom_hint_.reset();
  const bool was_localized = status_.localized;
  status_.localized = true;
  status_.last_fitness_m = r.fitness_m;
  status_.last_overlap = r.overlap;
  misses_ = 0;
  since_attempt_ = 0;
  if (!status_.first_localized_ns) {
    status_.first_localized_ns = stamp_ns;
    log::emit(log::Level::kInfo, "localized in the session map: ", r.reason);
  } else if (was_localized) {
    log::emit(log::Level::kInfo, "localized at the pose hint: ", r.reason);
  } else {
    ++status_.relocalizations;
    if (!status_.lost_spells.empty() && status_.lost_spells.back().second == 0)
      status_.lost_spells.back().second = stamp_ns;
    log::emit(log::Level::kInfo, "localized again: ", r.reason);
  }
  return true;
}

void MapLocalizer::track(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body,
                         const std::vector<Eigen::Vector3d>& cloud) {
  const Eigen::Isometry3d& T_map_odom = corrections_.back().second;
  const Eigen::Isometry3d predicted = T_map_odom * T_odom_body;
  IcpConfig icp;
  icp.max_corr_coarse_m = cfg_.track_max_corr_m;
  icp.max_corr_fine_m = cfg_.track_max_corr_fine_m;
  icp.levels = 2;
  icp.voxel_fine_m = cfg_.map_voxel_m;
  const IcpResult r = alignPointToPlane(cloud, map_, predicted, icp);
  const Eigen::Isometry3d correction = predicted.inverse() * r.T_target_source;
  const double moved_deg = Eigen::AngleAxisd(correction.rotation()).angle() * 180.0 / M_PI;
  const double walked_m = walked_since_update_m_;
  const bool fits =
      r.converged && r.fitness_m <= cfg_.track_max_fitness_m && r.overlap >= cfg_.track_min_overlap &&
      correction.translation().norm() <= cfg_.track_max_correction_m + cfg_.track_drift_per_m * walked_m &&
      moved_deg <= cfg_.track_max_correction_deg + cfg_.track_drift_deg_per_m * walked_m;
  status_.last_fitness_m = r.fitness_m;
  status_.last_overlap = r.overlap;
  if (fits) {
    misses_ = 0;
    ++status_.keyframes_fitted;
    if (r.min_translation_eigenvalue >= cfg_.track_min_eigenvalue) {
      corrections_.emplace_back(stamp_ns, r.T_target_source * T_odom_body.inverse());
      walked_since_update_m_ = 0.0;
    } else {
      ++status_.keyframes_degenerate;
    }
    return;
  }
  if (++misses_ < cfg_.lost_after) return;
  status_.localized = false;
  status_.lost_spells.emplace_back(stamp_ns, 0);
  since_attempt_ = 0;
  log::warn("lost in the session map: ", misses_, " keyframes in a row do not fit it (last fitness ", r.fitness_m,
            " m, overlap ", r.overlap, ")");
}

std::optional<Eigen::Isometry3d> MapLocalizer::mapFromOdom(Stamp t_ns) const {
  if (corrections_.empty()) return std::nullopt;
  const auto after = std::upper_bound(corrections_.begin(), corrections_.end(), t_ns,
                                      [](Stamp t, const auto& c) { return t < c.first; });
  return after == corrections_.begin() ? corrections_.front().second : std::prev(after)->second;
}

Trajectory MapLocalizer::inMap(const Trajectory& odometry) const {
  Trajectory out;
  if (corrections_.empty()) return out;
  out.reserve(odometry.size());
  for (const StampedPose& p : odometry) out.push_back({p.stamp_ns, *mapFromOdom(p.stamp_ns) * p.T_world_body});
  return out;
}

}  // namespace mmlio::backend
