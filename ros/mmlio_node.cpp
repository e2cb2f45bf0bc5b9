// mmlio_node: the live roscpp node. live/live_feeder.hpp does the work (the System `mmlio run`
// feeds from a bag, with live loop closure, the messages, the outputs); this file is its roscpp
// transport: subscriptions that only enqueue, publishers, tf and the save_map service.
#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <optional>

#include "live_feeder.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/livox_msg.hpp"

namespace mmlio::ros_node {
namespace {

constexpr const char* kUsage =
    "usage: mmlio_node [_config:=RIG.yaml] [_mode:=hvi|vi|hi] [_calib:=CALIB.yaml] [_out_dir:=DIR]\n"
    "                  [_map_frame:=map] [_odom_frame:=odom] [_body_frame:=imu] [_publish_tf:=true]\n"
    "                  [_map_publish_period_s:=5] [_point_sigma_m:=0.03] [_session:=DIR] [_autosave_period_s:=300]\n"
    "                  [_max_queued_scans:=10] [_max_queued_imu:=4000] [ROS remappings]\n"
    "Live multi-LiDAR-inertial odometry and mapping: subscribes to the IMU and LiDAR topics of the rig\n"
    "config; publishes ~odometry (nav_msgs/Odometry), ~path (nav_msgs/Path, corrected by loops), tf\n"
    "map -> odom -> body, ~cloud_registered and ~map (sensor_msgs/PointCloud2); the ~save_map service\n"
    "(std_srvs/Trigger) writes trajectory.tum, map.pcd and report.json into ~out_dir, as does shutdown.\n"
    "With ~session it localizes in that saved map: pose hints on /initialpose (rviz's 2D Pose Estimate),\n"
    "its state on /diagnostics (diagnostic_msgs/DiagnosticArray).\n"
    "Needs a running ROS master (ROS_MASTER_URI). See ros/README.md.\n";

struct NodeParams {
  std::string config;  // rig YAML; empty = built-in defaults (config/hvi.yaml)
  std::string calib;   // calibration YAML overriding the config's `calibration:`
  live::FeederOptions feeder;
};

NodeParams readParams(const ros::NodeHandle& pnh) {
  NodeParams p;
  live::FeederOptions& f = p.feeder;
  pnh.param("config", p.config, p.config);
  pnh.param("mode", f.mode, f.mode);
  pnh.param("calib", p.calib, p.calib);
  pnh.param("out_dir", f.out_dir, f.out_dir);
  pnh.param("session", f.session_dir, f.session_dir);
  pnh.param("autosave_period_s", f.autosave_period_s, f.autosave_period_s);
  pnh.param("map_frame", f.map_frame, f.map_frame);
  pnh.param("odom_frame", f.odom_frame, f.odom_frame);
  pnh.param("body_frame", f.body_frame, f.body_frame);
  pnh.param("publish_tf", f.publish_tf, f.publish_tf);
  pnh.param("map_publish_period_s", f.map_publish_period_s, f.map_publish_period_s);
  pnh.param("point_sigma_m", f.point_sigma_m, f.point_sigma_m);
  pnh.param("max_queued_scans", f.max_queued_scans, f.max_queued_scans);
  pnh.param("max_queued_imu", f.max_queued_imu, f.max_queued_imu);
  live::checkOptions(f);
  return p;
}

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

/// The feeder's messages onto roscpp publishers and tf2.
class RosOutlet : public live::Outlet {
 public:
  explicit RosOutlet(ros::NodeHandle& pnh)
      : odometry_(pnh.advertise<nav_msgs::Odometry>("odometry", 100)),
        path_(pnh.advertise<nav_msgs::Path>("path", 1, /*latch=*/true)),
        scan_(pnh.advertise<sensor_msgs::PointCloud2>("cloud_registered", 2)),
        map_(pnh.advertise<sensor_msgs::PointCloud2>("map", 1, /*latch=*/true)),
        diagnostics_(ros::NodeHandle().advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10)) {}

  bool open() const override { return ros::ok(); }
  void odometry(const nav_msgs::Odometry& msg) override { odometry_.publish(msg); }
  void transforms(const std::vector<geometry_msgs::TransformStamped>& msgs) override { tf_.sendTransform(msgs); }
  bool wantsScan() const override { return scan_.getNumSubscribers() > 0; }
  void scan(const sensor_msgs::PointCloud2& msg) override { scan_.publish(msg); }
  bool wantsPath() const override { return path_.getNumSubscribers() > 0; }
  void path(const nav_msgs::Path& msg) override { path_.publish(msg); }
  bool wantsMap() const override { return map_.getNumSubscribers() > 0; }
  void map(const sensor_msgs::PointCloud2& msg) override { map_.publish(msg); }
  void diagnostics(const diagnostic_msgs::DiagnosticArray& msg) override { diagnostics_.publish(msg); }

