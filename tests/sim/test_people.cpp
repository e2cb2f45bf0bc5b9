#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mmlio/sim/simulator.hpp"

namespace mmlio::sim {
namespace {

SimOptions withPeople(const std::string& scenario, int people, std::uint64_t seed = 1, double duration_s = 0) {
  SimOptions o;
  o.scenario = scenario;
  o.people = people;
  o.seed = seed;
  o.duration_s = duration_s;
  return o;
}

double distanceToBox(const Box& b, const Eigen::Vector3d& p) { return (p.cwiseMax(b.lo).cwiseMin(b.hi) - p).norm(); }

}  // namespace

TEST(People, EveryScenarioFindsRoomForFourPeopleWhoKeepClearOfWallsAndTheRigAndWalkAtPersonSpeed) {
  for (const std::string& scenario : scenarioNames()) {
    // People walk on the ground floor; the stairs' 2.4 m corridors leave no room beside the route.
    if (scenario == "stairs") continue;
    const Simulator sim(withPeople(scenario, 4));
    ASSERT_EQ(sim.crowd().size(), 4) << scenario;
    for (int i = 0; i < sim.crowd().size(); ++i) {
      const Person& p = sim.crowd().people()[static_cast<std::size_t>(i)];
      EXPECT_GE(p.speed_m_s, 0.8);
      EXPECT_LE(p.speed_m_s, 1.5);
      for (double t = 0.0; t < sim.durationS(); t += 0.5) {
        const Eigen::Vector2d c = sim.crowd().position(i, t);
        // Not inside anything: the person's centre at chest height is clear of every static box.
        EXPECT_GT(sim.scene().distanceToSurface(Eigen::Vector3d(c.x(), c.y(), 1.0)), 0.2) << scenario << " t " << t;
        const Eigen::Vector3d rig = sim.trueState(sim.startNs() + fromSec(t)).p_world;
        EXPECT_GT((rig.head<2>() - c).norm(), 0.6) << scenario << " t " << t;
        EXPECT_LE((sim.crowd().position(i, t + 0.1) - c).norm(), 0.1 * p.speed_m_s + 1e-9);
      }
    }
  }
}

TEST(People, PathsDependOnTheSeedAndRepeatForTheSameSeed) {
  const Simulator a(withPeople("corridor", 3, 1)), b(withPeople("corridor", 3, 1)), c(withPeople("corridor", 3, 2));
  EXPECT_TRUE(a.crowd().position(0, 20.0).isApprox(b.crowd().position(0, 20.0)));
  EXPECT_FALSE(a.crowd().position(0, 20.0).isApprox(c.crowd().position(0, 20.0)));
}

TEST(People, BothLidarsSeeThePeopleAndTheGroundTruthLabelsTheirReturns) {
  const Simulator sim(withPeople("corridor", 8, 3, 40));
  std::size_t person_returns[2] = {0, 0};
  for (int k = 30; k < 300; k += 30) {
    for (int lidar = 0; lidar < 2; ++lidar) {
      std::vector<std::uint8_t> on_person;
      const LidarScan scan = lidar == 0 ? sim.velodyneSweep(k, &on_person) : sim.livoxFrame(k, &on_person);
      const LidarExtrinsic ext = lidar == 0 ? sim.velodyneExtrinsic() : sim.livoxExtrinsic();
      ASSERT_EQ(on_person.size(), scan.points.size());
      const Stamp true_start = scan.start_ns + fromSec(ext.time_offset_s);
      const double t0 = toSec(true_start - sim.startNs());
      for (std::size_t i = 0; i < scan.points.size(); i += 5) {
        const Point& p = scan.points[i];
        const Eigen::Vector3d w =
            sim.trueState(true_start + fromSec(p.time_s)).pose() * ext.T_imu_sensor * p.xyz.cast<double>();
        if (on_person[i]) {
          ++person_returns[lidar];
          double nearest = 1e9;  // the person is where the crowd says at the point's own time
          for (int j = 0; j < sim.crowd().size(); ++j)
            nearest = std::min(nearest, distanceToBox(sim.crowd().boxAt(j, t0 + p.time_s), w));
          EXPECT_LT(nearest, 0.08);
          if (w.z() > 0.2) {
            EXPECT_GT(sim.scene().distanceToSurface(w), 0.05);  // not on a wall
          }
        } else {
          EXPECT_LT(sim.scene().distanceToSurface(w), 0.08);
        }
      }
    }
  }
  EXPECT_GT(person_returns[0], 100u);
  EXPECT_GT(person_returns[1], 100u);
}

TEST(People, NoPeopleMeansNoLabelsAndTheSameDataAsBefore) {
  const Simulator plain(withPeople("office", 0, 1, 8)), none(withPeople("office", 0, 1, 8));
  std::vector<std::uint8_t> on_person;
  const LidarScan a = plain.livoxFrame(20, &on_person), b = none.livoxFrame(20);
  EXPECT_TRUE(std::none_of(on_person.begin(), on_person.end(), [](std::uint8_t f) { return f != 0; }));
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_TRUE(plain.crowd().empty());
}

}  // namespace mmlio::sim
