// LiDAR front-end and local-map benchmarks on synthetic sweeps of the box room used by the lidar
// tests (BENCHMARK_MAIN lives in bench_main.cpp).
#include <benchmark/benchmark.h>

#include <random>

#include "../tests/lidar/synthetic_scans.hpp"
#include "mmlio/backend/map_accumulator.hpp"
#include "mmlio/lidar/deskew.hpp"
#include "mmlio/lidar/features.hpp"
#include "mmlio/lidar/voxel_filter.hpp"
#include "mmlio/map/range_image.hpp"
#include "mmlio/map/voxel_hash_map.hpp"

namespace {

using namespace mmlio;

// VLP-16-like sweep: 16 rings x 1800 columns = 28,800 points, 1 cm range noise.
void BM_FeaturesVlp16Sweep(benchmark::State& state) {
  const LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  const lidar::FeatureConfig cfg;
  std::size_t edges = 0, planes = 0;
  for (auto _ : state) {
    const auto f = lidar::extractFeatures(scan, LidarKind::kSpinning, 16, cfg);
    edges = f.edges.size();
    planes = f.planes.size();
    benchmark::DoNotOptimize(f.edges.data());
  }
  state.counters["points"] = static_cast<double>(scan.points.size());
  state.counters["edges"] = static_cast<double>(edges);
  state.counters["planes"] = static_cast<double>(planes);
}
BENCHMARK(BM_FeaturesVlp16Sweep)->Unit(benchmark::kMillisecond);

// Same sweep without ring numbers: range-image path.
void BM_FeaturesVlp16RangeImage(benchmark::State& state) {
  LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  for (auto& p : scan.points) p.ring = 0;
  const lidar::FeatureConfig cfg;
  for (auto _ : state)
    benchmark::DoNotOptimize(lidar::extractFeatures(scan, LidarKind::kSpinning, 1, cfg).edges.data());
}
BENCHMARK(BM_FeaturesVlp16RangeImage)->Unit(benchmark::kMillisecond);

// Livox-Horizon-like frame: 6 lines x 4000 points = 24,000 points, 2 cm range noise.
void BM_FeaturesLivoxFrame(benchmark::State& state) {
  const LidarScan scan = synth::livoxRoom(synth::BoxRoom{}, std::atan2(5.0, 6.0), 0.02);
  const lidar::FeatureConfig cfg;
  std::size_t edges = 0, planes = 0;
  for (auto _ : state) {
    const auto f = lidar::extractFeatures(scan, LidarKind::kSolidState, 6, cfg);
    edges = f.edges.size();
    planes = f.planes.size();
    benchmark::DoNotOptimize(f.edges.data());
  }
  state.counters["points"] = static_cast<double>(scan.points.size());
  state.counters["edges"] = static_cast<double>(edges);
  state.counters["planes"] = static_cast<double>(planes);
}
BENCHMARK(BM_FeaturesLivoxFrame)->Unit(benchmark::kMillisecond);

void BM_DeskewVlp16Sweep(benchmark::State& state) {
  const LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  const auto motion = lidar::SweepMotion::constantTwist({1.0, 0, 0}, {0, 0, M_PI / 2}, 0.1);
  for (auto _ : state) {
    state.PauseTiming();
    LidarScan s = scan;
    state.ResumeTiming();
    lidar::deskewToEnd(s, Eigen::Isometry3d::Identity(), motion, 0.1);
    benchmark::DoNotOptimize(s.points.data());
  }
}
BENCHMARK(BM_DeskewVlp16Sweep)->Unit(benchmark::kMillisecond);

// The visibility test of moving-object handling: a sweep's range image, built and asked about
// points of a VLP-16 sweep of the room taken 0.3 m away, on the walls, in front of and behind them
// (what the moved-in test and the map cleaning ask).
void BM_RangeImageBuild(benchmark::State& state) {
  const LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  const map::RangeImageConfig cfg;
  for (auto _ : state) benchmark::DoNotOptimize(map::RangeImage(scan.points, cfg).memoryBytes());
}
BENCHMARK(BM_RangeImageBuild)->Unit(benchmark::kMillisecond);

// Arg 0: the VLP-16's view; 1: a Livox frame's (82 deg), asked about the same points all around.
void BM_RangeImageClassify(benchmark::State& state) {
  const LidarScan scan = state.range(0) == 0 ? synth::vlp16Room(synth::BoxRoom{}, 0.01)
                                             : synth::livoxRoom(synth::BoxRoom{}, std::atan2(5.0, 6.0), 0.02);
  const map::RangeImage image(scan.points, map::RangeImageConfig{});
  std::vector<Eigen::Vector3d> queries;
  for (const Point& p : synth::vlp16Room(synth::BoxRoom{}, 0.01, 7).points) {
    const Eigen::Vector3d v = p.xyz.cast<double>() + Eigen::Vector3d(0.3, 0.0, 0.0);
    for (double scale : {0.7, 1.0, 1.2}) queries.push_back(scale * v);
  }
  std::size_t q = 0;
  int free = 0;
  for (auto _ : state) {
    free += image.classify(queries[q]) == map::Visibility::kFree;
    q = q + 1 == queries.size() ? 0 : q + 1;
  }
  benchmark::DoNotOptimize(free);
  state.counters["free_share"] = static_cast<double>(free) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_RangeImageClassify)->Arg(0)->Arg(1);

void BM_VoxelDownsample20cm(benchmark::State& state) {
  const LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  for (auto _ : state) benchmark::DoNotOptimize(lidar::voxelDownsample(scan.points, 0.2).data());
}
BENCHMARK(BM_VoxelDownsample20cm)->Unit(benchmark::kMillisecond);

// Local map of points on a floor and a 5 m grid of walls over 40 x 40 m; 5-NN within 1 m, per
// query. Args: voxel edge in cm, points per voxel at most, thousands of points (200: ~30 points/m^2,
// sparse like one downsampled sweep; 1200: the odometry's 0.5 m voxels full at 60, as in a hall
// after many keyframes).
void BM_VoxelHashMapKnn(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-20.0, 20.0), h(-1.5, 2.5);
  std::vector<Eigen::Vector3d> pts;
  // Points on a set of walls and a floor: a map-like surface distribution.
  for (int i = 0; i < 1000 * state.range(2); ++i) {
    const int kind = i % 4;
    if (kind == 0)
      pts.emplace_back(u(rng), u(rng), -1.5);
    else if (kind == 1)
      pts.emplace_back(std::round(u(rng) / 5) * 5, u(rng), h(rng));
    else
      pts.emplace_back(u(rng), std::round(u(rng) / 5) * 5, h(rng));
  }
  map::VoxelHashMap m(0.01 * static_cast<double>(state.range(0)), static_cast<int>(state.range(1)));
  m.add(pts);
  std::vector<Eigen::Vector3d> queries(4096);
  for (std::size_t k = 0; k < queries.size(); ++k) {
    queries[k] = pts[(k * 7919) % pts.size()] + Eigen::Vector3d(0.03, -0.02, 0.05);
  }
  std::vector<Eigen::Vector3d> out;
  std::size_t q = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(m.knn(queries[q++ % queries.size()], 5, 1.0, &out));
  }
  state.counters["map_points"] = static_cast<double>(m.size());
}
BENCHMARK(BM_VoxelHashMapKnn)
    ->Args({20, 20, 200})
    ->Args({50, 20, 200})
    ->Args({100, 20, 200})
    ->Args({50, 60, 1200})
    ->Unit(benchmark::kMicrosecond);

