// Rig config (strict YAML with documented defaults), calibration file, presets.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "../common/error_of.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/config/yaml_binder.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"

namespace fs = std::filesystem;
using namespace mmlio;
using namespace mmlio::config;

namespace {

const std::string kConfigDir = std::string(MMLIO_SOURCE_DIR) + "/config";

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("mmlio_test_config_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string file = (path / name).string();
    std::ofstream(file) << text;
    return file;
  }
};

/// Every key path of a YAML tree ("lidars[].T_imu_sensor", "imu.topic", ...).
void collectKeys(const YAML::Node& node, const std::string& prefix, std::set<std::string>& keys) {
  if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = prefix + it->first.as<std::string>();
      const YAML::Node value = it->second;
      keys.insert(key);
      if (value.IsMap()) collectKeys(value, key + ".", keys);
      for (std::size_t i = 0; value.IsSequence() && i < value.size(); ++i)
        if (value[i].IsMap()) collectKeys(value[i], key + "[].", keys);
    }
  }
}

}  // namespace

// ---- presets and defaults ----------------------------------------------------------------

TEST(Presets, AllThreeLoadWithTheReferenceRig) {
  for (const std::string mode : {"hvi", "vi", "hi"}) {
    SCOPED_TRACE(mode);
    const RigConfig cfg = loadRigConfig(kConfigDir + "/" + mode + ".yaml");
    EXPECT_EQ(cfg.mode, mode);
    ASSERT_EQ(cfg.lidars.size(), 2u);
    EXPECT_EQ(cfg.lidars[0].name, "velodyne");
    EXPECT_EQ(cfg.lidars[0].type, "velodyne");
    EXPECT_EQ(cfg.lidars[0].topic, "/velodyne_points");
    EXPECT_EQ(cfg.lidars[1].name, "livox");
    EXPECT_EQ(cfg.lidars[1].type, "livox");
    EXPECT_EQ(cfg.lidars[1].topic, "/livox/lidar");
    EXPECT_EQ(cfg.imu.topic, "/livox/imu");
    EXPECT_EQ(cfg.imu.acc_unit, "auto");
    // Livox Horizon factory extrinsic.
    EXPECT_TRUE(cfg.lidars[1].T_imu_sensor.linear().isIdentity(0.0));
    EXPECT_EQ(cfg.lidars[1].T_imu_sensor.translation(), Eigen::Vector3d(0.05512, 0.02226, -0.0297));
    EXPECT_EQ(cfg.source_path, kConfigDir + "/" + mode + ".yaml");
  }
}

TEST(Presets, DifferOnlyInModeAndReferenceLidar) {
  const RigConfig hvi = loadRigConfig(kConfigDir + "/hvi.yaml");
  RigConfig vi = loadRigConfig(kConfigDir + "/vi.yaml");
  RigConfig hi = loadRigConfig(kConfigDir + "/hi.yaml");
  EXPECT_EQ(hi.reference_lidar, "livox");
  vi.mode = hi.mode = "hvi";
  hi.reference_lidar = hvi.reference_lidar;
  EXPECT_EQ(toYaml(vi), toYaml(hvi));
  EXPECT_EQ(toYaml(hi), toYaml(hvi));
  // The hvi preset is the built-in default rig, which keeps the "(default: X)" comments of the
  // presets truthful: when tuning, change the default in rig_config.hpp and regenerate the
  // presets from defaultConfigYaml() (keeping their header and extrinsic notes).
  EXPECT_EQ(toYaml(hvi), toYaml(RigConfig{})) << "config/hvi.yaml and the defaults in rig_config.hpp diverged";
}

