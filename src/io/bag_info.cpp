#include "mmlio/io/bag_info.hpp"

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "bag_open.hpp"
#include "mmlio/io/cdr_messages.hpp"
#include "imu_unit.hpp"
#include "message_types.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "ros2_bag.hpp"

namespace mmlio::io {
namespace {

constexpr int kSampledMessages = 50;

// Frame names as tf2 spells them: without a leading '/'.
std::string withoutSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

const std::vector<std::string> kLivoxFields{"offset_time(uint32)", "x(float32)", "y(float32)", "z(float32)",
                                            "reflectivity(uint8)", "tag(uint8)", "line(uint8)"};

/// Fields and mean point count over the first messages of a cloud topic.
void sampleClouds(rosbag::Bag& bag, const std::vector<std::string>& names, TopicInfo& info) {
  rosbag::View view(bag, rosbag::TopicQuery(names));
  double points = 0;
  int n = 0;
  try {
    for (const rosbag::MessageInstance& m : view) {
      if (n >= kSampledMessages) break;
      if (const auto c = m.instantiate<sensor_msgs::PointCloud2>()) {
        if (info.fields.empty()) info.fields = pointFieldDescriptions(*c);
        if (n == 0) info.frame_id = withoutSlash(c->header.frame_id);
        points += static_cast<double>(c->width) * c->height;
        ++n;
      } else if (const auto l = m.instantiate<LivoxCustomMsg>()) {
        if (info.fields.empty()) info.fields = kLivoxFields;
        if (n == 0) info.frame_id = withoutSlash(l->header.frame_id);
        points += static_cast<double>(l->points.size());
        ++n;
      }
    }
  } catch (const std::exception& e) {
    log::warn("info: cannot read all sampled messages of ", info.topic, ": ", e.what());
  }
  if (n > 0) info.mean_points = points / n;
}

std::string imuFrameId(rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view)
    if (const auto imu = m.instantiate<sensor_msgs::Imu>()) return imu->header.frame_id;
  return "";
}

/// Every transform the bag's /tf_static holds (latched: usually one message at the start).
std::vector<StaticTransform> staticTransforms(rosbag::Bag& bag, const std::string& topic) {
  std::vector<StaticTransform> out;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const auto tf = m.instantiate<tf2_msgs::TFMessage>();
    if (!tf) continue;
    for (const geometry_msgs::TransformStamped& t : tf->transforms) {
      StaticTransform s;
      s.parent = withoutSlash(t.header.frame_id);
      s.child = withoutSlash(t.child_frame_id);
      const auto& r = t.transform.rotation;
      const auto& p = t.transform.translation;
      Eigen::Quaterniond q(r.w, r.x, r.y, r.z);
      if (!std::isfinite(q.norm()) || q.norm() < 1e-6) continue;
      s.T_parent_child.linear() = q.normalized().toRotationMatrix();
      s.T_parent_child.translation() = Eigen::Vector3d(p.x, p.y, p.z);
      out.push_back(std::move(s));
    }
  }
  return out;
}

BagInfo describeRos2Bag(const std::string& path) {
  BagInfo info;
  info.path = path;
  const auto bag = detail::openRos2Bag(path);
  info.format = bag->formatName();
  bool any = false;
  for (std::size_t i = 0; i < bag->topics().size(); ++i) {
    const detail::Ros2Topic& r = bag->topics()[i];
    TopicInfo t;
    t.topic = r.name;
    t.type = r.type;
    t.messages = r.messages;
    if (r.messages > 0) {
      info.begin_ns = any ? std::min(info.begin_ns, r.begin_ns) : r.begin_ns;
      info.end_ns = any ? std::max(info.end_ns, r.end_ns) : r.end_ns;
      any = true;
    }
    if (r.messages >= 2 && r.end_ns > r.begin_ns)
      t.rate_hz = static_cast<double>(r.messages - 1) / toSec(r.end_ns - r.begin_ns);
    const Ros2Type type = ros2Type(r.type);
    if (type == Ros2Type::kImu && r.messages > 0 && info.imu_unit_guess.empty()) {
      bag->restart({i});
      const auto next = [&](sensor_msgs::Imu* out) {
        detail::Ros2Message m;
        if (!bag->next(&m)) return false;
        *out = decodeImuCdr(m.data);
        return true;
      };
      info.imu_unit_guess = imuUnitFromMeanAcc(meanImuAccNorm(next, kSampledMessages));
    } else if (type != Ros2Type::kOther && type != Ros2Type::kImu && r.messages > 0) {
      bag->restart({i});
      detail::Ros2Message m;
      double points = 0;
      int n = 0;
      while (n < kSampledMessages && bag->next(&m)) {
        try {
          if (type == Ros2Type::kPointCloud2) {
            const auto c = decodePointCloud2Cdr(m.data);
            if (t.fields.empty()) t.fields = pointFieldDescriptions(c);
            points += static_cast<double>(c.width) * c.height;
          } else {
            if (t.fields.empty()) t.fields = kLivoxFields;
            points += static_cast<double>(decodeLivoxCdr(m.data).points.size());
          }
          ++n;
        } catch (const std::exception& e) {
          log::warn("info: cannot decode a sampled message of ", r.name, ": ", e.what());
          break;
        }
      }
      if (n > 0) t.mean_points = points / n;
    }
    info.topics.push_back(std::move(t));
  }
  std::sort(info.topics.begin(), info.topics.end(),
            [](const TopicInfo& a, const TopicInfo& b) { return a.topic < b.topic; });
  return info;
}

}  // namespace

