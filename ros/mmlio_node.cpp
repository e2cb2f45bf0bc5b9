// mmlio_node: the live feeder of pipeline::System, the same system `mmlio run` feeds from a bag
// (odometry, mapping back end with live loop closure, report).
//
// Threads: the ROS spinner runs the subscription and service callbacks, which only enqueue into a
// bounded queue (a full queue drops the message and says so); ONE processing thread decodes, feeds
// the System and publishes. A slow sweep therefore never blocks the spinner, and the System sees
// its input in one order. The back end runs on the System's own thread.
#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <future>
#include <iostream>
#include <memory>
#include <thread>

#include "bounded_queue.hpp"
#include "imu_unit_gate.hpp"
#include "mmlio/config/calibration_source.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "mmlio/io/livox_msg.hpp"
#include "mmlio/pipeline/system.hpp"
#include "ros_messages.hpp"

namespace mmlio::ros_node {
namespace {

constexpr const char* kUsage =
    "usage: mmlio_node [_config:=RIG.yaml] [_mode:=hvi|vi|hi] [_calib:=CALIB.yaml] [_out_dir:=DIR]\n"
    "                  [_map_frame:=map] [_odom_frame:=odom] [_body_frame:=imu] [_publish_tf:=true]\n"
    "                  [_map_publish_period_s:=5] [_point_sigma_m:=0.03]\n"
    "                  [_max_queued_scans:=10] [_max_queued_imu:=4000] [ROS remappings]\n"
    "Live multi-LiDAR-inertial odometry and mapping: subscribes to the IMU and LiDAR topics of the rig\n"
    "config; publishes ~odometry (nav_msgs/Odometry), ~path (nav_msgs/Path, corrected by loops), tf\n"
    "map -> odom -> body, ~cloud_registered and ~map (sensor_msgs/PointCloud2); the ~save_map service\n"
    "(std_srvs/Trigger) writes trajectory.tum, map.pcd and report.json into ~out_dir, as does shutdown.\n"
    "Needs a running ROS master (ROS_MASTER_URI). See ros/README.md.\n";

struct NodeParams {
  std::string config;                 // rig YAML; empty = built-in defaults (config/hvi.yaml)
  std::string mode;                   // hvi | vi | hi; empty = the config's
  std::string calib;                  // calibration YAML overriding the config's `calibration:`
  std::string out_dir;                // outputs on ~save_map and on shutdown; empty = none
  std::string map_frame = "map";      // loop-corrected world frame (Path, map cloud)
  std::string odom_frame = "odom";    // the odometry's world frame (Odometry, registered scan)
  std::string body_frame = "imu";     // the IMU (body) frame the poses are of
  bool publish_tf = true;             // map -> odom -> body through tf2
  double map_publish_period_s = 5.0;  // ~map refresh (assembling it pauses the back end); 0 = never
  double point_sigma_m = 0.03;        // LiDAR point noise behind the pose covariance
  int max_queued_scans = 10;          // LiDAR messages waiting for the processing thread
  int max_queued_imu = 4000;          // IMU messages waiting (20 s at 200 Hz)
};

NodeParams readParams(const ros::NodeHandle& pnh) {
  NodeParams p;
  pnh.param("config", p.config, p.config);
  pnh.param("mode", p.mode, p.mode);
  pnh.param("calib", p.calib, p.calib);
  pnh.param("out_dir", p.out_dir, p.out_dir);
  pnh.param("map_frame", p.map_frame, p.map_frame);
  pnh.param("odom_frame", p.odom_frame, p.odom_frame);
  pnh.param("body_frame", p.body_frame, p.body_frame);
  pnh.param("publish_tf", p.publish_tf, p.publish_tf);
  pnh.param("map_publish_period_s", p.map_publish_period_s, p.map_publish_period_s);
  pnh.param("point_sigma_m", p.point_sigma_m, p.point_sigma_m);
  pnh.param("max_queued_scans", p.max_queued_scans, p.max_queued_scans);
  pnh.param("max_queued_imu", p.max_queued_imu, p.max_queued_imu);
  if (p.max_queued_scans < 1 || p.max_queued_imu < 1) throw Error("~max_queued_scans and ~max_queued_imu must be >= 1");
  if (!(p.point_sigma_m > 0.0)) throw Error("~point_sigma_m must be > 0");
  if (p.map_frame.empty() || p.odom_frame.empty() || p.body_frame.empty() || p.map_frame == p.odom_frame ||
      p.odom_frame == p.body_frame)
    throw Error("~map_frame, ~odom_frame and ~body_frame must be distinct, non-empty frame names");
  return p;
}

/// The config, with `calibration:` (or ~calib, which wins) applied, as `mmlio run` does.
config::RigConfig loadConfig(const NodeParams& p) {
  config::RigConfig cfg;
  if (p.config.empty())
    log::info("no ~config: using the built-in defaults (same as config/hvi.yaml)");
  else
    cfg = config::loadRigConfig(p.config);
  if (config::resolveCalibration(cfg, p.calib) == "auto")
    throw Error("calibration: auto is not available live; run `mmlio calibrate` and set ~calib");
  return cfg;
}

/// One queued item: exactly one of the pointers is set. A save request carries the promise its
/// service call waits on.
struct Message {
  sensor_msgs::Imu::ConstPtr imu;
  sensor_msgs::PointCloud2::ConstPtr cloud;
  boost::shared_ptr<const io::LivoxCustomMsg> livox;
  std::shared_ptr<std::promise<std::string>> save;  // resolves to "" (written) or the error
  std::size_t lidar = 0;                            // index into the active LiDARs
};
enum QueueClass : std::size_t { kImuClass = 0, kScanClass = 1, kRequestClass = 2 };

/// Datatype the master lists for `topic` (empty if nobody publishes it yet).
std::string advertisedType(const std::string& topic) {
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return "";
  const std::string resolved = ros::names::resolve(topic);
  for (const auto& t : topics) {
    if (t.name == resolved) return t.datatype;
  }
  return "";
}

class Node {
 public:
  Node(ros::NodeHandle& nh, ros::NodeHandle& pnh, NodeParams params, const config::RigConfig& cfg)
      : params_(std::move(params)),
        queue_(
            {static_cast<std::size_t>(params_.max_queued_imu), static_cast<std::size_t>(params_.max_queued_scans), 8}),
        imu_gate_(cfg.imu.topic, cfg.imu.acc_unit),
        system_(cfg, params_.mode, [this](const estimator::SweepResult& r) { onSweep(r); }) {
    odometry_pub_ = pnh.advertise<nav_msgs::Odometry>("odometry", 100);
    path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, /*latch=*/true);
    scan_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("cloud_registered", 2);
    map_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("map", 1, /*latch=*/true);
    // The service waits for the processing thread: its own queue and spinner keep the sensor
    // callbacks flowing meanwhile.
    ros::NodeHandle service_nh(pnh);
    service_nh.setCallbackQueue(&service_queue_);
    save_srv_ = service_nh.advertiseService("save_map", &Node::onSaveMap, this);
    service_spinner_.start();

