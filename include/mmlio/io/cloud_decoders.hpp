#pragma once
// Stateless decoding of ROS messages into core types (io/ edge; ROS headers allowed here).
//
// PointCloud2 is read generically through its PointField offsets and datatypes, so any driver
// layout works. Per-point time, by the first field found:
//   `time`       float32/float64 s relative to header.stamp, may be negative (Velodyne);
//                values > 1e6 are taken as absolute s
//   `t`          uint32 ns relative to header.stamp (Ouster)
//   `timestamp`  float64 absolute s (Hesai); values < 1e6 are taken as relative s
//   none         from the azimuth, LOAM style: a clockwise turn of scan_period_s from the first point
// Ring: `ring` (any integer type); without it, from the elevation, num_rings evenly over -15..+15 deg.
// Intensity: `intensity`, else `reflectivity`, else 0.
//
// Output LidarScan: points sorted by time, start_ns = absolute time of the earliest kept point,
// time_s >= 0 relative to it, sensor = options.sensor. NaN/inf, all-zero and out-of-range
// points are dropped and counted.

#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstddef>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/io/decode_stats.hpp"
#include "mmlio/io/livox_msg.hpp"

namespace mmlio::io {

struct CloudDecodeOptions {
  std::string sensor;  // copied into LidarScan::sensor
  LidarKind kind = LidarKind::kSpinning;
  double min_range_m = 0.5;    // closer returns are dropped
  double max_range_m = 100.0;  // farther returns are dropped
  int num_rings = 16;          // rings assumed when the cloud has no `ring` field
  double scan_period_s = 0.1;  // one turn, for times from the azimuth (no time field)
};

/// Throws mmlio::Error when the cloud lacks x/y/z or its data is shorter than its size says.
LidarScan decodePointCloud2(const sensor_msgs::PointCloud2& msg, const CloudDecodeOptions& o,
                            DecodeStats* stats = nullptr);
/// Point time = timebase + offset_time (header.stamp when timebase is 0); line -> ring,
/// reflectivity -> intensity.
LidarScan decodeLivox(const LivoxCustomMsg& msg, const CloudDecodeOptions& o, DecodeStats* stats = nullptr);
/// stamp = header.stamp; linear_acceleration multiplied by acc_scale (9.80665 for a g-unit IMU).
ImuSample decodeImu(const sensor_msgs::Imu& msg, double acc_scale);

/// "x:float32@0 y:float32@4 ..." style names of the fields, in message order: "name(type)".
std::vector<std::string> pointFieldDescriptions(const sensor_msgs::PointCloud2& msg);

}  // namespace mmlio::io
