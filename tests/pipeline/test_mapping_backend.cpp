// The run's mapping back end: a walk around a room that ends where it started closes its loop at
// the end of the run, even when the last keyframe is not one the periodic loop check visits.
#include <gtest/gtest.h>

#include "../backend/synthetic_scene.hpp"
#include "mmlio/backend/mapping_backend.hpp"
#include "mmlio/pipeline/mapping_thread.hpp"

namespace mmlio::pipeline {
namespace {

using backend::testing::pose;
constexpr double kDeg = M_PI / 180.0;

struct Walk {
  std::vector<Eigen::Isometry3d> truth, odometry;
  std::vector<Stamp> stamps;
};

/// Six keyframes 4.5 s apart around room A, back at the start; the odometry gains 0.3 deg of yaw
/// and 3 cm of sideways drift per step (one or two sigmas of the pose graph's odometry edges).
Walk roomWalk() {
  Walk w;
  const std::vector<Eigen::Isometry3d> truth = {pose(-3, -2, 1, 0),          pose(0, -3, 1, 20 * kDeg),
                                                pose(3.5, -1, 1, 80 * kDeg), pose(3, 2.5, 1, 160 * kDeg),
                                                pose(-1, 3, 1, 220 * kDeg),  pose(-3.05, -1.95, 1, 2 * kDeg)};
  w.truth = truth;
  w.odometry = {truth[0]};
  for (std::size_t i = 1; i < truth.size(); ++i)
    w.odometry.push_back(w.odometry.back() * (truth[i - 1].inverse() * truth[i]) * pose(0, 0.03, 0, 0.3 * kDeg));
  for (std::size_t i = 0; i < truth.size(); ++i) w.stamps.push_back(fromSec(4.5 * static_cast<double>(i)));
  return w;
}

/// The odometry's poses as the run keeps them for the back end to correct.
PoseLog odometryLog(const Walk& w) {
  PoseLog log;
  for (std::size_t i = 0; i < w.odometry.size(); ++i) log.push_back({w.stamps[i], w.odometry[i]});
  return log;
}

estimator::SweepResult sweepAt(const Walk& w, std::size_t i, const backend::testing::Scene& scene) {
  estimator::SweepResult r;
  r.status = estimator::SweepResult::Status::kTracking;
  r.keyframe = true;
  r.state.stamp_ns = w.stamps[i];
  r.state.p_world = w.odometry[i].translation();
  r.state.q_world_body = Eigen::Quaterniond(w.odometry[i].rotation());
  for (const Eigen::Vector3d& p : backend::testing::scan(scene, w.truth[i], 100 + static_cast<unsigned>(i))) {
    Point q;
    q.xyz = p.cast<float>();
    r.points_body.push_back(q);
  }
  return r;
}

backend::MappingBackend::Config config() {
  backend::MappingBackend::Config cfg;
  cfg.loop_check_every = 4;  // keyframe 4 is checked (its candidates are too recent), 5 is not
  return cfg;
}

TEST(MappingBackend, ClosesTheLoopOfTheLastKeyframeWhenTheRunFinishes) {
  const auto scene = backend::testing::roomA();
  const Walk w = roomWalk();
  backend::MappingBackend backend(config());
  for (std::size_t i = 0; i < w.truth.size(); ++i) backend.addSweep(sweepAt(w, i, scene));
  ASSERT_EQ(backend.keyframes(), 6u);
  EXPECT_EQ(backend.loops(), 0u);
  const double drift_m = (w.odometry.back().translation() - w.truth.back().translation()).norm();
  EXPECT_GT(drift_m, 0.08);

  backend.finish();
  ASSERT_EQ(backend.loops(), 1u);
  const Trajectory corrected = backend.corrected(odometryLog(w));
  ASSERT_EQ(corrected.size(), w.truth.size());
  const Eigen::Isometry3d end_error = w.truth.back().inverse() * corrected.back().T_world_body;
  EXPECT_LT(end_error.translation().norm(), 0.25 * drift_m) << "drift before the loop " << drift_m << " m";
  EXPECT_LT(Eigen::AngleAxisd(end_error.rotation()).angle(), 0.2 * kDeg);
  // A few poses (the live path's) are corrected exactly as in the whole log.
  const PoseLog log = odometryLog(w);
  const Trajectory few = backend.corrected(Trajectory{log[2], log[5]});
  ASSERT_EQ(few.size(), 2u);
  EXPECT_EQ(few[0].T_world_body.matrix(), corrected[2].T_world_body.matrix());
  EXPECT_EQ(few[1].T_world_body.matrix(), corrected[5].T_world_body.matrix());
  backend.finish();  // idempotent: the last keyframe has had its check
  EXPECT_EQ(backend.loops(), 1u);
}

// What a later run needs: every keyframe at its corrected pose (the trajectory's pose at its
// stamp), its odometry pose and cloud, and the loop as it was added.
TEST(MappingBackend, ItsSessionHoldsTheKeyframesAtTheirCorrectedPosesAndTheLoop) {
  const auto scene = backend::testing::roomA();
  const Walk w = roomWalk();
  backend::MappingBackend backend(config());
  for (std::size_t i = 0; i < w.truth.size(); ++i) backend.addSweep(sweepAt(w, i, scene));
  backend.finish();
  ASSERT_EQ(backend.loops(), 1u);
  const Session s = backend.session();
  ASSERT_EQ(s.keyframes.size(), 6u);
  const Trajectory corrected = backend.corrected(odometryLog(w));
  for (std::size_t k = 0; k < s.keyframes.size(); ++k) {
    EXPECT_EQ(s.keyframes[k].stamp_ns, w.stamps[k]);
    EXPECT_TRUE(s.keyframes[k].T_map_body.isApprox(corrected[k].T_world_body, 1e-9)) << "keyframe " << k;
    EXPECT_TRUE(s.keyframes[k].T_odom_body.isApprox(w.odometry[k], 1e-12)) << "keyframe " << k;
    EXPECT_GT(s.keyframes[k].cloud_body.size(), 100u) << "keyframe " << k;
  }
  // The last keyframe is corrected back onto the start, the loop ties it to the first.
  EXPECT_LT((s.keyframes[5].T_map_body.translation() - w.truth[5].translation()).norm(), 0.05);
  ASSERT_EQ(s.loops.size(), 1u);
  EXPECT_EQ(s.loops[0].from, 0);
  EXPECT_EQ(s.loops[0].to, 5);
  EXPECT_TRUE(s.loops[0].T_from_to.isApprox(w.truth[0].inverse() * w.truth[5], 0.02));
  EXPECT_GT(s.loops[0].information(0, 0), 0.0);
  EXPECT_EQ(s.map_voxel_m, config().map_leaf_m);
}

TEST(MappingBackend, FinishDoesNothingWithLoopClosureOff) {
  const auto scene = backend::testing::roomA();
  const Walk w = roomWalk();
  backend::MappingBackend::Config cfg = config();
  cfg.loop_enabled = false;
  backend::MappingBackend backend(cfg);
  for (std::size_t i = 0; i < w.truth.size(); ++i) backend.addSweep(sweepAt(w, i, scene));
  backend.finish();
  EXPECT_EQ(backend.loops(), 0u);
  const Trajectory t = backend.corrected(odometryLog(w));
  EXPECT_TRUE(t.back().T_world_body.isApprox(w.odometry.back(), 1e-6));
}

TEST(MappingBackend, PerLidarMapsKeepEachLidarsPointsApart) {
  // One sweep: 30 Velodyne points on a wall at x = +5 m, then 20 Livox points at x = -5 m.
  estimator::SweepResult r;
  r.status = estimator::SweepResult::Status::kTracking;
  r.keyframe = true;
  r.lidars.resize(2);
  r.lidars[0].sensor = "velodyne";
  r.lidars[0].points = 30;
  r.lidars[1].sensor = "livox";
  r.lidars[1].points = 20;
  for (int i = 0; i < 50; ++i) {
    Point p;
    p.xyz = Eigen::Vector3f(i < 30 ? 5.f : -5.f, 0.1f * static_cast<float>(i), 1.f);
    r.points_body.push_back(p);
  }
  backend::MappingBackend::Config cfg;
  cfg.loop_enabled = false;
  cfg.map_leaf_m = 0.0;  // every point
  cfg.map_point_stride = 1;
  cfg.per_lidar_maps = true;
  backend::MappingBackend backend(cfg);
  backend.addSweep(r);
  const auto names = backend.lidarNames();
  ASSERT_EQ(names.size(), 2u);
  const auto velodyne = backend.lidarMap("velodyne"), livox = backend.lidarMap("livox");
  ASSERT_EQ(velodyne.size(), 30u);
  ASSERT_EQ(livox.size(), 20u);
  for (const Point& p : velodyne) EXPECT_FLOAT_EQ(p.xyz.x(), 5.f);
  for (const Point& p : livox) EXPECT_FLOAT_EQ(p.xyz.x(), -5.f);
  EXPECT_EQ(backend.map().size(), 50u);
  EXPECT_TRUE(backend.lidarMap("ouster").empty());

  cfg.per_lidar_maps = false;
  backend::MappingBackend merged(cfg);
  merged.addSweep(r);
  EXPECT_TRUE(merged.lidarNames().empty());
  EXPECT_EQ(merged.map().size(), 50u);
}

TEST(MappingThread, OnItsOwnThreadTheBackEndGivesExactlyWhatItGivesInline) {
  const auto scene = backend::testing::roomA();
  const Walk w = roomWalk();
  backend::MappingBackend inline_backend(config());
  for (std::size_t i = 0; i < w.truth.size(); ++i) inline_backend.addSweep(sweepAt(w, i, scene));
  inline_backend.finish();
  MappingThread thread(config(), 2);  // a queue shorter than the run: the producer waits
  for (std::size_t i = 0; i < w.truth.size(); ++i) thread.addSweep(sweepAt(w, i, scene));
  backend::MappingBackend& threaded = thread.finish();
  ASSERT_EQ(threaded.loops(), 1u);  // the loop of the last keyframe, as inline
  const Trajectory a = inline_backend.corrected(odometryLog(w)), b = threaded.corrected(odometryLog(w));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].T_world_body.isApprox(b[i].T_world_body, 0.0)) << i;
  EXPECT_EQ(inline_backend.map().size(), threaded.map().size());
  EXPECT_EQ(thread.timing().sweeps(), w.truth.size());
}

