// mmlio run BAG: the main job, bag in -> trajectory, map and report out.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "commands.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/calibration_source.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/session_io.hpp"
#include "mmlio/pipeline/bag_calibration.hpp"
#include "mmlio/pipeline/runner.hpp"

namespace mmlio::apps {
namespace {

struct RunArgs {
  std::string bag, config, out = "mmlio_out", mode, calib, gt;
  std::string session;       // localize: the session folder
  std::string initial_pose;  // localize: "x,y,z,yaw_deg" in the session's map frame
  bool extend = false;       // run --extend: map on in the session
  bool no_progress = false, no_loop = false;
  double duration_s = 0.0;
  double max_degraded_percent = 25.0;
  double max_drift_m = 0.3;
};

// Exit codes (README): 0 trustworthy outputs, 1 error (nothing usable written), 2 internal error,
// 3 outputs written but not trustworthy (interrupted, bag ended early, too many degraded sweeps
// or too short a trajectory).
constexpr int kExitUntrusted = 3;

/// Applies `calibration:` from the config or --calib (which wins). `auto` calibrates on the bag's
/// start and writes the result to OUT/calib.yaml.
void applyCalibrationSource(config::RigConfig& cfg, const std::string& calib_override, const std::string& bag,
                            const std::string& out_dir) {
  if (config::resolveCalibration(cfg, calib_override) != "auto") return;
  const pipeline::BagCalibrationResult r = pipeline::calibrateBag(bag, cfg);
  config::applyCalibration(cfg, r.calibration);
  std::filesystem::create_directories(out_dir);
  config::writeCalibration(out_dir + "/calib.yaml", r.calibration, r.extra);
  cfg.calibration = "auto (" + out_dir + "/calib.yaml)";  // what the report records
  printCalibration(r);
  std::printf("written: %s/calib.yaml\n", out_dir.c_str());
}

/// "x,y,z,yaw_deg" as T_map_body (roll and pitch 0: the odometry's gravity fixes them).
Eigen::Isometry3d parseInitialPose(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x))
      throw Error("--initial-pose '" + text + "': expected x,y,z,yaw_deg (four numbers)");
    v.push_back(x);
  }
  if (v.size() != 4) throw Error("--initial-pose '" + text + "': expected x,y,z,yaw_deg (four numbers)");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(v[3] * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

/// The rig must be the one that made the session: the same LiDARs, by name and kind.
void checkRigMatchesSession(const config::RigConfig& cfg, const std::string& session_dir) {
  const std::string path = session_dir + "/rig.yaml";
  if (!std::filesystem::exists(path)) return;  // readSession names the missing file
  const config::RigConfig made_by = config::loadRigConfig(path);
  const auto describe = [](const config::RigConfig& c) {
    std::string out;
    for (const config::LidarConfig& l : c.lidars) out += (out.empty() ? "" : ", ") + l.name + " (" + l.type + ")";
    return out;
  };
  if (describe(made_by) != describe(cfg))
    throw Error("the rig config's LiDARs [" + describe(cfg) + "] are not the session's [" + describe(made_by) + "] (" +
                path + "): localize with the rig that mapped, e.g. --config " + path);
}

std::atomic<bool> g_stop{false};

extern "C" void onStopSignal(int signal) {
  g_stop = true;
  std::signal(signal, SIG_DFL);  // a second Ctrl-C ends the process at once
}

void run(const RunArgs& a) {
  // localize: the session and the hint are checked before anything else is done or said.
  std::shared_ptr<const Session> session;
  std::optional<Eigen::Isometry3d> initial_pose;
  if (!a.session.empty()) {
    if (io::holdsSession(a.out, a.session))
      throw Error("--out " + a.out + " holds the session's own run: its trajectory and report would be replaced; " +
                  (a.extend ? "extend into another folder" : "localize into another folder"));
    if (!a.initial_pose.empty()) initial_pose = parseInitialPose(a.initial_pose);
    session = std::make_shared<const Session>(io::readSession(a.session));
  }
  config::RigConfig cfg;
  if (a.config.empty()) {
    log::emit(log::Level::kInfo, "no --config: using the built-in defaults (same as config/hvi.yaml)");
  } else {
    cfg = config::loadRigConfig(a.config);
  }
  if (a.no_loop || (session && !a.extend)) cfg.mapping.loop_enabled = false;
  if (session) checkRigMatchesSession(cfg, a.session);
  applyCalibrationSource(cfg, a.calib, a.bag, a.out);
  const std::string mode = a.mode.empty() ? cfg.mode : a.mode;
  if (config::isValidMode(mode))
    for (const std::string& name : config::placeholderExtrinsics(cfg, mode))
      log::warn("LiDAR '", name, "' is on the presets' placeholder mount (0.2 m above the IMU, axes aligned): ",
                "a real mount's offset from it becomes an error of every sweep; ",
                "calibrate it (mmlio calibrate, or --calib auto) or give the rig drawing's extrinsic");

  pipeline::RunOptions options;
  options.bag_path = a.bag;
  options.out_dir = a.out;
  options.config = cfg;
  options.mode = a.mode;
  options.progress = !a.no_progress;
  options.gt_path = a.gt;
  options.max_duration_s = a.duration_s;
  options.session = session;
  options.session_dir = a.session;
  options.initial_pose = initial_pose;
  options.extend = a.extend;
  options.stop = &g_stop;
  // A mount `calibration: auto` has just found on the same start needs no second look.
  options.check_mount = cfg.calibration.rfind("auto", 0) != 0;
  options.trust.max_degraded_fraction = a.max_degraded_percent / 100.0;
  options.trust.max_drift_sigma_m = a.max_drift_m;
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
  const pipeline::RunResult r = pipeline::runBag(options);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);

  std::cout << "trajectory: " << a.out << "/trajectory.tum (" << r.trajectory.size() << " poses"
            << (a.session.empty() ? "" : ", in the session's map frame") << ")\n";
  if (a.session.empty() || a.extend)
    std::cout << "map:        " << a.out << "/map.pcd (" << r.map_points << " points"
              << (a.extend ? ", the session's grown" : "") << ")\n";
  std::cout << "report:     " << a.out << "/report.json, " << a.out << "/report.md\n\n" << r.timing.table();
  if (r.report.localization.enabled) {
    const pipeline::RunReport::Localization& l = r.report.localization;
    if (l.localized)
      std::printf(
          "\nlocalized %.1f s after the start; %d keyframes of %d fit the map; %zu spells lost, %d relocalizations\n",
          l.first_localized_s, l.keyframes_fitted, l.keyframes, l.lost_s.size(), l.relocalizations);
    else
      std::printf("\nnot localized in the session's map: %s\n", l.last_reason.c_str());
  }
  if (r.report.extension.enabled) {
    const pipeline::RunReport::Extension& x = r.report.extension;
    std::printf("\nfound in the session %.1f s after the start; %zu keyframes added to its %zu (%s/session)\n",
                x.localized_at_s, x.keyframes_added, x.session_keyframes, a.out.c_str());
  }
  if (r.report.evaluation) {
    const eval::EvalResult& e = *r.report.evaluation;
    std::printf(
        "\nagainst %s: ATE %.2f cm RMSE (max %.2f cm, attitude %.3f deg) over %zu poses and %.1f m of path "
        "(report.json: evaluation)\n",
        a.gt.c_str(), 100.0 * e.ate_rmse_m, 100.0 * e.ate_max_m, e.ate_rot_rmse_deg, e.num_associated, e.path_length_m);
  }
  if (!r.untrusted.empty()) {
    std::cerr << "mmlio: outputs written but not trustworthy: " << r.untrusted << " (see " << a.out
              << "/report.json)\n";
    std::exit(kExitUntrusted);
  }
}

