#include "mmlio/pipeline/bag_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <Eigen/Eigenvalues>

#include "mmlio/config/source_options.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/short_number.hpp"
#include "mmlio/eval/svg_plot.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/lidar/voxel_filter.hpp"
#include "mmlio/map/kd_tree.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"

namespace mmlio::pipeline {
namespace {

const auto fixed = eval::fixedText;

void logCandidates(const calib::SpatialCalibrationResult& r) {
  for (const calib::MountCandidate& m : r.candidates)
    log::emit(log::Level::kInfo, "yaw search: yaw ", shortNumber(m.yaw_deg, 4), " deg, ", m.inliers, " of ",
              m.points_in_view, " spinning points in view matched (fitness ", shortNumber(m.fitness_m, 3), " m), ",
              shortNumber(100 * m.seen_through, 2), " % seen through", m.agrees ? "" : ": disagrees");
}

struct Collected {
  std::vector<ImuSample> imu;
  std::vector<LidarScan> solid_frames, spinning_rest, spinning_all;
  Stamp start_ns = 0, first_lidar_ns = 0;
};

constexpr double kTurnMarginS = 0.35;  // > the offset search range + a sweep: pairs stay together

/// Whether the gyro (its mean removed) turns faster than rate_rad_s within margin_s of a sweep.
bool turningNear(const std::vector<ImuSample>& imu, Stamp sweep_start, double margin_s, double rate_rad_s) {
  if (imu.size() < 2) return false;
  // The bias is a few mrad/s: irrelevant against the turn rates that carry timing information.
  const Stamp lo = sweep_start - fromSec(margin_s), hi = sweep_start + fromSec(0.1 + margin_s);
  for (auto it = imu.rbegin(); it != imu.rend() && it->stamp_ns >= lo; ++it)
    if (it->stamp_ns <= hi && it->gyro_rad_s.norm() > rate_rad_s) return true;
  return false;
}

std::vector<Eigen::Vector3d> positionsOf(const std::vector<LidarScan>& scans) {
  std::size_t n = 0;
  for (const LidarScan& s : scans) n += s.points.size();
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(n);
  for (const LidarScan& s : scans)
    for (const Point& p : s.points) pts.emplace_back(p.xyz.cast<double>());
  return pts;
}

/// The config's first spinning and first solid-state LiDAR (null where there is none).
std::pair<const config::LidarConfig*, const config::LidarConfig*> lidarPair(const config::RigConfig& cfg) {
  const config::LidarConfig *spinning = nullptr, *solid = nullptr;
  for (const config::LidarConfig& l : cfg.lidars) {
    if (l.kind() == LidarKind::kSpinning && !spinning) spinning = &l;
    if (l.kind() == LidarKind::kSolidState && !solid) solid = &l;
  }
  return {spinning, solid};
}

double restSeconds(const BagCalibrationOptions& opt) {
  return 0.1 * std::max(opt.solid_frames, opt.spinning_sweeps) + 0.05;
}

/// The bag's start: IMU, the solid-state frames and spinning sweeps of the still window, and (for the
/// clock offset) the spinning sweeps near turns within opt.temporal_window_s.
Collected collectStart(const std::string& bag_path, const config::RigConfig& cfg, const config::LidarConfig& solid,
                       const config::LidarConfig& spinning, const BagCalibrationOptions& opt) {
  io::BagSource source(bag_path, config::bagSourceOptions(cfg, "hvi"));
  Collected c;
  c.start_ns = source.beginNs();
  const double rest_s = restSeconds(opt);
  const Stamp temporal_end = c.start_ns + fromSec(opt.estimate_time_offset ? opt.temporal_window_s : rest_s + 0.5);
  std::deque<LidarScan> pending;
  const double turn_rate = opt.temporal.min_rate_rad_s;
  io::SensorEvent ev;
  while (source.next(&ev)) {
    if (ev.kind == io::SensorEvent::Kind::kImu) {
      if (ev.imu.stamp_ns > temporal_end) break;
      c.imu.push_back(ev.imu);
      continue;
    }
    LidarScan& scan = ev.scan;
    if (!c.first_lidar_ns) c.first_lidar_ns = scan.start_ns;
    const bool in_rest = scan.start_ns < c.first_lidar_ns + fromSec(rest_s);
    if (scan.sensor == solid.name && in_rest && static_cast<int>(c.solid_frames.size()) < opt.solid_frames) {
      c.solid_frames.push_back(scan);
    } else if (scan.sensor == spinning.name) {
      if (in_rest && static_cast<int>(c.spinning_rest.size()) < opt.spinning_sweeps) c.spinning_rest.push_back(scan);
      if (opt.estimate_time_offset) {
        // The scan-to-scan ICP works on 0.1 m voxels: thinner sweeps lose nothing and keep memory low.
        scan.points = lidar::voxelDownsample(scan.points, opt.temporal_voxel_m);
        pending.push_back(std::move(scan));
      }
    }
    // Sweeps wait until the IMU covers them (+ the offset search range); only those near a turn
    // are kept for the clock offset: a full sweep is ~0.7 MB.
    const Stamp imu_now = c.imu.empty() ? 0 : c.imu.back().stamp_ns;
    while (!pending.empty() && pending.front().start_ns + fromSec(0.1 + kTurnMarginS) < imu_now) {
      if (turningNear(c.imu, pending.front().start_ns, kTurnMarginS, turn_rate))
        c.spinning_all.push_back(std::move(pending.front()));
      pending.pop_front();
    }
  }
  for (LidarScan& scan : pending)
    if (turningNear(c.imu, scan.start_ns, kTurnMarginS, turn_rate)) c.spinning_all.push_back(std::move(scan));
  if (c.solid_frames.empty()) throw Error("no '" + solid.name + "' frames at the start of " + bag_path);
  if (c.spinning_rest.empty()) throw Error("no '" + spinning.name + "' sweeps at the start of " + bag_path);

  return c;
}

/// The gyroscope's mean over the still window; throws when the rig moves in it (the spatial step
/// assumes both LiDARs see the same, still scene).
Eigen::Vector3d stillGyroMean(const Collected& c, const std::string& bag_path, const BagCalibrationOptions& opt) {
  const double rest_s = restSeconds(opt);
  const Stamp rest_begin = c.first_lidar_ns, rest_end = c.first_lidar_ns + fromSec(rest_s);
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero(), acc_mean = Eigen::Vector3d::Zero();
  int n = 0;
  for (const ImuSample& s : c.imu)
    if (s.stamp_ns >= rest_begin && s.stamp_ns <= rest_end) {
      gyro_mean += s.gyro_rad_s;
      acc_mean += s.acc_m_s2;
      ++n;
    }
  if (n < 10)
    throw Error("fewer than 10 IMU samples during the first " + shortNumber(rest_s) + " s of LiDAR data in " +
                bag_path);
  gyro_mean /= n;
  acc_mean /= n;
  // Deviation of 50 ms block means from the window mean: single samples carry the sensor noise
  // (0.3 m/s^2, 0.03 rad/s per sample for a typical MEMS IMU at 200 Hz), blocks show motion.
  // Blocks start at the first IMU sample of the window: a LiDAR stamped before the IMU's first
  // sample would leave the first block half empty, and its mean twice as noisy (a still start
  // refused on 0.36 m/s^2).
  double gyro_dev = 0, acc_dev = 0;
  const auto first_imu =
      std::find_if(c.imu.begin(), c.imu.end(), [&](const ImuSample& s) { return s.stamp_ns >= rest_begin; });
  const Stamp blocks_begin = first_imu == c.imu.end() ? rest_begin : first_imu->stamp_ns;
  for (Stamp b = blocks_begin; b + fromSec(0.05) <= rest_end; b += fromSec(0.05)) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
    int m = 0;
    for (const ImuSample& s : c.imu)
      if (s.stamp_ns >= b && s.stamp_ns < b + fromSec(0.05)) {
        g += s.gyro_rad_s;
        a += s.acc_m_s2;
        ++m;
      }
    if (m == 0) continue;
    gyro_dev = std::max(gyro_dev, (g / m - gyro_mean).norm());
    acc_dev = std::max(acc_dev, (a / m - acc_mean).norm());
  }
  if (gyro_dev > opt.max_rest_gyro_rad_s || acc_dev > opt.max_rest_acc_m_s2)
    throw Error("the rig moves during the first " + shortNumber(rest_s) + " s (gyro deviates by up to " +
                shortNumber(gyro_dev) + " rad/s, accelerometer by " + shortNumber(acc_dev) +
                " m/s^2): calibration needs it standing still at "
                "the start; cut the bag to begin at rest (rosbag filter) or record a still second first");

