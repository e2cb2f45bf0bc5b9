#include "mmlio/config/source_options.hpp"

namespace mmlio::config {

io::CloudDecodeOptions decodeOptions(const LidarConfig& lidar) {
  io::CloudDecodeOptions d;
  d.sensor = lidar.name;
  d.kind = lidar.kind();
  d.min_range_m = lidar.min_range_m;
  d.max_range_m = lidar.max_range_m;
  d.num_rings = lidar.num_rings;
  return d;
}

io::BagSourceOptions bagSourceOptions(const RigConfig& cfg, const std::string& mode) {
  io::BagSourceOptions o;
  o.imu_topic = cfg.imu.topic;
  o.acc_unit = cfg.imu.acc_unit;
  for (const LidarConfig* l : activeLidars(cfg, mode)) o.lidars.push_back({l->topic, decodeOptions(*l)});
  return o;
}

}  // namespace mmlio::config
