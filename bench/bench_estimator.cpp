// Estimator benchmarks: the map-match residual block Ceres evaluates every solver iteration
// (BENCHMARK_MAIN lives in bench_main.cpp).
#include <benchmark/benchmark.h>

#include "../tests/estimator/synthetic_matches.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/map_matching.hpp"
#include "mmlio/estimator/pose_manifold.hpp"

namespace {

using namespace mmlio;
using namespace mmlio::estimator;

// A hall sweep's size: 9800 matches, every 12th an edge, within 20 m and 0-10 cm off at the pose
// (about half beyond the 5 cm Huber scale).
void BM_MapMatchesFactorEvaluate(benchmark::State& state) {
  const bool with_jacobian = state.range(0) != 0;
  Eigen::Matrix<double, 7, 1> x;
  x.head<3>() = Eigen::Vector3d(0.02, -0.01, 0.005);
  x.tail<4>() = so3::exp(Eigen::Vector3d(0.002, 0.001, -0.003)).coeffs();
  testing::MatchSpread spread;
  spread.count = 9800;
  spread.edge_every = 12;
  spread.extent_m = 20.0;
  spread.offset_m = 0.1;
  spread.seed = 2;
  const std::vector<MapMatch> matches = testing::randomMatches(blockToPose(x.data()), spread);
  const MapMatchesFactor factor(matches, 1.0 / 0.03, 0.05 / 0.03);
  std::vector<double> residuals(static_cast<std::size_t>(factor.num_residuals()));
  std::vector<double> jacobian(residuals.size() * 7);
  const double* params[] = {x.data()};
  double* jacobians[] = {jacobian.data()};
  for (auto _ : state) {
    factor.Evaluate(params, residuals.data(), with_jacobian ? jacobians : nullptr);
    benchmark::DoNotOptimize(residuals.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(matches.size()));
}
BENCHMARK(BM_MapMatchesFactorEvaluate)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
