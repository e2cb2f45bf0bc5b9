#pragma once
// Each subcommand lives in its own apps/cmd_<name>.cpp and registers itself on the app.
// Handlers throw mmlio::Error for user-facing problems; main() prints them as one line.
#include <CLI/CLI.hpp>

namespace mmlio::pipeline {
struct BagCalibrationResult;
}

namespace mmlio::apps {
void registerInfoCommand(CLI::App& app);
void registerSimulateCommand(CLI::App& app);
void registerEvaluateCommand(CLI::App& app);
void registerRunCommand(CLI::App& app);
void registerLocalizeCommand(CLI::App& app);
void registerBenchCommand(CLI::App& app);
void registerCalibrateCommand(CLI::App& app);
void registerConfigCommand(CLI::App& app);
void registerInitCommand(CLI::App& app);

/// What a calibration estimated, on stdout: the spinning LiDAR's extrinsic, the fit, the clock offset
/// (`mmlio calibrate` and `mmlio run --calib auto`).
void printCalibration(const pipeline::BagCalibrationResult& r);
}  // namespace mmlio::apps
