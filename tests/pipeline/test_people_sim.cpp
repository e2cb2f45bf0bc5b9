// People walking past the rig in the simulated corridor (25 s: 8 m up the corridor and back,
// four people pacing along it, as many as the held-out corridor had). What moves must neither pull the odometry nor
// stay in the map, and the static surfaces must stay.
#include <gtest/gtest.h>

#include <cstdio>

#include "mmlio/backend/mapping_backend.hpp"
#include "mmlio/eval/evaluation.hpp"
#include "mmlio/pipeline/odometry_setup.hpp"
#include "mmlio/sim/map_score.hpp"
#include "sim_feed.hpp"

namespace mmlio {
namespace {

struct PeopleRun {
  eval::EvalResult eval;
  double off_surface = 0.0;                 // map points farther than 10 cm from every static surface
  std::vector<Eigen::Vector3d> on_surface;  // the others (ground-truth frame)
  std::size_t rejected = 0, removed = 0;
  std::size_t sweeps = 0, judged = 0;  // tested for movers
  Trajectory trajectory;
};

PeopleRun runCorridor(int people, bool handle_dynamic, double duration_s = 25.0) {
  sim::SimOptions so;
  so.scenario = "corridor";
  so.duration_s = duration_s;
  so.people = people;
  so.seed = 4;
  const sim::Simulator sim(so);
  config::RigConfig cfg = testing::simRigConfig(sim);
  cfg.estimator.dynamic.enabled = handle_dynamic;
  cfg.mapping.clean_map = handle_dynamic;
  cfg.mapping.loop_enabled = false;
  backend::MappingBackend mapping(cfg.mapping);
  Trajectory trajectory;
  PeopleRun run;
  pipeline::OnlinePipeline online(cfg, "hvi", [&](const estimator::SweepResult& r) {
    if (r.status == estimator::SweepResult::Status::kInitializing) return;
    trajectory.push_back({r.state.stamp_ns, r.state.pose()});
    run.rejected += r.dynamic_points;
    ++run.sweeps;
    run.judged += r.judged_for_movers;
    mapping.addSweep(r);
  });
  testing::replay(sim, online);
  run.eval = eval::evaluate(sim.groundTruth(), trajectory);
  run.trajectory = trajectory;
  mapping.finish();
  const std::vector<Point> map = mapping.map();
  run.removed = mapping.ghostRemoval().removed_points;
  std::vector<Eigen::Vector3d> map_gt;
  for (const Point& p : map) map_gt.push_back(run.eval.T_gt_est_pose * p.xyz.cast<double>());
  sim::MapScore score = sim::scoreMap(sim.scene(), map_gt);
  run.off_surface = map.empty() ? 1.0 : score.off_surface_fraction;
  run.on_surface = std::move(score.on_surface);
  std::printf(
      "corridor 25 s, %d people, dynamic handling %s: ATE %.4f m, map %.2f %% off the surfaces, %zu static "
      "surface points, %zu feature points rejected, %zu map points removed\n",
      people, handle_dynamic ? "on" : "off", run.eval.ate_rmse_m, 100 * run.off_surface, run.on_surface.size(),
      run.rejected, run.removed);
  return run;
}

TEST(PeopleOnSimulation, WalkersNeitherPullTheOdometryNorStayInTheMapAndTheStaticSceneStays) {
  const PeopleRun empty = runCorridor(0, true);
  const PeopleRun ignored = runCorridor(4, false);
  const PeopleRun handled = runCorridor(4, true);
  EXPECT_LT(handled.eval.ate_rmse_m, 1.5 * empty.eval.ate_rmse_m);
  EXPECT_GT(ignored.off_surface, 0.03);  // the people leave trails when nothing handles them ...
  EXPECT_LT(handled.off_surface, 0.01);  // ... and none when the map is cleaned
  // No holes where nobody walked: the static surface the run without people maps is still there
  // (within 10 cm), but for what the people hid from every view of this short run.
  const double kept = sim::staticPointsKept(handled.on_surface, empty.on_surface);
  std::printf("static surface points of the run without people kept: %.2f %%\n", 100 * kept);
  EXPECT_GT(kept, 0.97);
  EXPECT_GT(handled.rejected, 1000u);
  EXPECT_LT(empty.removed, 0.001 * empty.on_surface.size());  // static surfaces are not mistaken for ghosts
  // Where nothing moves, movers are looked for at intervals; with walkers about, in every sweep.
  EXPECT_LT(empty.judged, 0.4 * empty.sweeps);
  EXPECT_GT(handled.judged, 0.9 * handled.sweeps);
}

TEST(PeopleOnSimulation, TheSameSequenceGivesTheSameTrajectoryAndMapCleaning) {
  const PeopleRun a = runCorridor(4, true, 12.0), b = runCorridor(4, true, 12.0);
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  ASSERT_GT(a.rejected, 0u);
  for (std::size_t i = 0; i < a.trajectory.size(); ++i)
    ASSERT_TRUE(a.trajectory[i].T_world_body.isApprox(b.trajectory[i].T_world_body, 0.0)) << "pose " << i;
  EXPECT_EQ(a.rejected, b.rejected);
  EXPECT_EQ(a.removed, b.removed);
}

}  // namespace
}  // namespace mmlio
