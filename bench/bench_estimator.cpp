// Estimator benchmarks: the map-match residual block Ceres evaluates every solver iteration
// (BENCHMARK_MAIN lives in bench_main.cpp).
#include <benchmark/benchmark.h>

#include <random>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/map_matching.hpp"

namespace {

using namespace mmlio;
using namespace mmlio::estimator;

// A hall sweep's size: ~9000 plane and ~800 edge matches 0-10 cm off at a pose, a tenth beyond the
// Huber scale.
void BM_MapMatchesFactorEvaluate(benchmark::State& state) {
  const bool with_jacobian = state.range(0) != 0;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> U(-20.0, 20.0), offset(-0.1, 0.1);
  std::vector<MapMatch> matches;
  for (int i = 0; i < 9800; ++i) {
    MapMatch m;
    m.kind = i % 12 == 0 ? MapMatch::Kind::kEdge : MapMatch::Kind::kPlane;
    m.p_body = {U(rng), U(rng), 0.1 * U(rng)};
    m.a = m.kind == MapMatch::Kind::kPlane ? Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized()
                                           : Eigen::Vector3d(m.p_body + Eigen::Vector3d::Constant(offset(rng)));
    m.b = m.kind == MapMatch::Kind::kPlane ? Eigen::Vector3d(-m.a.dot(m.p_body) + offset(rng), 0, 0)
                                           : Eigen::Vector3d(U(rng), U(rng), 1.0).normalized();
    matches.push_back(m);
  }
  const MapMatchesFactor factor(matches, 1.0 / 0.03, 0.05 / 0.03);
  Eigen::Matrix<double, 7, 1> x;
  x.head<3>() = Eigen::Vector3d(0.02, -0.01, 0.005);
  x.tail<4>() = so3::exp(Eigen::Vector3d(0.002, 0.001, -0.003)).coeffs();
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