TEST(Presets, ListEveryDeclaredFieldWithAComment) {
  std::set<std::string> declared;
  collectKeys(YAML::Load(defaultConfigYaml()), "", declared);
  EXPECT_GT(declared.size(), 50u);
  for (const std::string mode : {"hvi", "vi", "hi"}) {
    SCOPED_TRACE(mode);
    std::set<std::string> present;
    collectKeys(YAML::LoadFile(kConfigDir + "/" + mode + ".yaml"), "", present);
    EXPECT_EQ(present, declared);
    // Every key line is preceded by a comment line.
    std::ifstream in(kConfigDir + "/" + mode + ".yaml");
    std::string previous, line;
    int line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      const auto first = line.find_first_not_of(' ');
      const bool is_key = first != std::string::npos && line[first] != '#' && line.find(':') != std::string::npos &&
                          line.find('[') == std::string::npos;
      const bool is_continuation = first != std::string::npos && (line[first] == '0' || line[first] == '-') &&
                                   line.find(':') == std::string::npos;
      if (is_key && !is_continuation) {
        EXPECT_NE(previous.find('#'), std::string::npos) << "line " << line_no << " has no comment: " << line;
      }
      previous = line;
    }
  }
}

TEST(Defaults, DefaultConfigYamlLoadsBackToTheDefaults) {
  const std::string text = defaultConfigYaml();
  const RigConfig cfg = parseRigConfig(text, "defaults");
  EXPECT_EQ(toYaml(cfg), toYaml(RigConfig{}));
  EXPECT_EQ(cfg.estimator.window_size, 4);
  EXPECT_EQ(cfg.estimator.bad_frame.min_edge_points, 100);
  EXPECT_EQ(cfg.estimator.imu_noise.gyro_bias_random_walk, 0.0001);
  EXPECT_EQ(cfg.lidars[0].T_imu_sensor.translation(), Eigen::Vector3d(0, 0, 0.2));
}

TEST(Defaults, CommentsCarryEachDefault) {
  const std::string text = defaultConfigYaml();
  EXPECT_NE(text.find("# drop returns farther than this, m (default: 100.0)\n    max_range_m: 100.0\n"),
            std::string::npos);
  EXPECT_NE(text.find("(default: identity)"), std::string::npos);
  // A changed value keeps showing the default in the comment.
  RigConfig cfg;
  cfg.mapping.loop.search_radius_m = 25;
  EXPECT_NE(toYaml(cfg).find("(default: 10.0)\n  search_radius_m: 25.0\n"), std::string::npos);
}

TEST(Defaults, EmptyFileGivesTheDefaultRig) {
  const RigConfig cfg = parseRigConfig("", "empty.yaml");
  EXPECT_EQ(toYaml(cfg), toYaml(RigConfig{}));
}

TEST(Loading, AbsentKeysKeepDefaultsAndGivenOnesOverride) {
  const RigConfig cfg = parseRigConfig("odometry: {window_size: 7}\nloop:\n  enabled: false\n", "partial.yaml");
  EXPECT_EQ(cfg.estimator.window_size, 7);
  EXPECT_EQ(cfg.estimator.edge_voxel_m, 0.2);
  EXPECT_FALSE(cfg.mapping.loop_enabled);
  EXPECT_EQ(cfg.mapping.loop.search_radius_m, 10.0);
  EXPECT_EQ(cfg.lidars.size(), 2u);
}

TEST(Loading, SectionsBindTheStagesOwnSettings) {
  const RigConfig cfg = parseRigConfig(
      "imu: {gyro_noise_density: 0.004, init_duration_s: 2.0}\n"
      "odometry: {surface_points: all, degenerate_min_points: 12}\n"
      "bad_frame: {criterion: edges}\n"
      "dynamic: {enabled: false, clean_map: false}\n"
      "output: {map_voxel_m: 0.1, dynamic_map: false}\n",
      "stages.yaml");
  EXPECT_EQ(cfg.estimator.imu_noise.gyro_noise_density, 0.004);
  EXPECT_EQ(cfg.estimator.imu_init.duration_s, 2.0);
  EXPECT_EQ(cfg.estimator.surface_points, estimator::SurfacePoints::kAll);
  EXPECT_EQ(cfg.estimator.degeneracy.min_points, 12.0);
  EXPECT_FALSE(cfg.estimator.bad_frame.by_information);
  EXPECT_FALSE(cfg.estimator.dynamic.enabled);
  EXPECT_FALSE(cfg.mapping.clean_map);
  EXPECT_EQ(cfg.mapping.map_leaf_m, 0.1);
  EXPECT_FALSE(cfg.mapping.dynamic_map);
  // Written back, the named values keep their names.
  const std::string yaml = toYaml(cfg);
  EXPECT_NE(yaml.find("surface_points: all\n"), std::string::npos);
  EXPECT_NE(yaml.find("criterion: edges\n"), std::string::npos);
}

