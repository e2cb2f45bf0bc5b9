// mmlio_node: the live feeder of pipeline::OnlinePipeline (the same streaming core as `mmlio run`).
//
// Threads: the ROS spinner runs the subscription callbacks, which only enqueue the message
// pointers into a bounded queue (a full queue drops the message and says so); ONE processing
// thread decodes, feeds the pipeline and publishes. A slow sweep therefore never blocks the
// spinner, and the estimator stays single-threaded and deterministic in its input order.
#include <ros/master.h>
#include <ros/ros.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <thread>

#include "bounded_queue.hpp"
#include "imu_unit_gate.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/calib_file.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "mmlio/io/livox_msg.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/rig_config.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/pipeline/map_accumulator.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"
#include "ros_messages.hpp"

namespace mmlio::ros_node {
namespace {

constexpr const char* kUsage =
    "usage: mmlio_node [_config:=RIG.yaml] [_mode:=hvi|vi|hi] [_calib:=CALIB.yaml] [_out_dir:=DIR]\n"
    "                  [_frame_id:=map] [_child_frame_id:=imu] [_map_every_n_keyframes:=1]\n"
    "                  [_max_queued_scans:=10] [_max_queued_imu:=4000] [ROS remappings]\n"
    "Live multi-LiDAR-inertial odometry: subscribes to the IMU and LiDAR topics of the rig config,\n"
    "publishes ~pose (geometry_msgs/PoseStamped), ~transform (geometry_msgs/TransformStamped) and\n"
    "~keyframe_cloud (sensor_msgs/PointCloud2, world frame); on shutdown writes trajectory.tum and\n"
    "map.pcd into ~out_dir when set. Needs a running ROS master (ROS_MASTER_URI). See ros/README.md.\n";

struct NodeParams {
  std::string config;                 // rig YAML; empty = built-in defaults (config/hvi.yaml)
  std::string mode;                   // hvi | vi | hi; empty = the config's
  std::string calib;                  // calibration YAML overriding the config's `calibration:`
  std::string out_dir;                // trajectory.tum + map.pcd on shutdown; empty = none
  std::string frame_id = "map";       // world frame of the published pose and clouds
  std::string child_frame_id = "imu"; // body (IMU) frame
  int map_every_n_keyframes = 1;      // publish the keyframe cloud every n-th keyframe; 0 = never
  int max_queued_scans = 10;          // LiDAR messages waiting for the processing thread
  int max_queued_imu = 4000;          // IMU messages waiting (20 s at 200 Hz)
};

NodeParams readParams(const ros::NodeHandle& pnh) {
  NodeParams p;
  pnh.param("config", p.config, p.config);
  pnh.param("mode", p.mode, p.mode);
  pnh.param("calib", p.calib, p.calib);
  pnh.param("out_dir", p.out_dir, p.out_dir);
  pnh.param("frame_id", p.frame_id, p.frame_id);
  pnh.param("child_frame_id", p.child_frame_id, p.child_frame_id);
  pnh.param("map_every_n_keyframes", p.map_every_n_keyframes, p.map_every_n_keyframes);
  pnh.param("max_queued_scans", p.max_queued_scans, p.max_queued_scans);
  pnh.param("max_queued_imu", p.max_queued_imu, p.max_queued_imu);
  if (p.max_queued_scans < 1 || p.max_queued_imu < 1) throw Error("~max_queued_scans and ~max_queued_imu must be >= 1");
  return p;
}

/// The config, with `calibration:` (or ~calib, which wins) applied, as `mmlio run` does.
io::RigConfig loadConfig(const NodeParams& p) {
  io::RigConfig cfg;
  if (p.config.empty()) log::info("no ~config: using the built-in defaults (same as config/hvi.yaml)");
  else cfg = io::loadRigConfig(p.config);
  const std::string source = p.calib.empty() ? cfg.calibration : p.calib;
  if (source == "auto") throw Error("calibration: auto is not available live; run `mmlio calibrate` and set ~calib");
  if (source != "config") {
    for (const auto& name : io::applyCalibration(cfg, io::readCalibration(source))) {
      log::warn("calibration ", source, " has no entry for LiDAR '", name, "': keeping its extrinsic from the config");
    }
    log::info("extrinsics and clock offsets from ", source);
  }
  return cfg;
}

/// One queued message: exactly one of the pointers is set.
struct Message {
  sensor_msgs::Imu::ConstPtr imu;
  sensor_msgs::PointCloud2::ConstPtr cloud;
  boost::shared_ptr<const io::LivoxCustomMsg> livox;
  std::size_t lidar = 0;  // index into the active LiDARs
};
enum QueueClass : std::size_t { kImuClass = 0, kScanClass = 1 };

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
  Node(ros::NodeHandle& nh, ros::NodeHandle& pnh, NodeParams params, const io::RigConfig& cfg)
      : params_(std::move(params)),
        mode_(params_.mode.empty() ? cfg.mode : params_.mode),
        queue_({static_cast<std::size_t>(params_.max_queued_imu), static_cast<std::size_t>(params_.max_queued_scans)}),
        imu_gate_(cfg.imu.topic, cfg.imu.acc_unit),
        pipeline_(cfg, mode_, [this](const estimator::SweepResult& r) { onSweep(r); }) {
    if (!params_.out_dir.empty()) map_.emplace(cfg.output.map_voxel_m);
    pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("pose", 100);
    transform_pub_ = pnh.advertise<geometry_msgs::TransformStamped>("transform", 100);
    cloud_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("keyframe_cloud", 2);

    subs_.push_back(nh.subscribe<sensor_msgs::Imu>(
        cfg.imu.topic, 2000, [this](const sensor_msgs::Imu::ConstPtr& m) { enqueue(kImuClass, {m, {}, {}, 0}); },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay()));
    log::info("mode ", mode_, ", IMU ", cfg.imu.topic, " (sensor_msgs/Imu, acc unit ", cfg.imu.acc_unit, ")");
    for (const io::LidarConfig* l : io::activeLidars(cfg, mode_)) subscribeLidar(nh, *l);
    worker_ = std::thread([this] { run(); });
  }

