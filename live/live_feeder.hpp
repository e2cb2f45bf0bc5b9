#pragma once
// What a live node does whatever carries its messages (roscpp for the ROS 1 node, DDS for the
// ROS 2 one): feeds pipeline::System, the same system `mmlio run` feeds from a bag, and turns each
// sweep into the messages every LIO node publishes.
//
// Threads: the transport's callbacks only enqueue into a bounded queue (a full queue drops the
// message and counts it); ONE processing thread decodes, feeds the System and hands the messages
// to the transport's Outlet. A slow sweep therefore never blocks the transport, and the System
// sees its input in one order. The back end runs on the System's own thread.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <boost/shared_ptr.hpp>
#include <cstddef>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bounded_queue.hpp"
#include "imu_unit_gate.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "mmlio/io/livox_msg.hpp"
#include "mmlio/pipeline/system.hpp"

namespace mmlio::live {

struct FeederOptions {
  std::string mode;                   // hvi | vi | hi; empty = the config's
  std::string out_dir;                // outputs on a save request and at finish(); empty = none
  std::string map_frame = "map";      // loop-corrected world frame (Path, map cloud)
  std::string odom_frame = "odom";    // the odometry's world frame (Odometry, registered scan)
  std::string body_frame = "imu";     // the IMU (body) frame the poses are of
  bool publish_tf = true;             // map -> odom -> body
  double map_publish_period_s = 5.0;  // map refresh (assembling it pauses the back end); 0 = never
  double point_sigma_m = 0.03;        // LiDAR point noise behind the pose covariance
  int max_queued_scans = 10;          // LiDAR messages waiting for the processing thread
  int max_queued_imu = 4000;          // IMU messages waiting (20 s at 200 Hz)
  std::string session_dir;            // localize in this saved session (docs/session.md); empty = map anew
  // With out_dir: every this many seconds of sensor time the outputs (session included) are written,
  // each file and the session folder atomically, so a crash loses at most this much (0: never).
  double autosave_period_s = 300.0;
};

/// The rig config at `config_path` (built-in defaults if empty) with its `calibration:`, or the
/// calibration file `calib_path` when given, applied, as `mmlio run` does. `config_option` and
/// `calib_option` are what the node's user sets them with ("~config", "--config"), for messages.
/// Throws mmlio::Error for `calibration: auto` (not available live).
config::RigConfig loadRigConfig(const std::string& config_path, const std::string& calib_path,
                                const std::string& config_option, const std::string& calib_option);

/// Throws mmlio::Error naming the option when the options cannot work (queues < 1, sigma <= 0,
/// frames empty or equal).
void checkOptions(const FeederOptions& o);

/// The transport's side: called on the processing thread, in sweep order.
class Outlet {
 public:
  virtual ~Outlet() = default;
  /// False while the transport shuts down: the queue is drained into the outputs, nothing published.
  virtual bool open() const = 0;
  virtual void odometry(const nav_msgs::Odometry& msg) = 0;
  virtual void transforms(const std::vector<geometry_msgs::TransformStamped>& msgs) = 0;
  /// The costlier messages are only built when someone listens.
  virtual bool wantsScan() const = 0;
  virtual void scan(const sensor_msgs::PointCloud2& msg) = 0;
  virtual bool wantsPath() const = 0;
  virtual void path(const nav_msgs::Path& msg) = 0;
  virtual bool wantsMap() const = 0;
  virtual void map(const sensor_msgs::PointCloud2& msg) = 0;
  /// Every keyframe: the input's state, and the localization's when localizing.
  virtual void diagnostics(const diagnostic_msgs::DiagnosticArray& msg) = 0;
};

class LiveFeeder {
 public:
  /// Starts the processing thread. `outlet` must outlive the feeder.
  LiveFeeder(const config::RigConfig& cfg, FeederOptions options, Outlet& outlet);
  ~LiveFeeder();
  LiveFeeder(const LiveFeeder&) = delete;
  LiveFeeder& operator=(const LiveFeeder&) = delete;

  const std::string& mode() const { return system_.mode(); }
  /// The LiDARs the mode fuses; a scan is pushed with its index in this list.
  const std::vector<const config::LidarConfig*>& lidars() const { return lidars_; }

