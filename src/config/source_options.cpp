#include "mmlio/config/source_options.hpp"

namespace mmlio::config {

io::BagSourceOptions bagSourceOptions(const RigConfig& cfg, const std::string& mode) {
  io::BagSourceOptions o;
  o.imu_topic = cfg.imu.topic;
  o.acc_unit = cfg.imu.acc_unit;
  for (const LidarConfig* l : activeLidars(cfg, mode)) {
    io::SourceLidar s;
    s.name = l->name;
    s.topic = l->topic;
    s.kind = l->kind();
    s.min_range_m = l->min_range_m;
    s.max_range_m = l->max_range_m;
    s.num_rings = l->num_rings;
    o.lidars.push_back(s);
  }
  return o;
}

}  // namespace mmlio::config
