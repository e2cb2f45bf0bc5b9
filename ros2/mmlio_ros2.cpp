// mmlio_ros2: the live node on ROS 2, without a ROS 2 installation. live/live_feeder.hpp does the
// work (the System `mmlio run` feeds from a bag, the messages, the outputs), as in the ROS 1 node;
// this file is its DDS transport: a Fast DDS participant that reads the drivers' topics and writes
// the node's under ROS 2's names, types and QoS (ros2_wire.hpp, dds_transport.hpp).
#include <CLI/CLI.hpp>
#include <csignal>
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <condition_variable>
#include <deque>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

#include "dds_transport.hpp"
#include "live_feeder.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/cdr_messages.hpp"
#include "ros2_wire.hpp"

namespace mmlio::ros2 {
namespace {

constexpr const char* kDescription =
    "Live multi-LiDAR-inertial odometry and mapping on ROS 2 (Humble, Jazzy: DDS domain ROS_DOMAIN_ID).\n"
    "Reads the rig config's IMU (sensor_msgs/msg/Imu) and LiDAR topics (sensor_msgs/msg/PointCloud2,\n"
    "livox_ros_driver2/msg/CustomMsg); publishes /NAME/odometry (nav_msgs/msg/Odometry), /NAME/path\n"
    "(nav_msgs/msg/Path, corrected by loops, transient local), /tf (map -> odom -> body),\n"
    "/NAME/cloud_registered and /NAME/map (sensor_msgs/msg/PointCloud2, the map transient local);\n"
    "the /NAME/save_map service (std_srvs/srv/Trigger) writes trajectory.tum, map.pcd and report.json\n"
    "into --out-dir, as does Ctrl-C. See ros2/README.md.";

struct Options {
  std::string config, calib, name = "mmlio";
  std::string livox_type = "livox_ros_driver2/msg/CustomMsg";
  std::string transport = "udp";
  live::FeederOptions feeder;
  bool no_tf = false;
};

/// The feeder's messages onto DDS writers under ROS 2's names.
class DdsOutlet : public live::Outlet {
 public:
  DdsOutlet(DdsParticipant& dds, const std::string& node)
      : odometry_(
            dds.writer(topicOnWire("/" + node + "/odometry"), typeOnWire("nav_msgs/msg/Odometry"), reliableQos(100))),
        path_(dds.writer(topicOnWire("/" + node + "/path"), typeOnWire("nav_msgs/msg/Path"), latchedQos())),
        scan_(dds.writer(topicOnWire("/" + node + "/cloud_registered"), typeOnWire("sensor_msgs/msg/PointCloud2"),
                         reliableQos(2))),
        map_(dds.writer(topicOnWire("/" + node + "/map"), typeOnWire("sensor_msgs/msg/PointCloud2"), latchedQos())),
        tf_(dds.writer(topicOnWire("/tf"), typeOnWire("tf2_msgs/msg/TFMessage"), reliableQos(100))),
        diagnostics_(dds.writer(topicOnWire("/diagnostics"), typeOnWire("diagnostic_msgs/msg/DiagnosticArray"),
                                reliableQos(10))) {}

  void close() { open_ = false; }
  bool open() const override { return open_; }
  void odometry(const nav_msgs::Odometry& msg) override { odometry_.write(encode(msg)); }
  void transforms(const std::vector<geometry_msgs::TransformStamped>& msgs) override {
    tf2_msgs::TFMessage m;
    m.transforms = msgs;
    tf_.write(encode(m));
  }
  bool wantsScan() const override { return scan_.matched() > 0; }
  void scan(const sensor_msgs::PointCloud2& msg) override { scan_.write(encode(msg)); }
  // Built only for a reader (the map costs a pause of the back end); transient local gives a
  // late rviz2 the last one written.
  bool wantsPath() const override { return path_.matched() > 0; }
  void path(const nav_msgs::Path& msg) override { path_.write(encode(msg)); }
  bool wantsMap() const override { return map_.matched() > 0; }
  void map(const sensor_msgs::PointCloud2& msg) override { map_.write(encode(msg)); }
  void diagnostics(const diagnostic_msgs::DiagnosticArray& msg) override { diagnostics_.write(encode(msg)); }

