// Corrupt input is dropped before the estimator: one NaN IMU value, one of 1.8e109 (random bytes read
// as a double), one IMU or LiDAR stamp in the year 2106 must not poison what comes after it; an
// unusable output folder is refused before any work.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <thread>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/io/session_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/pipeline/imu_gate.hpp"
#include "mmlio/pipeline/runner.hpp"
#include "mmlio/pipeline/system.hpp"
#include "sim_feed.hpp"

namespace mmlio {
namespace {

ImuSample at(double t_s) {
  ImuSample s;
  s.stamp_ns = fromSec(100.0 + t_s);
  s.acc_m_s2 = Eigen::Vector3d(0, 0, 9.81);
  return s;
}

/// The simulated office of `duration_s` through the streaming pipeline (HVI, true calibration), its
/// scans and IMU samples edited as testing::replay does; counts the degraded sweeps and the
/// time-base jumps if asked. Poses carry the input's stamps.
Trajectory runOffice(const sim::Simulator& sim, const std::function<void(int, LidarScan&)>& edit,
                     const std::function<void(std::size_t, ImuSample&)>& edit_imu, std::size_t* degraded = nullptr,
                     std::size_t* time_base_jumps = nullptr) {
  Trajectory trajectory;
  pipeline::OnlinePipeline* pipeline = nullptr;
  pipeline::OnlinePipeline online(testing::simRigConfig(sim), "hvi", [&](const estimator::SweepResult& r) {
    if (r.status == estimator::SweepResult::Status::kInitializing) return;
    trajectory.push_back({pipeline->externalStamp(r.state.stamp_ns), r.state.pose()});
    if (degraded) *degraded += r.status == estimator::SweepResult::Status::kDegraded;
  });
  pipeline = &online;
  testing::replay(sim, online, edit, edit_imu);
  if (time_base_jumps) *time_base_jumps = online.timeBaseJumps().size();
  return trajectory;
}

/// The simulated sequence through the System the live node uses (no loops), its scans and IMU
/// samples edited as testing::replay does, finished: its report.
pipeline::RunReport systemReport(const sim::Simulator& sim, const std::function<void(int, LidarScan&)>& edit,
                                 const std::function<void(std::size_t, ImuSample&)>& edit_imu = {}) {
  config::RigConfig cfg = testing::simRigConfig(sim);
  cfg.mapping.loop_enabled = false;
  pipeline::System system(cfg, "hvi");
  testing::replay(sim, system, edit, edit_imu);
  system.finish();
  return system.report();
}

sim::Simulator office(double duration_s) {
  sim::SimOptions so;
  so.scenario = "office";
  so.duration_s = duration_s;
  return sim::Simulator(so);
}

}  // namespace

TEST(ImuGate, DropsAndCountsNonFiniteImpossibleAndDisorderedSamples) {
  pipeline::ImuGate gate;
  EXPECT_TRUE(gate.accept(at(0.000)));
  ImuSample nan = at(0.005);
  nan.gyro_rad_s.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(gate.accept(nan));
  ImuSample huge = at(0.010);
  huge.acc_m_s2.y() = 1.8e109;
  EXPECT_FALSE(gate.accept(huge));
  EXPECT_TRUE(gate.accept(at(0.015)));
  EXPECT_FALSE(gate.accept(at(0.015)));               // duplicate
  EXPECT_FALSE(gate.accept(at(0.012)));               // out of order
  EXPECT_FALSE(gate.accept(at(86.0 * 365 * 86400)));  // one stamp decades ahead ...
  EXPECT_TRUE(gate.accept(at(0.020)));                // ... does not block the stream that follows
  EXPECT_EQ(gate.counts().non_finite, 1u);
  EXPECT_EQ(gate.counts().out_of_range, 1u);
  EXPECT_EQ(gate.counts().out_of_order, 2u);
  EXPECT_EQ(gate.counts().jumped, 1u);
  // Where in the stream: the last accepted stamp at the first and the last drop.
  EXPECT_EQ(gate.counts().first_at_ns, at(0.000).stamp_ns);
  EXPECT_EQ(gate.counts().last_at_ns, at(0.015).stamp_ns);
}

TEST(ImuGate, AStreamThatStaysAfterAGapIsAcceptedAgainAfterAFewSamples) {
  pipeline::ImuGate gate;
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(gate.accept(at(0.005 * k)));
  int accepted = 0;
  for (int k = 0; k < 100; ++k) accepted += gate.accept(at(3.0 + 0.005 * k));  // 3 s later, for good
  EXPECT_EQ(gate.counts().jumped, 19u);                                        // until 20 samples agree
  EXPECT_EQ(accepted, 81);
}

TEST(ImuGate, AStreamThatGoesFarBackIsHeldOutButSaysSoAfterAFewSamples) {
  pipeline::ImuGate gate;
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(gate.accept(at(5.0 + 0.005 * k)));
  EXPECT_FALSE(gate.accept(at(0.0)));  // one stamp 5 s back: corrupt, or a clock set back
  EXPECT_FALSE(gate.wentBack());
  EXPECT_TRUE(gate.accept(at(5.05)));  // the stream goes on: it was one corrupt stamp
  int accepted = 0;
  for (int k = 0; k < 30; ++k) accepted += gate.accept(at(0.005 * k));  // for good: a bag played again
  EXPECT_EQ(accepted, 0);  // only the pipeline, seeing every LiDAR go back alike, lets them in
  EXPECT_TRUE(gate.wentBack());
  EXPECT_EQ(gate.counts().jumped, 31u);
}

TEST(InputGates, OneCorruptImuSampleOrScanStampLeavesTheTrajectoryAsGoodAsTheCleanRun) {
  const sim::Simulator sim = office(12.0);
  const Trajectory clean = runOffice(sim, {}, {});
  const Trajectory faulty = runOffice(sim, {}, [](std::size_t i, ImuSample& s) {
    if (i == 1200) s.gyro_rad_s.x() = std::numeric_limits<double>::quiet_NaN();  // moving, 6 s in
    if (i == 1400) s.acc_m_s2.z() = 1.8e109;
    if (i == 1600) s.stamp_ns += fromSec(4e9);  // the year 2106
  });
  ASSERT_EQ(faulty.size(), clean.size());
  for (const auto& p : faulty) ASSERT_TRUE(p.T_world_body.matrix().allFinite());
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const double faulty_ate = eval::evaluate(sim.groundTruth(), faulty).ate_rmse_m;
  EXPECT_LT(faulty_ate, 1.2 * clean_ate + 0.002) << "clean " << clean_ate;

  // One Velodyne sweep stamped in the year 2106: that sweep is lost, tracking goes on.
  const Trajectory late = runOffice(sim,
                                    [](int index, LidarScan& scan) {
                                      if ((index == 120 || index == 121) && scan.sensor == "velodyne")
                                        scan.start_ns += fromSec(4e9);
                                    },
                                    {});
  EXPECT_GE(late.size() + 2, clean.size());
  EXPECT_LT(eval::evaluate(sim.groundTruth(), late).ate_rmse_m, 1.2 * clean_ate + 0.002);
}

}  // namespace mmlio

