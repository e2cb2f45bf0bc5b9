#pragma once
// The odometry's state and its stages, private to estimator/: Odometry::process runs them in order
// (predict -> extract -> reject movers -> register -> window and map -> finish), one file each.
#include <deque>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "mmlio/estimator/degeneracy.hpp"
#include "mmlio/estimator/feature_budget.hpp"
#include "mmlio/estimator/free_space.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/estimator/odometry.hpp"
#include "mmlio/estimator/sliding_window.hpp"
#include "mmlio/imu/preintegration.hpp"
#include "mmlio/lidar/deskew.hpp"
#include "mmlio/map/voxel_hash_map.hpp"

namespace mmlio::estimator {

/// Fewer map matches than this leave a sweep untracked (the IMU prediction is kept).
inline constexpr std::size_t kMinCorrespondences = 30;

/// Registration rounds and the window find matches again once a pose moved a tenth of the plane
/// voxel or a tenth of a degree from where they were found.
inline Reassociation reassociationFor(const OdometryConfig& c) { return {0.1 * c.plane_voxel_m, 0.1 * M_PI / 180.0}; }

/// What the IMU says about one sweep: the predicted end state, the de-skew motion, and whether the
/// IMU covered the sweep at all.
struct Prediction {
  NavState prev;                             // the state at the end of the previous sweep
  NavState predicted;                        // at the sweep's end
  std::shared_ptr<imu::Preintegration> pre;  // prev -> sweep end (empty of samples without IMU)
  lidar::SweepMotion motion;
  double unobserved_s = 0.0;  // of the motion since prev: extrapolated, not measured
  bool imu_ok = false;
  bool prev_velocity_guessed = false;  // the previous sweep had no IMU
};

struct Odometry::Impl {
  OdometryConfig cfg;
  std::vector<LidarSetup> lidars;
  Eigen::Vector3d g_world;

  std::deque<ImuSample> imu;
  imu::ImuInitializer initializer;
  imu::ImuInitResult init_result;
  bool initialized = false;

  NavState last;  // at the end of the last processed sweep
  map::VoxelHashMap edge_map, plane_map;
  SlidingWindow window;
  std::shared_ptr<imu::Preintegration> pre_since_keyframe;
  std::size_t keyframes = 0;
  std::vector<char> rejected_sources;  // of the last registration, by LiDAR index
  std::vector<char> edge_poor;         // this sweep's solid-state frames the edge count marks bad
  PredictionDrift drift;               // how far the IMU prediction may have drifted, per direction
  FreeSpaceMemory free_space;
  MoverWatch mover_watch;
  std::shared_ptr<SweepView> view;                       // this sweep's, while it is processed
  bool in_imu_gap = false;                               // the last sweep had no usable IMU
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // last sweep's turn rate, rad/s
  OnlineCalibration calibration;
  // This sweep's features for the calibration (each LiDAR thinned on its own) and the body motion
  // its clock correction was made at.
  Features calibration_features;
  Eigen::Vector3d sweep_v_body = Eigen::Vector3d::Zero(), sweep_w_body = Eigen::Vector3d::Zero();

  Impl(OdometryConfig c, std::vector<LidarSetup> l);
  static SlidingWindowConfig windowConfig(const OdometryConfig& c);
  static OnlineCalibration onlineCalibration(const OdometryConfig& c, const std::vector<LidarSetup>& lidars);

  // ---- odometry.cpp ----
  /// Once the IMU initialiser is ready: the first state. False while it is not (or failed).
  bool initialise(Stamp sweep_start_ns);
  std::vector<ImuSample> imuBuffer() const { return {imu.begin(), imu.end()}; }
  std::size_t indexOf(const std::string& name) const;
  const LidarSetup* setupOf(const std::string& name) const;
  /// The residual gate of a pose predicted by the IMU from a tracked state; none otherwise.
  static double matchGate(bool imu_predicted, bool prev_velocity_guessed);

  // ---- odometry_predict.cpp: IMU prediction over the sweep, motion for de-skew ----
  Prediction predict(const lidar::AlignedSweep& sweep, SweepResult* out);
  /// Without IMU over the sweep: the last motion goes on (and the stream's IMU where it is back).
  void predictAcrossImuGap(const lidar::AlignedSweep& sweep, Prediction* p, SweepResult* out);

  // ---- odometry_extract.cpp: de-skew, features, bad frame, merge ----
  bool usesSurfacePoints(const std::string& sensor) const;
  Features extract(lidar::AlignedSweep& sweep, const lidar::SweepMotion& motion, bool with_view, SweepResult* out);

  // ---- odometry_movers.cpp: returns on things that moved in, carving ----
  bool rejectMovedIn(Features* f, const Eigen::Isometry3d& T_world_body, Stamp now, SweepResult* out) const;
  std::size_t carveMap(const Eigen::Vector3d& center, std::vector<Eigen::Vector3d>* carved);

  // ---- odometry_register.cpp: scan-to-map registration ----
  /// The sweep's registered state (the prediction where it could not be tracked); *tracked says which.
  NavState registration(const Features& features, const Prediction& p, Stamp sweep_end_ns, bool* tracked,
                        SweepResult* out);
  std::size_t registerSweep(const Features& f, const std::shared_ptr<imu::Preintegration>& pre, const NavState& prev,
                            bool prev_velocity_guessed, NavState* state, SweepResult* out);
  std::size_t registerAcrossGap(const Features& f, const NavState& prev, bool prev_velocity_guessed,
                                double unobserved_s, NavState* state, SweepResult* out);
  double fitScore(const Features& f, const Eigen::Isometry3d& T) const;
  void judgeLidars(const std::vector<MapMatch>& matches, const Eigen::Isometry3d& T, std::vector<char>* rejected,
                   SweepResult* out) const;
  FeatureBudget registrationBudget() const;
  void dropRejected(Features* f) const;

  // ---- odometry_window.cpp: keyframe, sliding window, local map ----
  bool isKeyframe(const NavState& s) const;
  /// A tracked keyframe's window step and map update; *state becomes its optimised state. False: the
  /// sweep is no keyframe.
  bool addKeyframe(Features features, const Prediction& p, bool tracked, NavState* state, Stopwatch* watch,
                   SweepResult* out);
  void addToMap(const WindowKeyframe& kf);
  /// The sweep's view, turn rate and state kept for the next sweep.
  void finishSweep(const NavState& state, const Prediction& p, bool tracked, SweepResult* out);
  void trimImu();
};

}  // namespace mmlio::estimator
