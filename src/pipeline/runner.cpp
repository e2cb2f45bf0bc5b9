#include "mmlio/pipeline/runner.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/source_options.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/estimator/odometry.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/pipeline/bag_calibration.hpp"
#include "mmlio/pipeline/progress.hpp"
#include "mmlio/pipeline/system.hpp"

namespace mmlio::pipeline {
namespace {

constexpr Stamp kImuAfterStopNs = 500000000;  // 0.5 s: past the end of the sweep a --duration cut falls in

// Found before hours of work, not after: the output folder exists (or is created) and takes a file.
// Returns the outermost folder created here (empty if the folder existed).
std::filesystem::path checkWritable(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::path created;
  for (fs::path p = fs::absolute(dir, error); !p.empty() && !fs::exists(p, error); p = p.parent_path()) {
    created = p;
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, error);
  if (!fs::is_directory(dir, error))
    throw Error("cannot create output directory '" + dir + "'" + (error ? ": " + error.message() : std::string()));
  const fs::path probe = fs::path(dir) / ".mmlio-write-test";
  {
    std::ofstream out(probe);
    if (!(out << "ok")) throw Error("cannot write to output directory '" + dir + "'");
  }
  fs::remove(probe, error);
  return created;
}

/// The output folders this run created are removed again if it ends in an error before writing
/// into them (a wrong topic, a bag that never initialises): no empty folder is left behind.
class CreatedFolder {
 public:
  CreatedFolder(const std::filesystem::path& leaf, std::filesystem::path outermost) : outermost_(std::move(outermost)) {
    std::error_code error;
    if (!outermost_.empty()) leaf_ = std::filesystem::absolute(leaf, error);
  }
  CreatedFolder(const CreatedFolder&) = delete;
  CreatedFolder& operator=(const CreatedFolder&) = delete;
  ~CreatedFolder() {
    if (outermost_.empty()) return;
    std::error_code error;
    for (std::filesystem::path p = leaf_; std::filesystem::is_empty(p, error); p = p.parent_path()) {
      if (!std::filesystem::remove(p, error) || p == outermost_) break;
    }
  }
  void keep() { outermost_.clear(); }