void BM_VoxelHashMapAdd(benchmark::State& state) {
  const LidarScan scan = synth::vlp16Room(synth::BoxRoom{}, 0.01);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : scan.points) pts.push_back(p.xyz.cast<double>());
  for (auto _ : state) {
    map::VoxelHashMap m(0.2, 20);
    m.add(pts);
    benchmark::DoNotOptimize(m.size());
  }
}
BENCHMARK(BM_VoxelHashMapAdd)->Unit(benchmark::kMillisecond);

// One keyframe's submap of the output map: ten VLP-16 sweeps of a 60 x 40 m hall, 10 cm apart,
// every 4th point (the back end's map_point_stride) into 5 cm voxels, the accumulator emptied and
// refilled per keyframe as the back end does.
void BM_MapAccumulatorKeyframe(benchmark::State& state) {
  synth::BoxRoom hall;
  hall.lo = {-30.0, -20.0, -1.5};
  hall.hi = {30.0, 20.0, 6.0};
  const LidarScan scan = synth::vlp16Room(hall, 0.01);
  std::vector<Point> strided;
  for (std::size_t i = 0; i < scan.points.size(); i += 4) strided.push_back(scan.points[i]);
  backend::MapAccumulator acc(0.05);
  for (auto _ : state) {
    acc.clear();
    for (int k = 0; k < 10; ++k) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translation() = Eigen::Vector3d(0.1 * k, 0.02 * k, 0.0);
      T.rotate(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()));
      acc.add(strided, T);
    }
    benchmark::DoNotOptimize(acc.size());
  }
  state.counters["voxels"] = static_cast<double>(acc.size());
}
BENCHMARK(BM_MapAccumulatorKeyframe)->Unit(benchmark::kMillisecond);

}  // namespace