 private:
  ros::Publisher odometry_, path_, scan_, map_, diagnostics_;
  tf2_ros::TransformBroadcaster tf_;
};

class Node {
 public:
  Node(ros::NodeHandle& nh, ros::NodeHandle& pnh, const NodeParams& params, const config::RigConfig& cfg)
      : outlet_(pnh), feeder_(cfg, params.feeder, outlet_) {
    // The service waits for the processing thread: its own queue and spinner keep the sensor
    // callbacks flowing meanwhile.
    ros::NodeHandle service_nh(pnh);
    service_nh.setCallbackQueue(&service_queue_);
    save_srv_ = service_nh.advertiseService("save_map", &Node::onSaveMap, this);
    service_spinner_.start();

    subs_.push_back(nh.subscribe<sensor_msgs::Imu>(
        cfg.imu.topic, 2000,
        [this](const sensor_msgs::Imu::ConstPtr& m) {
          if (!feeder_.pushImu(m)) warnDropped("IMU", feeder_.droppedImu());
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
    log::info("mode ", feeder_.mode(), ", IMU ", cfg.imu.topic, " (sensor_msgs/Imu, acc unit ", cfg.imu.acc_unit, ")");
    for (std::size_t i = 0; i < feeder_.lidars().size(); ++i) subscribeLidar(nh, i);
    if (!params.feeder.session_dir.empty()) {
      // Where rviz's "2D Pose Estimate" publishes.
      subs_.push_back(nh.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
          "/initialpose", 2, [this](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& m) {
            const std::string refused = feeder_.hintPose(*m);
            if (!refused.empty()) log::warn("/initialpose ignored: ", refused);
          }));
      log::info("localizing in ", params.feeder.session_dir, "; pose hints on /initialpose, status on /diagnostics");
    }
  }

  void finish() { feeder_.finish(); }

 private:
  void subscribeLidar(ros::NodeHandle& nh, std::size_t index) {
    const config::LidarConfig& l = *feeder_.lidars()[index];
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
        if (!feeder_.pushLivox(index, m)) warnDropped("LiDAR", feeder_.droppedScans());
      });
      if (advertisedType(l.topic) == io::kLivox2CustomMsgType) ops.datatype = io::kLivox2CustomMsgType;
      ops.transport_hints = ros::TransportHints().tcpNoDelay();
      subs_.push_back(nh.subscribe(ops));
      log::info("LiDAR '", l.name, "' on ", l.topic, " (", ops.datatype, ")");
    } else {
      subs_.push_back(nh.subscribe<sensor_msgs::PointCloud2>(
          l.topic, 10,
          [this, index](const sensor_msgs::PointCloud2::ConstPtr& m) {
            if (!feeder_.pushCloud(index, m)) warnDropped("LiDAR", feeder_.droppedScans());
          },
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
      log::info("LiDAR '", l.name, "' on ", l.topic, " (sensor_msgs/PointCloud2)");
    }
  }

  static void warnDropped(const char* what, std::size_t so_far) {
    ROS_WARN_THROTTLE(5.0, "mmlio_node: processing queue full, dropping %s messages (%zu dropped so far)", what,
                      so_far);
  }

  /// Spinner thread: the processing thread writes the files between two messages.
  bool onSaveMap(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    const live::LiveFeeder::SaveResult r = feeder_.save();
    res.success = r.success;
    res.message = r.message;
    return true;
  }

  RosOutlet outlet_;
  live::LiveFeeder feeder_;
  ros::CallbackQueue service_queue_;
  ros::AsyncSpinner service_spinner_{1, &service_queue_};
  ros::ServiceServer save_srv_;
  std::vector<ros::Subscriber> subs_;
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
    const mmlio::config::RigConfig cfg = mmlio::live::loadRigConfig(params.config, params.calib, "~config", "~calib");
    Node node(nh, pnh, params, cfg);
    ros::spin();  // until SIGINT / rosnode kill
    node.finish();
  } catch (const std::exception& e) {
    std::cerr << "mmlio_node: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
