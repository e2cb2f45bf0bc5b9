#include "mmlio/io/bag_source.hpp"

#include <console_bridge/console.h>

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include <algorithm>
#include <boost/make_shared.hpp>
#include <cmath>
#include <limits>
#include <set>
#include <type_traits>

#include "bag_open.hpp"
#include "mmlio/io/cdr_messages.hpp"
#include "imu_unit.hpp"
#include "message_types.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "raw_bag_scanner.hpp"
#include "ros2_bag.hpp"

namespace mmlio::io {
namespace {

using detail::isCloudType;
using detail::isImuType;
using detail::isLivoxType;
constexpr const char* kPointCloud2 = detail::kPointCloud2Type;
constexpr const char* kImu = detail::kImuType;

Stamp toNs(const ros::Time& t) { return static_cast<Stamp>(t.toNSec()); }

/// A message read through the bag index.
struct IndexedMessage {
  const rosbag::MessageInstance& m;
  std::string topic() const { return m.getTopic(); }
  std::string md5() const { return m.getMD5Sum(); }
  template <class T> boost::shared_ptr<T> instantiate() const { return m.instantiate<T>(); }
};

/// A message read from the chunks of an unindexed bag.
struct ChunkMessage {
  const detail::RawMessage& m;
  const detail::RawConnection& c;
  std::string topic() const { return c.topic; }
  std::string md5() const { return c.md5sum; }
  template <class T> boost::shared_ptr<T> instantiate() const {
    if (c.md5sum != ros::message_traits::MD5Sum<T>::value()) return {};
    auto out = boost::make_shared<T>();
    ros::serialization::IStream in(const_cast<std::uint8_t*>(m.data.data()), static_cast<std::uint32_t>(m.data.size()));
    ros::serialization::deserialize(in, *out);
    return out;
  }
};

/// A CDR message of a ROS 2 bag, decoded into the ROS 1 message structs the decoders take.
struct Ros2Msg {
  const detail::Ros2Message& m;
  const detail::Ros2Topic& t;
  std::string topic() const { return t.name; }
  std::string md5() const { return t.type; }
  template <class T> boost::shared_ptr<T> instantiate() const {
    if constexpr (std::is_same_v<T, sensor_msgs::Imu>) {
      return ros2Type(t.type) == Ros2Type::kImu ? boost::make_shared<T>(decodeImuCdr(m.data)) : nullptr;
    } else if constexpr (std::is_same_v<T, sensor_msgs::PointCloud2>) {
      return ros2Type(t.type) == Ros2Type::kPointCloud2 ? boost::make_shared<T>(decodePointCloud2Cdr(m.data)) : nullptr;
    } else {
      return ros2Type(t.type) == Ros2Type::kLivox ? boost::make_shared<T>(decodeLivoxCdr(m.data)) : nullptr;
    }
  }
};

}  // namespace

struct BagSource::Impl {
  /// What one streamed topic is and how to decode it.
  struct Stream {
    enum class Type { kImu, kCloud, kLivox } type = Type::kImu;
    int lidar = -1;  // index into lidars / decode options
    std::string topic;
    std::size_t messages = 0;
    std::size_t failed = 0;
    std::size_t decoded = 0;  // clouds decoded: after the first, a bad one is a damaged message
  };

  std::string path;
  rosbag::Bag bag;
  std::unique_ptr<rosbag::View> view;
  rosbag::View::iterator it;
  // Unindexed / truncated bag: read chunk by chunk instead of through the index.
  std::unique_ptr<detail::RawBagScanner> raw;
  std::size_t raw_chunk = 0, raw_pos = 0;
  std::vector<detail::RawMessage> raw_buf;
  // ROS 2 bag (rosbag2 folder, .db3 or .mcap).
  std::unique_ptr<detail::Ros2Bag> ros2;
  std::map<std::string, Stream> streams;  // by normalised topic
  std::vector<CloudDecodeOptions> decode;
  std::map<std::string, DecodeStats> stats;
  double acc_scale = 1.0;
  Stamp begin_ns = 0, end_ns = 0, current_ns = 0;
  std::size_t imu_count = 0, skipped = 0;
  bool truncated = false, done = false;

