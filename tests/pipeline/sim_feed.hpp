#pragma once
// Test helper: replays a simulated sequence into the streaming pipeline in bag order
// (IMU by stamp, LiDAR scans by their start stamp), as `mmlio run` would see it.
#include <algorithm>
#include <functional>
#include <limits>
#include <string>

#include "mmlio/config/rig_config.hpp"
#include "mmlio/io/bag_writer.hpp"
#include "mmlio/pipeline/online_pipeline.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio::testing {

/// The default rig config with the simulator's true extrinsics.
inline config::RigConfig simRigConfig(const sim::Simulator& sim) {
  config::RigConfig cfg;
  for (auto& l : cfg.lidars) {
    const LidarExtrinsic e = l.name == "velodyne" ? sim.velodyneExtrinsic() : sim.livoxExtrinsic();
    l.T_imu_sensor = e.T_imu_sensor;
    l.time_offset_s = e.time_offset_s;
  }
  return cfg;
}

/// Replays the simulator's data in stamp order, as a bag stores it. `edit` may corrupt a scan (by
/// its index among all scans fed) and `edit_imu` an IMU sample (by index) just before it is fed,
/// after the order was decided: a corrupt header stamp does not move a message in a bag.
/// Sink: an OnlinePipeline or a System (addImu, addScan). Leaves the sink unflushed, so that a
/// second feed continues the same stream (a bag played again).
template <typename Sink> void feed(const sim::Simulator& sim, Sink& pipeline,
                                   const std::function<void(int, LidarScan&)>& edit,
                                   const std::function<void(std::size_t, ImuSample&)>& edit_imu = {}) {
  const std::vector<ImuSample>& imu = sim.imu();
  int fed = 0;
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
      ImuSample sample = imu[i];
      if (edit_imu) edit_imu(i, sample);
      ++i;
      pipeline.addImu(sample);
    } else if (t == tv) {
      if (edit) edit(fed, next_v);
      ++fed;
      pipeline.addScan(std::move(next_v));
      if (++v < nv) next_v = sim.velodyneSweep(v);
    } else {
      if (edit) edit(fed, next_l);
      ++fed;
      pipeline.addScan(std::move(next_l));
      if (++l < nl) next_l = sim.livoxFrame(l);
    }
  }
}

/// feed(), then the end of the stream (flush).
template <typename Sink> void replay(const sim::Simulator& sim, Sink& pipeline,
                                     const std::function<void(int, LidarScan&)>& edit,
                                     const std::function<void(std::size_t, ImuSample&)>& edit_imu = {}) {
  feed(sim, pipeline, edit, edit_imu);
  pipeline.flush();
}

template <typename Sink> void replay(const sim::Simulator& sim, Sink& pipeline) { replay(sim, pipeline, {}); }

/// The simulated sequence as a bag at `path`, as `mmlio simulate` writes it (Livox IMU in g,
/// Livox CustomMsg, Velodyne PointCloud2), without the IMU samples `keep_imu` refuses.
inline void writeSimBag(
    const sim::Simulator& sim, const std::string& path,
    const std::function<bool(const ImuSample&)>& keep_imu = [](const ImuSample&) { return true; }) {
  io::BagWriter bag(path);
  const std::vector<ImuSample>& imu = sim.imu();
  const Stamp kNever = std::numeric_limits<Stamp>::max();
  std::size_t i = 0;
  int l = 0, v = 0;
  const auto livox = [&](int k) { return k < sim.numLivoxFrames() ? sim.startNs() + k * 100000000LL : kNever; };
  const auto velodyne = [&](int k) { return k < sim.numVelodyneSweeps() ? sim.velodyneTrueStartNs(k) : kNever; };
  while (i < imu.size() || livox(l) != kNever || velodyne(v) != kNever) {
    const Stamp ti = i < imu.size() ? imu[i].stamp_ns : kNever;
    if (ti <= livox(l) && ti <= velodyne(v)) {
      if (keep_imu(imu[i])) bag.writeImu("/livox/imu", "livox_frame", imu[i], true);
      ++i;
    } else if (livox(l) <= velodyne(v)) {
      bag.writeLivoxCloud("/livox/lidar", "livox_frame", sim.livoxFrame(l++));
    } else {
      bag.writeVelodyneCloud("/velodyne_points", "velodyne", sim.velodyneSweep(v++));
    }
  }
  bag.close();
}

}  // namespace mmlio::testing