namespace mmlio::pipeline {

TEST(RunBag, AnUnwritableOutputFolderIsRefusedBeforeTheBagIsRead) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "mmlio_not_a_folder";
  { std::ofstream(file) << "x"; }
  RunOptions options;
  options.bag_path = "/nonexistent.bag";  // never opened: the output is checked first
  options.out_dir = (file / "out").string();
  try {
    runBag(options);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("output directory"), std::string::npos) << e.what();
  }
  std::filesystem::remove(file);
}

// The live node's report comes from the same System: it must judge trust as `mmlio run` does.
TEST(LiveReport, JudgesCoverageDegradationAndTrustAsARunDoes) {
  const sim::Simulator sim = office(8.0);
  const Stamp imu_ends = sim.startNs() + fromSec(5.0);
  config::RigConfig cfg = testing::simRigConfig(sim);
  cfg.mapping.loop_enabled = false;
  System clean(cfg, "hvi");
  testing::replay(sim, clean);
  clean.finish();
  const RunReport ok = clean.report();
  EXPECT_TRUE(ok.untrusted.empty()) << ok.untrusted;
  EXPECT_GT(ok.sweeps.coverage, 0.95);
  EXPECT_EQ(ok.sweeps.degraded_fraction, 0.0);
  TrustLimits strict;
  strict.max_drift_sigma_m = 1e-6;
  EXPECT_NE(clean.report(0, strict).untrusted.find("drift"), std::string::npos);

  // The IMU stops 5 s into the 8 s.
  const RunReport bad = systemReport(sim, {}, [&](std::size_t, ImuSample& s) {
    if (s.stamp_ns >= imu_ends) s.acc_m_s2 = Eigen::Vector3d::Constant(std::nan(""));  // dropped by the IMU gate
  });
  EXPECT_GT(bad.sweeps.degraded_fraction, 0.25);
  EXPECT_NE(bad.untrusted.find("sweeps degraded"), std::string::npos) << bad.untrusted;
}