  void checkTopics(const BagSourceOptions& o, const std::vector<std::pair<std::string, std::string>>& connections);
  void estimateScanPeriods();
  void openRaw(const BagSourceOptions& options, const std::string& why);
  void openRos2(const BagSourceOptions& options);
  template <class Msg> bool decodeMessage(const Msg& m, SensorEvent* event);
  bool nextRaw(SensorEvent* event);
  bool nextRos2(SensorEvent* event);
};

void BagSource::Impl::checkTopics(const BagSourceOptions& o,
                                  const std::vector<std::pair<std::string, std::string>>& connections) {
  // topic -> datatype; a topic recorded with several types keeps the first one we can decode.
  std::map<std::string, std::string> types;
  for (const auto& [topic, datatype] : connections) {
    std::string& t = types[detail::normalizeTopic(topic)];
    if (t.empty() || !(isImuType(t) || isCloudType(t) || isLivoxType(t))) t = datatype;
  }
  auto topicList = [&] {
    std::string out;
    for (const auto& [t, type] : types) out += (out.empty() ? "" : ", ") + t + " (" + type + ")";
    return out.empty() ? std::string("(none)") : out;
  };
  auto lookup = [&](const std::string& topic, const std::string& what) -> const std::string& {
    const auto f = types.find(detail::normalizeTopic(topic));
    if (f == types.end()) {
      throw Error("topic " + topic + " (" + what + ") is not in " + path + "; its topics: " + topicList());
    }
    return f->second;
  };
  if (!o.imu_topic.empty()) {
    const std::string& t = lookup(o.imu_topic, "IMU");
    if (!isImuType(t)) throw Error("topic " + o.imu_topic + " in " + path + " is " + t + ", expected " + kImu);
    Stream s;
    s.type = Stream::Type::kImu;
    s.topic = o.imu_topic;
    streams[detail::normalizeTopic(o.imu_topic)] = s;
  }
  for (std::size_t i = 0; i < o.lidars.size(); ++i) {
    const SourceLidar& l = o.lidars[i];
    const std::string& name = l.decode.sensor;
    const std::string key = detail::normalizeTopic(l.topic);
    if (streams.count(key)) throw Error("topic " + l.topic + " is configured twice (LiDAR '" + name + "')");
    const std::string& t = lookup(l.topic, "LiDAR '" + name + "'");
    Stream s;
    s.lidar = static_cast<int>(i);
    s.topic = l.topic;
    if (isCloudType(t))
      s.type = Stream::Type::kCloud;
    else if (isLivoxType(t)) {
      // A Livox driver's own message comes from a solid-state LiDAR: read as a spinning one, its
      // points would be given rings, scan lines and a sweep they do not have, without a word.
      if (l.decode.kind != LidarKind::kSolidState)
        throw Error("topic " + l.topic + " (LiDAR '" + name + "') in " + path + " is " + t +
                    ", a solid-state Livox LiDAR's message, but the LiDAR is declared as a spinning one: give it "
                    "type: livox (or check that the topics are not swapped)");
      s.type = Stream::Type::kLivox;
    } else
      throw Error("topic " + l.topic + " (LiDAR '" + name + "') in " + path + " is " + t + ", expected " +
                  kPointCloud2 + " or " + kLivoxCustomMsgType);
    streams[key] = s;
    decode.push_back(l.decode);
    stats[name] = DecodeStats{};
  }
}

/// Clouds without per-point time get it from the azimuth over one turn: take the turn period
/// from the topic's message rate (index only, no message is read).
void BagSource::Impl::estimateScanPeriods() {
  for (auto& [key, s] : streams) {
    if (s.lidar < 0) continue;
    rosbag::View v(bag, rosbag::TopicQuery(s.topic));
    const std::uint32_t n = v.size();
    if (n < 2) continue;
    const double span_s = (v.getEndTime() - v.getBeginTime()).toSec();
    if (span_s > 0) decode[static_cast<std::size_t>(s.lidar)].scan_period_s = std::clamp(span_s / (n - 1), 0.01, 1.0);
  }
}

BagSource::BagSource(const std::string& path, const BagSourceOptions& options) : impl_(std::make_unique<Impl>()) {
  // rosbag prints every damaged record to stderr through console_bridge; the reader counts them
  // and warns once per topic instead.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  Impl& d = *impl_;
  d.path = path;
  if (detail::ros2Format(path) != detail::Ros2Format::kNone) {
    d.openRos2(options);
    return;
  }
  std::string why;
  if (!detail::tryOpenIndexed(d.bag, path, &why)) {
    d.openRaw(options, why);
    return;
  }
  try {
    std::vector<std::pair<std::string, std::string>> connections;
    {
      rosbag::View all(d.bag);
      for (const rosbag::ConnectionInfo* c : all.getConnections()) connections.emplace_back(c->topic, c->datatype);
    }
    d.checkTopics(options, connections);
    if (d.streams.empty()) throw Error("nothing to read from " + path + ": no IMU topic and no LiDAR configured");
    d.estimateScanPeriods();
    if (!options.imu_topic.empty()) {
      d.acc_scale = imuAccScale(d.bag, options.imu_topic, options.acc_unit, path);
    }
    std::vector<std::string> topics;
    for (const auto& [key, s] : d.streams) {
      topics.push_back(s.topic);
      if (s.topic != key) topics.push_back(key);  // the bag may spell it either way
      if (s.topic.front() == '/') topics.push_back(s.topic.substr(1));
    }
    d.view = std::make_unique<rosbag::View>(d.bag, rosbag::TopicQuery(topics));
    d.begin_ns = toNs(d.view->getBeginTime());
    d.end_ns = toNs(d.view->getEndTime());
    if (d.view->size() == 0) d.begin_ns = d.end_ns = 0;
    d.current_ns = d.begin_ns;
    d.it = d.view->begin();
  } catch (const rosbag::BagException& e) {
    throw Error(detail::reindexHint(path, e.what()));
  }
}

void BagSource::Impl::openRaw(const BagSourceOptions& options, const std::string& why) {
  raw = std::make_unique<detail::RawBagScanner>(path);
  if (raw->messages() == 0) throw Error(detail::reindexHint(path, why));
  std::vector<std::pair<std::string, std::string>> connections;
  for (const auto& [id, c] : raw->connections()) connections.emplace_back(c.topic, c.datatype);
  checkTopics(options, connections);
  if (streams.empty()) throw Error("nothing to read from " + path + ": no IMU topic and no LiDAR configured");
  truncated = true;
  begin_ns = current_ns = raw->beginNs();
  end_ns = raw->endNs();
  log::warn("bag ", path, " is truncated, unindexed or damaged (", why, "): reading its ", raw->messages(),
            " complete messages (", toSec(end_ns - begin_ns), " s) from the chunks",
            raw->damagedChunks() > 0 ? ", past " + std::to_string(raw->damagedChunks()) + " damaged stretch(es)" : "",
            "; `rosbag reindex ", path, "` would restore the index");
  if (!options.imu_topic.empty()) {
    const std::string imu_key = detail::normalizeTopic(options.imu_topic);
    // The IMU messages of the chunks in order, for the unit guess.
    std::size_t chunk = 0, pos = 0;
    std::vector<detail::RawMessage> messages;
    const auto next = [&](sensor_msgs::Imu* out) {
      while (true) {
        if (pos == messages.size()) {
          if (chunk == raw->chunks().size()) return false;
          messages = raw->readChunk(chunk++);
          pos = 0;
          continue;
        }
        const detail::RawMessage& m = messages[pos++];
        const auto c = raw->connections().find(m.conn);
        if (c == raw->connections().end() || detail::normalizeTopic(c->second.topic) != imu_key) continue;
        if (const auto imu = ChunkMessage{m, c->second}.instantiate<sensor_msgs::Imu>()) {
          *out = *imu;
          return true;
        }
      }
    };
    acc_scale = imuAccScaleFromMean([&] { return meanImuAccNorm(next); }, options.imu_topic, options.acc_unit, path);
  }
}

void BagSource::Impl::openRos2(const BagSourceOptions& options) {
  ros2 = detail::openRos2Bag(path);
  const std::vector<detail::Ros2Topic>& topics = ros2->topics();
  std::vector<std::pair<std::string, std::string>> connections;
  connections.reserve(topics.size());
  for (const detail::Ros2Topic& t : topics) connections.emplace_back(t.name, t.type);
  checkTopics(options, connections);
  if (streams.empty()) throw Error("nothing to read from " + path + ": no IMU topic and no LiDAR configured");
  std::vector<std::size_t> selected;
  std::size_t imu_topic = topics.size();
  begin_ns = std::numeric_limits<Stamp>::max();
  end_ns = std::numeric_limits<Stamp>::min();
  for (std::size_t i = 0; i < topics.size(); ++i) {
    const auto s = streams.find(detail::normalizeTopic(topics[i].name));
    if (s == streams.end() || topics[i].messages == 0) continue;
    selected.push_back(i);
    begin_ns = std::min(begin_ns, topics[i].begin_ns);
    end_ns = std::max(end_ns, topics[i].end_ns);
    if (s->second.type == Stream::Type::kImu) imu_topic = i;
    // Clouds without per-point time: the turn period from the topic's message rate.
    if (s->second.lidar >= 0 && topics[i].messages >= 2 && topics[i].end_ns > topics[i].begin_ns) {
      decode[static_cast<std::size_t>(s->second.lidar)].scan_period_s = std::clamp(
          toSec(topics[i].end_ns - topics[i].begin_ns) / static_cast<double>(topics[i].messages - 1), 0.01, 1.0);
    }
  }
  if (selected.empty()) begin_ns = end_ns = 0;
  if (imu_topic < topics.size()) {
    ros2->restart({imu_topic});
    const auto next = [&](sensor_msgs::Imu* out) {
      detail::Ros2Message m;
      if (!ros2->next(&m)) return false;
      *out = decodeImuCdr(m.data);
      return true;
    };
    acc_scale = imuAccScaleFromMean([&] { return meanImuAccNorm(next); }, options.imu_topic, options.acc_unit, path);
  }
  ros2->restart(selected);
  current_ns = begin_ns;
  log::info("reading ", path, " as ", ros2->formatName());
}

bool BagSource::Impl::nextRos2(SensorEvent* event) {
  detail::Ros2Message m;
  while (ros2->next(&m)) {
    current_ns = m.time_ns;
    if (decodeMessage(Ros2Msg{m, ros2->topics()[m.topic]}, event)) return true;
  }
  return false;
}

bool BagSource::Impl::nextRaw(SensorEvent* event) {
  while (true) {
    if (raw_pos >= raw_buf.size()) {
      if (raw_chunk >= raw->chunks().size()) return false;
      raw_buf = raw->readChunk(raw_chunk++);
      raw_pos = 0;
      continue;
    }
    const detail::RawMessage& m = raw_buf[raw_pos++];
    const auto c = raw->connections().find(m.conn);
    if (c == raw->connections().end()) continue;
    current_ns = m.time_ns;
    if (decodeMessage(ChunkMessage{m, c->second}, event)) return true;
  }
}

BagSource::~BagSource() = default;

template <class Msg> bool BagSource::Impl::decodeMessage(const Msg& m, SensorEvent* event) {
  auto f = streams.find(detail::normalizeTopic(m.topic()));
  if (f == streams.end()) return false;
  Stream& s = f->second;
  const std::size_t index = s.messages++;
  try {
    switch (s.type) {
      case Stream::Type::kImu: {
        const auto msg = m.template instantiate<sensor_msgs::Imu>();
        if (!msg) throw std::runtime_error("md5 " + m.md5() + " is not sensor_msgs/Imu");
        event->kind = SensorEvent::Kind::kImu;
        event->imu = decodeImu(*msg, acc_scale);
        ++imu_count;
        return true;
      }
      case Stream::Type::kCloud:
      case Stream::Type::kLivox: {
        const auto li = static_cast<std::size_t>(s.lidar);
        DecodeStats& st = stats[decode[li].sensor];
        LidarScan scan;
        if (s.type == Stream::Type::kCloud) {
          const auto msg = m.template instantiate<sensor_msgs::PointCloud2>();
          if (!msg) throw std::runtime_error("md5 " + m.md5() + " is not sensor_msgs/PointCloud2");
          try {
            scan = decodePointCloud2(*msg, decode[li], &st);
            ++s.decoded;
          } catch (const Error& e) {
            // The topic's first cloud failing is a format the decoder cannot read: stop with why. A
            // later one (data shorter than width x point_step, ...) is one damaged message: skipped.
            if (s.decoded == 0)
              throw Error("topic " + s.topic + " message " + std::to_string(index) + " in " + path + ": " + e.what());
            ++skipped;
            if (s.failed++ == 0)
              log::warn("skipping message ", index, " of ", s.topic, " in ", path, ": ", e.what(),
                        "; further damaged messages on this topic are counted in the report");
            return false;
          }
        } else {
          const auto msg = m.template instantiate<LivoxCustomMsg>();
          if (!msg) throw std::runtime_error("md5 " + m.md5() + " is not " + kLivoxCustomMsgType);
          scan = decodeLivox(*msg, decode[li], &st);
        }
        if (scan.points.empty()) return false;
        event->kind = SensorEvent::Kind::kLidar;
        event->scan = std::move(scan);
        return true;
      }
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    // rosbag / ros::serialization failures: skip this message, tell the user once per topic.
    ++skipped;
    if (s.failed++ == 0) {
      log::warn("skipping message ", index, " of ", s.topic, " in ", path, ": cannot deserialise (", e.what(),
                "); further failures on this topic are counted silently");
    }
  }
  return false;
}

bool BagSource::next(SensorEvent* event) {
  Impl& d = *impl_;
  if (d.done || (!d.view && !d.raw && !d.ros2)) return false;
  try {
    if (d.raw || d.ros2) {
      if (d.raw ? d.nextRaw(event) : d.nextRos2(event)) return true;
      d.done = true;
      d.current_ns = d.end_ns;
      return false;
    }
    while (d.it != d.view->end()) {
      const rosbag::MessageInstance& m = *d.it;
      d.current_ns = toNs(m.getTime());
      const bool got = d.decodeMessage(IndexedMessage{m}, event);
      ++d.it;
      if (got) return true;
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    d.truncated = true;
    d.done = true;
    log::warn("stopped reading ", d.path, " at ", toSec(d.current_ns - d.begin_ns), " s of ",
              toSec(d.end_ns - d.begin_ns), " s: ", e.what(), " (damaged bag? try `rosbag reindex ", d.path, "`)");
    return false;
  }
  d.done = true;
  d.current_ns = d.end_ns;
  return false;
}

double BagSource::accScale() const { return impl_->acc_scale; }
double BagSource::progress() const {
  const Impl& d = *impl_;
  if (d.done) return 1.0;
  if (d.end_ns <= d.begin_ns) return 0.0;
  return std::clamp(static_cast<double>(d.current_ns - d.begin_ns) / static_cast<double>(d.end_ns - d.begin_ns), 0.0,
                    1.0);
}
Stamp BagSource::beginNs() const { return impl_->begin_ns; }
Stamp BagSource::endNs() const { return impl_->end_ns; }
const std::map<std::string, DecodeStats>& BagSource::stats() const { return impl_->stats; }
std::size_t BagSource::imuCount() const { return impl_->imu_count; }
std::size_t BagSource::skippedMessages() const { return impl_->skipped; }
bool BagSource::truncated() const { return impl_->truncated || (impl_->ros2 && impl_->ros2->truncated()); }
std::size_t BagSource::damagedChunks() const {
  if (impl_->ros2) return impl_->ros2->damagedStretches();
  return impl_->raw ? impl_->raw->damagedChunks() : 0;
}

}  // namespace mmlio::io
