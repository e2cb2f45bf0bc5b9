// mmlio bench BAG: per-stage mean / p95 / p99 / max ms per sweep (the sweep loop, and the mapping
// back end on its own thread), wall-time and CPU-time real-time factors and peak memory, optionally
// over several passes of the same bag (memory must stay flat). Pin it to one core with
// `taskset -c 1 mmlio bench ...` for the single-core figures.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <vector>

#include "commands.hpp"
#include "mmlio/config/calib_file.hpp"
#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/timer.hpp"
#include "mmlio/io/session_io.hpp"
#include "mmlio/pipeline/runner.hpp"

namespace mmlio::apps {
namespace {

struct BenchArgs {
  std::string bag, config, mode, calib, curve;
  std::string session;  // localize in it instead of mapping (what a robot on yesterday's map costs)
  int repeat = 1;
  int replays = 1;
};

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux reports KiB
}

double residentMb() {  // now, not the peak: /proc/self/statm's second field, in pages
  std::ifstream statm("/proc/self/statm");
  long size_pages = 0, resident_pages = 0;
  statm >> size_pages >> resident_pages;
  return static_cast<double>(resident_pages) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

/// Per pass of a replayed bag: sweeps, mean ms per sweep and resident memory at its end, so that
/// growth with revisits and time reads off directly. Kept as sums, not per sweep: the bench must
/// not grow with the run it measures.
struct PassFigures {
  std::size_t sweeps = 0;
  double sum_ms = 0.0, rss_mb = 0.0;
};

void printPasses(const std::vector<PassFigures>& passes) {
  if (passes.size() < 2) return;
  std::printf("\npass   sweeps   mean ms per sweep (sweep loop)   resident MB at its end\n");
  for (std::size_t p = 0; p < passes.size(); ++p) {
    const PassFigures& f = passes[p];
    std::printf("%4zu %8zu %18.2f %30.0f\n", p + 1, f.sweeps, f.sweeps ? f.sum_ms / static_cast<double>(f.sweeps) : 0.0,
                f.rss_mb);
  }
}

double cpuSeconds() {  // user + system time of every thread of this process so far
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto sec = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return sec(usage.ru_utime) + sec(usage.ru_stime);
}

void bench(const BenchArgs& a) {
  pipeline::RunOptions options;
  options.bag_path = a.bag;
  if (!a.config.empty()) options.config = config::loadRigConfig(a.config);
  if (!a.calib.empty()) config::applyCalibration(options.config, config::readCalibration(a.calib));
  options.mode = a.mode;
  options.progress = false;
  options.replays = a.replays;
  if (!a.session.empty()) {
    options.session = std::make_shared<const Session>(io::readSession(a.session));
    options.session_dir = a.session;
    options.config.mapping.loop_enabled = false;  // as mmlio localize
  }
  std::ofstream curve;                    // every sweep's bag time, wall time, ms and resident MB, written as it comes
  const auto startCurve = [&curve, &a] {  // (re)started: it holds the last repeat
    curve.close();
    curve.open(a.curve);
    curve << "bag_s,wall_s,sweep_ms,rss_mb\n";
    if (!curve) throw Error("cannot write the curve to '" + a.curve + "'");
  };
  if (!a.curve.empty()) startCurve();  // a bad path fails before the run
  std::vector<PassFigures> passes;
  Stamp first_ns = 0;
  Stopwatch curve_wall;
  options.on_sweep = [&](Stamp stamp_ns, const StageTimes& times_ms, int replay) {
    if (first_ns == 0) first_ns = stamp_ns;
    double ms = 0;
    for (const auto& stage : times_ms) ms += stage.second;
    const double rss_mb = residentMb();
    if (passes.size() <= static_cast<std::size_t>(replay)) passes.resize(static_cast<std::size_t>(replay) + 1);
    PassFigures& pass = passes[static_cast<std::size_t>(replay)];
    ++pass.sweeps;
    pass.sum_ms += ms;
    pass.rss_mb = rss_mb;
    if (curve.is_open())
      curve << toSec(stamp_ns - first_ns) << ',' << curve_wall.elapsedMs() * 1e-3 << ',' << ms << ',' << rss_mb << '\n';
  };
  for (int pass = 1; pass <= a.repeat; ++pass) {
    passes.clear();
    first_ns = 0;
    curve_wall = Stopwatch();
    if (!a.curve.empty() && pass > 1) startCurve();
    Stopwatch wall;
    const double cpu0 = cpuSeconds();
    const pipeline::RunResult r = pipeline::runBag(options);
    const double wall_s = wall.elapsedMs() * 1e-3, cpu_s = cpuSeconds() - cpu0;
    const double bag_s =
        r.trajectory.empty() ? 0.0 : toSec(r.trajectory.back().stamp_ns - r.trajectory.front().stamp_ns);
    std::printf(
        "pass %d/%d: %zu sweeps, %.1f s of bag in %.2f s wall (%.1fx real time), CPU %.2f s (%.1fx real time "
        "on one core), peak RSS %.0f MB\n",
        pass, a.repeat, r.timing.sweeps(), bag_s, wall_s, bag_s / std::max(1e-9, wall_s), cpu_s,
        bag_s / std::max(1e-9, cpu_s), peakRssMb());
    if (pass == a.repeat) {
      printPasses(passes);
      if (curve.is_open() && !curve.flush()) throw Error("cannot write the curve to '" + a.curve + "'");
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
  cmd->add_option("bag", args->bag,
                  "Input bag: ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3 (e.g. from `mmlio simulate`)")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("-c,--config", args->config, "Rig config YAML (default: built-in)")->check(CLI::ExistingFile);
  cmd->add_option("-m,--mode", args->mode, "hvi | vi | hi")->check(CLI::IsMember({"hvi", "vi", "hi"}));
  cmd->add_option("--calib", args->calib,
                  "Calibration YAML overriding the config's extrinsics (as `mmlio run --calib`)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--replay", args->replays,
                  "Play the bag this many times back to back as ONE sequence (long-run memory)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--curve", args->curve,
                  "Write every sweep's bag time, wall time, ms (sweep loop) and resident MB to this CSV "
                  "(scripts/plot_bench_curve.py draws it)");
  cmd->add_option("--session", args->session,
                  "Localize in this session (OUT/session of a run) instead of mapping, as mmlio localize does")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--repeat", args->repeat, "Passes over the bag (memory must stay flat)")->check(CLI::PositiveNumber);
  cmd->callback([args] { bench(*args); });
}

}  // namespace mmlio::apps