TEST(Loading, ListReplacesTheDefaultLidars) {
  const RigConfig cfg = parseRigConfig(
      "mode: hi\nreference_lidar: front\nlidars:\n  - {name: front, type: livox, topic: /front}\n", "one.yaml");
  ASSERT_EQ(cfg.lidars.size(), 1u);
  EXPECT_EQ(cfg.lidars[0].name, "front");
  EXPECT_EQ(cfg.lidars[0].max_range_m, 100.0);  // item default
  EXPECT_TRUE(cfg.lidars[0].T_imu_sensor.matrix().isIdentity(0.0));
}

TEST(Loading, RelativeCalibrationPathResolvesAgainstTheConfigDirectory) {
  TempDir dir;
  const std::string path = dir.write("rig.yaml", "calibration: calib/out.yaml\n");
  EXPECT_ERROR_CONTAINS(loadRigConfig(path),
                        "calibration: file '" + (dir.path / "calib/out.yaml").string() + "' not found");
  fs::create_directories(dir.path / "calib");
  dir.write("calib/out.yaml", "");
  EXPECT_EQ(loadRigConfig(path).calibration, (dir.path / "calib/out.yaml").string());
  EXPECT_EQ(loadRigConfig(dir.write("rig2.yaml", "calibration: auto\n")).calibration, "auto");
}

// ---- strictness --------------------------------------------------------------------------

TEST(Strict, UnknownTopLevelKeyErrorNamesKeyFileAndLine) {
  TempDir dir;
  const std::string path = dir.write("typo.yaml", "mode: hvi\nmax_rang_m: 50\n");
  EXPECT_ERROR_CONTAINS(loadRigConfig(path), path + ":2: unknown key 'max_rang_m'");
  EXPECT_ERROR_CONTAINS(loadRigConfig(path), "known keys: mode, calibration");
}

TEST(Strict, UnknownNestedKeyInAListItemNamesItsPath) {
  const std::string text =
      "lidars:\n"
      "  - {name: velodyne, type: velodyne, topic: /velodyne_points}\n"
      "  - name: livox\n"
      "    type: livox\n"
      "    topik: /livox/lidar\n";
  EXPECT_ERROR_CONTAINS(parseRigConfig(text, "rig.yaml"), "rig.yaml:5: unknown key 'lidars[1].topik'");
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry:\n  window: 3\n", "rig.yaml"),
                        "unknown key 'odometry.window' (known keys in odometry: edge_voxel_m");
}

TEST(Strict, WrongTypeErrorNamesTheKeyPath) {
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry:\n  window_size: four\n", "rig.yaml"),
                        "rig.yaml:2: odometry.window_size: expected an integer, got 'four'");
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry:\n  window_size: 2.5\n", "rig.yaml"), "expected an integer");
  EXPECT_ERROR_CONTAINS(parseRigConfig("loop:\n  enabled: maybe\n", "rig.yaml"),
                        "loop.enabled: expected true or false");
  EXPECT_ERROR_CONTAINS(parseRigConfig("imu: /livox/imu\n", "rig.yaml"), "imu: expected a map of keys");
  EXPECT_ERROR_CONTAINS(parseRigConfig("lidars:\n  - name: a\n    topic: [1, 2]\n", "rig.yaml"),
                        "rig.yaml:3: lidars[0].topic: expected a string, got a sequence");
  EXPECT_ERROR_CONTAINS(parseRigConfig("lidars: velodyne\n", "rig.yaml"), "lidars: expected a sequence");
  EXPECT_ERROR_CONTAINS(parseRigConfig("features:\n  edge_threshold:\n", "rig.yaml"),
                        "features.edge_threshold: expected a number, got nothing");
}

TEST(Strict, DuplicateKeyIsAnError) {
  EXPECT_ERROR_CONTAINS(parseRigConfig("loop:\n  enabled: true\n  enabled: false\n", "d.yaml"),
                        "d.yaml:3: duplicate key 'loop.enabled'");
}

