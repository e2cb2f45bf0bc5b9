#include "mmlio/config/rig_config.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mmlio/config/yaml_binder.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"

namespace mmlio::config {

// ---- the schema: one line per field --------------------------------------------------------

namespace {

void bind(YamlBinder& b, LidarConfig& c) {
  b.field("name", c.name, "unique LiDAR name; calibration files and the run report use it (required)");
  b.field("type", c.type,
          "velodyne | ouster | hesai | generic_spinning (sensor_msgs/PointCloud2 with rings),\n"
          "livox (livox_ros_driver/CustomMsg, solid state) (required)");
  b.field("topic", c.topic, "ROS topic of this LiDAR's point clouds (required)");
  b.field(
      "T_imu_sensor", c.T_imu_sensor,
      "extrinsic: maps points from this LiDAR's frame into the IMU frame: 4x4 row-major, m, or\n"
      "{xyz: [x, y, z], rpy_deg: [roll, pitch, yaw]} (ROS/URDF order) or {xyz: [...], quaternion: [qx, qy, qz, qw]}");
  b.field("time_offset_s", c.time_offset_s, "clock offset, s: t_imu = t_stamp + time_offset_s");
  b.field("min_range_m", c.min_range_m, "drop returns closer than this (rig, vehicle), m");
  b.field("max_range_m", c.max_range_m, "drop returns farther than this, m");
  b.field("num_rings", c.num_rings, "laser rings (VLP-16: 16) or, for livox, scan lines (Horizon: 6)");
  b.field("enabled", c.enabled, "false: ignore this LiDAR in every mode");
  b.field("refine_online", c.refine_online,
          "spinning LiDAR: its extrinsic and clock offset are refined while running, against the solid-state "
          "LiDAR's (see online_calibration)");
  if (b.reading() && !b.has("T_imu_sensor"))
    log::warn(
        b.location(), ": ", b.path("T_imu_sensor"), " not given: LiDAR '", c.name,
        "' is taken to sit at the IMU, unrotated (identity); give its extrinsic or calibrate it (mmlio calibrate)");
}

// `imu:` holds how the IMU arrives (ImuConfig) and the estimator's model of it.
void bindImu(YamlBinder& b, RigConfig& c) {
  estimator::OdometryConfig& e = c.estimator;
  b.field("topic", c.imu.topic, "ROS topic of sensor_msgs/Imu");
  b.field("acc_unit", c.imu.acc_unit, "accelerometer unit: auto (detect from the standstill norm) | g | m/s2");
  b.field("acc_noise_density", e.imu_noise.acc_noise_density, "accelerometer white noise, m/s^2/sqrt(Hz)");
  b.field("gyro_noise_density", e.imu_noise.gyro_noise_density, "gyroscope white noise, rad/s/sqrt(Hz)");
  b.field("acc_bias_random_walk", e.imu_noise.acc_bias_random_walk, "accelerometer bias random walk, m/s^3/sqrt(Hz)");
  b.field("gyro_bias_random_walk", e.imu_noise.gyro_bias_random_walk, "gyroscope bias random walk, rad/s^2/sqrt(Hz)");
  b.field("gravity_m_s2", e.gravity_m_s2, "local gravity magnitude, m/s^2");
  b.field("init_duration_s", e.imu_init.duration_s,
          "standstill at the start used to estimate gravity direction and gyro bias, s");
}

void bind(YamlBinder& b, lidar::FeatureConfig& c) {
  b.field("neighbours", c.neighbours, "points on each side used for curvature / scatter");
  b.field("edge_threshold", c.edge_threshold, "curvature above which a point is an edge candidate");
  b.field("plane_threshold", c.plane_threshold, "curvature below which a point is a plane candidate");
  b.field("continuity_jump_m", c.continuity_jump_m,
          "depth difference between neighbours that breaks continuity (occlusion edge), m");
}

void bind(YamlBinder& b, lidar::BadFrameConfig& c) {
  b.field("enabled", c.enabled, "drop solid-state frames with too little structure");
  b.choice("criterion", c.by_information, {{true, "information"}, {false, "edges"}},
           "information (a frame with too few edges, see below, is dropped only if its own map matches "
           "also leave a translation direction with fewer than odometry.degenerate_min_points effective points) | "
           "edges (paper: tau_e, the edge count alone)");
  b.field("min_edge_range_m", c.min_edge_range_m, "only edge points farther than this count, m");
  b.field("min_edge_points", c.min_edge_points, "tau_e: a frame with fewer counted edge points is bad");
}

void bindOdometry(YamlBinder& b, estimator::OdometryConfig& c) {
  using estimator::SurfacePoints;
  b.field("edge_voxel_m", c.edge_voxel_m, "voxel size for downsampling edge features, m");
  b.field("plane_voxel_m", c.plane_voxel_m, "voxel size for downsampling plane features, m");
  b.field("registration_max_edges", c.registration_max_edges,
          "a sweep's registration matches at most this many edge features, thinned evenly over space (0: all); "
          "keyframes' window and the map use all");
  b.field("registration_max_planes", c.registration_max_planes,
          "... and at most this many plane features (0: all). 3000 makes a 60 m hall's run ~25 % cheaper and its "
          "ATE 8-16 % worse (docs/speed_history.md)");
  b.choice("surface_points", c.surface_points,
           {{SurfacePoints::kSolidState, "solid_state"}, {SurfacePoints::kAll, "all"}, {SurfacePoints::kNone, "none"}},
           "LiDARs whose every return (not only scan-line plane features) is matched point-to-plane, the map's "
           "local plane fit deciding: solid_state | all | none");
  b.field("degenerate_min_points", c.degeneracy.min_points,
          "a sweep is degenerate along a direction its map matches constrain less than this many perfectly "
          "aligned plane points would (translation; rotation per metre of lever arm)");
  b.field("degenerate_drift_m_s2", c.degeneracy.drift_m_s2,
          "how fast the IMU prediction is taken to drift along a direction the LiDARs leave unobserved "
          "(m/s^2/sqrt(Hz), the bias and tilt not yet pinned down); the longer it goes unobserved, the weaker "
          "the LiDAR evidence that counts there (0: degenerate_min_points alone)");
  b.field("degenerate_min_points_drifted", c.degeneracy.min_points_drifted,
          "... but never fewer effective points than this: a handful of matches is as likely a wrong association "
          "as a surface");
  b.field("remap_degenerate", c.remap_degenerate,
          "keep the IMU prediction along degenerate directions instead of the registration's solution");
  b.field("map_voxel_m", c.map_voxel_m, "local map resolution, m");
  b.field("voxel_planes", c.voxel_planes,
          "a plane feature in a planar cell of the local map (10+ points within 5 cm of one plane) matches "
          "that plane instead of a plane fitted to its 5 nearest map points: same accuracy, hall run 11-17 % "
          "cheaper (docs/speed_history.md)");
  b.field("local_map_radius_m", c.local_map_radius_m, "local map kept around the current pose, m");
  b.field("window_size", c.window_size, "keyframes in the sliding window");
  b.field("keyframe_rotation_deg", c.keyframe_rotation_deg, "new keyframe after this rotation, deg");
  b.field("keyframe_translation_m", c.keyframe_translation_m, "new keyframe after this translation, m");
  b.field("keyframe_interval_s", c.keyframe_interval_s, "new keyframe after this time, s");
  b.field("max_iterations", c.max_iterations, "solver iterations per window optimisation");
  b.field("huber_loss_m", c.huber_loss_m, "Huber loss scale of point-to-edge / point-to-plane residuals, m");
}

void bind(YamlBinder& b, estimator::OnlineCalibrationConfig& c) {
  b.field("enabled", c.enabled,
          "refine each spinning LiDAR's extrinsic and clock offset while running (hvi with a solid-state LiDAR): "
          "where the motion makes them observable, from how its points sit against the solid-state LiDAR's");
  b.field("prior_sigma_time_s", c.prior_sigma_time_s, "how far the given clock offset may be off, s");
  b.field("prior_sigma_rotation_deg", c.prior_sigma_rotation_deg,
          "how far the given extrinsic's rotation may be off, deg");
  b.field("prior_sigma_translation_m", c.prior_sigma_translation_m,
          "how far the given extrinsic's translation along the IMU's x and y may be off, m (0: kept as given)");
  b.field("prior_sigma_translation_z_m", c.prior_sigma_translation_z_m,
          "... and along its z, m (0: kept as given; from a ground robot only floors and ceilings observe it)");
  b.field("memory_s", c.memory_s, "older sweeps' evidence fades with this time constant, s");
  b.field("apply", c.apply,
          "apply corrections while running, as they are determined (live nodes; mmlio run with rerun: false); "
          "off: only estimated and reported, as a correction mid-run can leave the map inconsistent");
  b.field("rerun", c.rerun,
          "mmlio run: when the run settles on a calibration off from the one it started from by 2 ms, 0.1 deg or "
          "5 mm, run the bag twice more: once with the refined LiDARs measured from there but left out of the "
          "odometry (their error pulls the poses they are measured at), then with every LiDAR from what that "
          "found (what was mapped before the motion determined it stays in the map otherwise)");
}

void bindLoop(YamlBinder& b, backend::MappingConfig& c) {
  b.field("enabled", c.loop_enabled, "detect and close loops in the back end");
  b.field("search_radius_m", c.loop.search_radius_m, "loop candidates: past keyframes within this distance, m");
  b.field("min_time_gap_s", c.loop.min_time_gap_s, "loop candidates: at least this much older than the query, s");
  b.field("max_fitness_m", c.loop.max_fitness_m, "accept a loop when the mean ICP residual is below this, m");
  b.field("min_overlap", c.loop.min_overlap, "accept a loop when the inlier fraction is above this, 0..1");
}

void bindDynamic(YamlBinder& b, RigConfig& c) {
  b.field("enabled", c.estimator.dynamic.enabled,
          "returns in space an earlier sweep saw through (people, doors) are rejected before registration "
          "and kept out of the local map; local map points a keyframe sees through are removed");
  b.field("clean_map", c.mapping.clean_map,
          "remove from map.pcd the points keyframes saw through (at least twice, and by at least a third of "
          "the keyframes that saw that spot): ghosts of what moved");
  b.field("quiet_interval_s", c.estimator.dynamic.quiet_interval_s,
          "where nothing has moved for dynamic.hold_s, sweeps are tested for movers this far apart, s (0: every "
          "sweep); a mover found (8+ returns in a 1 m cell) makes every sweep tested again");
  b.field("hold_s", c.estimator.dynamic.hold_s, "after a mover was found, every sweep is tested for this long, s");
}

void bindOutput(YamlBinder& b, RigConfig& c) {
  b.field("map_voxel_m", c.mapping.map_leaf_m, "voxel size of the written map.pcd, m; 0 keeps every point");
  b.field("per_lidar_maps", c.mapping.per_lidar_maps, "also write one map_<lidar>.pcd per LiDAR");
  b.field("write_kitti", c.output.write_kitti, "also write the trajectory in KITTI format (poses + times.txt)");
  b.field("write_session", c.output.write_session,
          "write session/: keyframes, clouds, loops and map for a later run (docs/session.md)");
  b.field("dynamic_map", c.mapping.dynamic_map, "also write map_dynamic.pcd: the points removed as moving objects");
}

void bind(YamlBinder& b, RigConfig& c) {
  b.field("mode", c.mode, "which LiDARs to fuse: hvi (all) | vi (spinning only) | hi (solid state only)");
  b.field("calibration", c.calibration,
          "extrinsics source: config (T_imu_sensor / time_offset_s below) | auto (estimate at start-up)\n"
          "| path to a calibration YAML from `mmlio calibrate` (relative to this file)");
  b.field("reference_lidar", c.reference_lidar,
          "LiDAR whose sweeps define the fusion window (falls back to the first active one)");
  b.section("imu", c, bindImu, "IMU");
  b.list(
      "lidars", c.lidars, [](YamlBinder& s, LidarConfig& v) { bind(s, v); }, "LiDARs of the rig");
  b.section(
      "features", c.estimator.features, [](YamlBinder& s, lidar::FeatureConfig& v) { bind(s, v); },
      "feature extraction");
  b.section(
      "bad_frame", c.estimator.bad_frame, [](YamlBinder& s, lidar::BadFrameConfig& v) { bind(s, v); },
      "bad-frame check for solid-state LiDARs");
  b.section("odometry", c.estimator, bindOdometry, "sliding-window odometry");
  b.section(
      "online_calibration", c.estimator.online_calibration,
      [](YamlBinder& s, estimator::OnlineCalibrationConfig& v) { bind(s, v); }, "calibration refined while running");
  b.section("loop", c.mapping, bindLoop, "loop closure");
  b.section("dynamic", c, bindDynamic, "moving objects (people): rejection in the odometry, ghost removal in the map");
  b.section("output", c, bindOutput, "outputs");
}

const char* const kLidarTypes[] = {"velodyne", "ouster", "hesai", "generic_spinning", "livox"};

}  // namespace

// ---- defaults --------------------------------------------------------------------------------

LidarKind LidarConfig::kind() const { return type == "livox" ? LidarKind::kSolidState : LidarKind::kSpinning; }

namespace {
// Placeholder mount of the presets' VLP-16: 0.2 m above the Livox IMU, axes aligned. A real rig's
// differs: placeholderExtrinsics() names a LiDAR still on it.
Eigen::Isometry3d placeholderSpinningMount() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.0, 0.0, 0.2);
  return T;
}
}  // namespace

