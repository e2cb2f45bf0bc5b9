#pragma once
// The mapping back end of a run: keyframe pose graph with loop closure over the odometry, the
// trajectory corrected by it, and the high-resolution map built from per-keyframe submaps at
// their corrected poses (each sweep's points are stored once, voxel-averaged, in the frame of
// its keyframe, so memory grows with the mapped surface).
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mmlio/backend/loop_closer.hpp"
#include "mmlio/backend/loop_figures.hpp"
#include "mmlio/backend/map_accumulator.hpp"
#include "mmlio/backend/mapping_config.hpp"
#include "mmlio/backend/pose_graph.hpp"
#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/pose_log.hpp"
#include "mmlio/core/session.hpp"
#include "mmlio/estimator/odometry.hpp"

namespace mmlio::backend {

class MappingBackend {
 public:
  using Config = MappingConfig;

  /// What the ghost removal did so far.
  struct GhostRemoval {
    std::size_t judged_points = 0;  // map points at least one keyframe view could judge
    std::size_t removed_points = 0;
  };

  explicit MappingBackend(Config cfg);
  ~MappingBackend();

  /// Every tracked sweep in order (keyframe sweeps open a new submap and graph node).
  void addSweep(const estimator::SweepResult& sweep);
  /// Leaves a sweep that opens no keyframe with what addSweep takes of it, as the sweep number
  /// `index` of the stream (from 0): every map_point_stride-th point, no view. Sweeps waiting in a
  /// hand-off queue through a loop verification then hold a quarter of their points; the map is
  /// the same. The first sweep opens the first keyframe whatever it is, so it is left whole.
  static void keepWhatTheMapTakes(estimator::SweepResult* sweep, std::size_t index, const Config& cfg);

  /// After the last sweep: a loop check on the last keyframe if it has not had one.
  void finish();
  /// Surface already mapped (a session this run extends; T_world_points brings its points into this
  /// run's world frame): voxels it holds are not mapped again, as a revisit's are not.
  void coverAlready(const std::vector<Point>& points, const Eigen::Isometry3d& T_world_points);

  /// The odometry's poses (estimator stamps, as the sweeps carried them) corrected by the loops
  /// closed so far. The log is the caller's: one run keeps its poses once.
  Trajectory corrected(const PoseLog& odometry) const;
  /// The same for a few of them (the live path's keyframes).
  Trajectory corrected(Trajectory odometry) const;
  /// The loops' correction at the newest odometry pose: T_world_corrected * T_world_odometry^-1
  /// (identity before the first loop). Live nodes publish it as map -> odom.
  Eigen::Isometry3d correction() const;
  /// The map at the corrected poses. With clean_map it no longer holds the points that nearby
  /// keyframes (ghost_keyframes before and after the one that stored them) saw through at least
  /// twice and in at least a third of the views that decided: something stood there and left. A surface seen once
  /// is never removed: only rays that pass it can. Each submap is judged once, on the back end's
  /// thread, as soon as the keyframes after it exist (all of them by finish()).
  std::vector<Point> map() const;
  /// What was removed as moving: the odometry's rejected points and the ghosts (dynamic_map).
  std::vector<Point> dynamicMap() const;
  const GhostRemoval& ghostRemoval() const { return ghosts_; }
  /// With per_lidar_maps: the names of the LiDARs seen, and one LiDAR's map (empty if unknown).
  std::vector<std::string> lidarNames() const;
  std::vector<Point> lidarMap(const std::string& lidar) const;
  /// The keyframes (estimator stamps), their clouds and the loops, for a later run (no map: the
  /// caller has it from map(), which costs an assembly).
  Session session() const;
  std::size_t keyframes() const;
  /// Keyframes tied to the extended session's map.
  std::size_t sessionTies() const { return graph_.priors(); }
  std::size_t loops() const;
  LoopFigures loopFigures() const;

 private:
  bool plausibleCorrection(const backend::LoopResult& r) const;
  /// Keyframe k where the extended session's map places it (see SweepResult::T_world_body_measured).
  void tieToSession(int k, const Eigen::Isometry3d& T_world_body);
  int ties_unsolved_ = 0;
  /// Whether the graph moves the odometry's poses (a loop closed, or keyframes tied to a session).
  bool corrects() const { return graph_.loops() > 0 || graph_.priors() > 0; }
  void tryLoop(int keyframe);

  Config cfg_;
  backend::PoseGraph graph_;
  std::unique_ptr<backend::LoopCloser> closer_;
  // One submap per keyframe (in its frame), per LiDAR ("" = all LiDARs): voxel accumulators while
  // the keyframe is the newest, then frozen into plain point lists (about 3x smaller than the hash
  // maps; a closed submap only moves with its keyframe).
  using Submap = std::map<std::string, std::vector<Point>>;
  std::vector<Submap> submaps_;
  std::map<std::string, MapAccumulator> open_;
  std::map<std::string, MapAccumulator> emptied_;  // closed accumulators, kept for their storage
  std::map<std::string, FlatKeySet> covered_;      // world voxels held, per LiDAR key
  FlatKeySet covered_before_;                      // ... and by the session extended
  bool mappedBefore(const Eigen::Vector3d& world) const;
  void closeSubmap();
  MapAccumulator& openAccumulator(const std::string& key);  // the newest keyframe's, for this LiDAR key
  std::vector<Point> mergedMap(const std::string* only_lidar) const;
  void judgeSubmaps(bool all);
  void removeGhosts(std::size_t submap);
  // Keyframe views still needed by a submap not yet judged, by keyframe index, without their
  // images' window summaries (few of their pixels are ever asked about).
  std::map<std::size_t, estimator::SweepView> views_;
  bool nearAMover(std::size_t submap) const;
  std::size_t judged_ = 0;  // submaps [0, judged_) are judged
  // World cells (and their neighbours) where the odometry saw something move: only map points in
  // them are judged (nearly all of a map is static and never near a mover).
  FlatKeySet moved_cells_;
  FlatKeyIndex mover_index_;                  // cell with a mover -> index into mover_returns_
  std::vector<std::uint32_t> mover_returns_;  // moved-in returns the odometry saw per cell
  bool nearMoved(const Eigen::Vector3d& world) const;
  /// How many moved-in returns the odometry reported in world's cell.
  std::uint32_t moverReturns(const Eigen::Vector3d& world) const;
  GhostRemoval ghosts_;
  MapAccumulator dynamic_;                                // world frame, at the poses of the moment (map_leaf_m)
  StampedPose newest_{0, Eigen::Isometry3d::Identity()};  // the newest sweep's odometry pose
  Eigen::Isometry3d T_world_keyframe_ = Eigen::Isometry3d::Identity();
  std::size_t loop_attempts_ = 0;
  int last_checked_ = -1;
  std::vector<ClosedLoop> loops_;
  std::size_t rejected_ = 0;
  std::size_t sweeps_ = 0;
  std::vector<Point> strided_;  // scratch
};

}  // namespace mmlio::backend
