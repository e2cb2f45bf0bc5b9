#pragma once
// Test helper: replays a simulated sequence into the streaming pipeline in bag order
// (IMU by stamp, LiDAR scans by their start stamp), as `mmlio run` would see it.
#include <algorithm>

#include "mmlio/io/rig_config.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio::testing {

/// The default rig config with the simulator's true extrinsics.
inline io::RigConfig simRigConfig(const sim::Simulator& sim) {
  io::RigConfig cfg;
  for (auto& l : cfg.lidars) {
    const LidarExtrinsic e = l.name == "velodyne" ? sim.velodyneExtrinsic() : sim.livoxExtrinsic();
    l.T_imu_sensor = e.T_imu_sensor;
    l.time_offset_s = e.time_offset_s;
  }
  return cfg;
}

/// Replays the simulator's LiDARs with these IMU samples (default: the simulator's own).
inline void replay(const sim::Simulator& sim, pipeline::OnlinePipeline& pipeline, const std::vector<ImuSample>& imu) {
  std::size_t i = 0;
  int v = 0, l = 0;
  const int nv = sim.numVelodyneSweeps(), nl = sim.numLivoxFrames();
  LidarScan next_v = nv > 0 ? sim.velodyneSweep(0) : LidarScan{};
  LidarScan next_l = nl > 0 ? sim.livoxFrame(0) : LidarScan{};
  constexpr Stamp kNever = std::numeric_limits<Stamp>::max();
  while (true) {
    const Stamp ti = i < imu.size() ? imu[i].stamp_ns : kNever;
    const Stamp tv = v < nv ? next_v.start_ns : kNever;
    const Stamp tl = l < nl ? next_l.start_ns : kNever;
    const Stamp t = std::min({ti, tv, tl});
    if (t == kNever) break;
    if (t == ti) {
      pipeline.addImu(imu[i++]);
    } else if (t == tv) {
      pipeline.addScan(std::move(next_v));
      if (++v < nv) next_v = sim.velodyneSweep(v);
    } else {
      pipeline.addScan(std::move(next_l));
      if (++l < nl) next_l = sim.livoxFrame(l);
    }
  }
  pipeline.flush();
}

inline void replay(const sim::Simulator& sim, pipeline::OnlinePipeline& pipeline) { replay(sim, pipeline, sim.imu()); }

}  // namespace mmlio::testing