 private:
  std::filesystem::path leaf_, outermost_;
};

/// The mode asked for, else the config's.
std::string modeOf(const RunOptions& options) { return options.mode.empty() ? options.config.mode : options.mode; }

/// Where the bag's start lies in options.session: its odometry frame in the session's (map <- odom)
/// and when it found itself (seconds from the first IMU sample). Reads the bag until the
/// localization finds the rig; throws when it never does.
std::pair<Eigen::Isometry3d, double> findInSession(const RunOptions& options) {
  const std::string mode = modeOf(options);
  io::BagSource source(options.bag_path, config::bagSourceOptions(options.config, mode));
  System system(options.config, mode);
  system.localizeIn(options.session, options.session_dir, options.initial_pose);
  const Stamp stop_ns = options.max_duration_s > 0 ? source.beginNs() + fromSec(options.max_duration_s)
                                                   : std::numeric_limits<Stamp>::max();
  io::SensorEvent event;
  while (!(options.stop && options.stop->load()) && !system.localization()->localized && source.next(&event)) {
    if (event.kind == io::SensorEvent::Kind::kImu) {
      if (event.imu.stamp_ns > stop_ns) break;
      system.addImu(event.imu);
    } else {
      system.addScan(std::move(event.scan));
    }
  }
  const backend::LocalizationStatus& status = *system.localization();
  if (!status.localized)
    throw Error("not localized in the session's map " + options.session_dir + " (" +
                (status.last_reason.empty() ? "no keyframe to try" : status.last_reason) +
                "): nothing to extend; without --extend the bag is mapped as a session of its own");
  const double at_s = system.report().localization.first_localized_s;
  return {system.mapFromOdom(), at_s};
}

RunResult runPass(const RunOptions& options) {
  const config::RigConfig& cfg = options.config;
  CreatedFolder out_folder(options.out_dir,
                           options.out_dir.empty() ? std::filesystem::path() : checkWritable(options.out_dir));
  const std::string mode = modeOf(options);
  if (!config::isValidMode(mode)) throw Error("unknown mode '" + mode + "' (expected hvi, vi or hi)");

  auto source = std::make_unique<io::BagSource>(options.bag_path, config::bagSourceOptions(cfg, mode));
  System system(cfg, mode);
  if (options.session && options.extend) {
    const auto [T_map_odom, at_s] = findInSession(options);
    log::emit(log::Level::kInfo, "found in ", options.session_dir, " ", at_s, " s in: mapping on in its frame");
    system.extend(options.session, options.session_dir, T_map_odom, at_s);
  } else if (options.session) {
    log::emit(log::Level::kInfo, "localizing in ", options.session_dir, ": ", options.session->keyframes.size(),
              " keyframes, ", options.session->map.size(), " map points");
    system.localizeIn(options.session, options.session_dir, options.initial_pose);
  }
  const estimator::Odometry& odometry = system.odometry();
  ProgressBar progress("mmlio run", options.progress);
  Stopwatch wall;

  RunResult result;
  const bool cut = options.max_duration_s > 0;
  const Stamp stop_ns = cut ? source->beginNs() + fromSec(options.max_duration_s) : std::numeric_limits<Stamp>::max();
  const Stamp imu_stop_ns = cut ? stop_ns + kImuAfterStopNs : stop_ns;
  try {
    io::SensorEvent event;
    std::size_t events = 0;
    const Stamp bag_begin_ns = source->beginNs();
    const Stamp period_ns = source->endNs() - bag_begin_ns + fromSec(1.0);
    if (options.on_sweep)
      system.setTimingObserver([&options, begin_ns = bag_begin_ns, period_ns](Stamp end_ns, const StageTimes& t) {
        options.on_sweep(end_ns, t, static_cast<int>(std::max<Stamp>(0, end_ns - begin_ns) / period_ns));
      });
    for (int replay = 0; replay < std::max(1, options.replays); ++replay) {
      // Replays open the bag again (the pass before closed first: one reader in memory, as a run
      // has) and shift its stamps past the previous pass.
      if (replay > 0) {
        source.reset();
        source = std::make_unique<io::BagSource>(options.bag_path, config::bagSourceOptions(cfg, mode));
      }
      const Stamp shift = replay * period_ns;
      while (!(options.stop && options.stop->load()) && source->next(&event)) {
        if (event.kind == io::SensorEvent::Kind::kImu) {
          event.imu.stamp_ns += shift;
          // Scans end at the requested duration; the IMU goes on a little so that the sweep the
          // last scans fall in is predicted and de-skewed like any other, not reported degraded.
          if (event.imu.stamp_ns > imu_stop_ns) break;
          system.addImu(event.imu);
        } else {
          event.scan.start_ns += shift;
          if (event.scan.start_ns > stop_ns) continue;
          system.addScan(std::move(event.scan));
        }
        if (++events % 50 == 0) {
          std::ostringstream status;
          const double bag_s = toSec(odometry.lastImuNs() - bag_begin_ns);
          status.precision(3);
          status << system.sweepsProcessed() << " sweeps, " << odometry.keyframes() << " kf, "
                 << bag_s / std::max(1e-3, wall.elapsedMs() * 1e-3) << "x rt";
          progress.update((replay + source->progress()) / std::max(1, options.replays), status.str());
        }
      }
    }
    result.interrupted = options.stop && options.stop->load();
    if (result.interrupted)
      log::warn("interrupted: writing the trajectory, map and report computed so far");
    else
      system.flush();  // an interrupted run's last sweeps may lack IMU: they are left out
  } catch (const Error& e) {
    if (system.posesTracked() == 0) throw;
    result.complete = false;
    result.error = e.what();
    log::emit(log::Level::kError, "stopped early: ", e.what(), " (writing the ", system.posesTracked(),
              " poses computed so far)");
  }
  system.finish();
  progress.finish(std::to_string(system.sweepsProcessed()) + " sweeps, " + std::to_string(system.posesTracked()) +
                  " poses");

  if (system.posesTracked() == 0 && result.complete) {
    throw Error(odometry.initialized()
                    ? "no sweep could be tracked in " + options.bag_path
                    : "IMU initialisation never succeeded in " + options.bag_path + ": " + odometry.imuInit().message);
  }

  // To the bag's end (its last message, whatever was readable), not just to the last IMU sample read.
  // A run cut by --duration is judged on the span asked for.
  const Stamp stream_end_ns = options.replays > 1 ? odometry.lastImuNs()
                              : cut               ? std::min(source->endNs(), stop_ns)
                                                  : std::max(odometry.lastImuNs(), source->endNs());
  RunReport report = system.report(stream_end_ns, options.trust);
  RunReport::Input& input = report.input;
  input.source = options.bag_path;
  input.duration_s = toSec(source->endNs() - source->beginNs());
  input.imu_messages = source->imuCount();
  input.imu_acc_scale = source->accScale();
  input.skipped_messages = source->skippedMessages();
  input.truncated = source->truncated();
  input.damaged_chunks = source->damagedChunks();
  input.decoded = source->stats();
  if (input.imu_dropped.total() > 0)
    log::warn("IMU: ", input.imu_dropped.total(), " samples dropped (non-finite ", input.imu_dropped.non_finite,
              ", beyond range ", input.imu_dropped.out_of_range, ", out of order ", input.imu_dropped.out_of_order,
              ", stamp jumps ", input.imu_dropped.jumped, ")");
  if (input.scans_out_of_order + input.scans_stamp_jumps > 0)
    log::warn("LiDAR: ", input.scans_out_of_order + input.scans_stamp_jumps, " scans dropped (out of order ",
              input.scans_out_of_order, ", stamp jumps ", input.scans_stamp_jumps, ")");
  report.status = !result.complete     ? "incomplete: " + result.error
                  : result.interrupted ? std::string("interrupted")
                                       : report.inputStatus();

  if (options.mount_check) {
    report.mount_check = *options.mount_check;
    if (report.mount_check.checked && !report.mount_check.agrees && report.untrusted.empty())
      report.untrusted = report.mount_check.message + " (mmlio calibrate finds it)";
  }
  result.untrusted = report.untrusted;
  if (!result.complete) result.untrusted = "the bag ended early: " + result.error;
  if (result.interrupted) result.untrusted = "interrupted";
  report.untrusted = result.untrusted;
  report.online_calibration_first_pass = options.first_pass_calibration;
  if (options.pass > 1)
    report.run.calibration += " (pass " + std::to_string(options.pass) + ": refined by the passes before)";
  if (result.interrupted && !options.write_if_interrupted) return result;
  if (!options.out_dir.empty()) report = system.writeOutputs(options.out_dir, std::move(report), options.gt_path);
  out_folder.keep();
  result.trajectory = system.trajectory();
  result.map_points = report.outputs.map_points;
  result.timing = report.timing;
  result.backend_timing = report.timing_backend;
  result.report = std::move(report);
  return result;
}

// A refined calibration worth running the bag again: off from the given one by more than these,
// counting only what differs from it by more than kRerunSigmas of its standard deviation (a height
// seen on a few floors and ceilings moves by its noise).
constexpr double kRerunClockS = 0.002;
constexpr double kRerunRotationRad = 0.1 * M_PI / 180.0;
constexpr double kRerunTranslationM = 0.005;
constexpr double kRerunSigmas = 2.0;

/// v with the components within kRerunSigmas of their sigmas zeroed.
Eigen::Vector3d significant(const Eigen::Vector3d& v, const Eigen::Vector3d& sigma) {
  return (v.array().abs() > kRerunSigmas * sigma.array()).select(v, Eigen::Vector3d::Zero());
}

/// The calibration a next run should start from: the given one with what the run settled on.
config::RigConfig withRefinedCalibration(config::RigConfig cfg,
                                         const std::vector<RunReport::RefinedCalibration>& refined) {
  for (const RunReport::RefinedCalibration& c : refined)
    for (config::LidarConfig& l : cfg.lidars)
      if (l.name == c.given.name) {
        l.T_imu_sensor = c.T_imu_sensor;  // settled (System::refinedCalibration)
        l.time_offset_s = c.given.time_offset_s + c.last.settled_time_offset_s;
      }
  return cfg;
}

/// What the run settled on that differs enough from the given calibration to run the bag again ("" if nothing).
std::string significantChange(const std::vector<RunReport::RefinedCalibration>& refined) {
  std::ostringstream what;
  for (const RunReport::RefinedCalibration& c : refined) {
    const estimator::LidarCalibrationEstimate& e = c.last;
    const double clock =
        std::abs(e.settled_time_offset_s) > kRerunSigmas * e.time_offset_sigma_s ? e.settled_time_offset_s : 0.0;
    if (std::abs(clock) < kRerunClockS &&
        significant(e.settled_rotation_rad, e.rotation_sigma_rad).norm() < kRerunRotationRad &&
        significant(e.settled_translation_m, e.translation_sigma_m).norm() < kRerunTranslationM)
      continue;
    what.precision(3);
    what << (what.tellp() > 0 ? "; " : "") << c.given.name << ": clock offset " << 1e3 * e.settled_time_offset_s
         << " ms, rotation " << e.settled_rotation_rad.norm() * 180.0 / M_PI << " deg, translation "
         << 1e3 * e.settled_translation_m.norm() << " mm";
  }
  return what.str();
}

/// The calibration the run ended with, every LiDAR of the rig, as `mmlio calibrate` writes it.
void writeRefinedCalibration(const std::string& path, const config::RigConfig& cfg,
                             const std::vector<RunReport::RefinedCalibration>& refined) {
  const config::RigConfig final_cfg = withRefinedCalibration(cfg, refined);
  config::Calibration calibration;
  YAML::Node extra;
  for (const config::LidarConfig& l : final_cfg.lidars) calibration[l.name] = {l.T_imu_sensor, l.time_offset_s};
  for (const RunReport::RefinedCalibration& c : refined) {
    extra[c.given.name]["refined_online"] = true;
    extra[c.given.name]["time_offset_sigma_s"] = c.last.time_offset_sigma_s;
    extra[c.given.name]["rotation_sigma_deg"] = c.last.rotation_sigma_rad.norm() * 180.0 / M_PI;
  }
  extra["generated_by"] = "mmlio run (online_calibration)";
  config::writeCalibration(path, calibration, extra);
}

}  // namespace

RunResult runBag(const RunOptions& options) {
  RunOptions pass = options;
  if (options.check_mount && !options.mount_check && modeOf(options) == "hvi") {
    pass.mount_check = checkMountAtStart(options.bag_path, options.config);
    if (pass.mount_check->checked && !pass.mount_check->agrees)
      log::warn(pass.mount_check->message, ": the outputs will not be trusted; run mmlio calibrate");
    else if (!pass.mount_check->lidar.empty())
      log::info("mount check: ", pass.mount_check->message);
  }
  const bool rerun =
      options.config.estimator.online_calibration.rerun && options.replays <= 1 && (!options.session || options.extend);
  // Passes that may be run again keep their calibration fixed and only estimate it.
  if (rerun) pass.config.estimator.online_calibration.apply = false;
  RunResult result = runPass(pass);
  config::RigConfig result_config = options.config;  // the calibration `result` started from
  const std::string change = rerun && result.complete && !result.interrupted
                                 ? significantChange(result.report.online_calibration)
                                 : std::string();
  if (!change.empty()) {
    // A LiDAR off by this much pulls the poses the solid-state map is built at toward its error, and
    // a pass that runs with it measures only part of the error. So the bag is run again with the
    // refined LiDARs measured but left out of the odometry, from what this pass settled on; the
    // last pass runs with every LiDAR from what that measuring pass found.
    log::info("online calibration settled on ", change,
              ": measuring it again without its pull (online_calibration.rerun)");
    pass.first_pass_calibration = result.report.online_calibration;
    pass.config = withRefinedCalibration(pass.config, result.report.online_calibration);
    RunOptions measuring = pass;
    measuring.config.estimator.online_calibration.measure_only = true;
    measuring.out_dir.clear();  // the first pass's outputs stand until the last pass replaces them
    measuring.gt_path.clear();
    measuring.pass = 2;
    const RunResult measured = runPass(measuring);
    if (measured.interrupted) {
      log::warn("interrupted while measuring the calibration: the outputs of pass 1 stand");
      result.interrupted = true;
    } else {
      if (measured.complete && measured.untrusted.empty())
        pass.config = withRefinedCalibration(pass.config, measured.report.online_calibration);
      else
        log::warn("the measuring pass ",
                  measured.complete ? "is untrusted (" + measured.untrusted : "ended early (" + measured.error,
                  "): the last pass runs from what pass 1 settled on");
      pass.pass = 3;
      pass.write_if_interrupted = false;  // an interrupted pass leaves the outputs of the one before
      RunResult last = runPass(pass);
      if (last.interrupted) {
        log::warn("interrupted in pass 3: the outputs of pass 1 stand");
        result.interrupted = true;
      } else {
        result = std::move(last);
        result_config = pass.config;
      }
    }
  }
  if (!options.out_dir.empty() && !result.report.online_calibration.empty())
    writeRefinedCalibration(options.out_dir + "/calibration_refined.yaml", result_config,
                            result.report.online_calibration);
  return result;
}

}  // namespace mmlio::pipeline