  return gyro_mean;
}

/// What the solid-state LiDAR sees of the room in the first opt.motion_window_s of the bag, in its
/// frame at the still start: the still frames, then every fifth frame its own odometry (HI: it and
/// the IMU) places while the rig stays within opt.motion_radius_m of the start (farther, the
/// start's sweeps see other sides of things and the odometry's drift grows).
calib::SolidView solidViewFromMotion(const std::string& bag_path, const config::RigConfig& cfg,
                                     const config::LidarConfig& solid, const Collected& c,
                                     const BagCalibrationOptions& opt) {
  calib::SolidView view;
  view.frames.push_back({Eigen::Isometry3d::Identity(), positionsOf(c.solid_frames)});
  std::optional<Eigen::Isometry3d> T_solid0_world;
  int tracked = 0;
  OnlinePipeline odometry(cfg, "hi", [&](const estimator::SweepResult& r) {
    if (r.status != estimator::SweepResult::Status::kTracking) return;
    const Eigen::Isometry3d T_world_solid = r.state.pose() * solid.T_imu_sensor;
    if (!T_solid0_world) T_solid0_world = T_world_solid.inverse();
    if (tracked++ % 5 != 0) return;
    const Eigen::Isometry3d T_start_solid = *T_solid0_world * T_world_solid;
    if (T_start_solid.translation().norm() > opt.motion_radius_m) return;
    // The sweep's points are de-skewed into the body frame at its end: into the sensor's frame there.
    const Eigen::Isometry3d T_solid_body = solid.T_imu_sensor.inverse();
    std::vector<Eigen::Vector3d> returns;
    returns.reserve(r.points_body.size());
    for (const Point& p : r.points_body) returns.push_back(T_solid_body * p.xyz.cast<double>());
    view.frames.push_back({T_start_solid, map::voxelCentroids(returns, opt.spatial.target_voxel_m)});
  });
  io::BagSource source(bag_path, config::bagSourceOptions(cfg, "hi"));
  const Stamp end_ns = c.first_lidar_ns + fromSec(opt.motion_window_s);
  io::SensorEvent ev;
  while (source.next(&ev)) {
    if (ev.kind == io::SensorEvent::Kind::kImu) {
      if (ev.imu.stamp_ns > end_ns) break;
      odometry.addImu(ev.imu);
    } else if (ev.scan.start_ns + fromSec(0.2) < end_ns) {  // a sweep the IMU read covers
      odometry.addScan(std::move(ev.scan));
    }
  }
  odometry.flush();
  return view;
}

/// res->translation_sigma_m and rotation_sigma_rad: the spatial calibration's covariance turned
/// into the IMU frame (R_imu_solid), at least the drift of a view from motion.
void stateSigmas(const Eigen::Matrix3d& R_imu_solid, const BagCalibrationOptions& opt, BagCalibrationResult* res) {
  Eigen::Matrix<double, 6, 6> to_imu = Eigen::Matrix<double, 6, 6>::Zero();
  to_imu.topLeftCorner<3, 3>() = to_imu.bottomRightCorner<3, 3>() = R_imu_solid;
  Eigen::Matrix<double, 6, 1> var = (to_imu * res->spatial.covariance * to_imu.transpose()).diagonal();
  if (res->from_motion) {
    var.head<3>().array() += std::pow(opt.motion_sigma_translation_m, 2);
    var.tail<3>().array() += std::pow(opt.motion_sigma_rotation_deg * M_PI / 180.0, 2);
  }
  res->translation_sigma_m = var.head<3>().cwiseMax(0).cwiseSqrt();
  res->rotation_sigma_rad = var.tail<3>().cwiseMax(0).cwiseSqrt();
}

/// The mount check's verdict on GICP run from the given mount (no search) on what `where` names.
MountCheck judgeMount(const calib::SpatialCalibrationResult& r, const Eigen::Isometry3d& given,
                      const std::string& spinning, const std::string& where, const BagCalibrationOptions& opt,
                      bool judge_move = true) {
  MountCheck check;
  check.lidar = spinning;
  // Moved along what the view constrains: a start facing a hall's wall leaves GICP free to slide
  // a right mount along it by decimetres.
  const Eigen::Vector3d shift = r.T_solid_spinning.translation() - given.translation();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(r.hessian.topLeftCorner<3, 3>());
  for (int i = 0; i < 3; ++i)
    if (es.eigenvalues()(i) >= kMountCheckConstrained * es.eigenvalues()(2))
      check.moved_m = std::hypot(check.moved_m, es.eigenvectors().col(i).dot(shift));
  check.moved_deg = Eigen::AngleAxisd((given.inverse() * r.T_solid_spinning).rotation()).angle() * 180.0 / M_PI;
  check.seen_through = r.seen_through;
  check.overlap = r.overlap;
  using Refusal = calib::SpatialCalibrationResult::Refusal;
  // GICP's strict convergence test fails on correspondences flickering at the fine gate too: the
  // clouds' agreement decides then.
  const bool clouds_agree = calib::cloudsAgree(r.fitness_m, r.overlap, r.seen_through, opt.spatial);
  switch (r.refusal) {
    case Refusal::kTooFewPoints:
    case Refusal::kNoOverlap:
    case Refusal::kDegenerate:
    case Refusal::kAmbiguous:
      check.message = "not checked: " + r.message;
      return check;
    case Refusal::kNotConverged:
      if (clouds_agree) break;
      [[fallthrough]];
    case Refusal::kSeenThrough:
    case Refusal::kDisagree:
      check.checked = true;
      check.agrees = false;
      check.message = "the clouds of " + where + " contradict the mount given for '" + spinning + "' (overlap " +
                      shortNumber(r.overlap, 3) + ", fitness " + shortNumber(r.fitness_m, 3) + " m, " +
                      shortNumber(100 * r.seen_through, 2) +
                      " % of its points where the solid-state LiDAR sees through)";
      return check;
    case Refusal::kNone:
      break;
  }
  check.checked = true;
  // What GICP moves a right mount by is the calibration's error, a few millimetres and hundredths
  // of a degree; a rig file's rough mount a few centimetres and degrees (online refinement's job).
  check.agrees = (!judge_move || check.moved_m <= kMountCheckMaxMoveM) && check.moved_deg <= kMountCheckMaxTurnDeg;
  check.message = check.agrees ? "the clouds of " + where + " agree with the mount given for '" + spinning + "' (" +
                                     fixed(1e3 * check.moved_m, 1) + " mm, " + fixed(check.moved_deg, 3) + " deg)"
                               : "the clouds of " + where + " put '" + spinning + "' " + fixed(1e2 * check.moved_m, 1) +
                                     " cm and " + fixed(check.moved_deg, 1) + " deg from the mount given";
  return check;
}

}  // namespace