TEST(LiveReport, StatesTheAccelerometerBiasTheEstimatorFound) {
  sim::SimOptions so;
  so.scenario = "office";
  so.duration_s = 16.0;
  so.acc_bias_m_s2 = 0.1;  // per axis, signs from the seed
  const sim::Simulator sim(so);
  const RunReport r = systemReport(sim, {});
  const double truth = 0.1 * std::sqrt(3.0);
  std::printf("accelerometer bias: end %.3f, at most %.3f at %.1f s (truth %.3f); gyroscope %.4f rad/s\n",
              r.imu_bias.acc_end_m_s2.norm(), r.imu_bias.max_acc_m_s2, r.imu_bias.max_acc_at_s, truth,
              r.imu_bias.gyro_end_rad_s.norm());
  EXPECT_NEAR(r.imu_bias.acc_end_m_s2.norm(), truth, 0.3 * truth);
  EXPECT_GE(r.imu_bias.max_acc_m_s2, r.imu_bias.acc_end_m_s2.norm());
  EXPECT_GT(r.imu_bias.max_acc_at_s, 0.0);
  EXPECT_LE(r.imu_bias.max_acc_at_s, 16.5);
}

TEST(LiveReport, ScansThatNeverArriveMakeTheRunDegradedAndNameTheLidar) {
  const sim::Simulator sim = office(6.0);
  const RunReport ok = systemReport(sim, {});
  ASSERT_EQ(ok.input.lidar_streams.size(), 2u);
  for (const auto& [name, st] : ok.input.lidar_streams) {
    EXPECT_EQ(st.missing, 0u) << name;
    EXPECT_GT(st.received, 50u) << name;
  }
  EXPECT_EQ(ok.inputStatus(), "complete");

  // A transport that loses every fifth Velodyne sweep from 2 s on: the scans never reach the
  // pipeline (renamed to a LiDAR it does not use).
  const Stamp from = sim.startNs() + fromSec(2.0);
  std::size_t lost = 0;
  int velodyne = 0;
  const RunReport bad = systemReport(sim, [&](int, LidarScan& scan) {
    if (scan.sensor != "velodyne") return;
    if (scan.start_ns >= from && velodyne++ % 5 == 0) {
      scan.sensor = "lost";
      ++lost;
    }
  });
  ASSERT_GT(lost, 5u);
  EXPECT_EQ(bad.input.lidar_streams.at("velodyne").missing, lost);
  EXPECT_EQ(bad.input.lidar_streams.at("livox").missing, 0u);
  EXPECT_TRUE(bad.inputDegraded());
  EXPECT_NE(bad.inputStatus().find(std::to_string(lost) + " of"), std::string::npos) << bad.inputStatus();
  EXPECT_NE(bad.inputStatus().find("velodyne"), std::string::npos) << bad.inputStatus();

  // The Velodyne sends nothing usable all run (only zeros, say).
  const RunReport hi = systemReport(sim, [&](int, LidarScan& scan) {
    if (scan.sensor == "velodyne") scan.sensor = "lost";
  });
  EXPECT_EQ(hi.input.lidar_streams.at("velodyne").received, 0u);
  EXPECT_NE(hi.inputStatus().find("velodyne sent no scan"), std::string::npos) << hi.inputStatus();
}

// Every IMU sample is accounted for too: received, expected from the rate, missing (here: every
// fiftieth between 2 and 5 s never usable).
TEST(LiveReport, ImuSamplesThatNeverArriveAreCounted) {
  const sim::Simulator sim = office(6.0);
  const RunReport ok = systemReport(sim, {});
  EXPECT_EQ(ok.input.imu_stream.missing, 0u);
  EXPECT_GT(ok.input.imu_stream.received, 1100u);  // 200 Hz over 6 s
  EXPECT_NEAR(ok.input.imu_stream.period_s, 0.005, 1e-4);

  const Stamp from = sim.startNs() + fromSec(2.0), to = sim.startNs() + fromSec(5.0);
  std::size_t lost = 0;
  const RunReport holes = systemReport(sim, {}, [&](std::size_t i, ImuSample& s) {
    if (s.stamp_ns < from || s.stamp_ns >= to || i % 50 != 0) return;
    s.acc_m_s2 = Eigen::Vector3d::Constant(std::nan(""));  // dropped by the IMU gate: a hole in the stream
    ++lost;
  });
  ASSERT_GT(lost, 10u);
  EXPECT_EQ(holes.input.imu_stream.missing, lost);
  EXPECT_EQ(holes.input.imu_stream.expected(), ok.input.imu_stream.expected());
  EXPECT_EQ(holes.input.imu_stream.gaps.size(), lost);
}

}  // namespace mmlio::pipeline

namespace mmlio {

TEST(InputGates, AnImuGapIsNotInterpolatedTheLidarsCarryTheSweepsThrough) {
  const sim::Simulator sim = office(16.0);
  std::size_t clean_degraded = 0, gap_degraded = 0;
  const Trajectory clean = runOffice(sim, {}, {}, &clean_degraded);
  // No IMU from 6 to 8 s (walking): the samples are simply not there.
  const Trajectory gapped = runOffice(
      sim, {},
      [](std::size_t i, ImuSample& s) {
        if (i >= 1200 && i < 1600) s.stamp_ns = 0;  // a stamp the gate drops as out of order
      },
      &gap_degraded);
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const double gap_ate = eval::evaluate(sim.groundTruth(), gapped).ate_rmse_m;
  std::printf("office 16 s: clean ATE %.4f m; 2 s without IMU: ATE %.4f m, %zu degraded sweeps\n", clean_ate, gap_ate,
              gap_degraded);
  EXPECT_EQ(clean_degraded, 0u);
  EXPECT_GE(gap_degraded, 15u);  // the sweeps of the gap are marked
  EXPECT_GE(gapped.size() + 2, clean.size());
  EXPECT_LT(gap_ate, 2.0 * clean_ate) << "clean " << clean_ate;
}

}  // namespace mmlio