    subs_.push_back(nh.subscribe<sensor_msgs::Imu>(
        cfg.imu.topic, 2000,
        [this](const sensor_msgs::Imu::ConstPtr& m) {
          enqueue(kImuClass, {m, {}, {}, {}, 0});
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
    log::info("mode ", system_.mode(), ", IMU ", cfg.imu.topic, " (sensor_msgs/Imu, acc unit ", cfg.imu.acc_unit, ")");
    for (const config::LidarConfig* l : config::activeLidars(cfg, system_.mode())) subscribeLidar(nh, *l);
    worker_ = std::thread([this] { run(); });
  }

  ~Node() {
    queue_.close();
    if (worker_.joinable()) worker_.join();
  }

  /// After the spinner stopped: processes what is queued, flushes, finishes the back end (a last
  /// loop check) and writes the outputs.
  void finish() {
    queue_.close();
    if (worker_.joinable()) worker_.join();
    log::info(system_.sweepsProcessed(), " sweeps, ", system_.posesTracked(), " poses, ", system_.loops(),
              " loops; dropped ", queue_.dropped(kImuClass), " IMU and ", queue_.dropped(kScanClass),
              " LiDAR messages (queue full)");
    if (params_.out_dir.empty()) return;
    const std::string error = save();
    if (!error.empty()) log::error("cannot write the outputs: ", error);
  }

 private:
  void subscribeLidar(ros::NodeHandle& nh, const config::LidarConfig& l) {
    const std::size_t index = decode_.size();
    io::CloudDecodeOptions d;
    d.sensor = l.name;
    d.kind = l.kind();
    d.min_range_m = l.min_range_m;
    d.max_range_m = l.max_range_m;
    d.num_rings = l.num_rings;
    decode_.push_back(d);
    last_stamp_ns_.push_back(0);
    for (const auto& s : subs_) {
      if (ros::names::resolve(s.getTopic()) == ros::names::resolve(l.topic)) {
        throw Error("topic " + l.topic + " of LiDAR '" + l.name + "' is already subscribed");
      }
    }
    if (l.type == "livox") {
      // The struct's static traits say livox_ros_driver/CustomMsg; driver2 publishes the same
      // layout and MD5 under another package name, so take the name the master advertises.
      ros::SubscribeOptions ops;
      ops.init<io::LivoxCustomMsg>(l.topic, 10, [this, index](const boost::shared_ptr<const io::LivoxCustomMsg>& m) {
        enqueue(kScanClass, {{}, {}, m, {}, index});
      });
      if (advertisedType(l.topic) == io::kLivox2CustomMsgType) ops.datatype = io::kLivox2CustomMsgType;
      ops.transport_hints = ros::TransportHints().tcpNoDelay();
      subs_.push_back(nh.subscribe(ops));
      log::info("LiDAR '", l.name, "' on ", l.topic, " (", ops.datatype, ")");
    } else {
      subs_.push_back(nh.subscribe<sensor_msgs::PointCloud2>(
          l.topic, 10,
          [this, index](const sensor_msgs::PointCloud2::ConstPtr& m) {
            enqueue(kScanClass, {{}, m, {}, {}, index});
          },
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
      log::info("LiDAR '", l.name, "' on ", l.topic, " (sensor_msgs/PointCloud2)");
    }
  }

  /// Spinner thread: never blocks on the processing thread.
  void enqueue(QueueClass c, Message m) {
    if (!queue_.push(c, std::move(m))) {
      ROS_WARN_THROTTLE(5.0, "mmlio_node: processing queue full, dropping %s messages (%zu dropped so far)",
                        c == kImuClass ? "IMU" : "LiDAR", queue_.dropped(c));
    }
  }

  /// Spinner thread: the processing thread writes the files between two messages.
  bool onSaveMap(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    if (params_.out_dir.empty()) {
      res.success = false;
      res.message = "~out_dir is not set";
      return true;
    }
    auto done = std::make_shared<std::promise<std::string>>();
    std::future<std::string> result = done->get_future();
    if (!queue_.push(kRequestClass, {{}, {}, {}, done, 0})) {
      res.success = false;
      res.message = "busy or shutting down: try again";
      return true;
    }
    const std::string error = result.get();
    res.success = error.empty();
    res.message = error.empty() ? "wrote trajectory.tum, map.pcd, report.json to " + params_.out_dir : error;
    return true;
  }

  /// Processing thread.
  void run() {
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

  void process(const Message& m) {
    if (m.save) {
      m.save->set_value(save());
      return;
    }
    if (m.imu) {
      ++imu_messages_;
      for (const ImuSample& s : imu_gate_.add(*m.imu)) system_.addImu(s);
      return;
    }
    io::CloudDecodeOptions& d = decode_[m.lidar];
    LidarScan scan;
    if (m.cloud) {
      // Clouds without per-point time get it from the azimuth over one turn: the turn period
      // follows the topic's message interval.
      const Stamp stamp_ns = static_cast<Stamp>(m.cloud->header.stamp.toNSec());
      const double dt_s = toSec(stamp_ns - last_stamp_ns_[m.lidar]);
      if (last_stamp_ns_[m.lidar] > 0 && dt_s > 0.01 && dt_s < 1.0) d.scan_period_s = dt_s;
      last_stamp_ns_[m.lidar] = stamp_ns;
      scan = io::decodePointCloud2(*m.cloud, d);
    } else {
      scan = io::decodeLivox(*m.livox, d);
    }
    if (!scan.points.empty()) system_.addScan(std::move(scan));
  }

  /// Processing thread: the System calls it for every sweep after initialisation.
  void onSweep(const estimator::SweepResult& r) {
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
    if (!ros::ok()) return;  // draining the queue after shutdown: outputs only

    // Messages carry the input's stamps, also after a jump of its time base.
    NavState state = r.state;
    state.stamp_ns = system_.externalStamp(r.state.stamp_ns);
    const Stamp stamp_ns = state.stamp_ns;
    odometry_pub_.publish(toOdometry(state, T_odom_body, omega_body,
                                     poseCovariance(r.degeneracy, r.state.q_world_body, params_.point_sigma_m),
                                     params_.odom_frame, params_.body_frame));
    if (params_.publish_tf) {
      // map -> odom only changes when a loop closes; it is sent with every pose so tf can
      // interpolate both at the pose's stamp.
      const Eigen::Isometry3d T_map_odom = r.keyframe || !map_odom_known_ ? system_.mapFromOdom() : T_map_odom_;
      T_map_odom_ = T_map_odom;
      map_odom_known_ = true;
      tf_.sendTransform({toTransform(T_map_odom, stamp_ns, params_.map_frame, params_.odom_frame),
                         toTransform(T_odom_body, stamp_ns, params_.odom_frame, params_.body_frame)});
    }
    if (scan_pub_.getNumSubscribers() > 0)
      scan_pub_.publish(toPointCloud2(r.points_body, T_odom_body, stamp_ns, params_.odom_frame));
    if (!r.keyframe) return;
    // Keyframes: the corrected path (loops move it), and now and then the global map.
    if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(toPath(system_.trajectory(), params_.map_frame));
    const double since_map_s = toSec(r.state.stamp_ns - last_map_ns_);
    if (params_.map_publish_period_s > 0 && since_map_s >= params_.map_publish_period_s &&
        map_pub_.getNumSubscribers() > 0) {
      map_pub_.publish(toPointCloud2(system_.map(), Eigen::Isometry3d::Identity(), stamp_ns, params_.map_frame));
      last_map_ns_ = r.state.stamp_ns;
    }
  }

  /// Processing thread: trajectory.tum, map.pcd, report.json/.md into out_dir. "" or the error.
  std::string save() {
    if (system_.posesTracked() == 0) return "no pose estimated yet: nothing written";
    try {
      pipeline::RunReport report = system_.report();
      report.input.source = "live";
      report.input.imu_messages = imu_messages_;
      report.input.imu_acc_scale = imu_gate_.decided() ? imu_gate_.accScale() : 1.0;
      report.input.queue_dropped_imu = queue_.dropped(kImuClass);
      report.input.queue_dropped_scans = queue_.dropped(kScanClass);
      const Trajectory odometry = system_.odometryTrajectory();
      report.input.duration_s = toSec(odometry.back().stamp_ns - odometry.front().stamp_ns);
      report.status = report.inputStatus();
      report = system_.writeOutputs(params_.out_dir, std::move(report));
      log::info("wrote ", report.outputs.trajectory, " (", report.outputs.poses, " poses), ", report.outputs.map, " (",
                report.outputs.map_points, " points) and the report");
      return "";
    } catch (const std::exception& e) {
      return e.what();
    }
  }

  NodeParams params_;
  BoundedQueue<Message, 3> queue_;
  // Processing thread only, from here on.
  ImuUnitGate imu_gate_;
  std::size_t imu_messages_ = 0;
  std::vector<io::CloudDecodeOptions> decode_;  // per active LiDAR (written before the thread starts)
  std::vector<Stamp> last_stamp_ns_;
  pipeline::System system_;
  std::size_t degraded_ = 0;
  Eigen::Quaterniond last_q_ = Eigen::Quaterniond::Identity();
  Stamp last_stamp_ns_pose_ = 0, last_map_ns_ = 0;
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
  bool map_odom_known_ = false;
  ros::Publisher odometry_pub_, path_pub_, scan_pub_, map_pub_;
  ros::CallbackQueue service_queue_;
  ros::AsyncSpinner service_spinner_{1, &service_queue_};
  ros::ServiceServer save_srv_;
  tf2_ros::TransformBroadcaster tf_;
  std::vector<ros::Subscriber> subs_;
  std::thread worker_;
};

/// mmlio's logger (the pipeline's and the node's messages) into rosconsole, so it reaches /rosout.
/// ros::shutdown() also shuts rosconsole down: from then on the messages go to stderr.
void routeLogToRosconsole() {
  log::configure(log::Level::kInfo, [](log::Level level, const std::string& msg) {
    if (!ros::ok()) {  // shutting down: rosconsole may be gone already
      static const char* names[] = {"debug", "info", "warn", "error", "error"};
      std::cerr << "[" << names[static_cast<int>(level)] << "] mmlio_node: " << msg << "\n";
      return;
    }
    switch (level) {
      case log::Level::kDebug:
        ROS_DEBUG_STREAM("mmlio_node: " << msg);
        break;
      case log::Level::kInfo:
        ROS_INFO_STREAM("mmlio_node: " << msg);
        break;
      case log::Level::kWarn:
        ROS_WARN_STREAM("mmlio_node: " << msg);
        break;
      default:
        ROS_ERROR_STREAM("mmlio_node: " << msg);
        break;
    }
  });
}

bool hasArg(int argc, char** argv, const char* prefix) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], prefix, std::strlen(prefix)) == 0) return true;
  }
  return false;
}

}  // namespace
}  // namespace mmlio::ros_node

