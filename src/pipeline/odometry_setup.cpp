#include "mmlio/pipeline/odometry_setup.hpp"

namespace mmlio::pipeline {

std::vector<estimator::LidarSetup> lidarSetups(const config::RigConfig& cfg, const std::string& mode) {
  std::vector<estimator::LidarSetup> out;
  for (const config::LidarConfig* lidar : config::activeLidars(cfg, mode)) {
    estimator::LidarSetup s;
    s.extrinsic = config::toExtrinsic(*lidar);
    s.num_rings = lidar->num_rings;
    s.refine_online = lidar->refine_online;
    out.push_back(s);
  }
  return out;
}

}  // namespace mmlio::pipeline
