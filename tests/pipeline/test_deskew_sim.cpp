// De-skew on simulated sweeps taken during a fast turn (the hall starts with a half turn at
// 1.2 rad/s): corrected with the true motion or with the IMU-propagated motion, the points of the
// sweep, placed at the true pose of the sweep end, lie on the scene's surfaces.
#include <gtest/gtest.h>

#include <algorithm>

#include "mmlio/imu/imu_integrator.hpp"
#include "mmlio/lidar/deskew.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio {
namespace {

struct SweepCase {
  sim::Simulator sim{sim::fullWalk("hall")};
  int k = 29;  // true start 2.937 s: the turn is at full rate
  LidarScan scan = sim.velodyneSweep(k);
  Stamp start_ns = sim.velodyneTrueStartNs(k);
  Stamp end_ns = start_ns + 100000000LL;
  Eigen::Isometry3d T_imu_sensor = sim.velodyneExtrinsic().T_imu_sensor;

  /// Median distance of the sweep's points, placed at the true end pose, to the scene.
  double medianSurfaceDistance(const LidarScan& s) const {
    const Eigen::Isometry3d T_world_sensor = sim.trueState(end_ns).pose() * T_imu_sensor;
    std::vector<double> d;
    for (std::size_t i = 0; i < s.points.size(); i += 7)
      d.push_back(sim.scene().distanceToSurface(T_world_sensor * s.points[i].xyz.cast<double>()));
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    return d[d.size() / 2];
  }

  lidar::SweepMotion motionFrom(const std::vector<NavState>& states, const std::vector<Stamp>& times) const {
    const Eigen::Isometry3d T_end_inv = states.back().pose().inverse();
    std::vector<double> t;
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t i = 0; i < states.size(); ++i) {
      t.push_back(toSec(times[i] - start_ns));
      poses.push_back(T_end_inv * states[i].pose());
    }
    return lidar::SweepMotion(t, poses);
  }

  std::vector<Stamp> queryTimes() const {
    std::vector<Stamp> q;
    for (int i = 0; i <= 10; ++i) q.push_back(start_ns + (end_ns - start_ns) * i / 10);
    return q;
  }
};

TEST(DeskewOnSimulation, TrueMotionPutsATurningSweepOnTheSurfaces) {
  SweepCase c;
  const double raw = c.medianSurfaceDistance(c.scan);
  std::vector<NavState> states;
  for (Stamp t : c.queryTimes()) states.push_back(c.sim.trueState(t));
  LidarScan fixed = c.scan;
  lidar::deskewToEnd(fixed, c.T_imu_sensor, c.motionFrom(states, c.queryTimes()), 0.1);
  const double deskewed = c.medianSurfaceDistance(fixed);
  EXPECT_GT(raw, 3.0 * deskewed);  // the turn smears the raw sweep by centimetres
  EXPECT_LT(deskewed, 0.012);
}

TEST(DeskewOnSimulation, ImuPropagatedMotionPutsATurningSweepOnTheSurfaces) {
  SweepCase c;
  const NavState start = c.sim.trueState(c.start_ns);
  std::vector<ImuSample> samples;
  for (const ImuSample& s : c.sim.imu())
    if (s.stamp_ns >= c.start_ns - 10000000LL && s.stamp_ns <= c.end_ns + 10000000LL) samples.push_back(s);
  const std::vector<NavState> states = imu::propagate(start, samples, c.queryTimes(), Eigen::Vector3d(0, 0, -9.81));
  LidarScan fixed = c.scan;
  lidar::deskewToEnd(fixed, c.T_imu_sensor, c.motionFrom(states, c.queryTimes()), 0.1);
  const double deskewed = c.medianSurfaceDistance(fixed);
  EXPECT_LT(deskewed, 0.012);
}

}  // namespace
}  // namespace mmlio