namespace mmlio {

TEST(InputGates, AJumpOfTheWholeStreamsTimeBaseIsARestartNotAGapToExtrapolate) {
  const sim::Simulator sim = office(16.0);
  const Trajectory clean = runOffice(sim, {}, {});
  // Every stamp from 6 s on (walking) is 5 s later: IMU and both LiDARs (a clock re-sync).
  std::size_t jumps = 0;
  const Stamp jump_at = sim.groundTruth().front().stamp_ns + fromSec(6.0);
  const Trajectory jumped = runOffice(
      sim,
      [&](int, LidarScan& scan) {
        if (scan.start_ns >= jump_at) scan.start_ns += fromSec(5.0);
      },
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= jump_at) s.stamp_ns += fromSec(5.0);
      },
      nullptr, &jumps);
  EXPECT_EQ(jumps, 1u);
  // Scored against the truth re-timed the same way: the poses keep the input's stamps.
  Trajectory truth = sim.groundTruth();
  for (auto& p : truth)
    if (p.stamp_ns >= jump_at) p.stamp_ns += fromSec(5.0);
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const eval::EvalResult ev = eval::evaluate(truth, jumped);
  std::printf("office 16 s: clean ATE %.4f m; stamps +5 s from 6 s: ATE %.4f m over %zu poses\n", clean_ate,
              ev.ate_rmse_m, jumped.size());
  EXPECT_GE(jumped.size() + 3, clean.size());
  EXPECT_LT(ev.ate_rmse_m, 2.0 * clean_ate) << "clean " << clean_ate;

  // The IMU alone jumping is no time-base jump (its gap is handled as a gap).
  std::size_t imu_only = 0;
  runOffice(
      sim, {},
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= jump_at) s.stamp_ns += fromSec(5.0);
      },
      nullptr, &imu_only);
  EXPECT_EQ(imu_only, 0u);
}

TEST(System, ItsRouteIsTheKeyframesAndTheNewestPoseAsTheTrajectoryHasThem) {
  // The live nodes' path: bounded by the keyframes, not rebuilt from every pose at each one.
  const sim::Simulator sim = office(16.0);
  pipeline::System system(testing::simRigConfig(sim), "hvi");
  testing::replay(sim, system, {}, {});
  system.finish();
  const Trajectory route = system.route(), trajectory = system.trajectory();
  const std::size_t keyframes = system.report().sweeps.keyframes;
  ASSERT_GE(keyframes, 5u);
  ASSERT_GE(route.size(), keyframes);
  ASSERT_LE(route.size(), keyframes + 1);
  EXPECT_LT(route.size(), trajectory.size() / 4);
  EXPECT_EQ(route.back().stamp_ns, trajectory.back().stamp_ns);
  for (const StampedPose& p : route) {
    const auto same = std::find_if(trajectory.begin(), trajectory.end(),
                                   [&](const StampedPose& q) { return q.stamp_ns == p.stamp_ns; });
    ASSERT_NE(same, trajectory.end());
    EXPECT_EQ(same->T_world_body.matrix(), p.T_world_body.matrix());
  }
}