  ~Node() {
    queue_.close();
    if (worker_.joinable()) worker_.join();
  }

  /// After the spinner stopped: processes what is queued, flushes, writes the outputs.
  void finish() {
    queue_.close();
    if (worker_.joinable()) worker_.join();
    log::info(pipeline_.sweepsProcessed(), " sweeps, ", trajectory_.size(), " poses; dropped ", queue_.dropped(kImuClass),
              " IMU and ", queue_.dropped(kScanClass), " LiDAR messages (queue full)");
    writeOutputs();
  }

 private:
  void subscribeLidar(ros::NodeHandle& nh, const io::LidarConfig& l) {
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
        enqueue(kScanClass, {{}, {}, m, index});
      });
      if (advertisedType(l.topic) == io::kLivox2CustomMsgType) ops.datatype = io::kLivox2CustomMsgType;
      ops.transport_hints = ros::TransportHints().tcpNoDelay();
      subs_.push_back(nh.subscribe(ops));
      log::info("LiDAR '", l.name, "' on ", l.topic, " (", ops.datatype, ")");
    } else {
      subs_.push_back(nh.subscribe<sensor_msgs::PointCloud2>(
          l.topic, 10,
          [this, index](const sensor_msgs::PointCloud2::ConstPtr& m) { enqueue(kScanClass, {{}, m, {}, index}); },
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
      for (const ImuSample& s : imu_gate_.release()) pipeline_.addImu(s);
      pipeline_.flush();
    } catch (const std::exception& e) {
      log::error("at shutdown: ", e.what());
    }
  }

  void process(const Message& m) {
    if (m.imu) {
      for (const ImuSample& s : imu_gate_.add(*m.imu)) pipeline_.addImu(s);
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
    if (!scan.points.empty()) pipeline_.addScan(std::move(scan));
  }

  /// Called by the pipeline on the processing thread.
  void onSweep(const estimator::SweepResult& r) {
    using Status = estimator::SweepResult::Status;
    if (r.status == Status::kInitializing) return;
    if (r.status == Status::kDegraded && ++degraded_ % 50 == 1) {
      log::warn("degraded sweep (", degraded_, " so far): ", r.note);
    }
    const Eigen::Isometry3d T_world_body = r.state.pose();
    trajectory_.push_back({r.state.stamp_ns, T_world_body});
    if (map_) map_->add(r.points_body, T_world_body);
    if (!ros::ok()) return;  // draining the queue after shutdown: outputs only
    pose_pub_.publish(toPoseStamped(r.state, params_.frame_id));
    transform_pub_.publish(toTransformStamped(r.state, params_.frame_id, params_.child_frame_id));
    if (!r.keyframe) return;
    ++keyframes_;
    const int n = params_.map_every_n_keyframes;
    if (n > 0 && keyframes_ % static_cast<std::size_t>(n) == 0 && cloud_pub_.getNumSubscribers() > 0) {
      cloud_pub_.publish(toPointCloud2(r.points_body, T_world_body, r.state.stamp_ns, params_.frame_id));
    }
  }

  void writeOutputs() {
    if (params_.out_dir.empty()) return;
    if (trajectory_.empty()) {
      log::warn("no pose was estimated; nothing written to ", params_.out_dir);
      return;
    }
    try {
      std::filesystem::create_directories(params_.out_dir);
      const std::string tum = params_.out_dir + "/trajectory.tum", pcd = params_.out_dir + "/map.pcd";
      io::writeTum(tum, trajectory_);
      const std::vector<Point> points = map_->points();
      io::writePcdBinary(pcd, points);
      log::info("wrote ", tum, " (", trajectory_.size(), " poses) and ", pcd, " (", points.size(), " points)");
    } catch (const std::exception& e) {
      log::error("cannot write the outputs: ", e.what());
    }
  }

  NodeParams params_;
  std::string mode_;
  BoundedQueue<Message, 2> queue_;
  // Processing thread only, from here on.
  ImuUnitGate imu_gate_;
  std::vector<io::CloudDecodeOptions> decode_;  // per active LiDAR (written before the thread starts)
  std::vector<Stamp> last_stamp_ns_;
  pipeline::OnlinePipeline pipeline_;
  std::optional<pipeline::MapAccumulator> map_;
  Trajectory trajectory_;
  std::size_t keyframes_ = 0, degraded_ = 0;
  ros::Publisher pose_pub_, transform_pub_, cloud_pub_;
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
      case log::Level::kDebug: ROS_DEBUG_STREAM("mmlio_node: " << msg); break;
      case log::Level::kInfo: ROS_INFO_STREAM("mmlio_node: " << msg); break;
      case log::Level::kWarn: ROS_WARN_STREAM("mmlio_node: " << msg); break;
      default: ROS_ERROR_STREAM("mmlio_node: " << msg); break;
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
    const mmlio::io::RigConfig cfg = loadConfig(params);
    Node node(nh, pnh, params, cfg);
    ros::spin();  // until SIGINT / rosnode kill
    node.finish();
  } catch (const std::exception& e) {
    std::cerr << "mmlio_node: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