/// The options `run` and `localize` share: the bag, the rig, where outputs go, mode and calibration.
void addInputOptions(CLI::App* cmd, RunArgs& args) {
  cmd->add_option("bag", args.bag, "Input bag: ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("-c,--config", args.config, "Rig config YAML (default: built-in = config/hvi.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", args.out, "Output directory")->capture_default_str();
  cmd->add_option("-m,--mode", args.mode, "Sensor mode: hvi | vi | hi (default: the config's)")
      ->check(CLI::IsMember({"hvi", "vi", "hi"}));
  cmd->add_option("--calib", args.calib, "Calibration YAML overriding extrinsics and clock offsets, or auto")
      ->check(CLI::ExistingFile | CLI::IsMember({"auto"}));
}

}  // namespace

void registerRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd =
      app.add_subcommand("run", "Odometry and mapping on a ROS 1 or ROS 2 bag: trajectory.tum, map.pcd, report.json");
  addInputOptions(cmd, *args);
  cmd->add_option("--gt", args->gt, "Ground-truth TUM trajectory: adds the evaluation to the report")
      ->check(CLI::ExistingFile);
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds of the bag");
  cmd->add_flag("--no-progress", args->no_progress, "No progress bar");
  cmd->add_flag("--no-loop", args->no_loop, "Disable loop closure");
  cmd->add_option("--extend", args->session,
                  "Session folder of an earlier run (OUT/session) to map on in: the bag is localized in it first, "
                  "then mapped in its frame; OUT/map.pcd and OUT/session hold both runs")
      ->check(CLI::ExistingDirectory)
      ->each([args](const std::string&) { args->extend = true; });
  cmd->add_option("--max-degraded", args->max_degraded_percent,
                  "Exit code 3 (outputs not trustworthy) when more than this % of the sweeps are degraded or the "
                  "poses cover less than 100 - this % of the stream")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--max-drift", args->max_drift_m,
                  "Exit code 3 also when the IMU alone carried the position along a direction the LiDARs did not "
                  "observe long enough to drift by more than this (m, 1 sigma; report: degeneracy.max_drift_sigma_m)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->callback([args] { run(*args); });
}

void registerLocalizeCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "localize", "Localize a bag in a saved session's map (OUT/session of a run): trajectory.tum in its frame");
  addInputOptions(cmd, *args);
  cmd->add_option("-s,--session", args->session, "Session folder written by mmlio run (OUT/session)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--initial-pose", args->initial_pose,
                  "Where the rig starts in the map, roughly: x,y,z,yaw_deg (default: found by place recognition)");
  cmd->add_option("--gt", args->gt, "Ground-truth TUM trajectory in the map's frame: adds the evaluation")
      ->check(CLI::ExistingFile);
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds of the bag");
  cmd->add_flag("--no-progress", args->no_progress, "No progress bar");
  cmd->callback([args] { run(*args); });
}

}  // namespace mmlio::apps