TEST(InputGates, ABagPlayedAgainFromItsStartGoesOnFromWhereTheRigIs) {
  // `rosbag play -l` of a route that ends where it starts (the 16 s office: out and back, at rest
  // at both ends): the second pass's stamps repeat the first's, 16 s back, IMU and LiDARs alike.
  const sim::Simulator sim = office(16.0);
  const Trajectory clean = runOffice(sim, {}, {});
  config::RigConfig cfg = testing::simRigConfig(sim);
  cfg.mapping.loop_enabled = false;
  pipeline::System system(cfg, "hvi");
  testing::feed(sim, system, {});
  testing::feed(sim, system, {});
  system.flush();
  system.finish();
  const pipeline::RunReport report = system.report();
  ASSERT_EQ(report.input.time_base_jumps.size(), 1u);
  EXPECT_NEAR(report.input.time_base_jumps[0].shift_s, -16.0, 0.3);
  EXPECT_GT(report.sweeps.coverage, 0.95);  // judged in the estimator's time, which did not go back
  EXPECT_NE(report.inputStatus().find("time base"), std::string::npos) << report.inputStatus();
  const std::size_t degraded = report.sweeps.degraded;
  const Trajectory looped = system.odometryTrajectory();

  // Outputs keep the input's stamps: the second pass starts where the stamps go back.
  const auto back = std::adjacent_find(
      looped.begin(), looped.end(), [](const StampedPose& a, const StampedPose& b) { return b.stamp_ns < a.stamp_ns; });
  ASSERT_NE(back, looped.end());
  const Trajectory first(looped.begin(), back + 1), second(back + 1, looped.end());
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const double second_ate = eval::evaluate(sim.groundTruth(), second).ate_rmse_m;
  // Both passes in one world: the second's poses lie on the first's, without any alignment.
  double apart = 0;
  for (const StampedPose& p : second) {
    const auto same =
        std::find_if(first.begin(), first.end(), [&](const StampedPose& q) { return q.stamp_ns == p.stamp_ns; });
    if (same != first.end())
      apart = std::max(apart, (same->T_world_body.translation() - p.T_world_body.translation()).norm());
  }
  std::printf(
      "office 16 s played twice: clean ATE %.4f m; second pass ATE %.4f m over %zu poses (first %zu), "
      "%.4f m at most from the first pass, %zu degraded\n",
      clean_ate, second_ate, second.size(), first.size(), apart, degraded);
  EXPECT_GE(second.size() + 5, clean.size());
  EXPECT_LT(second_ate, 2.0 * clean_ate) << "clean " << clean_ate;
  EXPECT_LT(apart, 0.05);
  EXPECT_LE(degraded, 5u);

  // The IMU alone going back is no time-base jump: its samples stay out (counted).
  std::size_t imu_only = 0;
  const Stamp back_at = sim.groundTruth().front().stamp_ns + fromSec(8.0);
  runOffice(
      sim, {},
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= back_at) s.stamp_ns -= fromSec(5.0);
      },
      nullptr, &imu_only);
  EXPECT_EQ(imu_only, 0u);
}

}  // namespace mmlio

namespace mmlio::pipeline {

/// The simulated office as a bag in the temp folder, without the IMU samples `keep_imu` refuses.
std::string officeBag(const sim::Simulator& sim, const std::string& name,
                      const std::function<bool(const ImuSample&)>& keep_imu) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  testing::writeSimBag(sim, path, keep_imu);
  return path;
}

/// The simulated office written whole to a bag, run without loop closure or a progress bar.
RunOptions officeRun(const sim::Simulator& sim, const std::string& bag_name) {
  RunOptions options;
  options.config = testing::simRigConfig(sim);
  options.config.mapping.loop_enabled = false;
  options.progress = false;
  options.bag_path = officeBag(sim, bag_name, [](const ImuSample&) { return true; });
  return options;
}