 private:
  std::atomic<bool> open_{true};
  DdsParticipant::Writer &odometry_, &path_, &scan_, &map_, &tf_, &diagnostics_;
};

/// Answers save_map requests on a thread of its own: saving waits for the processing thread, and
/// DDS's listener thread must keep delivering the sensors meanwhile.
class SaveService {
 public:
  SaveService(DdsParticipant& dds, const std::string& node, live::LiveFeeder& feeder)
      : feeder_(feeder),
        reply_(dds.writer(replyTopicOnWire("/" + node + "/save_map"), typeOnWire("std_srvs/srv/Trigger_Response"),
                          reliableQos(10))) {
    dds.requestReader(requestTopicOnWire("/" + node + "/save_map"), typeOnWire("std_srvs/srv/Trigger_Request"),
                      reliableQos(10), [this](Cdr&&, const SampleIdentity& id) {
                        const std::lock_guard<std::mutex> lock(mutex_);
                        requests_.push_back(id);
                        wake_.notify_one();
                      });
    thread_ = std::thread([this] { run(); });
  }
  ~SaveService() { stop(); }
  void stop() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      wake_.notify_one();
    }
    if (thread_.joinable()) thread_.join();
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [this] { return stopping_ || !requests_.empty(); });
      if (stopping_) return;
      const SampleIdentity id = requests_.front();
      requests_.pop_front();
      lock.unlock();
      const live::LiveFeeder::SaveResult r = feeder_.save();
      log::info("save_map: ", r.message);
      reply_.writeReply(encodeTriggerReply(r.success, r.message), id);
      lock.lock();
    }
  }

  live::LiveFeeder& feeder_;
  DdsParticipant::Writer& reply_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<SampleIdentity> requests_;
  bool stopping_ = false;
  std::thread thread_;
};

/// ROS 2 node names: a letter or underscore, then letters, digits and underscores.
void checkNodeName(const std::string& name) {
  const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])) || !std::all_of(name.begin(), name.end(), word))
    throw Error("--name '" + name + "' is not a ROS 2 node name (letters, digits and '_', not starting with a digit)");
}

/// A VLP-16 sweep is 0.9 MB, an Ouster's several: a receive buffer below two such bursts drops
/// clouds whenever the receive thread is a moment late.
void warnOnSmallReceiveBuffer(const Transport& t) {
  constexpr std::uint32_t kNeeded = 2u << 20;
  const std::uint32_t granted = grantedReceiveBuffer(t.socket_buffer_bytes);
  if (granted != 0 && granted < kNeeded)
    log::warn("the kernel caps UDP receive buffers at ", granted, " bytes (net.core.rmem_max): point clouds ",
              "will be lost; raise it, e.g. sudo sysctl -w net.core.rmem_max=", t.socket_buffer_bytes);
}

void subscribe(DdsParticipant& dds, live::LiveFeeder& feeder, const config::RigConfig& cfg, const Options& o) {
  using Encoded = live::LiveFeeder::Encoded;
  // Best effort readers: they match the drivers' sensor-data writers and reliable ones alike.
  dds.reader(topicOnWire(cfg.imu.topic), typeOnWire("sensor_msgs/msg/Imu"), Qos{false, false, 100},
             [&feeder](Cdr&& m) { feeder.pushCdr(Encoded::kImu, 0, std::move(m)); });
  log::info("mode ", feeder.mode(), ", IMU ", cfg.imu.topic, " (sensor_msgs/msg/Imu, acc unit ", cfg.imu.acc_unit, ")");
  for (std::size_t i = 0; i < feeder.lidars().size(); ++i) {
    const config::LidarConfig& l = *feeder.lidars()[i];
    const bool livox = l.type == "livox";
    const std::string type = livox ? o.livox_type : "sensor_msgs/msg/PointCloud2";
    const Encoded kind = livox ? Encoded::kLivox : Encoded::kPointCloud2;
    dds.reader(topicOnWire(l.topic), typeOnWire(type), Qos{false, false, 10},
               [&feeder, i, kind](Cdr&& m) { feeder.pushCdr(kind, i, std::move(m)); });
    log::info("LiDAR '", l.name, "' on ", l.topic, " (", type, ")");
  }
  if (o.feeder.session_dir.empty()) return;
  // Where rviz2's "2D Pose Estimate" publishes.
  dds.reader(topicOnWire("/initialpose"), typeOnWire("geometry_msgs/msg/PoseWithCovarianceStamped"),
             Qos{false, false, 2}, [&feeder](Cdr&& m) {
               try {
                 const std::string refused = feeder.hintPose(io::decodePoseWithCovarianceStampedCdr(m));
                 if (!refused.empty()) log::warn("/initialpose ignored: ", refused);
               } catch (const std::exception& e) {
                 log::warn("/initialpose ignored: ", e.what());
               }
             });
  log::info("localizing in ", o.feeder.session_dir, "; pose hints on /initialpose, status on /diagnostics");
}

