#pragma once
// The rig's LiDARs as the estimator sees them.
#include <string>
#include <vector>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/estimator/odometry.hpp"

namespace mmlio::pipeline {

/// The LiDARs active in `mode`, with extrinsics from the config (after any calibration override).
std::vector<estimator::LidarSetup> lidarSetups(const config::RigConfig& cfg, const std::string& mode);

}  // namespace mmlio::pipeline