TEST(Strict, MissingFileErrorNamesThePath) {
  EXPECT_ERROR_CONTAINS(loadRigConfig("/nonexistent/rig.yaml"), "/nonexistent/rig.yaml");
}

TEST(Strict, InvalidYamlErrorNamesFileAndLine) {
  EXPECT_ERROR_CONTAINS(parseRigConfig("mode: hvi\nimu: {topic: [\n", "bad.yaml"), "bad.yaml:");
}

TEST(Validation, BadValuesAreErrorsNamingTheKey) {
  EXPECT_ERROR_CONTAINS(parseRigConfig("mode: lio\n", "r.yaml"), "r.yaml: mode: must be hvi, vi or hi");
  EXPECT_ERROR_CONTAINS(parseRigConfig("imu: {acc_unit: mg}\n", "r.yaml"), "imu.acc_unit");
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry: {edge_voxel_m: -0.1}\n", "r.yaml"),
                        "odometry.edge_voxel_m: must be a finite number > 0, got -0.1");
  EXPECT_ERROR_CONTAINS(parseRigConfig("loop: {min_overlap: 1.5}\n", "r.yaml"), "loop.min_overlap");
  EXPECT_ERROR_CONTAINS(parseRigConfig("\nbad_frame: {criterion: corners}\n", "r.yaml"),
                        "r.yaml:2: bad_frame.criterion: must be one of information, edges, got 'corners'");
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry:\n  surface_points: some\n", "r.yaml"),
                        "r.yaml:2: odometry.surface_points: must be one of solid_state, all, none, got 'some'");
  EXPECT_ERROR_CONTAINS(parseRigConfig("reference_lidar: ouster\n", "r.yaml"),
                        "reference_lidar: 'ouster' is not one of the lidars (velodyne, livox)");
  EXPECT_ERROR_CONTAINS(
      parseRigConfig("lidars:\n  - {name: a, type: velodyne, topic: /a}\n  - {name: b, type: lidar, topic: /b}\n"
                     "reference_lidar: a\n",
                     "r.yaml"),
      "lidars[1].type: must be velodyne, ouster, hesai, generic_spinning or livox, got 'lidar'");
  EXPECT_ERROR_CONTAINS(
      parseRigConfig("lidars:\n  - {name: a, type: velodyne, topic: /a}\n  - {name: a, type: livox, topic: /b}\n"
                     "reference_lidar: a\n",
                     "r.yaml"),
      "lidars[1].name: 'a' is used twice");
  EXPECT_ERROR_CONTAINS(parseRigConfig("lidars:\n  - {name: a, type: velodyne}\nreference_lidar: a\n", "r.yaml"),
                        "lidars[0].topic: is required");
  EXPECT_ERROR_CONTAINS(
      parseRigConfig("lidars:\n  - {name: a, type: velodyne, topic: /a, min_range_m: 5, max_range_m: 2}\n"
                     "reference_lidar: a\n",
                     "r.yaml"),
      "lidars[0].max_range_m: must be > min_range_m");
  // hi on a rig without a livox.
  EXPECT_ERROR_CONTAINS(parseRigConfig("mode: hi\nlidars:\n  - {name: a, type: velodyne, topic: /a}\n"
                                       "reference_lidar: a\n",
                                       "r.yaml"),
                        "mode: 'hi' uses no enabled LiDAR");
}