std::vector<LidarConfig> defaultLidars() {
  LidarConfig velodyne;
  velodyne.name = "velodyne";
  velodyne.type = "velodyne";
  velodyne.topic = "/velodyne_points";
  velodyne.T_imu_sensor = placeholderSpinningMount();  // replace with `mmlio calibrate` or the rig drawing
  velodyne.num_rings = 16;

  LidarConfig livox;
  livox.name = "livox";
  livox.type = "livox";
  livox.topic = "/livox/lidar";
  // Livox Horizon factory LiDAR-to-IMU extrinsic: identity rotation, translation in m.
  livox.T_imu_sensor.translation() = Eigen::Vector3d(0.05512, 0.02226, -0.0297);
  livox.num_rings = 6;  // Horizon scans with 6 lines
  return {velodyne, livox};
}

// ---- loading ---------------------------------------------------------------------------------

RigConfig parseRigConfig(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw Error(source_name + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  RigConfig cfg;
  YamlBinder reader(root, source_name);
  bind(reader, cfg);
  reader.finish();
  cfg.source_path = source_name;
  validateRigConfig(cfg);
  return cfg;
}

RigConfig loadRigConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open rig config '" + path + "' (missing file? presets are in config/)");
  std::stringstream text;
  text << in.rdbuf();
  RigConfig cfg = parseRigConfig(text.str(), path);
  if (cfg.calibration != "config" && cfg.calibration != "auto") {
    const std::filesystem::path calib(cfg.calibration);
    if (calib.is_relative())
      cfg.calibration = (std::filesystem::path(path).parent_path() / calib).lexically_normal().string();
    if (!std::filesystem::exists(cfg.calibration))
      throw Error(path + ": calibration: file '" + cfg.calibration +
                  "' not found (use config, auto, or the output of `mmlio calibrate`)");
  }
  return cfg;
}

