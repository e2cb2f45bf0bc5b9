#include <gtest/gtest.h>

#include <cstdlib>

#include "mmlio/backend/map_accumulator.hpp"
#include "mmlio/eval/evaluation.hpp"
#include <algorithm>
#include "sim_feed.hpp"

namespace mmlio {
namespace {

struct SimRun {
  Trajectory trajectory;
  std::vector<double> map_error_m;  // |distance to the true surface| of map points (2 cm voxels)
  eval::EvalResult eval;
  std::size_t degraded = 0;
  ImuBias final_bias_error;  // estimate - truth at the last sweep
};

SimRun runSimulated(const std::string& scenario, double duration_s, const std::string& mode) {
  sim::SimOptions so;
  so.scenario = scenario;
  so.duration_s = duration_s;
  sim::Simulator sim(so);
  SimRun run;
  backend::MapAccumulator map(0.02);
  pipeline::OnlinePipeline online(testing::simRigConfig(sim), mode, [&](const estimator::SweepResult& r) {
    if (r.status == estimator::SweepResult::Status::kInitializing) return;
    if (r.status == estimator::SweepResult::Status::kDegraded) ++run.degraded;
    run.trajectory.push_back({r.state.stamp_ns, r.state.pose()});
    const ImuBias truth = sim.trueState(r.state.stamp_ns).bias;
    run.final_bias_error.acc_m_s2 = r.state.bias.acc_m_s2 - truth.acc_m_s2;
    run.final_bias_error.gyro_rad_s = r.state.bias.gyro_rad_s - truth.gyro_rad_s;
    map.add(r.points_body, r.state.pose());
    if (std::getenv("MMLIO_SIM_DEBUG")) {
      const NavState t = sim.trueState(r.state.stamp_ns);
      std::printf(
          "%.2f kf%d corr %zu p (%.3f %.3f %.3f) true (%.3f %.3f %.3f) v %.2f truev %.2f ba %.3f %.3f %.3f %s ms:",
          toSec(r.state.stamp_ns - sim::kSimStartNs), r.keyframe, r.correspondences, r.state.p_world.x(),
          r.state.p_world.y(), r.state.p_world.z(), t.p_world.x(), t.p_world.y(), t.p_world.z(), r.state.v_world.norm(),
          t.v_world.norm(), r.state.bias.acc_m_s2.x(), r.state.bias.acc_m_s2.y(), r.state.bias.acc_m_s2.z(),
          r.note.c_str());
      const Eigen::Vector3d tilt_error = r.state.q_world_body.conjugate() * Eigen::Vector3d::UnitZ() -
                                         t.q_world_body.conjugate() * Eigen::Vector3d::UnitZ();
      std::printf(" tilt err %.1f %.1f mrad", 1e3 * tilt_error.x(), 1e3 * tilt_error.y());
      for (const auto& [k, ms] : r.times_ms) std::printf(" %s=%.1f", k.c_str(), ms);
      for (const auto& l : r.lidars)
        std::printf(" | %s e%zu p%zu%s", l.sensor.c_str(), l.edges, l.planes, l.bad_frame ? " BAD" : "");
      std::printf("\n");
    }
  });
  testing::replay(sim, online);
  run.eval = eval::evaluate(sim.groundTruth(), run.trajectory);
  // Map quality: every map voxel brought into the true world should sit on a scene surface. The
  // estimate's world is anchored to the truth at the first pose (as the estimator anchors it),
  // not by a trajectory fit whose yaw is weak on a short walk.
  const Eigen::Isometry3d T_gt_est =
      sim.trueState(run.trajectory.front().stamp_ns).pose() * run.trajectory.front().T_world_body.inverse();
  for (const Point& p : map.points()) {
    run.map_error_m.push_back(sim.scene().distanceToSurface(T_gt_est * p.xyz.cast<double>()));
  }
  std::sort(run.map_error_m.begin(), run.map_error_m.end());
  return run;
}

TEST(OdometryOnSimulation, HviTracksTheOfficeWalkToCentimetres) {
  // MMLIO_SIM_SECONDS / _SCENARIO / _MODE turn this into a manual accuracy run.
  const char* env = std::getenv("MMLIO_SIM_SECONDS");
  const char* scenario_env = std::getenv("MMLIO_SIM_SCENARIO");
  const char* mode_env = std::getenv("MMLIO_SIM_MODE");
  const std::string scenario = scenario_env ? scenario_env : "office";
  const std::string mode = mode_env ? mode_env : "hvi";
  const double seconds = env ? std::atof(env) : 12.0;
  const SimRun run = runSimulated(scenario, seconds, mode);
  std::printf("%s %s %.0f s: %zu poses, ATE %.4f m, RPE %.3f %%, e2e %.3f m, degraded %zu\n", scenario.c_str(),
              mode.c_str(), seconds, run.trajectory.size(), run.eval.ate_rmse_m, run.eval.rpe_10m_pct,
              run.eval.end_to_end_m, run.degraded);
  const auto& e = run.map_error_m;
  ASSERT_FALSE(e.empty());
  const double median = e[e.size() / 2], p90 = e[e.size() * 9 / 10];
  std::printf("map: %zu voxels of 2 cm, distance to the true surfaces: median %.1f mm, p90 %.1f mm\n", e.size(),
              1e3 * median, 1e3 * p90);
  EXPECT_LT(median, 0.015);  // measured 10 mm: range noise 1.5-2 cm, pose error ~1 cm
  EXPECT_LT(p90, 0.05);      // measured 34 mm
  // Biases are only observable through the sliding window's IMU factors: it must have converged
  // from the initialiser's guess (gyro from the standstill, accelerometer zero) to the truth.
  std::printf("bias error: acc %.4f m/s^2, gyro %.5f rad/s\n", run.final_bias_error.acc_m_s2.norm(),
              run.final_bias_error.gyro_rad_s.norm());
  EXPECT_LT(run.final_bias_error.gyro_rad_s.norm(), 0.0025);  // initialiser: 0.0055, measured 0.0015
  EXPECT_LT(run.final_bias_error.acc_m_s2.norm(), 0.03);      // initialiser: 0.032 (zero), measured 0.019
  EXPECT_GT(run.eval.coverage, 0.8);
  EXPECT_LT(run.eval.ate_rmse_m, 0.05);
  EXPECT_EQ(run.degraded, 0u);
}

}  // namespace
}  // namespace mmlio
