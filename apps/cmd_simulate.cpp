// `mmlio simulate`: writes a simulated sequence (bag with Velodyne, Livox and IMU topics as the
// real drivers publish them), its ground truth (TUM, IMU pose at 200 Hz) and its true calibration.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include "commands.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/io/bag_writer.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/pipeline/progress.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio::apps {
namespace {

struct SimulateArgs {
  std::string scenario;
  std::string out_dir;
  double duration_s = 0.0;
  std::uint64_t seed = 1;
  double time_offset_s = 0.0;
  double velodyne_phase_s = -1.0;
  std::string pattern = "lissajous";
  sim::ImuNoiseConfig imu;
  double acc_bias_m_s2 = -1;
  bool random_mount = false;
  int people = 0;
  bool handheld = false;
  int route_start = 0;
  bool rearranged = false;
};

YAML::Node vec3(const Eigen::Vector3d& v) {
  YAML::Node n(YAML::NodeType::Sequence);
  for (int i = 0; i < 3; ++i) n.push_back(v[i]);
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

void writeTruth(const std::string& path, const sim::Simulator& sim, const SimulateArgs& args) {
  config::Calibration calib;
  for (const LidarExtrinsic& e : {sim.velodyneExtrinsic(), sim.livoxExtrinsic()})
    calib[e.name] = config::SensorCalibration{e.T_imu_sensor, e.time_offset_s};
  YAML::Node extra;
  extra["velodyne"]["topic"] = "/velodyne_points";
  extra["velodyne"]["kind"] = "spinning";
  extra["livox"]["topic"] = "/livox/lidar";
  extra["livox"]["kind"] = "solid_state";
  const sim::ImuNoiseConfig& noise = sim.imuNoise();
  YAML::Node imu;
  imu["topic"] = "/livox/imu";
  imu["rate_hz"] = noise.rate_hz;
  imu["acc_unit"] = "g (9.80665 m/s^2)";
  imu["gravity_m_s2"] = sim::kGravityM_s2;
  imu["acc_noise_density"] = noise.acc_noise_density;
  imu["gyro_noise_density"] = noise.gyro_noise_density;
  imu["acc_random_walk"] = noise.acc_random_walk;
  imu["gyro_random_walk"] = noise.gyro_random_walk;
  imu["initial_acc_bias_m_s2"] = vec3(sim.initialBias().acc_m_s2);
  imu["initial_gyro_bias_rad_s"] = vec3(sim.initialBias().gyro_rad_s);
  extra["imu"] = imu;
  extra["scenario"] = args.scenario;
  extra["livox_pattern"] = args.pattern;
  extra["random_mount"] = args.random_mount;
  extra["velodyne_phase_s"] = toSec(sim.velodyneTrueStartNs(0) - sim.startNs());
  extra["seed"] = args.seed;
  extra["people"] = sim.crowd().size();
  extra["handheld"] = args.handheld;
  extra["route_start"] = args.route_start;
  extra["furniture_moved"] = sim.furnitureMoved();
  extra["duration_s"] = sim.durationS();
  extra["path_length_m"] = sim.pathLengthM();
  extra["start_stamp_ns"] = sim.startNs();
  extra["generated_by"] = "mmlio simulate";
  config::writeCalibration(path, calib, extra);
}

void runSimulate(const SimulateArgs& args) {
  Stopwatch watch;
  sim::SimOptions options;
  options.scenario = args.scenario;
  options.duration_s = args.duration_s;
  options.seed = args.seed;
  options.velodyne_time_offset_s = args.time_offset_s;
  options.velodyne_phase_s = args.velodyne_phase_s;
  options.imu = args.imu;
  options.acc_bias_m_s2 = args.acc_bias_m_s2;
  options.random_mount = args.random_mount;
  options.people = args.people;
  options.handheld = args.handheld;
  options.route_start = args.route_start;
  options.rearranged = args.rearranged;
  options.livox_pattern =
      args.pattern == "rosette" ? sim::SolidStatePattern::kRosette : sim::SolidStatePattern::kLissajous;
  options.livox_no_returns_as_zero = true;  // what livox_ros_driver publishes
  const sim::Simulator sim(options);        // throws for an unknown scenario

  std::error_code error;
  std::filesystem::create_directories(args.out_dir, error);
  if (!std::filesystem::is_directory(args.out_dir))
    throw Error("cannot create output directory '" + args.out_dir + "'");
  const std::string base = (std::filesystem::path(args.out_dir) / args.scenario).string();

  io::writeTum(base + "_gt.tum", sim.groundTruth());
  writeTruth(base + "_truth.yaml", sim, args);

  // Messages in bag-time order: IMU samples, Livox frames and Velodyne sweeps by their stamps.
  io::BagWriter bag(base + ".bag");
  const std::vector<ImuSample>& imu = sim.imu();
  const int num_livox = sim.numLivoxFrames(), num_velodyne = sim.numVelodyneSweeps();
  const Stamp kNever = std::numeric_limits<Stamp>::max();
  const Stamp velodyne_shift = fromSec(args.time_offset_s);
  auto livoxStamp = [&](int k) { return k < num_livox ? sim.startNs() + k * 100000000LL : kNever; };
  auto velodyneStamp = [&](int k) { return k < num_velodyne ? sim.velodyneTrueStartNs(k) - velodyne_shift : kNever; };
  size_t i = 0;
  int kl = 0, kv = 0;
  std::size_t num_points = 0;
  const int total_scans = std::max(1, num_livox + num_velodyne);
  pipeline::ProgressBar progress("simulate " + args.scenario);
  while (i < imu.size() || kl < num_livox || kv < num_velodyne) {
    const Stamp ti = i < imu.size() ? imu[i].stamp_ns : kNever, tl = livoxStamp(kl), tv = velodyneStamp(kv);
    if (ti <= tl && ti <= tv) {
      bag.writeImu("/livox/imu", "livox_frame", imu[i++], true);
      continue;
    }
    if (tl <= tv) {
      const LidarScan scan = sim.livoxFrame(kl++);
      num_points += scan.points.size();
      bag.writeLivoxCloud("/livox/lidar", "livox_frame", scan);
    } else {
      const LidarScan scan = sim.velodyneSweep(kv++);
      num_points += scan.points.size();
      bag.writeVelodyneCloud("/velodyne_points", "velodyne", scan);
    }
    const int done = kl + kv;
    if (done % 20 == 0) {
      char status[96];
      std::snprintf(status, sizeof(status), "%d/%d scans, %.1fx real time", done, total_scans,
                    (done * 0.05) / std::max(1e-3, watch.elapsedMs() * 1e-3));
      progress.update(static_cast<double>(done) / total_scans, status);
    }
  }
  bag.close();
  char status[160];
  std::snprintf(status, sizeof(status), "%d Livox frames, %d Velodyne sweeps, %zu IMU samples, %.1f M points in %.1f s",
                num_livox, num_velodyne, imu.size(), num_points * 1e-6, watch.elapsedMs() * 1e-3);
  progress.finish(status);
  if (sim.crowd().size() < args.people)
    log::warn("only ", sim.crowd().size(), " of ", args.people, " people found room to walk in ", args.scenario);
  log::info("simulated ", args.scenario, ": ", sim.durationS(), " s, path ", sim.pathLengthM(), " m -> ", base,
            ".bag, ", base, "_gt.tum, ", base, "_truth.yaml");
}

}  // namespace

void registerSimulateCommand(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand("simulate", "Write a simulated sequence: bag, ground truth and true calibration");
  cmd->add_option("--scenario", args->scenario, "office, corridor, corridor_blind, hall, stairs, ramp or lab")
      ->required();
  cmd->add_option("--out", args->out_dir, "Output directory (created): NAME.bag, NAME_gt.tum, NAME_truth.yaml")
      ->required();
  cmd->add_option("--duration", args->duration_s,
                  "Seconds (default 0 = the full walk: office ~40 s, corridor ~110 s, hall ~150 s); a shorter "
                  "duration walks a part of the route out and back, still ending at the start pose");
  cmd->add_option("--seed", args->seed, "Noise seed (same seed, same bytes)");
  cmd->add_option("--time-offset", args->time_offset_s,
                  "Velodyne stamps are written as t_true - S (truth time_offset_s = S)");
  cmd->add_option("--velodyne-phase", args->velodyne_phase_s,
                  "Seconds (0 to 0.1) the Velodyne's sweeps start after the Livox's frames (default 0.037, or drawn "
                  "with --random-mount)");
  cmd->add_option("--pattern", args->pattern,
                  "Solid-state scan pattern: lissajous (Horizon-like lines) or rosette (Mid-40 / Avia-like petals)")
      ->check(CLI::IsMember({"lissajous", "rosette"}));
  cmd->add_option("--acc-noise", args->imu.acc_noise_density, "Accelerometer white noise, m/s^2/sqrt(Hz)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--gyro-noise", args->imu.gyro_noise_density, "Gyroscope white noise, rad/s/sqrt(Hz)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--acc-walk", args->imu.acc_random_walk, "Accelerometer bias random walk, m/s^3/sqrt(Hz)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--gyro-walk", args->imu.gyro_random_walk, "Gyroscope bias random walk, rad/s^2/sqrt(Hz)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--acc-bias", args->acc_bias_m_s2,
                  "Initial accelerometer bias per axis, m/s^2 (signs drawn from the seed; default: a fixed 0.02 bias)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--random-mount", args->random_mount,
                "Draw both LiDAR extrinsics and the Velodyne sweep phase from the seed (written to NAME_truth.yaml)");
  cmd->add_option("--people", args->people,
                  "People walking through the scene (person-sized boxes at 0.8-1.5 m/s along and across the rig's "
                  "route; paths from the seed)")
      ->check(CLI::Range(0, 64));
  cmd->add_flag("--handheld", args->handheld,
                "Carry the route by hand: ~3 cm bounce at 1.9 steps/s, 3 deg sway and nod, turns up to 150 deg/s, "
                "looks 25 deg down and 20 deg up (the stairs scenario is always carried by hand)");
  cmd->add_option("--route-start", args->route_start,
                  "Walk the scenario's closed route from this waypoint on (default 0, as designed): a localization "
                  "that starts elsewhere than the mapping walk did");
  cmd->add_flag("--rearranged", args->rearranged,
                "Move the furniture 0.4-1 m (directions from the seed; clear of the route): the building revisited "
                "after it changed");
  cmd->callback([args] { runSimulate(*args); });
}

}  // namespace mmlio::apps