int run(const Options& o, const sigset_t& stop_signals) {
  const config::RigConfig cfg = live::loadRigConfig(o.config, o.calib, "--config", "--calib");
  Transport transport;
  transport.kind = transportKind(o.transport);
  if (transport.kind != Transport::Kind::kFastDdsDefault) warnOnSmallReceiveBuffer(transport);
  auto dds = std::make_unique<DdsParticipant>(domainIdFromEnvironment(), o.name, transport);
  DdsOutlet outlet(*dds, o.name);
  live::LiveFeeder feeder(cfg, o.feeder, outlet);
  SaveService service(*dds, o.name, feeder);
  subscribe(*dds, feeder, cfg, o);
  log::info("running as /", o.name, " in DDS domain ", domainIdFromEnvironment(),
            "; Ctrl-C stops and writes the outputs");
  int signal = 0;
  sigwait(&stop_signals, &signal);
  log::info("stopping (signal ", signal, ")");
  outlet.close();
  service.stop();
  feeder.finish();  // what is queued, the last loop check, the outputs
  dds.reset();      // no reader calls into the feeder after this
  return 0;
}

}  // namespace
}  // namespace mmlio::ros2

int main(int argc, char** argv) {
  using namespace mmlio;
  ros2::Options o;
  live::FeederOptions& f = o.feeder;
  CLI::App app(ros2::kDescription, "mmlio_ros2");
  app.add_option("-c,--config", o.config, "Rig config YAML (default: built-in, as config/hvi.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("-m,--mode", f.mode, "hvi | vi | hi (default: the config's)")
      ->check(CLI::IsMember({"hvi", "vi", "hi"}));
  app.add_option("--calib", o.calib, "Calibration YAML from `mmlio calibrate`, overriding the config's extrinsics")
      ->check(CLI::ExistingFile);
  app.add_option("-o,--out-dir", f.out_dir, "Where save_map and Ctrl-C write trajectory.tum, map.pcd, report.json");
  app.add_option("--autosave", f.autosave_period_s,
                 "With --out-dir: seconds between autosaves of the outputs and the session (0: never)")
      ->capture_default_str();
  app.add_option("--session", f.session_dir, "Localize in this saved session (OUT/session of a run) instead of mapping")
      ->check(CLI::ExistingDirectory);
  app.add_option("--name", o.name, "Node name: the namespace of its topics and service")->capture_default_str();
  app.add_option("--livox-type", o.livox_type,
                 "ROS 2 type of the Livox topics: livox_ros_driver2/msg/CustomMsg or "
                 "livox_interfaces/msg/CustomMsg (livox_ros2_driver)")
      ->capture_default_str();
  app.add_option("--map-frame", f.map_frame, "Loop-corrected world frame (Path, map)")->capture_default_str();
  app.add_option("--odom-frame", f.odom_frame, "The odometry's world frame")->capture_default_str();
  app.add_option("--body-frame", f.body_frame, "The IMU (body) frame")->capture_default_str();
  app.add_option("--transport", o.transport,
                 "udp: UDP with 8 MB socket buffers (drivers on any host, on Fast DDS's defaults); shm: shared "
                 "memory with 32 MB segments, UDP as udp; default: Fast DDS's own (loses some 0.9 MB clouds); "
                 "see ros2/README.md")
      ->check(CLI::IsMember({"udp", "shm", "default"}))
      ->capture_default_str();
  app.add_flag("--no-tf", o.no_tf, "Do not publish map -> odom -> body on /tf");
  app.add_option("--map-period", f.map_publish_period_s, "Seconds between map publications (0: never)")
      ->capture_default_str();
  app.add_option("--point-sigma", f.point_sigma_m, "LiDAR point noise behind the pose covariance, m")
      ->capture_default_str();
  app.add_option("--max-queued-scans", f.max_queued_scans, "LiDAR messages waiting for the processing thread")
      ->capture_default_str();
  app.add_option("--max-queued-imu", f.max_queued_imu, "IMU messages waiting")->capture_default_str();
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "Print debug messages");
  app.add_flag("-q,--quiet", quiet, "Print warnings and errors only");
  CLI11_PARSE(app, argc, argv);
  f.publish_tf = !o.no_tf;
  log::configure(verbose ? log::Level::kDebug : quiet ? log::Level::kWarn : log::Level::kInfo);

  // SIGINT and SIGTERM are taken by sigwait in main only: blocked before any thread (DDS's
  // included) starts, so each thread inherits the mask.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  try {
    ros2::checkNodeName(o.name);
    return ros2::run(o, stop_signals);
  } catch (const std::exception& e) {
    std::cerr << "mmlio_ros2: " << e.what() << "\n";
    return 1;
  }
}
