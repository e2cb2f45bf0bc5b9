// mmlio bench BAG: per-stage mean / p95 / p99 / max ms per sweep (the sweep loop, and the mapping
// back end on its own thread), wall-time and CPU-time real-time factors and peak memory, optionally
// over several passes of the same bag (memory must stay flat). Pin it to one core with
// `taskset -c 1 mmlio bench ...` for the single-core figures.
#include <sys/resource.h>

#include <algorithm>
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

double cpuSeconds() {  // user + system time of every thread of this process so far
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto sec = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return sec(usage.ru_utime) + sec(usage.ru_stime);
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
    const double cpu0 = cpuSeconds();
    const pipeline::RunResult r = pipeline::runBag(options);
    const double wall_s = wall.elapsedMs() * 1e-3, cpu_s = cpuSeconds() - cpu0;
    const double bag_s = r.trajectory.empty()
                             ? 0.0
                             : toSec(r.trajectory.back().stamp_ns - r.trajectory.front().stamp_ns);
    std::printf("pass %d/%d: %zu sweeps, %.1f s of bag in %.2f s wall (%.1fx real time), CPU %.2f s (%.1fx real time "
                "on one core), peak RSS %.0f MB\n",
                pass, a.repeat, r.timing.sweeps(), bag_s, wall_s, bag_s / std::max(1e-9, wall_s), cpu_s,
                bag_s / std::max(1e-9, cpu_s), peakRssMb());
    if (pass == a.repeat) {
      std::cout << "\nsweep loop (odometry; the back end's hand-off)\n" << r.timing.table();
      std::cout << "\nmapping back end (its own thread)\n" << r.backend_timing.table();
    }
  }
}

}  // namespace

void registerBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "Per-stage timing (mean / p95 / p99 / max ms per sweep), real-time factors and memory on a bag");
  cmd->add_option("bag", args->bag, "Input bag: ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3 (e.g. from `mmlio simulate`)")->required()->check(CLI::ExistingPath);
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
