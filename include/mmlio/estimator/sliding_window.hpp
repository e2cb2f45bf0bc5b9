#pragma once
// The keyframe sliding window of the odometry (paper, "Sliding Window Optimization"): the last
// keyframes' poses, velocities and IMU biases, optimised with Ceres against point-to-edge and
// point-to-plane residuals on the local map, IMU preintegration factors between consecutive
// keyframes, and the Schur-complement prior left by the keyframes marginalised before them.
// Without a prior (the first keyframes, or after a reset) the oldest pose is held fixed.
// Parameter blocks follow the estimator convention: pose {p, q(x,y,z,w)}, speed-bias {v, ba, bg}.
#include <ceres/solver.h>

#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/imu/preintegration.hpp"
#include "mmlio/map/voxel_hash_map.hpp"

namespace mmlio::estimator {

class MarginalizationInfo;

/// One state as Ceres parameter blocks.
struct StateBlocks {
  double pose[7];
  double speed_bias[9];
};
StateBlocks toBlocks(const NavState& s);
NavState fromBlocks(const StateBlocks& b, Stamp stamp);
Eigen::Isometry3d poseOf(const double* pose);

struct WindowKeyframe {
  Stamp stamp = 0;
  StateBlocks x;
  Features features;
  std::shared_ptr<imu::Preintegration> pre;  // from the previous keyframe of the window to this one
  // Its map matches and the pose they were found at (kept while the pose stays near it).
  std::vector<MapMatch> matches;
  Eigen::Isometry3d matched_at = Eigen::Isometry3d::Identity();
  bool matched = false;
  // Farthest a point may lie from its map plane or line to be matched (MapMatchConfig): infinity
  // for a keyframe whose pose was only registered by the LiDARs (across a gap in the data).
  double max_match_residual_m = std::numeric_limits<double>::infinity();
};

struct SlidingWindowConfig {
  int size = 4;                 // keyframes kept; the oldest beyond is marginalised
  int max_iterations = 10;      // solver iterations per optimisation
  double lidar_sigma_m = 0.05;  // point-to-map residual standard deviation
  double huber_loss_m = 0.05;   // robust loss scale of the point-to-map residuals
  MapMatchConfig matching;
  Reassociation reassociation;  // when a keyframe's kept matches are found again
};

/// Solver options shared by the odometry's problems (small, dense, one thread).
ceres::Solver::Options odometrySolverOptions(int max_iterations);

/// Adds the matches of `pose` as one residual block (MapMatchesFactor): whitened, Huber-robust per match.
void addMapResiduals(ceres::Problem& problem, double* pose, const std::vector<MapMatch>& matches, double sigma_m,
                     double huber_m);

class SlidingWindow {
 public:
  SlidingWindow(SlidingWindowConfig cfg, const Eigen::Vector3d& g_world);
  ~SlidingWindow();

  /// Appends a keyframe; its `pre` must span from the current newest keyframe (ignored if empty).
  void push(WindowKeyframe kf);
  /// Matches each keyframe's features against the maps at its estimate (again only where it moved
  /// since: see reassociation), then solves.
  void optimize(const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map);
  /// When more than `size` keyframes are held: folds the oldest into the prior and drops it.
  void marginalizeOldest(const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map);
  /// Forgets every keyframe and the prior (e.g. after an IMU gap).
  void clear();

  bool empty() const { return keyframes_.empty(); }
  std::size_t size() const { return keyframes_.size(); }
  bool hasPrior() const;
  const WindowKeyframe& back() const { return keyframes_.back(); }
  const WindowKeyframe& at(std::size_t i) const { return keyframes_.at(i); }

 private:
  const std::vector<MapMatch>& matchesOf(WindowKeyframe& kf, const map::VoxelHashMap& edge_map,
                                         const map::VoxelHashMap& plane_map) const;

  SlidingWindowConfig cfg_;
  Eigen::Vector3d g_world_;
  std::deque<WindowKeyframe> keyframes_;  // deque: parameter addresses stay valid on pop_front
  std::shared_ptr<MarginalizationInfo> prior_;
  std::vector<double*> prior_blocks_;
};

}  // namespace mmlio::estimator