BagInfo describeBag(const std::string& path) {
  if (detail::ros2Format(path) != detail::Ros2Format::kNone) return describeRos2Bag(path);
  BagInfo info;
  info.path = path;
  info.format = "ROS 1 bag";
  rosbag::Bag bag;
  detail::openBagForReading(bag, path);
  try {
    rosbag::View all(bag);
    if (all.size() > 0) {
      info.begin_ns = static_cast<Stamp>(all.getBeginTime().toNSec());
      info.end_ns = static_cast<Stamp>(all.getEndTime().toNSec());
    }
    std::map<std::string, std::string> types;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      if (!types.count(c->topic)) types[c->topic] = c->datatype;
    }
    for (const auto& [topic, type] : types) {
      TopicInfo t;
      t.topic = topic;
      t.type = type;
      rosbag::View v(bag, rosbag::TopicQuery(topic));
      t.messages = v.size();
      if (t.messages >= 2) {
        const double span_s = (v.getEndTime() - v.getBeginTime()).toSec();
        if (span_s > 0) t.rate_hz = static_cast<double>(t.messages - 1) / span_s;
      }
      if (detail::isCloudType(type) || detail::isLivoxType(type)) {
        sampleClouds(bag, {topic}, t);
      }
      if (detail::isImuType(type)) {
        if (info.imu_unit_guess.empty()) info.imu_unit_guess = guessImuUnit(bag, topic);
        t.frame_id = withoutSlash(imuFrameId(bag, topic));
      }
      if (type == "tf2_msgs/TFMessage" && withoutSlash(topic) == "tf_static")
        info.static_transforms = staticTransforms(bag, topic);
      info.topics.push_back(std::move(t));
    }
  } catch (const rosbag::BagException& e) {
    throw Error("cannot read bag " + path + " (" + e.what() + "): it may be truncated; try `rosbag reindex " + path +
                "`");
  }
  return info;
}

std::string formatBagInfo(const BagInfo& info) {
  std::string out;
  char line[512];
  const double duration_s = toSec(info.end_ns - info.begin_ns);
  std::snprintf(line, sizeof(line), "bag       %s\nformat    %s\nduration  %.3f s (%.3f .. %.3f)\n", info.path.c_str(),
                info.format.c_str(), duration_s, toSec(info.begin_ns), toSec(info.end_ns));
  out += line;
  std::size_t tw = 5, yw = 4;
  for (const TopicInfo& t : info.topics) {
    tw = std::max(tw, t.topic.size());
    yw = std::max(yw, t.type.size());
  }
  std::snprintf(line, sizeof(line), "%-*s  %-*s  %8s  %8s  %10s\n", static_cast<int>(tw), "topic", static_cast<int>(yw),
                "type", "messages", "rate Hz", "points/msg");
  out += line;
  for (const TopicInfo& t : info.topics) {
    char pts[32] = "";
    if (t.mean_points > 0 || !t.fields.empty()) std::snprintf(pts, sizeof(pts), "%.0f", t.mean_points);
    std::snprintf(line, sizeof(line), "%-*s  %-*s  %8zu  %8.2f  %10s\n", static_cast<int>(tw), t.topic.c_str(),
                  static_cast<int>(yw), t.type.c_str(), t.messages, t.rate_hz, pts);
    out += line;
    if (!t.fields.empty()) {
      std::string f;
      for (const std::string& s : t.fields) f += (f.empty() ? "" : " ") + s;
      out += std::string(tw + 2, ' ') + "fields: " + f + "\n";
    }
  }
  out += "IMU acceleration unit (guess): " +
         (info.imu_unit_guess.empty() ? std::string("no readable sensor_msgs/Imu topic") : info.imu_unit_guess) + "\n";
  return out;
}

}  // namespace mmlio::io
