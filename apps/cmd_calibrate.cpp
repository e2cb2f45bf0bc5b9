// mmlio calibrate BAG: the spinning LiDAR's extrinsic (GICP against the solid-state LiDAR on the
// stationary start) and clock offset (scan-to-scan rotation vs gyroscope), written in the
// calibration format `mmlio run --calib` reads.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/pipeline/bag_calibration.hpp"

namespace mmlio::apps {
namespace {

struct CalibrateArgs {
  std::string bag, config, out = "calib.yaml";
  int frames = 10;
  bool no_time_offset = false;
};

void calibrate(const CalibrateArgs& a) {
  config::RigConfig cfg;
  if (a.config.empty())
    log::emit(log::Level::kInfo, "no --config: using the built-in defaults (same as config/hvi.yaml)");
  else
    cfg = config::loadRigConfig(a.config);
  pipeline::BagCalibrationOptions opt;
  opt.solid_frames = a.frames;
  opt.estimate_time_offset = !a.no_time_offset;
  const pipeline::BagCalibrationResult r = pipeline::calibrateBag(a.bag, cfg, opt);
  config::writeCalibration(a.out, r.calibration, r.extra);
  printCalibration(r);
  std::printf("written: %s\n", a.out.c_str());
}

}  // namespace

void printCalibration(const pipeline::BagCalibrationResult& r) {
  const Eigen::Isometry3d& T = r.calibration.at(r.spinning).T_imu_sensor;
  const Eigen::Vector3d ypr = T.rotation().eulerAngles(2, 1, 0) * 180.0 / M_PI;
  std::printf("%s -> IMU: translation (%.4f, %.4f, %.4f) m, yaw/pitch/roll (%.3f, %.3f, %.3f) deg\n",
              r.spinning.c_str(), T.translation().x(), T.translation().y(), T.translation().z(), ypr.x(), ypr.y(),
              ypr.z());
  const Eigen::Vector3d ts = 1e3 * r.translation_sigma_m, rs = r.rotation_sigma_rad * (180.0 / M_PI);
  std::printf("  +- (%.1f, %.1f, %.1f) mm, (%.3f, %.3f, %.3f) deg about the IMU's x, y, z (one sigma)\n", ts.x(),
              ts.y(), ts.z(), rs.x(), rs.y(), rs.z());
  std::printf("  %s\n", r.spatial.message.c_str());
  if (r.from_motion)
    std::printf(
        "  the still start could not tell the mount: found on the solid-state LiDAR's map of the first seconds, "
        "to centimetres or decimetres and up to a degree (the sigmas above); mmlio run refines it (online_calibration) "
        "and writes calibration_refined.yaml\n");
  if (r.temporal.ok)
    std::printf("  clock offset %.2f +- %.2f ms (t_imu = t_stamp + offset)%s%s\n", 1e3 * r.temporal.offset_s,
                1e3 * r.temporal.sigma_s,
                r.temporal.advice.empty() ? "" : "\n  uncertain: ", r.temporal.advice.c_str());
  else
    std::printf("  clock offset not estimated: %s\n",
                r.temporal.message.empty() ? "disabled" : r.temporal.message.c_str());
}

void registerCalibrateCommand(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate", "Spinning-to-solid-state LiDAR extrinsic and clock offset from a bag that starts at rest");
  cmd->add_option("bag", args->bag,
                  "Input bag (ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3): standing still for the first second, "
                  "then turning")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("-c,--config", args->config, "Rig config YAML (its extrinsics are the initial guess)")
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", args->out, "Calibration YAML to write")->capture_default_str();
  cmd->add_option("--frames", args->frames, "Solid-state frames accumulated at the start")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->add_flag("--no-time-offset", args->no_time_offset, "Keep the config's clock offsets");
  cmd->callback([args] { calibrate(*args); });
}

}  // namespace mmlio::apps
