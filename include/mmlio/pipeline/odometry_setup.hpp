#pragma once
// Translation of the rig configuration (io) into the estimator's own config structs (core).
#include <string>
#include <vector>

#include "mmlio/estimator/odometry.hpp"
#include "mmlio/io/rig_config.hpp"

namespace mmlio::pipeline {

estimator::OdometryConfig odometryConfig(const io::RigConfig& cfg);
/// The LiDARs active in `mode`, with extrinsics from the config (after any calibration override).
std::vector<estimator::LidarSetup> lidarSetups(const io::RigConfig& cfg, const std::string& mode);

}  // namespace mmlio::pipeline
