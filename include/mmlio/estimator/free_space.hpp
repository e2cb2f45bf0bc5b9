#pragma once
// Moving objects by visibility. A return that lies where an earlier sweep saw through (its rays
// went on to a wall behind: free space then) is on something that moved in: a person, a door, a
// car. Such returns must neither pull the registration nor enter the map. The same test run the
// other way cleans the map: a map point that the current sweep sees through was left by
// something that has gone (M-detector's occlusion principle and Removert's / ERASOR's visibility
// removal, reduced to a per-LiDAR range image per sweep).
//
// Why visibility and not residuals: a person walking through a corridor's empty middle has no map
// surface near them, so a residual check cannot tell them from a newly seen wall; free space can.

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/map/range_image.hpp"

namespace mmlio::estimator {

struct DynamicConfig {
  bool enabled = true;           // reject returns on moving objects, carve the local map
  map::RangeImageConfig image;   // visibility test (margins, window)
  double look_back_min_s = 0.4;  // earlier sweeps tested: old enough for a walker to have moved
  double look_back_max_s = 1.2;  // ... a body length, young enough to overlap the current view
  double carve_radius_m = 20.0;  // local map points farther than this are not tested (image.max_range_m)
  // Where nothing has moved lately, sweeps are judged this far apart (0: every sweep); see MoverWatch.
  double quiet_interval_s = 0.4;
  double hold_s = 5.0;  // after a mover was found, every sweep is judged this long
};

/// A mover among the flagged returns: kMoverReturns of them in one 1 m cell. A walker leaves dozens
/// in most sweeps; a static scene gives scattered single returns (the simulated office and hall: at
/// most 7 in a cell, in 4 of 1767 sweeps 8 or more).
inline constexpr int kMoverReturns = 8;
bool moverFound(const std::vector<Eigen::Vector3d>& world_points, const std::vector<std::uint8_t>& moved);

/// When to look for movers. The visibility test costs a range image per LiDAR and a look-up per
/// feature, every sweep, and where nothing moves it only finds the odd false return. So sweeps are
/// judged quiet_interval_s apart (views that far apart still cover the look-back interval) until a
/// judged sweep finds a mover, then every sweep for hold_s: a walker that enters is rejected from
/// the next judged sweep on, and what reached the local map before is carved by the next keyframe.
class MoverWatch {
 public:
  explicit MoverWatch(const DynamicConfig& config) : cfg_(config) {}
  bool shouldJudge(Stamp now) const;
  void judged(Stamp now, bool mover_found);
  /// A mover was found within hold_s (with quiet_interval_s 0: always, as every sweep is judged).
  bool moversLately(Stamp now) const { return cfg_.quiet_interval_s <= 0 || now <= movers_until_ns_; }

 private:
  DynamicConfig cfg_;
  Stamp last_judged_ns_ = std::numeric_limits<Stamp>::min(), movers_until_ns_ = std::numeric_limits<Stamp>::min();
};

/// One LiDAR's view at the end of a sweep.
struct SensorView {
  std::uint8_t source = 0;  // the LiDAR, by index
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_sensor_world = Eigen::Isometry3d::Identity();  // at the odometry estimate
  map::RangeImage image;
};

/// All LiDARs of one sweep.
struct SweepView {
  Stamp stamp_ns = 0;
  std::vector<SensorView> sensors;

  /// Sets every sensor's world pose from the body pose.
  void place(const Eigen::Isometry3d& T_world_body);
  /// Free in at least one sensor's view (seen through).
  bool seesThrough(const Eigen::Vector3d& p_world) const;
  std::size_t memoryBytes() const;
};

/// The recent sweeps' views, for telling what moved in.
class FreeSpaceMemory {
 public:
  explicit FreeSpaceMemory(DynamicConfig config) : cfg_(config) {}

  void remember(std::shared_ptr<const SweepView> view);
  /// One flag per point: 1 where the point lies in space an earlier sweep saw through and none saw
  /// a surface at (the oldest and youngest sweeps of the look-back interval are asked).
  std::vector<std::uint8_t> movedIn(const std::vector<Eigen::Vector3d>& world_points, Stamp now) const;
  void clear() { views_.clear(); }

 private:
  DynamicConfig cfg_;
  std::deque<std::shared_ptr<const SweepView>> views_;
};

}  // namespace mmlio::estimator
