#include "mmlio/pipeline/odometry_setup.hpp"

namespace mmlio::pipeline {

std::vector<estimator::LidarSetup> lidarSetups(const io::RigConfig& cfg, const std::string& mode) {
  std::vector<estimator::LidarSetup> out;
  for (const io::LidarConfig* lidar : io::activeLidars(cfg, mode)) {
    estimator::LidarSetup s;
    s.extrinsic = io::toExtrinsic(*lidar);
    s.num_rings = lidar->num_rings;
    out.push_back(s);
  }
  return out;
}

}  // namespace mmlio::pipeline