TEST(MappingThread, QueuesSweepsWithoutAKeyframeThinnedToWhatTheMapTakesAndMapsTheSame) {
  const auto scene = backend::testing::roomA();
  const Walk w = roomWalk();
  backend::MappingBackend::Config cfg = config();
  cfg.map_point_stride = 3;  // with map_leaf_m 0: every point the map takes shows in it
  cfg.map_leaf_m = 0.0;
  // Each keyframe is followed by two sweeps that open none (other scans from the same place).
  std::vector<estimator::SweepResult> sweeps;
  for (std::size_t i = 0; i < w.truth.size(); ++i)
    for (unsigned extra = 0; extra < 3; ++extra) {
      estimator::SweepResult r = sweepAt(w, i, scene);
      if (extra > 0) {
        r.keyframe = false;
        r.points_body.clear();
        const unsigned seed = 500 + 10 * static_cast<unsigned>(i) + extra;
        for (const Eigen::Vector3d& p : backend::testing::scan(scene, w.truth[i], seed)) {
          Point q;
          q.xyz = p.cast<float>();
          r.points_body.push_back(q);
        }
      }
      sweeps.push_back(r);
    }
  backend::MappingBackend inline_backend(cfg);
  for (const auto& r : sweeps) inline_backend.addSweep(r);
  inline_backend.finish();
  estimator::SweepResult thinned = sweeps[1];
  backend::MappingBackend::keepWhatTheMapTakes(&thinned, 1, cfg);
  EXPECT_TRUE(thinned.points_body_thinned);
  EXPECT_EQ(thinned.points_body.size(), (sweeps[1].points_body.size() + 1) / 3);  // from offset 1 of 3
  MappingThread thread(cfg, 2);
  for (const auto& r : sweeps) thread.addSweep(r);
  backend::MappingBackend& threaded = thread.finish();
  const std::vector<Point> a = inline_backend.map(), b = threaded.map();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i].xyz, b[i].xyz) << i;
}

}  // namespace
}  // namespace mmlio::pipeline
