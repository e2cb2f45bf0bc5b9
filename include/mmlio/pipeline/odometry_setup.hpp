#pragma once
// Translation of the rig configuration (io) into the estimator's own config structs (core).
#include <string>
#include <vector>

#include "mmlio/estimator/odometry.hpp"
#include "mmlio/io/rig_config.hpp"
#include "mmlio/pipeline/mapping_backend.hpp"

namespace mmlio::pipeline {

estimator::OdometryConfig odometryConfig(const io::RigConfig& cfg);
/// The LiDARs active in `mode`, with extrinsics from the config (after any calibration override).
std::vector<estimator::LidarSetup> lidarSetups(const io::RigConfig& cfg, const std::string& mode);
/// Loop closure and output map settings of the run (shared by `mmlio run` and the ROS node).
MappingBackend::Config mappingBackendConfig(const io::RigConfig& cfg);

}  // namespace mmlio::pipeline
