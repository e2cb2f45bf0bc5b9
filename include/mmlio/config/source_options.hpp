#pragma once
// What the bag reader and the live node's subscriptions take of a rig config: topics, units and
// each active LiDAR's decoding options.
#include <string>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/io/cloud_decoders.hpp"

namespace mmlio::config {

/// How a LiDAR's messages are decoded: its name, kind, range filter and rings (the scan period is
/// the source's to tell).
io::CloudDecodeOptions decodeOptions(const LidarConfig& lidar);

/// From activeLidars(cfg, mode) and cfg.imu.
io::BagSourceOptions bagSourceOptions(const RigConfig& cfg, const std::string& mode);

}  // namespace mmlio::config