BagCalibrationResult calibrateBag(const std::string& bag_path, const config::RigConfig& cfg_in,
                                  const BagCalibrationOptions& opt) {
  BagCalibrationResult res;
  const auto [spinning, solid] = lidarPair(cfg_in);
  if (!spinning || !solid)
    throw Error("calibration needs one spinning and one solid-state LiDAR in the config (found " +
                std::string(spinning ? "a spinning one" : "no spinning one") + " and " +
                std::string(solid ? "a solid-state one" : "no solid-state one") + ")");
  res.spinning = spinning->name;
  res.solid = solid->name;

  const Collected c = collectStart(bag_path, cfg_in, *solid, *spinning, opt);
  const Eigen::Vector3d gyro_mean = stillGyroMean(c, bag_path, opt);

  // ---- spatial ----
  const std::vector<Eigen::Vector3d> solid_pts = positionsOf(c.solid_frames);
  const std::vector<Eigen::Vector3d> spinning_pts = positionsOf(c.spinning_rest);
  const Eigen::Isometry3d guess = solid->T_imu_sensor.inverse() * spinning->T_imu_sensor;
  res.spatial = calib::calibrateSpinningToSolid(spinning_pts, solid_pts, guess, opt.spatial);
  logCandidates(res.spatial);
  if (!res.spatial.ok && opt.motion_window_s > 0) {
    // A wall or a view alike turned by a quarter: the room around, seen while the rig moves on,
    // tells what the start cannot.
    log::emit(log::Level::kInfo, "the still start cannot tell the mount (", res.spatial.message,
              "); mapping the first ", shortNumber(opt.motion_window_s), " s of motion with '", solid->name, "'");
    const calib::SolidView view = solidViewFromMotion(bag_path, cfg_in, *solid, c, opt);
    calib::SpatialCalibrationResult moving = calib::calibrateSpinningToSolid(spinning_pts, view, guess, opt.spatial);
    logCandidates(moving);
    if (!moving.ok)
      throw Error("spatial calibration refused: at the still start, " + res.spatial.message + "; with the first " +
                  shortNumber(opt.motion_window_s) + " s of motion (" + std::to_string(view.frames.size() - 1) +
                  " frames within " + shortNumber(opt.motion_radius_m) + " m), " + moving.message);
    moving.message += " (the first " + shortNumber(opt.motion_window_s) +
                      " s of motion: " + std::to_string(view.frames.size() - 1) + " solid-state frames)";
    // Its map carries the solid-state odometry's drift (centimetres): the run's online
    // calibration takes the rest. (The still start, told the way round, is no help: what it
    // could not tell, it cannot measure either; a hall's start slides it decimetres along a wall.)
    res.spatial = std::move(moving);
    res.from_motion = true;
  }
  if (!res.spatial.ok) throw Error("spatial calibration refused: " + res.spatial.message);
  const Eigen::Isometry3d T_imu_spinning = solid->T_imu_sensor * res.spatial.T_solid_spinning;
  stateSigmas(solid->T_imu_sensor.linear(), opt, &res);
  log::emit(log::Level::kInfo, "spatial calibration: ", res.spatial.message);

  // ---- temporal ----
  double offset_s = spinning->time_offset_s;
  if (opt.estimate_time_offset) {
    res.temporal = calib::calibrateTimeOffset(c.spinning_all, T_imu_spinning, c.imu, gyro_mean, opt.temporal);
    if (res.temporal.ok) {
      offset_s = res.temporal.offset_s;
      log::emit(log::Level::kInfo, "clock offset of '", spinning->name, "': ", shortNumber(1e3 * offset_s, 4), " +- ",
                shortNumber(1e3 * res.temporal.sigma_s, 2), " ms (", res.temporal.message, ")");
      if (!res.temporal.advice.empty()) log::emit(log::Level::kWarn, res.temporal.advice);
    } else {
      log::emit(log::Level::kWarn, "clock offset not estimated (", res.temporal.message, "); keeping ",
                spinning->time_offset_s, " s from the config");
    }
  }

  config::SensorCalibration sc_spin{T_imu_spinning, offset_s}, sc_solid{solid->T_imu_sensor, solid->time_offset_s};
  res.calibration[spinning->name] = sc_spin;
  res.calibration[solid->name] = sc_solid;

  res.extra[spinning->name]["fitness_m"] = res.spatial.fitness_m;
  res.extra[spinning->name]["overlap"] = res.spatial.overlap;
  res.extra[spinning->name]["points_used"] = res.spatial.spinning_points;
  res.extra[spinning->name]["reference_points_used"] = res.spatial.solid_points;
  res.extra[spinning->name]["yaw_searched"] = res.spatial.yaw_searched;
  res.extra[spinning->name]["seen_through"] = res.spatial.seen_through;
  res.extra[spinning->name]["from_motion"] = res.from_motion;
  const Eigen::Vector3d rotation_sigma_deg = res.rotation_sigma_rad * (180.0 / M_PI);
  for (int i = 0; i < 3; ++i) {
    res.extra[spinning->name]["translation_sigma_m"].push_back(res.translation_sigma_m(i));
    res.extra[spinning->name]["rotation_sigma_deg"].push_back(rotation_sigma_deg(i));
  }
  res.extra[spinning->name]["translation_sigma_m"].SetStyle(YAML::EmitterStyle::Flow);
  res.extra[spinning->name]["rotation_sigma_deg"].SetStyle(YAML::EmitterStyle::Flow);
  res.extra[spinning->name]["time_offset_estimated"] = res.temporal.ok;
  if (res.temporal.ok) {
    res.extra[spinning->name]["time_offset_sigma_s"] = res.temporal.sigma_s;
    res.extra[spinning->name]["time_offset_increments"] = res.temporal.increments;
    res.extra[spinning->name]["time_offset_stride_spread_s"] = res.temporal.stride_spread_s;
    if (!res.temporal.advice.empty()) res.extra[spinning->name]["time_offset_advice"] = res.temporal.advice;
  }
  res.extra["generated_by"] = "mmlio calibrate " + bag_path;

  Json j = Json::object();
  j["reference"] = solid->name;
  j["calibrated"] = spinning->name;
  j["T_imu_sensor"] = matrixRows(T_imu_spinning);
  j["fitness_m"] = res.spatial.fitness_m;
  j["overlap"] = res.spatial.overlap;
  j["points_used"] = res.spatial.spinning_points;
  j["reference_points_used"] = res.spatial.solid_points;
  j["spatial"] = res.spatial.message;
  j["from_motion"] = res.from_motion;
  j["translation_sigma_m"] = {res.translation_sigma_m.x(), res.translation_sigma_m.y(), res.translation_sigma_m.z()};
  j["rotation_sigma_deg"] = {rotation_sigma_deg.x(), rotation_sigma_deg.y(), rotation_sigma_deg.z()};
  j["time_offset_s"] = offset_s;
  j["time_offset_estimated"] = res.temporal.ok;
  j["time_offset_sigma_s"] = res.temporal.sigma_s;
  j["time_offset_stride_spread_s"] = res.temporal.stride_spread_s;
  j["temporal"] = res.temporal.message;
  res.report = j;
  return res;
}

