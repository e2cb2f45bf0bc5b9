// The solid-state LiDAR's reach in a corridor: a 60 m corridor's axis is observed only by its far
// end wall (and sparse door frames), which a scan line crosses in fewer points than a curvature
// neighbourhood needs. These runs walk 5 m up the corridor and back (20 s).
#include <gtest/gtest.h>

#include "mmlio/eval/evaluation.hpp"
#include "sim_feed.hpp"

namespace mmlio {
namespace {

struct CorridorRun {
  eval::EvalResult eval;
  std::size_t degenerate = 0, registered = 0;
};

CorridorRun runCorridor(const std::string& mode, estimator::SurfacePoints surface_points, sim::SolidStatePattern pattern) {
  sim::SimOptions so;
  so.scenario = "corridor";
  so.duration_s = 20.0;
  so.livox_pattern = pattern;
  const sim::Simulator sim(so);
  io::RigConfig cfg = testing::simRigConfig(sim);
  cfg.estimator.surface_points = surface_points;
  Trajectory trajectory;
  CorridorRun run;
  pipeline::OnlinePipeline online(cfg, mode, [&](const estimator::SweepResult& r) {
    if (r.status == estimator::SweepResult::Status::kInitializing) return;
    trajectory.push_back({r.state.stamp_ns, r.state.pose()});
    run.registered += r.registered ? 1 : 0;
    run.degenerate += r.registered && r.degeneracy.translation_degenerate ? 1 : 0;
  });
  testing::replay(sim, online);
  run.eval = eval::evaluate(sim.groundTruth(), trajectory);
  return run;
}

TEST(FusionOnSimulation, EverySolidStateReturnReachesTheEstimatorAndHoldsTheCorridorAxis) {
  const CorridorRun lines = runCorridor("hi", estimator::SurfacePoints::kNone, sim::SolidStatePattern::kLissajous);
  const CorridorRun surface = runCorridor("hi", estimator::SurfacePoints::kSolidState, sim::SolidStatePattern::kLissajous);
  std::printf("HI corridor 20 s: scan-line planes ATE %.3f m; every return ATE %.3f m, %zu/%zu sweeps degenerate\n",
              lines.eval.ate_rmse_m, surface.eval.ate_rmse_m, surface.degenerate, surface.registered);
  EXPECT_LT(surface.eval.ate_rmse_m, 0.10);
  EXPECT_GT(lines.eval.ate_rmse_m, 5 * surface.eval.ate_rmse_m);  // why surface_points defaults to solid_state
}

TEST(FusionOnSimulation, HviBeatsVelodyneAloneWithEitherSolidStatePattern) {
  const CorridorRun vi = runCorridor("vi", estimator::SurfacePoints::kSolidState, sim::SolidStatePattern::kLissajous);
  for (const auto pattern : {sim::SolidStatePattern::kLissajous, sim::SolidStatePattern::kRosette}) {
    const CorridorRun hvi = runCorridor("hvi", estimator::SurfacePoints::kSolidState, pattern);
    std::printf("corridor 20 s: HVI ATE %.4f m (%s), VI %.4f m\n", hvi.eval.ate_rmse_m,
                pattern == sim::SolidStatePattern::kRosette ? "rosette" : "lissajous", vi.eval.ate_rmse_m);
    EXPECT_LT(hvi.eval.ate_rmse_m, 0.025);
    EXPECT_LE(hvi.eval.ate_rmse_m, vi.eval.ate_rmse_m);
  }
}

}  // namespace
}  // namespace mmlio
