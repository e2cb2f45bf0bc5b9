#include "mmlio/io/rig_starter.hpp"

#include <cstdio>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "message_types.hpp"
#include "mmlio/core/error.hpp"

namespace mmlio::io {
namespace {

bool hasField(const TopicInfo& t, const std::string& name) {
  for (const std::string& f : t.fields)
    if (f == name || f.rfind(name + "(", 0) == 0) return true;
  return false;
}

std::string rate(const TopicInfo& t) {
  char text[96];
  if (t.mean_points > 0)
    std::snprintf(text, sizeof text, "%.1f Hz, %zu messages, %.0f points each", t.rate_hz, t.messages, t.mean_points);
  else
    std::snprintf(text, sizeof text, "%.1f Hz, %zu messages", t.rate_hz, t.messages);
  return text;
}

struct Lidar {
  std::string name, type, topic, what, why, frame;
  int rings = 16;
  std::string rings_note, extrinsic, extrinsic_note;
};

// The driver a PointCloud2 comes from, told by its per-point time field.
Lidar spinningLidar(const TopicInfo& t) {
  Lidar l;
  l.topic = t.topic;
  l.what = rate(t);
  l.frame = t.frame_id;
  const bool ring = hasField(t, "ring");
  if (ring && hasField(t, "time")) {
    l.type = "velodyne";
    l.why = "PointCloud2 with ring and time fields: the Velodyne driver's layout";
    l.rings_note = "CHECK: 16 for a VLP-16 / Puck, 32 or 128 for the larger ones";
  } else if (ring && hasField(t, "t")) {
    l.type = "ouster";
    l.why = "PointCloud2 with ring and t fields: the Ouster driver's layout";
    l.rings = 64;
    l.rings_note = "CHECK: the sensor's beams (OS0/OS1/OS2: 32, 64 or 128)";
  } else if (ring && hasField(t, "timestamp")) {
    l.type = "hesai";
    l.why = "PointCloud2 with ring and timestamp fields: the Hesai driver's layout";
    l.rings = 32;
    l.rings_note = "CHECK: the sensor's channels (XT32: 32, Pandar64: 64)";
  } else {
    l.type = "generic_spinning";
    l.why = std::string("PointCloud2 without ") + (ring ? "a time field" : "ring and time fields") +
            ": time from the azimuth, ring from the elevation";
    l.rings_note = "CHECK: the sensor's rings; elevations are binned into this many";
  }
  l.extrinsic = "{xyz: [0.0, 0.0, 0.0], rpy_deg: [0.0, 0.0, 0.0]}";
  l.extrinsic_note = "CHECK: not in the bag; measure it, or run `mmlio calibrate` with the solid-state LiDAR";
  return l;
}

Lidar solidStateLidar(const TopicInfo& t) {
  Lidar l;
  l.topic = t.topic;
  l.what = rate(t);
  l.frame = t.frame_id;
  l.type = "livox";
  l.why = t.type + ": a Livox solid-state LiDAR";
  l.rings = 6;
  l.rings_note = "CHECK: scan lines, 6 for a Horizon or an Avia";
  l.extrinsic = "{xyz: [0.05512, 0.02226, -0.0297], rpy_deg: [0.0, 0.0, 0.0]}";
  l.extrinsic_note = "a Livox Horizon's factory LiDAR-to-IMU extrinsic: CHECK for another model or an external IMU";
  return l;
}

/// T_to_from through the static transform tree (either direction of each edge), if connected.
std::optional<Eigen::Isometry3d> chain(const std::vector<StaticTransform>& tfs, const std::string& to,
                                       const std::string& from) {
  if (to.empty() || from.empty()) return std::nullopt;
  std::map<std::string, Eigen::Isometry3d> T_to;  // T_to_frame of every frame reached
  T_to[to] = Eigen::Isometry3d::Identity();
  std::deque<std::string> open{to};
  while (!open.empty()) {
    const std::string f = open.front();
    open.pop_front();
    if (f == from) return T_to[f];
    for (const StaticTransform& t : tfs) {
      if (t.parent == f && !T_to.count(t.child)) {
        T_to[t.child] = T_to[f] * t.T_parent_child;
        open.push_back(t.child);
      } else if (t.child == f && !T_to.count(t.parent)) {
        T_to[t.parent] = T_to[f] * t.T_parent_child.inverse();
        open.push_back(t.parent);
      }
    }
  }
  return std::nullopt;
}

std::string xyzQuaternion(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  char text[256];
  std::snprintf(text, sizeof text, "{xyz: [%.6f, %.6f, %.6f], quaternion: [%.9f, %.9f, %.9f, %.9f]}",
                T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w());
  return text;
}

// Unique names: the type for the first of its kind, then type_2, type_3 ...
void name(std::vector<Lidar>& lidars) {
  std::set<std::string> used;
  for (Lidar& l : lidars) {
    const std::string base = l.type == "generic_spinning" ? "spinning" : l.type;
    l.name = base;
    for (int k = 2; used.count(l.name); ++k) l.name = base + "_" + std::to_string(k);
    used.insert(l.name);
  }
}

}  // namespace

std::string starterRigConfig(const BagInfo& info) {
  std::vector<const TopicInfo*> imus;
  std::vector<Lidar> spinning, solid;
  for (const TopicInfo& t : info.topics) {
    // The types the bag reader takes, no others: a guess it would refuse helps nobody.
    if (detail::isImuType(t.type))
      imus.push_back(&t);
    else if (detail::isCloudType(t.type))
      spinning.push_back(spinningLidar(t));
    else if (detail::isLivoxType(t.type))
      solid.push_back(solidStateLidar(t));
  }
  if (imus.empty()) throw Error(info.path + " has no sensor_msgs/Imu topic: mmlio needs an IMU");
  if (spinning.empty() && solid.empty())
    throw Error(info.path + " has no point-cloud topic (sensor_msgs/PointCloud2 or a Livox CustomMsg)");
  // The IMU with the most samples per second: a LiDAR's built-in IMU (Livox: 200 Hz) over a
  // vehicle's slower one.
  const TopicInfo* imu = imus.front();
  for (const TopicInfo* t : imus)
    if (t->rate_hz > imu->rate_hz) imu = t;
  std::vector<Lidar> lidars = spinning;
  lidars.insert(lidars.end(), solid.begin(), solid.end());
  name(lidars);
  // Extrinsics the bag's /tf_static gives: the IMU's frame to each LiDAR's.
  const std::string& imu_frame = imu->frame_id;
  for (Lidar& l : lidars) {
    if (info.static_transforms.empty()) continue;
    if (const auto T = chain(info.static_transforms, imu_frame, l.frame)) {
      l.extrinsic = xyzQuaternion(*T);
      l.extrinsic_note =
          "from /tf_static: " + l.frame + " in " + imu_frame + "; CHECK it is the mount, not a placeholder";
    } else {
      l.extrinsic_note += " (/tf_static does not connect '" + imu_frame + "' and '" + l.frame + "')";
    }
  }
  const std::string mode = !spinning.empty() && !solid.empty() ? "hvi" : (!spinning.empty() ? "vi" : "hi");
  const std::string reference = lidars.front().name;

  std::ostringstream y;
  y << "# mmlio rig config for " << info.path << ", written by `mmlio init`.\n"
    << "# Only what differs from the defaults (`mmlio config --dump-defaults` lists every key with its\n"
    << "# meaning); `mmlio config THIS_FILE` checks it. Read every line marked CHECK.\n";
  y << "mode: " << mode << "  # "
    << (mode == "hvi"
            ? "a spinning and a solid-state LiDAR: fused (vi: the spinning one alone, hi: the solid-state one)"
        : mode == "vi" ? "only spinning LiDARs in the bag"
                       : "only solid-state LiDARs in the bag")
    << "\n";
  y << "reference_lidar: " << reference << "  # its sweeps define the fusion window\n";
  y << "imu:\n  topic: " << imu->topic << "  # " << rate(*imu);
  if (imus.size() > 1) {
    y << "; the fastest of";
    for (const TopicInfo* t : imus) y << " " << t->topic;
  }
  y << "\n";
  if (!info.imu_unit_guess.empty())
    y << "  # accelerations read as " << info.imu_unit_guess
      << " at the bag's start; acc_unit: auto (the default) detects it again at every run\n";
  y << "lidars:\n";
  for (const Lidar& l : lidars) {
    y << "  - name: " << l.name << "\n"
      << "    type: " << l.type << "  # " << l.why << "\n"
      << "    topic: " << l.topic << "  # " << l.what << "\n"
      << "    num_rings: " << l.rings << "  # " << l.rings_note << "\n"
      << "    T_imu_sensor: " << l.extrinsic << "  # " << l.extrinsic_note << "\n";
  }
  return y.str();
}

}  // namespace mmlio::io