MountCheck checkMountAtStart(const std::string& bag_path, const config::RigConfig& cfg) {
  MountCheck check;
  const auto [spinning, solid] = lidarPair(cfg);
  if (!spinning || !solid) return check;
  check.lidar = spinning->name;
  BagCalibrationOptions opt;
  opt.estimate_time_offset = false;
  opt.spatial.yaw_search = false;
  const Eigen::Isometry3d given = solid->T_imu_sensor.inverse() * spinning->T_imu_sensor;
  try {
    const Collected c = collectStart(bag_path, cfg, *solid, *spinning, opt);
    stillGyroMean(c, bag_path, opt);
    const std::vector<Eigen::Vector3d> spinning_pts = positionsOf(c.spinning_rest);
    check = judgeMount(calib::calibrateSpinningToSolid(spinning_pts, positionsOf(c.solid_frames), given, opt.spatial),
                       given, spinning->name, "the still start", opt);
    if (check.checked) return check;
    // A wall or a view alike turned: the room around, seen in the first seconds of motion.
    const calib::SolidView view = solidViewFromMotion(bag_path, cfg, *solid, c, opt);
    // Its map carries the solid-state odometry's drift (centimetres, decimetres along a wall):
    // judged by the clouds' agreement and the turn, not by the move.
    MountCheck moving =
        judgeMount(calib::calibrateSpinningToSolid(spinning_pts, view, given, opt.spatial), given, spinning->name,
                   "the first " + shortNumber(opt.motion_window_s) + " s of motion", opt,
                   /*judge_move=*/false);
    if (!moving.checked) moving.message = check.message + "; with the first seconds of motion too";
    return moving;
  } catch (const Error& e) {
    check.message = std::string("not checked: ") + e.what();
    return check;
  }
}

}  // namespace mmlio::pipeline
