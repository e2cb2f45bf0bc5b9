#pragma once
// Localization in a saved session's map: the odometry runs as in any run (its own frame, "odom"),
// and this keeps map <- odom. Until it has found itself, every few keyframes are relocalized (the
// Relocalizer: no pose needed; a hint narrows it). Once found, every keyframe is aligned onto the
// session map from where map <- odom predicts it; a well-conditioned, close alignment updates
// map <- odom, a degenerate one (a corridor) leaves it as it was, and a run of keyframes that do
// not fit the map (a part of the building not mapped, a wrong correction, a kidnapped robot) means
// lost: relocalization again, and the spell is counted. A pose hint (rviz's "2D Pose Estimate", an
// operator's "the robot is here") is tried at the next keyframe whether localized or not: verified
// like any relocalization, it replaces map <- odom; refuted, tracking goes on as it was.
#include <Eigen/Geometry>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "mmlio/backend/point_to_plane_icp.hpp"
#include "mmlio/backend/relocalizer.hpp"
#include "mmlio/core/session.hpp"
#include "mmlio/core/types.hpp"

namespace mmlio::backend {

struct MapLocalizerConfig {
  RelocalizerConfig relocalization;
  int relocalize_every = 3;       // while not localized, keyframes between two attempts
  int relocalize_keyframes = 5;   // a relocalization is verified with this many latest keyframes' clouds
  double map_voxel_m = 0.1;       // the session map as the tracking's target
  double track_max_corr_m = 0.5;  // tracking ICP's coarsest gate (the prediction is close)
  // ... and its finest: a piece of furniture moved since the map was made (0.4 m or more) must not
  // pull the alignment (a 0.25 m gate let it: 3.5 cm ATE in a rearranged office, 1.5 at 0.1 m).
  double track_max_corr_fine_m = 0.1;
  double track_max_fitness_m = 0.05;  // a keyframe fits the map: fitness at most this ...
  double track_min_overlap = 0.6;     // ... and overlap at least this
  // ... and the correction to the prediction at most this, plus the odometry's drift over the way
  // walked since the last update: map <- odom drifts by millimetres between keyframes, a larger
  // change is a wrong alignment (a changed room offers those). A longer stretch without an update
  // (a corridor) allows more; beyond that, the keyframes do not fit, and relocalization decides.
  double track_max_correction_m = 0.05;
  double track_max_correction_deg = 1.0;
  double track_drift_per_m = 0.02;  // of the way walked
  double track_drift_deg_per_m = 0.1;
  double track_min_eigenvalue = 0.05;  // weaker (normalised, translation): it keeps map <- odom
  int lost_after = 5;                  // this many keyframes in a row not fitting: lost
};

struct LocalizationStatus {
  bool localized = false;                   // now
  std::optional<Stamp> first_localized_ns;  // none: never
  int relocalizations = 0;                  // found again after being lost
  int keyframes = 0, keyframes_fitted = 0, keyframes_degenerate = 0, relocalization_attempts = 0;
  int pose_hints = 0, pose_hints_refuted = 0;  // given after the start (hint()), and not confirmed by the map
  double last_fitness_m = 0, last_overlap = 0;
  std::vector<std::pair<Stamp, Stamp>> lost_spells;  // [from, to); to = 0 while still lost
  std::string last_reason;
};

class MapLocalizer {
 public:
  /// initial_pose: T_map_body of the first keyframe, roughly (a hint), or none. Keeps a reference
  /// to the session (through its Relocalizer): it must outlive the MapLocalizer.
  MapLocalizer(const Session& session, MapLocalizerConfig cfg = MapLocalizerConfig(),
               std::optional<Eigen::Isometry3d> initial_pose = std::nullopt);

  /// Every keyframe of the odometry, in time order: its pose in the odometry's frame and its
  /// cloud (body frame, voxel centroids).
  void addKeyframe(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body,
                   const std::vector<Eigen::Vector3d>& cloud_body);

  /// The rig is roughly at T_map_body now: tried at the next keyframe, and on every attempt after it
  /// until the rig is found. Without height (a 2D pose, as rviz sends), the height is that of the
  /// session keyframe nearest in x and y.
  void hint(const Eigen::Isometry3d& T_map_body, bool with_height = true);

  const LocalizationStatus& status() const { return status_; }
  /// map <- odom in force at t: the latest correction at or before t, the first one before it
  /// (the odometry before the first localization is in the same frame). Empty before any.
  std::optional<Eigen::Isometry3d> mapFromOdom(Stamp t_ns) const;
  /// Where the map placed the keyframe stamped stamp_ns (T_map_body) if it updated map <- odom
  /// there (found, or tracked well conditioned); none otherwise.
  std::optional<Eigen::Isometry3d> placed(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body) const {
    if (corrections_.empty() || corrections_.back().first != stamp_ns) return std::nullopt;
    return corrections_.back().second * T_odom_body;
  }
  /// The odometry's poses in the map frame (poses before the first localization too; none at all
  /// when it never localized).
  Trajectory inMap(const Trajectory& odometry) const;

 private:
  /// Whether it found the rig.
  bool relocalize(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body, const std::vector<Eigen::Vector3d>& cloud);
  void track(Stamp stamp_ns, const Eigen::Isometry3d& T_odom_body, const std::vector<Eigen::Vector3d>& cloud);

  const Session* session_;
  MapLocalizerConfig cfg_;
  std::optional<Eigen::Isometry3d> pending_hint_;     // T_map_body, not yet tried
  std::optional<Eigen::Isometry3d> T_map_odom_hint_;  // from the hint and the keyframe after it, until found
  LocalizationStatus status_;
  Relocalizer relocalizer_;
  IcpTarget map_;
  std::vector<std::pair<Stamp, Eigen::Isometry3d>> corrections_;  // map <- odom from the stamp on
  struct Recent {
    Eigen::Isometry3d T_odom_body;
    std::vector<Eigen::Vector3d> cloud_body;
  };
  std::deque<Recent> recent_;  // the latest keyframes, for relocalization
  int misses_ = 0;
  double walked_since_update_m_ = 0.0;  // by the odometry, since map <- odom was last updated
  Eigen::Vector3d last_keyframe_odom_ = Eigen::Vector3d::Zero();
  int since_attempt_ = 0;
};

}  // namespace mmlio::backend
