// Backend benchmarks: pose-graph optimisation, point-to-plane ICP and loop detection on the
// synthetic ray-cast scenes of the backend tests (BENCHMARK_MAIN lives in another bench file).
#include <benchmark/benchmark.h>

#include "../tests/backend/synthetic_scene.hpp"
#include "mmlio/backend/loop_closer.hpp"
#include "mmlio/backend/point_to_plane_icp.hpp"
#include "mmlio/backend/pose_graph.hpp"

namespace {

using namespace mmlio;
using namespace mmlio::backend;
using testing::pose;

// A circle of N keyframes with yaw drift, closed by one loop edge.
void BM_PoseGraphOptimizeCircle(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    state.PauseTiming();
    PoseGraph graph;
    Eigen::Isometry3d odom = Eigen::Isometry3d::Identity();
    for (int i = 0; i < n; ++i) {
      KeyframeNode node;
      node.stamp_ns = fromSec(i);
      node.T_world_body_odom = odom;
      graph.addKeyframe(node);
      odom = odom * pose(1.0, 0, 0, 2 * M_PI / n + 0.001);
    }
    graph.addLoop(n - 1, 0, pose(1.0, 0, 0, 2 * M_PI / n), isotropicInformation(0.01, 0.001));
    state.ResumeTiming();
    benchmark::DoNotOptimize(graph.optimize());
  }
}
BENCHMARK(BM_PoseGraphOptimizeCircle)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_PointToPlaneIcpRoom(benchmark::State& state) {
  const auto scene = testing::roomA();
  const Eigen::Isometry3d T_world_a = pose(-1.0, 0.5, 1.0, 0.2);
  const auto a = testing::scan(scene, T_world_a, 1);
  const auto b = map::voxelCentroids(testing::scan(scene, T_world_a * pose(0.6, -0.4, 0.05, 0.1), 2), 0.1);
  const IcpTarget target(map::voxelCentroids(a, 0.1));
  for (auto _ : state) benchmark::DoNotOptimize(alignPointToPlane(b, target, Eigen::Isometry3d::Identity()));
  state.counters["source_points"] = static_cast<double>(b.size());
}
BENCHMARK(BM_PointToPlaneIcpRoom)->Unit(benchmark::kMillisecond);

void BM_LoopCloserTrueRevisit(benchmark::State& state) {
  const auto scene = testing::roomA();
  const Eigen::Isometry3d T0 = pose(-2.0, 1.0, 1.0, 0.3);
  const Eigen::Isometry3d T1 = T0 * pose(0.8, -0.5, 0.0, 0.26);
  PoseGraph graph;
  KeyframeNode k0, k1;
  k0.T_world_body_odom = T0;
  k0.cloud_body = map::voxelCentroids(testing::scan(scene, T0, 10), 0.1);
  k1.stamp_ns = fromSec(30.0);
  k1.T_world_body_odom = T1 * pose(0.4, 0.3, 0.02, 0.05);
  k1.cloud_body = map::voxelCentroids(testing::scan(scene, T1, 11), 0.1);
  graph.addKeyframe(k0);
  const int q = graph.addKeyframe(k1);
  const LoopCloser closer{LoopCloser::Config{}};
  for (auto _ : state) benchmark::DoNotOptimize(closer.detect(graph, q));
}
BENCHMARK(BM_LoopCloserTrueRevisit)->Unit(benchmark::kMillisecond);

}  // namespace
