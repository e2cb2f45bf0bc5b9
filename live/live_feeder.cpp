#include "live_feeder.hpp"

#include <cmath>

#include "mmlio/config/calibration_source.hpp"
#include "mmlio/config/source_options.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/io/cdr_messages.hpp"
#include "mmlio/io/session_io.hpp"
#include "ros_messages.hpp"

namespace mmlio::live {

config::RigConfig loadRigConfig(const std::string& config_path, const std::string& calib_path,
                                const std::string& config_option, const std::string& calib_option) {
  config::RigConfig cfg;
  if (config_path.empty())
    log::info("no ", config_option, ": using the built-in defaults (same as config/hvi.yaml)");
  else
    cfg = config::loadRigConfig(config_path);
  if (config::resolveCalibration(cfg, calib_path) == "auto")
    throw Error("calibration: auto is not available live; run `mmlio calibrate` and set " + calib_option);
  return cfg;
}

void checkOptions(const FeederOptions& o) {
  if (o.max_queued_scans < 1 || o.max_queued_imu < 1) throw Error("max_queued_scans and max_queued_imu must be >= 1");
  if (!(o.point_sigma_m > 0.0)) throw Error("point_sigma_m must be > 0");
  if (o.autosave_period_s < 0) throw Error("autosave period must be >= 0 s (0: never)");
  if (o.map_frame.empty() || o.odom_frame.empty() || o.body_frame.empty() || o.map_frame == o.odom_frame ||
      o.odom_frame == o.body_frame)
    throw Error("map_frame, odom_frame and body_frame must be distinct, non-empty frame names");
}

namespace {
FeederOptions checked(FeederOptions o) {
  checkOptions(o);
  return o;
}
}  // namespace

LiveFeeder::LiveFeeder(const config::RigConfig& cfg, FeederOptions options, Outlet& outlet)
    : options_(checked(std::move(options))),
      outlet_(outlet),
      queue_(
          {static_cast<std::size_t>(options_.max_queued_imu), static_cast<std::size_t>(options_.max_queued_scans), 8},
          {false, true, false}),  // behind, the oldest sweeps go first; never IMU, never a request
      imu_gate_(cfg.imu.topic, cfg.imu.acc_unit),
      system_(cfg, options_.mode, [this](const estimator::SweepResult& r) { onSweep(r); }) {
  if (!options_.session_dir.empty() && !options_.out_dir.empty() &&
      io::holdsSession(options_.out_dir, options_.session_dir))
    throw Error("the output folder " + options_.out_dir + " holds the session's own run: localize into another");
  if (!options_.session_dir.empty())
    system_.localizeIn(std::make_shared<const Session>(io::readSession(options_.session_dir)), options_.session_dir);
  lidars_ = config::activeLidars(cfg, system_.mode());
  for (const config::LidarConfig* l : lidars_) {
    decode_.push_back(config::decodeOptions(*l));
    last_stamp_ns_.push_back(0);
  }
  worker_ = std::thread([this] { run(); });
}

LiveFeeder::~LiveFeeder() {
  queue_.close();
  if (worker_.joinable()) worker_.join();
}

bool LiveFeeder::pushImu(boost::shared_ptr<const sensor_msgs::Imu> msg) {
  Message m;
  m.imu = std::move(msg);
  return queue_.push(kImuClass, std::move(m));
}

bool LiveFeeder::pushCloud(std::size_t lidar, boost::shared_ptr<const sensor_msgs::PointCloud2> msg) {
  Message m;
  m.cloud = std::move(msg);
  m.lidar = lidar;
  return lidar < lidars_.size() && queue_.push(kScanClass, std::move(m));
}

bool LiveFeeder::pushLivox(std::size_t lidar, boost::shared_ptr<const io::LivoxCustomMsg> msg) {
  Message m;
  m.livox = std::move(msg);
  m.lidar = lidar;
  return lidar < lidars_.size() && queue_.push(kScanClass, std::move(m));
}

bool LiveFeeder::pushCdr(Encoded kind, std::size_t lidar, std::vector<std::uint8_t> cdr) {
  Message m;
  m.cdr = std::move(cdr);
  m.kind = kind;
  m.lidar = lidar;
  if (kind == Encoded::kImu) return queue_.push(kImuClass, std::move(m));
  return lidar < lidars_.size() && queue_.push(kScanClass, std::move(m));
}

std::size_t LiveFeeder::droppedImu() const { return queue_.dropped(kImuClass); }
std::size_t LiveFeeder::droppedScans() const { return queue_.dropped(kScanClass); }

std::string LiveFeeder::hintPose(const geometry_msgs::PoseWithCovarianceStamped& msg) {
  if (options_.session_dir.empty()) return "not localizing in a session: a pose hint has nothing to act on";
  if (!msg.header.frame_id.empty() && msg.header.frame_id != options_.map_frame)
    return "pose hint in frame '" + msg.header.frame_id + "', not the map frame '" + options_.map_frame + "'";
  const geometry_msgs::Pose& p = msg.pose.pose;
  for (const double v :
       {p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w})
    if (!std::isfinite(v)) return "pose hint with a non-finite value";
  Message m;
  m.pose_hint = msg;
  if (!queue_.push(kRequestClass, std::move(m))) return "busy or shutting down: try again";
  return "";
}

LiveFeeder::SaveResult LiveFeeder::save() {
  if (options_.out_dir.empty()) return {false, "out_dir is not set"};
  auto done = std::make_shared<std::promise<std::string>>();
  std::future<std::string> result = done->get_future();
  Message request;
  request.save = done;
  if (!queue_.push(kRequestClass, std::move(request))) return {false, "busy or shutting down: try again"};
  const std::string error = result.get();
  if (!error.empty()) return {false, error};
  return {true, "wrote trajectory.tum, map.pcd, report.json to " + options_.out_dir};
}

void LiveFeeder::finish() {
  if (finished_) return;
  finished_ = true;
  queue_.close();
  if (worker_.joinable()) worker_.join();
  log::info(system_.sweepsProcessed(), " sweeps, ", system_.posesTracked(), " poses, ", system_.loops(),
            " loops; dropped ", droppedImu(), " IMU and ", droppedScans(), " LiDAR messages (queue full)");
  if (options_.out_dir.empty()) return;
  const std::string error = writeOutputs();
  if (!error.empty()) log::error("cannot write the outputs: ", error);
}

void LiveFeeder::run() {
  Message m;
  while (queue_.pop(&m)) {
    try {
      process(m);
    } catch (const std::exception& e) {
      log::error(e.what());
    }
  }
  try {
    for (const ImuSample& s : imu_gate_.release()) system_.addImu(s);
    system_.flush();
  } catch (const std::exception& e) {
    log::error("at shutdown: ", e.what());
  }
  system_.finish();
}

void LiveFeeder::process(const Message& m) {
  if (m.save) {
    m.save->set_value(writeOutputs());
    return;
  }
  if (save_due_) {
    save_due_ = false;
    const std::string error = writeOutputs();
    if (!error.empty()) log::error("autosave: ", error);
  }
  if (m.pose_hint) {
    const Eigen::Isometry3d T_map_body = fromPose(m.pose_hint->pose.pose);
    // rviz's "2D Pose Estimate" has z = 0: no height.
    const bool with_height = m.pose_hint->pose.pose.position.z != 0.0;
    system_.hintPose(T_map_body, with_height);
    log::info("pose hint at (", T_map_body.translation().x(), ", ", T_map_body.translation().y(),
              with_height ? ", " + std::to_string(T_map_body.translation().z()) : std::string(),
              "): tried at the next keyframe");
    return;
  }
  if (m.imu) return addImu(*m.imu);
  if (m.cloud) return addCloud(m.lidar, *m.cloud);
  if (m.livox) return addScan(io::decodeLivox(*m.livox, decode_[m.lidar]));
  switch (m.kind) {
    case Encoded::kImu:
      return addImu(io::decodeImuCdr(m.cdr));
    case Encoded::kPointCloud2:
      return addCloud(m.lidar, io::decodePointCloud2Cdr(m.cdr));
    case Encoded::kLivox:
      return addScan(io::decodeLivox(io::decodeLivoxCdr(m.cdr), decode_[m.lidar]));
  }
}

void LiveFeeder::addImu(const sensor_msgs::Imu& msg) {
  ++imu_messages_;
  for (const ImuSample& s : imu_gate_.add(msg)) system_.addImu(s);
}

void LiveFeeder::addCloud(std::size_t lidar, const sensor_msgs::PointCloud2& msg) {
  // Clouds without per-point time get it from the azimuth over one turn: the turn period follows
  // the topic's message interval.
  io::CloudDecodeOptions& d = decode_[lidar];
  const Stamp stamp_ns = static_cast<Stamp>(msg.header.stamp.toNSec());
  const double dt_s = toSec(stamp_ns - last_stamp_ns_[lidar]);
  if (last_stamp_ns_[lidar] > 0 && dt_s > 0.01 && dt_s < 1.0) d.scan_period_s = dt_s;
  last_stamp_ns_[lidar] = stamp_ns;
  addScan(io::decodePointCloud2(msg, d));
}

void LiveFeeder::addScan(LidarScan scan) {
  if (!scan.points.empty()) system_.addScan(std::move(scan));
}

void LiveFeeder::onSweep(const estimator::SweepResult& r) {
  using Status = estimator::SweepResult::Status;
  if (r.status == Status::kDegraded && ++degraded_ % 50 == 1) {
    log::warn("degraded sweep (", degraded_, " so far): ", r.note);
  }
  const Eigen::Isometry3d T_odom_body = r.state.pose();
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // from the previous sweep's attitude
  if (last_stamp_ns_pose_ > 0 && r.state.stamp_ns > last_stamp_ns_pose_)
    omega_body = so3::log(last_q_.conjugate() * r.state.q_world_body) / toSec(r.state.stamp_ns - last_stamp_ns_pose_);
  last_q_ = r.state.q_world_body;
  last_stamp_ns_pose_ = r.state.stamp_ns;
  if (!outlet_.open()) return;  // draining the queue after shutdown: outputs only

  // Messages carry the input's stamps, also after a jump of its time base.
  NavState state = r.state;
  state.stamp_ns = system_.externalStamp(r.state.stamp_ns);
  const Stamp stamp_ns = state.stamp_ns;
  outlet_.odometry(toOdometry(state, T_odom_body, omega_body,
                              poseCovariance(r.degeneracy, r.state.q_world_body, options_.point_sigma_m),
                              options_.odom_frame, options_.body_frame));
  if (options_.publish_tf) {
    // map -> odom only changes when a loop closes; it is sent with every pose so tf can
    // interpolate both at the pose's stamp.
    const Eigen::Isometry3d T_map_odom = r.keyframe || !map_odom_known_ ? system_.mapFromOdom() : T_map_odom_;
    T_map_odom_ = T_map_odom;
    map_odom_known_ = true;
    outlet_.transforms({toTransform(T_map_odom, stamp_ns, options_.map_frame, options_.odom_frame),
                        toTransform(T_odom_body, stamp_ns, options_.odom_frame, options_.body_frame)});
  }
  if (outlet_.wantsScan()) outlet_.scan(toPointCloud2(r.points_body, T_odom_body, stamp_ns, options_.odom_frame));
  if (!r.keyframe) return;
  publishDiagnostics(r.state.stamp_ns, stamp_ns);
  if (last_save_ns_ == 0) last_save_ns_ = r.state.stamp_ns;
  if (!options_.out_dir.empty() && options_.autosave_period_s > 0 &&
      toSec(r.state.stamp_ns - last_save_ns_) >= options_.autosave_period_s) {
    save_due_ = true;
    last_save_ns_ = r.state.stamp_ns;
  }
  // Keyframes: the corrected route (loops move it), and now and then the global map.
  if (outlet_.wantsPath()) outlet_.path(toPath(system_.route(), options_.map_frame));
  const double since_map_s = toSec(r.state.stamp_ns - last_map_ns_);
  if (options_.map_publish_period_s > 0 && since_map_s >= options_.map_publish_period_s && outlet_.wantsMap()) {
    outlet_.map(toPointCloud2(system_.map(), Eigen::Isometry3d::Identity(), stamp_ns, options_.map_frame));
    last_map_ns_ = r.state.stamp_ns;
  }
}

void LiveFeeder::publishDiagnostics(Stamp now_ns, Stamp stamp_ns) {
  InputFigures f;
  f.imu_messages = imu_messages_;
  f.sweeps = system_.sweepsProcessed();
  f.sweeps_degraded = degraded_;
  f.dropped_imu = droppedImu();
  f.dropped_scans = droppedScans();
  const std::size_t trouble = f.dropped_imu + f.dropped_scans + f.sweeps_degraded;
  if (trouble != trouble_so_far_) {
    trouble_so_far_ = trouble;
    last_trouble_ns_ = now_ns;
  }
  f.quiet_s = toSec(now_ns - last_trouble_ns_);
  std::vector<diagnostic_msgs::DiagnosticStatus> statuses{inputStatus(f, "mmlio: input")};
  if (const backend::LocalizationStatus* s = system_.localization())
    statuses.push_back(localizationStatus(*s, now_ns, "mmlio: localization"));
  outlet_.diagnostics(toDiagnostics(std::move(statuses), stamp_ns));
}

std::string LiveFeeder::writeOutputs() {
  if (system_.posesTracked() == 0) return "no pose estimated yet: nothing written";
  try {
    pipeline::RunReport report = system_.report();
    report.input.source = "live";
    report.input.imu_messages = imu_messages_;
    report.input.imu_acc_scale = imu_gate_.decided() ? imu_gate_.accScale() : 1.0;
    report.input.queue_dropped_imu = droppedImu();
    report.input.queue_dropped_scans = droppedScans();
    const Trajectory odometry = system_.odometryTrajectory();
    report.input.duration_s = toSec(odometry.back().stamp_ns - odometry.front().stamp_ns);
    report.status = report.inputStatus();
    report = system_.writeOutputs(options_.out_dir, std::move(report));
    log::info("wrote ", report.outputs.trajectory, " (", report.outputs.poses, " poses), ", report.outputs.map, " (",
              report.outputs.map_points, " points) and the report");
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

}  // namespace mmlio::live