  // Any thread; never blocks on the processing thread. False: dropped (queue full or finishing).
  bool pushImu(boost::shared_ptr<const sensor_msgs::Imu> msg);
  bool pushCloud(std::size_t lidar, boost::shared_ptr<const sensor_msgs::PointCloud2> msg);
  bool pushLivox(std::size_t lidar, boost::shared_ptr<const io::LivoxCustomMsg> msg);
  /// A ROS 2 message as DDS delivers it (CDR, rosbag2's encoding): decoded on the processing
  /// thread, so the transport's receive thread only queues it and never falls behind a burst.
  enum class Encoded { kImu, kPointCloud2, kLivox };
  bool pushCdr(Encoded kind, std::size_t lidar, std::vector<std::uint8_t> cdr);
  /// While localizing in a session: an operator's "the rig is about here" (/initialpose, rviz's
  /// "2D Pose Estimate"), in the map frame; tried at the next keyframe. Any thread. The reason it
  /// was not taken, or "".
  std::string hintPose(const geometry_msgs::PoseWithCovarianceStamped& msg);
  std::size_t droppedImu() const;
  std::size_t droppedScans() const;

  struct SaveResult {
    bool success = false;
    std::string message;
  };
  /// Has the processing thread write trajectory.tum, map.pcd and report.json into out_dir between
  /// two messages, and waits for it.
  SaveResult save();

  /// After the transport stopped: processes what is queued, flushes, finishes the back end (a last
  /// loop check) and writes the outputs. Idempotent.
  void finish();

 private:
  /// One queued item: exactly one of the pointers is set, or `cdr` holds a `kind` message. A save
  /// request carries the promise its caller waits on.
  struct Message {
    boost::shared_ptr<const sensor_msgs::Imu> imu;
    boost::shared_ptr<const sensor_msgs::PointCloud2> cloud;
    boost::shared_ptr<const io::LivoxCustomMsg> livox;
    std::shared_ptr<std::promise<std::string>> save;  // resolves to "" (written) or the error
    std::optional<geometry_msgs::PoseWithCovarianceStamped> pose_hint;
    std::size_t lidar = 0;  // index into lidars_
    std::vector<std::uint8_t> cdr;
    Encoded kind = Encoded::kImu;
  };
  void addImu(const sensor_msgs::Imu& msg);
  void addCloud(std::size_t lidar, const sensor_msgs::PointCloud2& msg);
  void addScan(LidarScan scan);
  enum QueueClass : std::size_t { kImuClass = 0, kScanClass = 1, kRequestClass = 2 };

  void run();
  void process(const Message& m);
  void onSweep(const estimator::SweepResult& r);
  /// The input's state, and the localization's when localizing, on /diagnostics.
  void publishDiagnostics(Stamp now_ns, Stamp stamp_ns);
  std::string writeOutputs();

  FeederOptions options_;
  Outlet& outlet_;
  BoundedQueue<Message, 3> queue_;
  // Processing thread only, from here on.
  ImuUnitGate imu_gate_;
  std::size_t imu_messages_ = 0;
  std::vector<const config::LidarConfig*> lidars_;
  std::vector<io::CloudDecodeOptions> decode_;  // per active LiDAR
  std::vector<Stamp> last_stamp_ns_;
  pipeline::System system_;
  std::size_t degraded_ = 0;
  std::size_t trouble_so_far_ = 0;  // drops and degraded sweeps at the last diagnostics
  Stamp last_trouble_ns_ = 0;       // when that count last grew (estimator time)
  Eigen::Quaterniond last_q_ = Eigen::Quaterniond::Identity();
  Stamp last_stamp_ns_pose_ = 0, last_map_ns_ = 0, last_save_ns_ = 0;
  bool save_due_ = false;  // an autosave, done between two messages (not inside the System's callback)
  Eigen::Isometry3d T_map_odom_ = Eigen::Isometry3d::Identity();
  bool map_odom_known_ = false;
  bool finished_ = false;
  std::thread worker_;
};

}  // namespace mmlio::live
