// mmlio bench BAG: per-stage mean / p95 ms per sweep, real-time factor and peak memory, optionally
// over several passes of the same bag (memory must stay flat).
#include <sys/resource.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/io/calib_file.hpp"
#include "mmlio/io/rig_config.hpp"
#include "mmlio/pipeline/runner.hpp"

namespace mmlio::apps {
namespace {

struct BenchArgs {
  std::string bag, config, mode, calib;
  int repeat = 1;
  int replays = 1;
};

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux reports KiB
}

void bench(const BenchArgs& a) {
  pipeline::RunOptions options;
  options.bag_path = a.bag;
  if (!a.config.empty()) options.config = io::loadRigConfig(a.config);
  if (!a.calib.empty()) io::applyCalibration(options.config, io::readCalibration(a.calib));
  options.mode = a.mode;
  options.progress = false;
  options.replays = a.replays;
  for (int pass = 1; pass <= a.repeat; ++pass) {
    Stopwatch wall;
    const pipeline::RunResult r = pipeline::runBag(options);
    const double bag_s = r.trajectory.empty()
                             ? 0.0
                             : toSec(r.trajectory.back().stamp_ns - r.trajectory.front().stamp_ns);
    std::printf("pass %d/%d: %zu sweeps, %.1f s of bag in %.2f s (%.1fx real time), peak RSS %.0f MB\n", pass,
                a.repeat, r.timing.sweeps(), bag_s, wall.elapsedMs() * 1e-3, bag_s / (wall.elapsedMs() * 1e-3),
                peakRssMb());
    if (pass == a.repeat) std::cout << '\n' << r.timing.table();
  }
}

}  // namespace

void registerBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("bench", "Per-stage timing (mean / p95 ms per sweep) and memory on a bag");
  cmd->add_option("bag", args->bag, "Input ROS1 bag (e.g. from `mmlio simulate`)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-c,--config", args->config, "Rig config YAML (default: built-in)")->check(CLI::ExistingFile);
  cmd->add_option("-m,--mode", args->mode, "hvi | vi | hi")->check(CLI::IsMember({"hvi", "vi", "hi"}));
  cmd->add_option("--calib", args->calib, "Calibration YAML overriding the config's extrinsics (as `mmlio run --calib`)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--replay", args->replays,
                  "Play the bag this many times back to back as ONE sequence (long-run memory)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--repeat", args->repeat, "Passes over the bag (memory must stay flat)")->check(CLI::PositiveNumber);
  cmd->callback([args] { bench(*args); });
}

}  // namespace mmlio::apps
