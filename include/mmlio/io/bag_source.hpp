#pragma once
// Streams a bag as time-ordered sensor events (IMU samples, decoded LiDAR scans), one message at a
// time: the bag is never loaded whole. No ROS types here. A ROS 1 bag is read through rosbag::View
// (or its chunks when its index is damaged); a ROS 2 bag — a rosbag2 folder, a .db3 or an .mcap
// file, recognised by its magic bytes — through src/io's own readers, its CDR messages decoded
// into the same messages, so everything downstream is the same.
//
// Each configured LiDAR topic may carry sensor_msgs/PointCloud2 (any driver layout, see
// cloud_decoders.hpp) or a Livox CustomMsg (livox_ros_driver[2], livox_interfaces of
// livox_ros2_driver); the type found in the bag decides.
// Topics match with or without the leading '/'.

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/io/cloud_decoders.hpp"
#include "mmlio/io/decode_stats.hpp"

namespace mmlio::io {

struct SourceLidar {
  std::string topic;
  CloudDecodeOptions decode;  // its name (decode.sensor), kind and filters; the scan period is the bag's
};

struct BagSourceOptions {
  std::string imu_topic;          // empty: no IMU stream
  std::string acc_unit = "auto";  // auto | g | m/s2; auto: mean |acc| of the first 50 messages < 3 -> g
  std::vector<SourceLidar> lidars;
};

struct SensorEvent {
  enum class Kind { kImu, kLidar } kind = Kind::kImu;
  ImuSample imu;   // kImu: acceleration already in m/s^2
  LidarScan scan;  // kLidar: scan.sensor = SourceLidar::decode.sensor; never empty
};

class BagSource {
 public:
  /// Opens and checks the bag. A truncated or unindexed bag (ROS 1 or .mcap) is read from its chunks
  /// up to the last complete message, with one warning. Throws mmlio::Error: missing file, not a bag, nothing
  /// readable (suggesting `rosbag reindex`), configured topic missing (listing the bag's topics),
  /// topic of an unexpected type.
  BagSource(const std::string& path, const BagSourceOptions& options);
  ~BagSource();
  BagSource(const BagSource&) = delete;
  BagSource& operator=(const BagSource&) = delete;

  /// Next event in bag-time order; false at the end. Scans whose points were all dropped are
  /// skipped (their drops still counted). A message that fails to deserialise is skipped,
  /// counted and logged once per topic; a read error mid-bag ends the stream with one warning.
  bool next(SensorEvent* event);

  double accScale() const;                                  // multiplier applied to raw IMU acc: 1 or 9.80665
  double progress() const;                                  // 0..1 by bag time
  Stamp beginNs() const;                                    // first message of the streamed topics (bag time)
  Stamp endNs() const;                                      // last message of the streamed topics (bag time)
  const std::map<std::string, DecodeStats>& stats() const;  // per LiDAR name
  std::size_t imuCount() const;                             // IMU samples delivered so far
  std::size_t skippedMessages() const;                      // messages that failed to deserialise
  bool truncated() const;             // unindexed/truncated bag read from its chunks, or a read error ended the stream
  std::size_t damagedChunks() const;  // damaged stretches skipped: reading went on at the next intact chunk

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mmlio::io
