#include "mmlio/config/calibration_source.hpp"

#include "mmlio/config/calib_file.hpp"
#include "mmlio/core/log.hpp"

namespace mmlio::config {

std::string resolveCalibration(RigConfig& cfg, const std::string& override_source) {
  std::string source = override_source.empty() ? cfg.calibration : override_source;
  if (source == "config" || source == "auto") return source;
  for (const auto& name : applyCalibration(cfg, readCalibration(source)))
    log::emit(log::Level::kWarn, "calibration ", source, " has no entry for LiDAR '", name,
              "': keeping its extrinsic from the config");
  cfg.calibration = source;
  log::emit(log::Level::kInfo, "extrinsics and clock offsets from ", source);
  return source;
}

}  // namespace mmlio::config