int main(int argc, char** argv) {
  using namespace mmlio::ros_node;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "--help") == 0) {
      std::cout << kUsage;
      return 0;
    }
  }
  // roscpp aborts (ROS_BREAK) inside ros::init when it has no master URI at all: say it first.
  if (!std::getenv("ROS_MASTER_URI") && !hasArg(argc, argv, "__master:=")) {
    std::cerr << "mmlio_node: ROS_MASTER_URI is not set (e.g. export ROS_MASTER_URI=http://localhost:11311 and run "
                 "roscore)\n"
              << kUsage;
    return 1;
  }
  ros::init(argc, argv, "mmlio_node");
  if (!ros::master::check()) {
    std::cerr << "mmlio_node: no ROS master reachable at " << ros::master::getURI()
              << " (start roscore, or set ROS_MASTER_URI / __master:=URI)\n";
    return 1;
  }
  routeLogToRosconsole();
  try {
    ros::NodeHandle nh, pnh("~");
    const NodeParams params = readParams(pnh);
    const mmlio::config::RigConfig cfg = loadConfig(params);
    Node node(nh, pnh, params, cfg);
    ros::spin();  // until SIGINT / rosnode kill
    node.finish();
  } catch (const std::exception& e) {
    std::cerr << "mmlio_node: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
