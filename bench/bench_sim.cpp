// Simulator speed: one VLP-16 sweep (28,800 beams) and one Livox frame (24,000 beams) ray cast
// in the office (50 boxes) and the hall (~240 boxes), while walking.
#include <benchmark/benchmark.h>

#include "mmlio/sim/simulator.hpp"

namespace {

const mmlio::sim::Simulator& simulator(const std::string& scenario) {
  static const mmlio::sim::Simulator office(mmlio::sim::fullWalk("office")), hall(mmlio::sim::fullWalk("hall"));
  return scenario == "office" ? office : hall;
}

void BM_VelodyneSweep(benchmark::State& state, const std::string& scenario) {
  const auto& sim = simulator(scenario);
  int k = 100;
  for (auto _ : state) {
    const auto scan = sim.velodyneSweep(k);
    benchmark::DoNotOptimize(scan.points.data());
    k = k % 200 + 100;
  }
  state.SetItemsProcessed(state.iterations() * 28800);
}

void BM_LivoxFrame(benchmark::State& state, const std::string& scenario) {
  const auto& sim = simulator(scenario);
  int k = 100;
  for (auto _ : state) {
    const auto scan = sim.livoxFrame(k);
    benchmark::DoNotOptimize(scan.points.data());
    k = k % 200 + 100;
  }
  state.SetItemsProcessed(state.iterations() * 24000);
}

}  // namespace

BENCHMARK_CAPTURE(BM_VelodyneSweep, office, std::string("office"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_VelodyneSweep, hall, std::string("hall"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LivoxFrame, office, std::string("office"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LivoxFrame, hall, std::string("hall"))->Unit(benchmark::kMillisecond);