TEST(RunBag, ASpinningLidarMountTheStartContradictsMakesTheOutputsUntrusted) {
  const sim::Simulator sim = office(3.0);
  RunOptions options = officeRun(sim, "mmlio_mount_check.bag");
  options.mode = "hvi";
  options.check_mount = true;
  const RunResult right = runBag(options);
  const MountCheck& ok = right.report.mount_check;
  std::printf("true mount: %s\n", ok.message.c_str());
  EXPECT_EQ(ok.lidar, "velodyne");
  EXPECT_TRUE(ok.checked);
  EXPECT_TRUE(ok.agrees);
  EXPECT_LT(ok.moved_m, 0.01);
  EXPECT_LT(ok.moved_deg, 0.1);
  EXPECT_TRUE(right.untrusted.empty()) << right.untrusted;

  // The Velodyne written into the rig file turned by a quarter about its axis.
  for (config::LidarConfig& l : options.config.lidars)
    if (l.name == "velodyne")
      l.T_imu_sensor.linear() = l.T_imu_sensor.linear() * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  const RunResult turned = runBag(options);
  const MountCheck& bad = turned.report.mount_check;
  std::printf("turned mount: %s\n", bad.message.c_str());
  EXPECT_TRUE(bad.checked);
  EXPECT_FALSE(bad.agrees);
  EXPECT_NE(turned.untrusted.find("contradict"), std::string::npos) << turned.untrusted;
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, AStopRequestEndsTheRunWithWhatWasComputedWrittenAndFlagged) {
  // What Ctrl-C / SIGTERM do to `mmlio run`: the handler sets the stop flag; here a thread sets it
  // once the run has tracked for a while. The whole office walk, so that no machine runs it in
  // the 1.5 s before the stop (it takes 4-8 s on two cores here).
  const sim::Simulator sim = office(0.0);
  RunOptions options;
  options.config = testing::simRigConfig(sim);
  options.progress = false;
  options.out_dir = (std::filesystem::temp_directory_path() / "mmlio_interrupted_out").string();
  options.bag_path = officeBag(sim, "mmlio_interrupted.bag", [](const ImuSample&) { return true; });
  std::atomic<bool> stop{false};
  options.stop = &stop;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    stop = true;
  });
  const RunResult r = runBag(options);
  stopper.join();
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.untrusted, "interrupted");
  EXPECT_GT(r.trajectory.size(), 0u);
  EXPECT_LT(r.trajectory.size(), 400u);  // the 42 s walk would be ~420
  std::ifstream written(options.out_dir + "/report.json");
  const std::string text((std::istreambuf_iterator<char>(written)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"status\": \"interrupted\""), std::string::npos) << text.substr(0, 200);
  std::ifstream tum(options.out_dir + "/trajectory.tum");
  std::size_t lines = 0;
  for (std::string line; std::getline(tum, line);) lines += !line.empty() && line[0] != '#';
  EXPECT_EQ(lines, r.trajectory.size());
  EXPECT_TRUE(std::filesystem::exists(options.out_dir + "/map.pcd"));
  std::filesystem::remove_all(options.out_dir);
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, TheReportNamesItsMmlioAndTheConfigThatRerunsTheRunExactly) {
  const sim::Simulator sim = office(4.0);
  RunOptions options = officeRun(sim, "mmlio_provenance.bag");
  options.mode = "vi";
  options.out_dir = (std::filesystem::temp_directory_path() / "mmlio_provenance_out").string();
  const RunResult first = runBag(options);
  std::ifstream in(options.out_dir + "/report.json");
  const Json report = Json::parse(in);
  const Json& run = report["run"];
  EXPECT_EQ(run["schema_version"].get<int>(), 2);
  EXPECT_FALSE(run["mmlio_version"].get<std::string>().empty());
  EXPECT_FALSE(run["commit"].get<std::string>().empty());
  EXPECT_EQ(run["calibration"].get<std::string>(), "config");
  // config_used.yaml is the effective config: the mode chosen on the command line, the extrinsics
  // as given; running with it alone gives the same trajectory, pose for pose.
  const config::RigConfig used = config::loadRigConfig(options.out_dir + "/config_used.yaml");
  EXPECT_EQ(used.mode, "vi");
  EXPECT_EQ(config::toYaml(used), run["config_yaml"].get<std::string>());
  // The session holds the same config, and its keyframes are poses of the trajectory written.
  io::SessionInfo info;
  const Session session = io::readSession(options.out_dir + "/session", &info);
  EXPECT_EQ(info.rig_yaml, run["config_yaml"].get<std::string>());
  EXPECT_EQ(info.mode, "vi");
  ASSERT_GE(session.keyframes.size(), 2u);
  EXPECT_EQ(report["outputs"]["session_keyframes"].get<std::size_t>(), session.keyframes.size());
  const Trajectory written = io::readTum(options.out_dir + "/trajectory.tum");
  for (const SessionKeyframe& k : session.keyframes) {
    const auto at =
        std::find_if(written.begin(), written.end(), [&](const StampedPose& p) { return p.stamp_ns == k.stamp_ns; });
    ASSERT_NE(at, written.end()) << "keyframe stamp " << k.stamp_ns << " is no pose of trajectory.tum";
    EXPECT_TRUE(at->T_world_body.isApprox(k.T_map_body, 1e-6));
  }
  RunOptions again = options;
  again.config = used;
  again.mode.clear();
  again.out_dir.clear();
  const RunResult second = runBag(again);
  ASSERT_EQ(second.trajectory.size(), first.trajectory.size());
  for (std::size_t i = 0; i < first.trajectory.size(); ++i)
    EXPECT_TRUE(second.trajectory[i].T_world_body.isApprox(first.trajectory[i].T_world_body, 1e-12)) << "pose " << i;
  std::filesystem::remove_all(options.out_dir);
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, ADurationCutEndsWithAnOrdinaryTrackedSweepAndFullCoverage) {
  // `--duration`: the scans stop at the cut; the IMU must not stop before the last sweep ends
  // (that sweep was reported degraded, and coverage above 1).
  const sim::Simulator sim = office(8.0);
  RunOptions options = officeRun(sim, "mmlio_duration_cut.bag");
  options.max_duration_s = 5.0;
  const RunResult r = runBag(options);
  ASSERT_GT(r.trajectory.size(), 10u);
  EXPECT_EQ(r.report.sweeps.degraded, 0u);
  EXPECT_LE(r.report.sweeps.coverage, 1.0);
  EXPECT_GT(r.report.sweeps.coverage, 0.95);
  EXPECT_TRUE(r.untrusted.empty()) << r.untrusted;
  const double last_s = toSec(r.trajectory.back().stamp_ns - sim.startNs());
  EXPECT_GT(last_s, 4.8);
  EXPECT_LT(last_s, 5.25);
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, AnErrorBeforeAnyOutputLeavesNoFolderItCreatedButKeepsTheUsers) {
  const sim::Simulator sim = office(2.0);
  RunOptions options;
  options.config = testing::simRigConfig(sim);
  options.config.imu.topic = "/no/such/imu";
  options.progress = false;
  options.bag_path = officeBag(sim, "mmlio_wrong_topic.bag", [](const ImuSample&) { return true; });
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "mmlio_wrong_topic_out" / "run";
  std::filesystem::remove_all(out.parent_path());
  options.out_dir = out.string();
  EXPECT_THROW(runBag(options), Error);
  EXPECT_FALSE(std::filesystem::exists(out.parent_path()));  // both levels it created
  std::filesystem::create_directories(out);                  // the user's own folder stays, empty or not
  EXPECT_THROW(runBag(options), Error);
  EXPECT_TRUE(std::filesystem::is_directory(out));
  std::filesystem::remove_all(out.parent_path());
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, TellsItsTimingObserverEverySweepOnceInTimeOrderAcrossReplays) {
  // What `mmlio bench --curve` records: one call per sweep the report times, later stamps for the
  // second pass of a replayed bag, and the same stage times the report sums.
  const sim::Simulator sim = office(6.0);
  RunOptions options = officeRun(sim, "mmlio_timing_observer.bag");
  options.replays = 2;
  std::vector<Stamp> stamps;
  std::vector<int> replays;
  double observed_ms = 0.0;
  options.on_sweep = [&](Stamp sweep_end_ns, const StageTimes& times_ms, int replay) {
    stamps.push_back(sweep_end_ns);
    replays.push_back(replay);
    for (const auto& stage : times_ms) observed_ms += stage.second;
  };
  const RunResult r = runBag(options);
  ASSERT_GT(stamps.size(), 40u);
  EXPECT_EQ(stamps.size(), r.timing.sweeps());
  EXPECT_TRUE(std::adjacent_find(stamps.begin(), stamps.end(), std::greater_equal<Stamp>()) == stamps.end());
  EXPECT_GT(toSec(stamps.back() - stamps.front()), 1.5 * sim.durationS());  // both passes
  // Each sweep is told its pass, which changes where the bag starts again (sweeps 0.1 s apart, the
  // passes 1 s apart).
  ASSERT_EQ(replays.front(), 0);
  ASSERT_EQ(replays.back(), 1);
  EXPECT_TRUE(std::is_sorted(replays.begin(), replays.end()));
  const std::size_t second = std::find(replays.begin(), replays.end(), 1) - replays.begin();
  EXPECT_GT(toSec(stamps[second] - stamps[second - 1]), 0.5);
  double reported_ms = 0.0;
  const Json timing = r.timing.toJson();
  for (const auto& stage : timing.items())
    if (stage.key() != "total" && stage.key() != "mapping_backend")
      reported_ms += stage.value()["mean_ms"].get<double>() * stage.value()["samples"].get<double>();
  EXPECT_NEAR(observed_ms, reported_ms, 1e-3 * reported_ms);
  std::filesystem::remove(options.bag_path);
}