TEST(Validation, ExtrinsicMustBeSixteenNumbersOfARigidTransform) {
  const std::string head = "lidars:\n  - name: a\n    type: velodyne\n    topic: /a\n    T_imu_sensor: ";
  const std::string tail = "\nreference_lidar: a\n";
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]" + tail, "r.yaml"),
                        "r.yaml:5: lidars[0].T_imu_sensor: expected 16 numbers");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "[1, 0, 0, 0, 0, 1.1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]" + tail, "r.yaml"),
                        "lidars[0].T_imu_sensor: rotation is not orthonormal");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]" + tail, "r.yaml"),
                        "bottom row must be 0 0 0 1");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1]" + tail, "r.yaml"),
                        "reflection");
  // A 90 degree yaw written with 9 decimals is accepted.
  const RigConfig cfg = parseRigConfig(
      head + "[0.000000000, -1.000000000, 0, 1, 1.000000000, 0.000000000, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]" + tail,
      "r.yaml");
  EXPECT_TRUE(cfg.lidars[0].T_imu_sensor.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  EXPECT_EQ(cfg.lidars[0].T_imu_sensor.translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(Validation, ExtrinsicAlsoAsXyzWithRollPitchYawOrAQuaternion) {
  const std::string head = "lidars:\n  - name: a\n    type: velodyne\n    topic: /a\n    T_imu_sensor: ";
  const std::string tail = "\nreference_lidar: a\n";
  // ROS / URDF order: roll about x, then pitch about y, then yaw about z (fixed axes).
  const Eigen::Matrix3d want = (Eigen::AngleAxisd(30 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(-10 * M_PI / 180, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(5 * M_PI / 180, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  const RigConfig rpy = parseRigConfig(head + "{xyz: [0.1, -0.2, 0.3], rpy_deg: [5, -10, 30]}" + tail, "r.yaml");
  EXPECT_TRUE(rpy.lidars[0].T_imu_sensor.linear().isApprox(want, 1e-12));
  EXPECT_TRUE(rpy.lidars[0].T_imu_sensor.translation().isApprox(Eigen::Vector3d(0.1, -0.2, 0.3), 1e-15));
  const Eigen::Quaterniond q(want);
  const RigConfig quaternion = parseRigConfig(head + "{xyz: [0.1, -0.2, 0.3], quaternion: [" + std::to_string(q.x()) +
                                                  ", " + std::to_string(q.y()) + ", " + std::to_string(q.z()) + ", " +
                                                  std::to_string(q.w()) + "]}" + tail,
                                              "r.yaml");
  EXPECT_TRUE(quaternion.lidars[0].T_imu_sensor.linear().isApprox(want, 1e-5));  // 6 digits, normalised
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "{xyz: [0, 0, 0]}" + tail, "r.yaml"), "exactly one of rpy_deg");
  EXPECT_ERROR_CONTAINS(
      parseRigConfig(head + "{xyz: [0, 0, 0], rpy_deg: [0, 0, 0], quaternion: [0, 0, 0, 1]}" + tail, "r.yaml"),
      "exactly one of rpy_deg");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "{rpy_deg: [0, 0, 0]}" + tail, "r.yaml"), "missing xyz");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "{xyz: [0, 0], rpy_deg: [0, 0, 0]}" + tail, "r.yaml"),
                        "lidars[0].T_imu_sensor.xyz: expected 3 numbers");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "{xyz: [0, 0, 0], quaternion: [0, 0, 0, 2]}" + tail, "r.yaml"),
                        "not a unit quaternion");
  EXPECT_ERROR_CONTAINS(parseRigConfig(head + "{xyz: [0, 0, 0], ypr_deg: [0, 0, 0]}" + tail, "r.yaml"),
                        "unknown key 'ypr_deg'");
  // A matrix typed with 4 digits (a 30 deg yaw) is taken as the nearest rotation.
  const RigConfig typed =
      parseRigConfig(head + "[0.8660, -0.5000, 0, 0, 0.5000, 0.8660, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]" + tail, "r.yaml");
  EXPECT_TRUE(typed.lidars[0].T_imu_sensor.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-4));
}

TEST(Validation, APlaceholderMountAndAMissingExtrinsicAreNamed) {
  RigConfig cfg;  // the presets' rig: the VLP-16 on its placeholder mount
  EXPECT_EQ(placeholderExtrinsics(cfg, "hvi"), std::vector<std::string>{"velodyne"});
  EXPECT_EQ(placeholderExtrinsics(cfg, "vi"), std::vector<std::string>{"velodyne"});
  EXPECT_TRUE(placeholderExtrinsics(cfg, "hi").empty());  // the Livox's is its factory extrinsic
  cfg.lidars[0].T_imu_sensor.translation().z() = 0.21;
  EXPECT_TRUE(placeholderExtrinsics(cfg, "hvi").empty());

  std::string warned;
  log::configure(log::Level::kInfo, [&](log::Level, const std::string& m) { warned += m + "\n"; });
  parseRigConfig(
      "lidars:\n  - {name: a, type: velodyne, topic: /a}\n"
      "  - {name: b, type: livox, topic: /b, T_imu_sensor: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}}\n"
      "reference_lidar: a\n",
      "r.yaml");
  log::configure(log::Level::kInfo);
  EXPECT_NE(warned.find("r.yaml:2: lidars[0].T_imu_sensor not given: LiDAR 'a'"), std::string::npos) << warned;
  EXPECT_EQ(warned.find("LiDAR 'b'"), std::string::npos) << warned;
}

