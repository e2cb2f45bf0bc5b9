#pragma once
// Where a run's extrinsics and clock offsets come from: the rig config's `calibration:` or a
// command-line / node parameter that overrides it. One rule for `mmlio run` and the live node.
#include <string>

#include "mmlio/config/rig_config.hpp"

namespace mmlio::config {

/// The source is `override_source` when set, else cfg.calibration. "config" keeps the config's
/// extrinsics; a calibration file is read and applied here (a LiDAR it does not cover keeps its
/// extrinsic from the config, with a warning) and recorded in cfg.calibration; "auto" is left to
/// the caller, who calibrates on the data. Returns the source.
std::string resolveCalibration(RigConfig& cfg, const std::string& override_source);

}  // namespace mmlio::config