TEST(RunBag, OutputsAreFlaggedUntrustedWhenTooManySweepsAreDegraded) {
  const sim::Simulator sim = office(8.0);
  const Stamp imu_ends = sim.startNs() + fromSec(5.0);
  RunOptions options = officeRun(sim, "mmlio_clean.bag");
  options.out_dir = (std::filesystem::temp_directory_path() / "mmlio_untrusted_out").string();
  const RunResult clean = runBag(options);
  EXPECT_TRUE(clean.untrusted.empty()) << clean.untrusted;
  // The report's drift bound: what the IMU carried alone. Millimetres in the office; a bound below
  // what the run reached makes it untrusted, with the figure.
  const double drift = toJson(clean.report)["degeneracy"]["max_drift_sigma_m"].get<double>();
  EXPECT_GT(drift, 0.0);
  EXPECT_LT(drift, 0.05);
  RunOptions strict = options;
  strict.trust.max_drift_sigma_m = 0.5 * drift;
  EXPECT_NE(runBag(strict).untrusted.find("drift"), std::string::npos);

  // The IMU stops 5 s into the 8 s: the last sweeps are registered by the LiDARs alone.
  options.bag_path = officeBag(sim, "mmlio_imu_stops.bag", [&](const ImuSample& s) { return s.stamp_ns < imu_ends; });
  const RunResult stopped = runBag(options);
  EXPECT_NE(stopped.untrusted.find("sweeps degraded"), std::string::npos) << stopped.untrusted;
  EXPECT_FALSE(toJson(stopped.report)["trustworthy"].get<bool>());
  std::ifstream written(options.out_dir + "/report.json");
  const std::string text((std::istreambuf_iterator<char>(written)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"untrusted_because\""), std::string::npos);
  std::filesystem::remove_all(options.out_dir);
  std::filesystem::remove(options.bag_path);
  std::filesystem::remove(std::filesystem::temp_directory_path() / "mmlio_clean.bag");
}

}  // namespace mmlio::pipeline