// ---- modes -------------------------------------------------------------------------------

TEST(Modes, HviUsesBothViTheVelodyneHiTheLivox) {
  const RigConfig cfg;
  auto names = [&](const std::string& mode) {
    std::vector<std::string> out;
    for (const LidarConfig* l : activeLidars(cfg, mode)) out.push_back(l->name);
    return out;
  };
  EXPECT_EQ(names("hvi"), (std::vector<std::string>{"velodyne", "livox"}));
  EXPECT_EQ(names("vi"), (std::vector<std::string>{"velodyne"}));
  EXPECT_EQ(names("hi"), (std::vector<std::string>{"livox"}));
  EXPECT_EQ(referenceLidar(cfg, "hvi").name, "velodyne");
  EXPECT_EQ(referenceLidar(cfg, "hi").name, "livox");  // velodyne is inactive: falls back
  EXPECT_ERROR_CONTAINS(activeLidars(cfg, "lio"), "unknown mode 'lio'");
  RigConfig disabled;
  disabled.lidars[1].enabled = false;
  EXPECT_TRUE(activeLidars(disabled, "hi").empty());
  EXPECT_EQ(toExtrinsic(cfg.lidars[1]).kind, LidarKind::kSolidState);
  EXPECT_EQ(toExtrinsic(cfg.lidars[0]).kind, LidarKind::kSpinning);
}

// ---- calibration file --------------------------------------------------------------------

TEST(Calibration, RoundTripKeepsTransformsAndOffsetsExactly) {
  TempDir dir;
  Calibration in;
  in["velodyne"].T_imu_sensor.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  in["velodyne"].T_imu_sensor.translation() = Eigen::Vector3d(0.1, -1.0 / 3.0, 0.2);
  in["velodyne"].time_offset_s = -0.0125;
  in["livox"].T_imu_sensor.translation() = Eigen::Vector3d(0.05512, 0.02226, -0.0297);
  YAML::Node extra;
  extra["velodyne"]["fitness"] = 0.031;
  extra["velodyne"]["num_points"] = 12345;
  extra["imu"]["acc_noise_density"] = 0.05;
  extra["path_length_m"] = 152.5;
  const std::string path = (dir.path / "calib.yaml").string();
  writeCalibration(path, in, extra);
  const Calibration out = readCalibration(path);
  ASSERT_EQ(out.size(), 2u);
  for (const auto& [name, c] : in) {
    SCOPED_TRACE(name);
    EXPECT_EQ(out.at(name).T_imu_sensor.matrix(), c.T_imu_sensor.matrix());
    EXPECT_EQ(out.at(name).time_offset_s, c.time_offset_s);
  }
  // Extra keys are written where they belong.
  const YAML::Node root = YAML::LoadFile(path);
  EXPECT_EQ(root["velodyne"]["fitness"].as<double>(), 0.031);
  EXPECT_EQ(root["velodyne"]["num_points"].as<int>(), 12345);
  EXPECT_EQ(root["imu"]["acc_noise_density"].as<double>(), 0.05);
  EXPECT_EQ(root["path_length_m"].as<double>(), 152.5);
}

TEST(Calibration, AppliesToTheRigConfigByName) {
  RigConfig cfg;
  Calibration calib;
  calib["velodyne"].T_imu_sensor.translation() = Eigen::Vector3d(0.3, 0, 0.1);
  calib["velodyne"].time_offset_s = 0.02;
  EXPECT_EQ(applyCalibration(cfg, calib), std::vector<std::string>{"livox"});
  EXPECT_EQ(cfg.lidars[0].T_imu_sensor.translation(), Eigen::Vector3d(0.3, 0, 0.1));
  EXPECT_EQ(cfg.lidars[0].time_offset_s, 0.02);
  calib["ouster"] = {};
  EXPECT_ERROR_CONTAINS(applyCalibration(cfg, calib), "'ouster'");
}