// ---- validation ------------------------------------------------------------------------------

namespace {

class Checker {
 public:
  explicit Checker(const std::string& file) : file_(file) {}
  void require(bool ok, const std::string& key_path, const std::string& problem) const {
    if (!ok) throw Error(file_ + ": " + key_path + ": " + problem);
  }
  template <typename T> void positive(T value, const std::string& key_path) const {
    require(std::isfinite(static_cast<double>(value)) && value > T(0), key_path,
            "must be a finite number > 0, got " + toString(value));
  }
  template <typename T> void nonNegative(T value, const std::string& key_path) const {
    require(std::isfinite(static_cast<double>(value)) && value >= T(0), key_path,
            "must be a finite number >= 0, got " + toString(value));
  }

 private:
  template <typename T> static std::string toString(T value) {
    std::ostringstream os;
    os << value;
    return os.str();
  }
  std::string file_;
};

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

bool isValidMode(const std::string& mode) { return mode == "hvi" || mode == "vi" || mode == "hi"; }

void validateRigConfig(const RigConfig& cfg) {
  const Checker check(cfg.source_path);
  check.require(isValidMode(cfg.mode), "mode", "must be hvi, vi or hi, got '" + cfg.mode + "'");
  check.require(!cfg.calibration.empty(), "calibration", "must be config, auto or a file path");

  const ImuConfig& imu = cfg.imu;
  const estimator::OdometryConfig& e = cfg.estimator;
  check.require(!imu.topic.empty(), "imu.topic", "must not be empty");
  check.require(imu.acc_unit == "auto" || imu.acc_unit == "g" || imu.acc_unit == "m/s2", "imu.acc_unit",
                "must be auto, g or m/s2, got '" + imu.acc_unit + "'");
  check.positive(e.imu_noise.acc_noise_density, "imu.acc_noise_density");
  check.positive(e.imu_noise.gyro_noise_density, "imu.gyro_noise_density");
  check.positive(e.imu_noise.acc_bias_random_walk, "imu.acc_bias_random_walk");
  check.positive(e.imu_noise.gyro_bias_random_walk, "imu.gyro_bias_random_walk");
  check.positive(e.gravity_m_s2, "imu.gravity_m_s2");
  check.positive(e.imu_init.duration_s, "imu.init_duration_s");

  check.require(!cfg.lidars.empty(), "lidars", "at least one LiDAR is needed");
  std::vector<std::string> names;
  for (std::size_t i = 0; i < cfg.lidars.size(); ++i) {
    const LidarConfig& l = cfg.lidars[i];
    const std::string p = "lidars[" + std::to_string(i) + "].";
    check.require(!l.name.empty(), p + "name", "is required");
    for (const auto& n : names) check.require(n != l.name, p + "name", "'" + l.name + "' is used twice");
    names.push_back(l.name);
    bool known_type = false;
    for (const char* t : kLidarTypes) known_type = known_type || l.type == t;
    check.require(known_type, p + "type",
                  "must be velodyne, ouster, hesai, generic_spinning or livox, got '" + l.type + "'");
    check.require(!l.topic.empty(), p + "topic", "is required");
    check.nonNegative(l.min_range_m, p + "min_range_m");
    check.require(l.max_range_m > l.min_range_m, p + "max_range_m", "must be > min_range_m");
    check.positive(l.num_rings, p + "num_rings");
    validateRigidTransform(l.T_imu_sensor.matrix(), cfg.source_path + ": " + p + "T_imu_sensor");
  }
  bool reference_known = false;
  for (const auto& n : names) reference_known = reference_known || n == cfg.reference_lidar;
  check.require(reference_known, "reference_lidar",
                "'" + cfg.reference_lidar + "' is not one of the lidars (" + join(names) + ")");
  check.require(!activeLidars(cfg, cfg.mode).empty(), "mode",
                "'" + cfg.mode + "' uses no enabled LiDAR of this rig (vi needs a spinning one, hi a livox)");

  const lidar::FeatureConfig& f = e.features;
  check.positive(f.neighbours, "features.neighbours");
  check.nonNegative(f.edge_threshold, "features.edge_threshold");
  check.nonNegative(f.plane_threshold, "features.plane_threshold");
  check.require(f.plane_threshold <= f.edge_threshold, "features.plane_threshold",
                "must be <= features.edge_threshold");
  check.positive(f.continuity_jump_m, "features.continuity_jump_m");

  check.nonNegative(e.bad_frame.min_edge_range_m, "bad_frame.min_edge_range_m");
  check.nonNegative(e.bad_frame.min_edge_points, "bad_frame.min_edge_points");

  check.positive(e.edge_voxel_m, "odometry.edge_voxel_m");
  check.positive(e.plane_voxel_m, "odometry.plane_voxel_m");
  check.nonNegative(e.registration_max_edges, "odometry.registration_max_edges");
  check.nonNegative(e.registration_max_planes, "odometry.registration_max_planes");
  check.nonNegative(e.degeneracy.min_points, "odometry.degenerate_min_points");
  check.nonNegative(e.dynamic.quiet_interval_s, "dynamic.quiet_interval_s");
  check.nonNegative(e.dynamic.hold_s, "dynamic.hold_s");
  check.nonNegative(e.degeneracy.drift_m_s2, "odometry.degenerate_drift_m_s2");
  check.nonNegative(e.degeneracy.min_points_drifted, "odometry.degenerate_min_points_drifted");
  check.positive(e.map_voxel_m, "odometry.map_voxel_m");
  check.positive(e.local_map_radius_m, "odometry.local_map_radius_m");
  check.positive(e.window_size, "odometry.window_size");
  check.nonNegative(e.keyframe_rotation_deg, "odometry.keyframe_rotation_deg");
  check.nonNegative(e.keyframe_translation_m, "odometry.keyframe_translation_m");
  check.nonNegative(e.keyframe_interval_s, "odometry.keyframe_interval_s");
  check.positive(e.max_iterations, "odometry.max_iterations");
  check.positive(e.huber_loss_m, "odometry.huber_loss_m");
  const estimator::OnlineCalibrationConfig& oc = e.online_calibration;
  check.positive(oc.prior_sigma_time_s, "online_calibration.prior_sigma_time_s");
  check.positive(oc.prior_sigma_rotation_deg, "online_calibration.prior_sigma_rotation_deg");
  check.nonNegative(oc.prior_sigma_translation_m, "online_calibration.prior_sigma_translation_m");
  check.nonNegative(oc.prior_sigma_translation_z_m, "online_calibration.prior_sigma_translation_z_m");
  check.positive(oc.memory_s, "online_calibration.memory_s");

  const backend::LoopCloser::Config& loop = cfg.mapping.loop;
  check.positive(loop.search_radius_m, "loop.search_radius_m");
  check.nonNegative(loop.min_time_gap_s, "loop.min_time_gap_s");
  check.positive(loop.max_fitness_m, "loop.max_fitness_m");
  check.require(loop.min_overlap >= 0 && loop.min_overlap <= 1, "loop.min_overlap", "must be within 0..1");

  check.nonNegative(cfg.mapping.map_leaf_m, "output.map_voxel_m");
}

// ---- emitting --------------------------------------------------------------------------------

std::string toYaml(const RigConfig& cfg) {
  RigConfig copy = cfg;
  return documentedYaml(copy, [](YamlBinder& b, RigConfig& c) { bind(b, c); });
}

std::string defaultConfigYaml() {
  return "# mmlio rig configuration: every parameter with its meaning, unit and default.\n"
         "# Unknown keys are errors; absent keys take the default shown.\n" +
         toYaml(RigConfig{});
}

// ---- modes -----------------------------------------------------------------------------------

std::vector<std::string> placeholderExtrinsics(const RigConfig& cfg, const std::string& mode) {
  std::vector<std::string> names;
  for (const LidarConfig* l : activeLidars(cfg, mode))
    if (l->kind() == LidarKind::kSpinning && l->T_imu_sensor.matrix() == placeholderSpinningMount().matrix())
      names.push_back(l->name);
  return names;
}

std::vector<const LidarConfig*> activeLidars(const RigConfig& cfg, const std::string& mode) {
  if (!isValidMode(mode)) throw Error("unknown mode '" + mode + "' (hvi, vi or hi)");
  std::vector<const LidarConfig*> active;
  for (const auto& l : cfg.lidars) {
    if (!l.enabled) continue;
    const bool spinning = l.kind() == LidarKind::kSpinning;
    if (mode == "hvi" || (mode == "vi" && spinning) || (mode == "hi" && !spinning)) active.push_back(&l);
  }
  return active;
}

const LidarConfig& referenceLidar(const RigConfig& cfg, const std::string& mode) {
  const auto active = activeLidars(cfg, mode);
  if (active.empty()) throw Error(cfg.source_path + ": mode '" + mode + "' uses no enabled LiDAR of this rig");
  for (const LidarConfig* l : active)
    if (l->name == cfg.reference_lidar) return *l;
  return *active.front();
}

LidarExtrinsic toExtrinsic(const LidarConfig& lidar) {
  LidarExtrinsic e;
  e.name = lidar.name;
  e.kind = lidar.kind();
  e.T_imu_sensor = lidar.T_imu_sensor;
  e.time_offset_s = lidar.time_offset_s;
  return e;
}

std::vector<std::string> applyCalibration(RigConfig& cfg, const Calibration& calibration) {
  for (const auto& [name, calib] : calibration) {
    bool found = false;
    for (auto& l : cfg.lidars) {
      if (l.name != name) continue;
      l.T_imu_sensor = calib.T_imu_sensor;
      l.time_offset_s = calib.time_offset_s;
      found = true;
    }
    if (!found) {
      std::vector<std::string> names;
      for (const auto& l : cfg.lidars) names.push_back(l.name);
      throw Error("calibration names LiDAR '" + name + "' which the rig config does not have (" + join(names) + ")");
    }
  }
  std::vector<std::string> uncovered;
  for (const auto& l : cfg.lidars)
    if (!calibration.count(l.name)) uncovered.push_back(l.name);
  return uncovered;
}

}  // namespace mmlio::config