namespace mmlio {

TEST(InputGates, ALossOfAllDataWhileTheRigAcceleratesOutOfATurnIsBridged) {
  // Office, 20 s out and back: at 10 s the rig has just turned round and accelerates to 0.8 m/s.
  // 0.2 s of every message lost there (a damaged chunk): the sweep after the gap is de-skewed by
  // its own IMU samples, not by the turn rate from before the gap.
  const sim::Simulator sim = office(20.0);
  const Trajectory clean = runOffice(sim, {}, {});
  const Stamp from = sim.startNs() + fromSec(10.0), to = from + fromSec(0.2);
  std::size_t degraded = 0;
  const Trajectory lost = runOffice(
      sim,
      [&](int, LidarScan& s) {
        if (s.start_ns >= from && s.start_ns < to) s.start_ns = 0;
      },
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= from && s.stamp_ns < to) s.stamp_ns = 0;
      },
      &degraded);
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const double lost_ate = eval::evaluate(sim.groundTruth(), lost).ate_rmse_m;
  std::printf("office 20 s: clean ATE %.4f m; 0.2 s of all data lost at 10 s: %.4f m, %zu degraded sweeps\n", clean_ate,
              lost_ate, degraded);
  EXPECT_GE(degraded, 1u);
  // The gap's cost in ATE, absolute: a ratio to the clean run moves with whatever else changes the
  // clean run. De-skewed by the turn from before the gap this costs +4 cm; bridged, under +1 cm.
  EXPECT_LT(lost_ate, clean_ate + 0.01) << "clean " << clean_ate;
}

TEST(InputGates, ALossOfAllDataWhileATurnEndsIsBridgedByTryingSeveralTurns) {
  // Office, 30 s out and back: from 14 s the rig turns round at 90 deg/s, slowing down to a stop at
  // 15.3 s. 0.4 s of every message lost from 15.05 s: the turn rate carried over the gap would turn
  // the rig 20 deg too far, beyond where registration converges from (was 78-81 cm ATE).
  const sim::Simulator sim = office(30.0);
  const Trajectory clean = runOffice(sim, {}, {});
  const Stamp from = sim.startNs() + fromSec(15.05), to = from + fromSec(0.4);
  const Trajectory lost = runOffice(
      sim,
      [&](int, LidarScan& s) {
        if (s.start_ns >= from && s.start_ns < to) s.start_ns = 0;
      },
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= from && s.stamp_ns < to) s.stamp_ns = 0;
      });
  const double clean_ate = eval::evaluate(sim.groundTruth(), clean).ate_rmse_m;
  const double lost_ate = eval::evaluate(sim.groundTruth(), lost).ate_rmse_m;
  std::printf("office 30 s: clean ATE %.4f m; 0.4 s of all data lost as the U-turn ends: %.4f m\n", clean_ate,
              lost_ate);
  EXPECT_LT(lost_ate, 2.0 * clean_ate) << "clean " << clean_ate;
}

}  // namespace mmlio

namespace mmlio {

// An IMU that stops for good: the sweeps after it do not wait for it until the end of the stream
// (a long bag would hold all of them in memory) but go on, LiDAR-only, two seconds behind the LiDARs.
TEST(InputGates, SweepsWaitForAnImuThatStoppedAtMostTwoSeconds) {
  const sim::Simulator sim = office(14.0);
  const Stamp imu_ends = sim.startNs() + fromSec(4.0);
  std::size_t degraded = 0, delivered_while_feeding = 0, fed = 0;
  const std::size_t scans = sim.numLivoxFrames() + sim.numVelodyneSweeps();
  pipeline::OnlinePipeline online(testing::simRigConfig(sim), "hvi", [&](const estimator::SweepResult& r) {
    degraded += r.status == estimator::SweepResult::Status::kDegraded;
    if (r.state.stamp_ns > imu_ends && fed < scans) ++delivered_while_feeding;
  });
  testing::replay(
      sim, online, [&](int, LidarScan&) { ++fed; },
      [&](std::size_t, ImuSample& s) {
        if (s.stamp_ns >= imu_ends) s.stamp_ns = 0;
      });
  const std::size_t bound = pipeline::OnlinePipeline::kMaxImuWaitNs / 100000000LL + 3;  // 10 Hz sweeps
  EXPECT_LE(online.waitingHighWater(), bound);
  EXPECT_GT(delivered_while_feeding, 50u);  // 10 s after the IMU stopped, less the last 2 s
  EXPECT_GT(degraded, 80u);
  EXPECT_EQ(online.sweepsProcessed(), static_cast<std::size_t>(sim.numLivoxFrames()) - 1);
}

}  // namespace mmlio