TEST(Calibration, HandWrittenFileWithMetadataReads) {
  TempDir dir;
  const std::string path = dir.write("c.yaml",
                                     "generated_by: hand\n"
                                     "imu: {acc_noise_density: 0.1}\n"
                                     "velodyne:\n"
                                     "  T_imu_sensor: [1, 0, 0, 0.1, 0, 1, 0, 0, 0, 0, 1, 0.2, 0, 0, 0, 1]\n"
                                     "  overlap: 0.8\n");
  const Calibration c = readCalibration(path);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.at("velodyne").T_imu_sensor.translation(), Eigen::Vector3d(0.1, 0, 0.2));
  EXPECT_EQ(c.at("velodyne").time_offset_s, 0.0);
}

TEST(Calibration, RoundedRotationIsOrthonormalisedAndAWrongOneRejectedNamingFileAndSensor) {
  TempDir dir;
  const std::string path = dir.write("c.yaml",
                                     "livox:\n"
                                     "  T_imu_sensor: [1, 0.001, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
                                     "  time_offset_s: 0\n");
  // Off by 1e-3 (digits typed by hand): the nearest rotation, with a warning; off by 0.1: refused.
  const Calibration rounded = readCalibration(path);
  const Eigen::Matrix3d R = rounded.at("livox").T_imu_sensor.linear();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(R(0, 1), 0.0005, 1e-6);  // halfway: the nearest rotation splits the skew
  dir.write("c.yaml", "livox:\n  T_imu_sensor: [1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  EXPECT_ERROR_CONTAINS(readCalibration(path), path + ":2: sensor 'livox': T_imu_sensor: rotation is not orthonormal");
  // 1e-7 perturbations (printing with 7 digits) pass.
  dir.write("c.yaml", "livox:\n  T_imu_sensor: [1, 1e-7, 0, 0, -1e-7, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  EXPECT_EQ(readCalibration(path).size(), 1u);
  Calibration bad;
  bad["velodyne"].T_imu_sensor.matrix()(0, 0) = 2.0;
  EXPECT_ERROR_CONTAINS(writeCalibration((dir.path / "w.yaml").string(), bad), "sensor 'velodyne'");
  EXPECT_FALSE(fs::exists(dir.path / "w.yaml"));
}

TEST(Calibration, MalformedFilesAreErrorsNamingThePath) {
  TempDir dir;
  EXPECT_ERROR_CONTAINS(readCalibration("/nonexistent/c.yaml"), "/nonexistent/c.yaml");
  const std::string short_path =
      dir.write("s.yaml", "velodyne:\n  T_imu_sensor: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]\n");
  EXPECT_ERROR_CONTAINS(readCalibration(short_path), "expected 16 numbers");
  const std::string none = dir.write("n.yaml", "fitness: 0.1\n");
  EXPECT_ERROR_CONTAINS(readCalibration(none), "no sensor found");
  const std::string bad_offset =
      dir.write("o.yaml",
                "velodyne:\n  T_imu_sensor: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
                "  time_offset_s: soon\n");
  EXPECT_ERROR_CONTAINS(readCalibration(bad_offset), "sensor 'velodyne': time_offset_s: expected a number");
}

namespace mmlio::io {

TEST(Validation, InfiniteOrNanSizesAreRefusedNamingTheKey) {
  EXPECT_ERROR_CONTAINS(parseRigConfig("output:\n  map_voxel_m: .inf\n", "rig.yaml"),
                        "output.map_voxel_m: must be a finite number >= 0, got inf");
  EXPECT_ERROR_CONTAINS(parseRigConfig("odometry:\n  plane_voxel_m: .nan\n", "rig.yaml"),
                        "odometry.plane_voxel_m: must be a finite number > 0");
}

}  // namespace mmlio::io
