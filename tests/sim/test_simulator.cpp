#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/sim/simulator.hpp"

namespace mmlio::sim {
namespace {

SimOptions opts(const std::string& scenario, double duration_s, std::uint64_t seed = 1, double offset_s = 0) {
  SimOptions o;
  o.scenario = scenario;
  o.duration_s = duration_s;
  o.seed = seed;
  o.velodyne_time_offset_s = offset_s;
  return o;
}

TEST(Motion, AnalyticVelocityAccelerationAndBodyRateMatchFiniteDifferences) {
  const Scenario s = makeScenario("office");
  const SplineMotion m(walkKeyframes(s.waypoints, s.walk));
  const double h = 1e-5;
  for (double t : {3.1, 7.77, 15.2, 16.9, 25.0}) {
    const MotionState a = m.at(t - h), b = m.at(t + h), c = m.at(t);
    EXPECT_LT(((b.p_world - a.p_world) / (2 * h) - c.v_world).norm(), 1e-6) << t;
    EXPECT_LT(((b.v_world - a.v_world) / (2 * h) - c.a_world).norm(), 1e-5) << t;
    const Eigen::Vector3d omega = so3::log(a.q_world_body.conjugate() * b.q_world_body) / (2 * h);
    EXPECT_LT((omega - c.omega_body).norm(), 1e-5) << t;
  }
}

TEST(Motion, OfficeUTurnsPeakNear90DegPerSecondAndWalkNear08MetresPerSecond) {
  const Scenario s = makeScenario("office");
  const SplineMotion m(walkKeyframes(s.waypoints, s.walk));
  double max_rate = 0, max_speed = 0;
  for (double t = 0; t < m.durationS(); t += 0.01) {
    max_rate = std::max(max_rate, m.at(t).omega_body.norm());
    max_speed = std::max(max_speed, m.at(t).v_world.norm());
  }
  EXPECT_NEAR(max_rate * 180 / M_PI, 90.0, 15.0);
  EXPECT_NEAR(max_speed, 0.8, 0.2);
}

// Midpoint integration of the ideal IMU of `m` from its true state at t0 over span_s.
NavState integrateImu(const SplineMotion& m, double t0, double span_s) {
  const double step_s = 5e-4;
  const MotionState m0 = m.at(t0);
  NavState s;
  s.p_world = m0.p_world;
  s.v_world = m0.v_world;
  s.q_world_body = m0.q_world_body;
  const Eigen::Vector3d g(0, 0, -kGravityM_s2);
  for (int i = 0; i < static_cast<int>(span_s / step_s); ++i) {
    const double t = t0 + i * step_s;
    const MotionState a = m.at(t), mid = m.at(t + step_s / 2), b = m.at(t + step_s);
    const Eigen::Quaterniond q_mid = s.q_world_body * so3::exp(0.5 * step_s * mid.omega_body);
    const Eigen::Quaterniond q_end = s.q_world_body * so3::exp(step_s * mid.omega_body);
    const Eigen::Vector3d acc_a = s.q_world_body * a.specificForce() + g, acc_m = q_mid * mid.specificForce() + g,
                          acc_b = q_end * b.specificForce() + g;
    s.p_world += s.v_world * step_s + step_s * step_s * (acc_a + 2 * acc_m) / 6.0;
    s.v_world += step_s * (acc_a + 4 * acc_m + acc_b) / 6.0;
    s.q_world_body = q_end.normalized();
  }
  return s;
}

TEST(Motion, ImuIntegratedBackAtLargePitchAndRollReproducesTheHandheldWalk) {
  // Climbing 2 m while pitched up to 60 deg and rolled up to 50 deg, with the hand-held gait.
  const std::vector<Waypoint> route = {{0, 0, 0},
                                       {3, 0, 0.5, 0.6, 1.05, 0.0},
                                       {5, 2, 1.5, 1.5, -0.8, 0.87},
                                       {4, 5, 2.5, 2.0, 0.3, -0.6},
                                       {1, -1, 3.0, 0.4}};
  const SplineMotion m = walkMotion(route, handheldWalk());
  double max_pitch = 0, max_roll = 0;
  for (double t = 0; t < m.durationS(); t += 0.01) {
    const Eigen::Matrix<double, 6, 1> c = m.coordinates(t);
    max_pitch = std::max(max_pitch, std::abs(c[4]));
    max_roll = std::max(max_roll, std::abs(c[5]));
  }
  EXPECT_GT(max_pitch, 55 * M_PI / 180);
  EXPECT_GT(max_roll, 45 * M_PI / 180);
  const double t0 = 2.0, span_s = m.durationS() - 4.0;
  const NavState s = integrateImu(m, t0, span_s);
  const MotionState truth = m.at(t0 + span_s);
  EXPECT_LT((s.p_world - truth.p_world).norm(), 0.003);
  EXPECT_LT((s.v_world - truth.v_world).norm(), 0.001);
  EXPECT_LT(so3::log(s.q_world_body.conjugate() * truth.q_world_body).norm(), 1e-4);
  EXPECT_GT((truth.p_world - m.at(t0).p_world).norm(), 1.0);  // it did move
}

TEST(Motion, HandheldGaitBouncesAtTheStepRateOnTopOfTheSameRoute) {
  const Scenario office = makeScenario("office"), carried = carriedByHand(office);
  const SplineMotion robot(walkKeyframes(office.waypoints, office.walk)),
      hand = walkMotion(carried.waypoints, carried.walk);
  // Mid-leg, the height's oscillation: 3 cm at 1.9 Hz by hand, 1.5 cm at 0.9 Hz on the robot walk
  // (carried by 0.25 s knots, which smooth it to ~1.1 cm).
  const auto bounce = [](const SplineMotion& m, double t0) {
    double lo = 1e9, hi = -1e9;
    for (double t = t0; t < t0 + 1.1; t += 0.005) {
      lo = std::min(lo, m.at(t).p_world.z());
      hi = std::max(hi, m.at(t).p_world.z());
    }
    return 0.5 * (hi - lo);
  };
  EXPECT_NEAR(bounce(hand, 5.0), 0.03, 0.006);
  EXPECT_NEAR(bounce(robot, 5.0), 0.011, 0.003);
  double max_rate = 0;
  for (double t = 0; t < hand.durationS(); t += 0.01) max_rate = std::max(max_rate, hand.at(t).omega_body.norm());
  EXPECT_GT(max_rate * 180 / M_PI, 140.0);
  EXPECT_LT(max_rate * 180 / M_PI, 200.0);
  EXPECT_LT(hand.durationS(), robot.durationS());  // faster turns, the same legs
}

TEST(Simulator, StairsClimbOneStoreyOnTheStepsAndComeBack) {
  const Simulator sim(opts("stairs", 0));
  double lo = 1e9, hi = -1e9;
  for (const auto& p : sim.groundTruth()) {
    lo = std::min(lo, p.T_world_body.translation().z());
    hi = std::max(hi, p.T_world_body.translation().z());
  }
  EXPECT_NEAR(hi - lo, 3.0, 0.1);
  EXPECT_NEAR(sim.durationS(), 110.0, 15.0);
  // Every body position is clear of the steps, the slabs and the walls: at least 0.9 m above
  // whatever lies beneath it, and not inside anything.
  for (std::size_t i = 0; i < sim.groundTruth().size(); i += 50) {
    const Eigen::Vector3d p = sim.groundTruth()[i].T_world_body.translation();
    EXPECT_GT(sim.scene().distanceToSurface(p), 0.3) << sim.groundTruth()[i].stamp_ns;
    const RayHit down = sim.scene().cast(p, Eigen::Vector3d(0, 0, -1), 10.0);
    EXPECT_NEAR(down.range_m, 1.2, 0.25) << "t " << toSec(sim.groundTruth()[i].stamp_ns - sim.startNs());
  }
}

TEST(Simulator, RampRobotPitchesWithTheSlopeAndClimbsOneMetre) {
  const Simulator sim(opts("ramp", 0));
  double lo = 1e9, hi = -1e9, max_pitch = 0;
  for (const auto& p : sim.groundTruth()) {
    lo = std::min(lo, p.T_world_body.translation().z());
    hi = std::max(hi, p.T_world_body.translation().z());
    const Eigen::Vector3d forward = p.T_world_body.linear().col(0);
    max_pitch = std::max(max_pitch, std::asin(std::abs(forward.z())));
  }
  EXPECT_NEAR(hi - lo, 1.0, 0.05);
  EXPECT_NEAR(max_pitch * 180 / M_PI, std::atan2(1.0, 12.0) * 180 / M_PI, 1.0);  // 4.8 deg, and the bobbing
  for (std::size_t i = 0; i < sim.groundTruth().size(); i += 50) {
    const Eigen::Vector3d p = sim.groundTruth()[i].T_world_body.translation();
    EXPECT_NEAR(sim.scene().cast(p, Eigen::Vector3d(0, 0, -1), 10.0).range_m, 1.2, 0.1);
  }
}

TEST(Simulator, UnknownScenarioThrowsNamingTheValidOnes) { EXPECT_THROW(Simulator(opts("garage", 5)), Error); }

TEST(Simulator, StartsAtRestAndEndsAtRestAtTheStartPose) {
  for (const std::string name : {"office", "corridor", "corridor_blind", "hall"}) {
    const Simulator sim(opts(name, name == "office" ? 0.0 : 12.0));
    const Trajectory& gt = sim.groundTruth();
    ASSERT_GT(gt.size(), 100u);
    const Eigen::Isometry3d first = gt.front().T_world_body, last = gt.back().T_world_body;
    EXPECT_LT((first.translation() - last.translation()).norm(), 1e-9) << name;
    EXPECT_LT(Eigen::AngleAxisd(first.linear().transpose() * last.linear()).angle(), 1e-9) << name;
    EXPECT_NEAR(first.translation().z(), 1.2, 1e-9);
    for (double t : {0.0, 1.0, 2.0}) {
      const NavState s = sim.trueState(sim.startNs() + fromSec(t));
      EXPECT_LT(s.v_world.norm(), 1e-12) << name << " t=" << t;
      const ImuSample imu = sim.idealImu(sim.startNs() + fromSec(t));
      EXPECT_LT(imu.gyro_rad_s.norm(), 1e-12);
    }
    const NavState end = sim.trueState(sim.startNs() + fromSec(sim.durationS() - 0.5));
    EXPECT_LT(end.v_world.norm(), 1e-12) << name;
    EXPECT_GT(sim.pathLengthM(), name == "office" ? 20.0 : 0.0) << name;
  }
}

TEST(Simulator, AClosedRouteWalkedFromAnotherWaypointStartsThereAndIsTheSameRoute) {
  SimOptions o = opts("office", 0.0);
  const Simulator designed(o);
  o.route_start = 2;
  const Simulator later(o);
  const Waypoint w = later.scenario().waypoints.front();
  EXPECT_NEAR((later.groundTruth().front().T_world_body.translation() - Eigen::Vector3d(w.x_m, w.y_m, 1.2)).norm(), 0.0,
              1e-9);
  EXPECT_EQ(later.scenario().waypoints.size(), designed.scenario().waypoints.size());
  EXPECT_NEAR(later.pathLengthM(), designed.pathLengthM(), 0.05 * designed.pathLengthM());
  const Trajectory& gt = later.groundTruth();  // closed: it ends where it started, facing the same way
  EXPECT_LT((gt.front().T_world_body.translation() - gt.back().T_world_body.translation()).norm(), 1e-9);
  EXPECT_LT(Eigen::AngleAxisd(gt.front().T_world_body.linear().transpose() * gt.back().T_world_body.linear()).angle(),
            1e-9);
  o.route_start = 99;
  EXPECT_THROW(Simulator{o}, Error);
  SimOptions lab = opts("lab", 5.0);
  lab.route_start = 1;  // a recorded motion has one start
  EXPECT_THROW(Simulator{lab}, Error);
}

TEST(Simulator, RearrangedFurnitureMovesClearOfTheRouteAndLeavesTheWalls) {
  SimOptions o = opts("office", 0.0);
  const Simulator designed(o);
  o.rearranged = true;
  const Simulator changed(o);
  EXPECT_GE(changed.furnitureMoved(), 3u);
  const std::vector<Box>& before = designed.scenario().boxes;
  const std::vector<Box>& after = changed.scenario().boxes;
  ASSERT_EQ(before.size(), after.size());
  std::size_t moved = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const Eigen::Vector3d shift = after[i].lo - before[i].lo;
    if (shift.norm() == 0.0) continue;
    ++moved;
    EXPECT_NEAR((after[i].hi - before[i].hi - shift).norm(), 0.0, 1e-12);  // moved, not resized
    EXPECT_LE(before[i].hi.z() - before[i].lo.z(), 2.1);                   // furniture, not a wall
    EXPECT_GE(shift.head<2>().norm(), 0.4 - 1e-9);
    EXPECT_EQ(shift.z(), 0.0);
    for (const StampedPose& p : changed.groundTruth()) {  // the rig never walks into it
      const Eigen::Vector2d q = p.T_world_body.translation().head<2>();
      const double dx = std::max({after[i].lo.x() - q.x(), 0.0, q.x() - after[i].hi.x()});
      const double dy = std::max({after[i].lo.y() - q.y(), 0.0, q.y() - after[i].hi.y()});
      ASSERT_GE(std::hypot(dx, dy), 0.69) << "box " << i;
    }
  }
  EXPECT_EQ(moved, changed.furnitureMoved());
}

TEST(Simulator, DefaultDurationsAreNearTheAdvertisedOnes) {
  EXPECT_NEAR(Simulator(opts("office", 0)).durationS(), 40.0, 8.0);
  EXPECT_NEAR(Simulator(opts("corridor", 0)).durationS(), 110.0, 15.0);
  EXPECT_NEAR(Simulator(opts("hall", 0)).durationS(), 150.0, 20.0);
  EXPECT_NEAR(Simulator(opts("hall", 30)).durationS(), 30.0, 1e-9);
}

TEST(Simulator, StaticImuReadsGravityPlusBiasUpwards) {
  const Simulator sim(opts("office", 10));
  Eigen::Vector3d acc = Eigen::Vector3d::Zero(), gyro = Eigen::Vector3d::Zero();
  const int n = 300;  // 1.5 s at rest
  for (int k = 0; k < n; ++k) {
    acc += sim.imu()[k].acc_m_s2 / n;
    gyro += sim.imu()[k].gyro_rad_s / n;
  }
  // White noise of the mean: 0.02 / sqrt(0.005 s) / sqrt(300) = 0.016 m/s^2, 0.0016 rad/s per axis.
  EXPECT_LT((acc - Eigen::Vector3d(0, 0, 9.81) - sim.initialBias().acc_m_s2).cwiseAbs().maxCoeff(), 0.07);
  EXPECT_LT((gyro - sim.initialBias().gyro_rad_s).cwiseAbs().maxCoeff(), 0.007);
  EXPECT_EQ(sim.imu()[1].stamp_ns - sim.imu()[0].stamp_ns, 5000000);
}

TEST(Simulator, IntegratingTheNoiselessImuFromTheTrueInitialStateReproducesTheGroundTruthToMillimetres) {
  const Simulator sim(opts("office", 0));
  const Stamp t0 = sim.startNs() + fromSec(2.0);  // includes the start of motion and a U-turn
  const double step_s = 5e-4, span_s = 10.0;
  NavState s = sim.trueState(t0);
  const Eigen::Vector3d g(0, 0, -kGravityM_s2);
  for (int i = 0; i < static_cast<int>(span_s / step_s); ++i) {
    const Stamp t = t0 + fromSec(i * step_s);
    // Midpoint rule: rotation by the mid-step rate, velocity by the mid-step acceleration.
    const ImuSample a = sim.idealImu(t), m = sim.idealImu(t + fromSec(step_s / 2)),
                    b = sim.idealImu(t + fromSec(step_s));
    const Eigen::Quaterniond q_mid = s.q_world_body * so3::exp(0.5 * step_s * m.gyro_rad_s);
    const Eigen::Quaterniond q_end = s.q_world_body * so3::exp(step_s * m.gyro_rad_s);
    // Simpson on the world acceleration for velocity, trapezoid-corrected for position.
    const Eigen::Vector3d acc_a = s.q_world_body * a.acc_m_s2 + g, acc_m = q_mid * m.acc_m_s2 + g,
                          acc_b = q_end * b.acc_m_s2 + g;
    s.p_world += s.v_world * step_s + step_s * step_s * (acc_a + 2 * acc_m) / 6.0;
    s.v_world += step_s * (acc_a + 4 * acc_m + acc_b) / 6.0;
    s.q_world_body = q_end.normalized();
  }
  const NavState truth = sim.trueState(t0 + fromSec(span_s));
  EXPECT_LT((s.p_world - truth.p_world).norm(), 0.003);
  EXPECT_LT((s.v_world - truth.v_world).norm(), 0.001);
  EXPECT_LT(so3::log(s.q_world_body.conjugate() * truth.q_world_body).norm(), 1e-4);
  EXPECT_GT((truth.p_world - sim.trueState(t0).p_world).norm(), 3.0);  // it did move
}

// Median and 95th percentile distance to the scene of scan points projected with ground truth.
std::pair<double, double> surfaceDistance(const Simulator& sim, const LidarScan& scan, const LidarExtrinsic& ext) {
  std::vector<double> d;
  const Stamp true_start = scan.start_ns + fromSec(ext.time_offset_s);
  for (size_t i = 0; i < scan.points.size(); i += 7) {
    const Point& p = scan.points[i];
    const Eigen::Isometry3d T = sim.trueState(true_start + fromSec(p.time_s)).pose() * ext.T_imu_sensor;
    d.push_back(sim.scene().distanceToSurface(T * p.xyz.cast<double>()));
  }
  std::sort(d.begin(), d.end());
  return {d[d.size() / 2], d[d.size() * 95 / 100]};
}

TEST(Simulator, PointsOfSweepsProjectedWithGroundTruthLieOnSceneSurfaces) {
  const Simulator sim(opts("office", 12, 1, 0.05));
  for (int k : {30, 60}) {  // moving
    const LidarScan v = sim.velodyneSweep(k);
    EXPECT_EQ(v.sensor, "velodyne");
    EXPECT_GT(v.points.size(), 20000u);
    EXPECT_EQ(v.start_ns, sim.startNs() + kVelodynePhaseNs + k * 100000000LL - 50000000LL);
    const auto [med_v, p95_v] = surfaceDistance(sim, v, sim.velodyneExtrinsic());
    EXPECT_LT(med_v, 0.015);
    EXPECT_LT(p95_v, 0.05);
    const LidarScan l = sim.livoxFrame(k);
    EXPECT_EQ(l.sensor, "livox");
    EXPECT_GT(l.points.size(), 23000u);
    const auto [med_l, p95_l] = surfaceDistance(sim, l, sim.livoxExtrinsic());
    EXPECT_LT(med_l, 0.02);
    EXPECT_LT(p95_l, 0.05);
  }
}

TEST(Simulator, ExtrinsicsAreTheDocumentedOnes) {
  const Simulator sim(opts("office", 5, 1, 0.02));
  EXPECT_LT((sim.livoxExtrinsic().T_imu_sensor.translation() - Eigen::Vector3d(0.05512, 0.02226, -0.0297)).norm(),
            1e-12);
  EXPECT_TRUE(sim.livoxExtrinsic().T_imu_sensor.linear().isIdentity(1e-12));
  const LidarExtrinsic v = sim.velodyneExtrinsic();
  EXPECT_NEAR(Eigen::AngleAxisd(v.T_imu_sensor.linear()).angle() * 180 / M_PI, 3.9, 0.3);
  EXPECT_DOUBLE_EQ(v.time_offset_s, 0.02);
  EXPECT_EQ(v.kind, LidarKind::kSpinning);
  EXPECT_EQ(sim.livoxExtrinsic().kind, LidarKind::kSolidState);
}

TEST(Simulator, SameSeedGivesIdenticalDataAndAnotherSeedDifferentNoise) {
  const Simulator a(opts("corridor", 6, 7)), b(opts("corridor", 6, 7)), c(opts("corridor", 6, 8));
  const LidarScan va = a.velodyneSweep(20), vb = b.velodyneSweep(20), vc = c.velodyneSweep(20);
  ASSERT_EQ(va.points.size(), vb.points.size());
  for (size_t i = 0; i < va.points.size(); ++i) ASSERT_EQ(va.points[i].xyz, vb.points[i].xyz);
  const LidarScan la = a.livoxFrame(5), la2 = a.livoxFrame(5);  // on demand, repeatable
  ASSERT_EQ(la.points.size(), la2.points.size());
  for (size_t i = 0; i < la.points.size(); ++i) ASSERT_EQ(la.points[i].xyz, la2.points[i].xyz);
  EXPECT_EQ(a.imu().back().acc_m_s2, b.imu().back().acc_m_s2);
  EXPECT_NE(a.imu().back().acc_m_s2, c.imu().back().acc_m_s2);
  EXPECT_NE(va.points[100].xyz, vc.points[100].xyz);
}

TEST(Simulator, SolidStateLidarSeesOnlyTheEndWallAtTheStartOfTheHall) {
  const Simulator sim(opts("hall", 10));
  const LidarScan l = sim.livoxFrame(5);
  const Eigen::Isometry3d T = sim.trueState(l.start_ns).pose() * sim.livoxExtrinsic().T_imu_sensor;
  ASSERT_GT(l.points.size(), 20000u);
  for (size_t i = 0; i < l.points.size(); i += 50) EXPECT_NEAR((T * l.points[i].xyz.cast<double>()).x(), -12.0, 0.1);
}

TEST(Simulator, FrameCountsFitInsideTheSequence) {
  const Simulator sim(opts("office", 5));
  EXPECT_EQ(sim.numLivoxFrames(), 50);
  EXPECT_EQ(sim.numVelodyneSweeps(), 49);
  EXPECT_EQ(sim.groundTruth().size(), 1001u);
  EXPECT_THROW(sim.livoxFrame(50), Error);
}

TEST(Simulator, RandomMountIsDrawnFromTheSeedWithinItsBoundsAndTheNominalMountOtherwise) {
  SimOptions a = opts("office", 5.0, 7), b = opts("office", 5.0, 7), c = opts("office", 5.0, 8);
  a.random_mount = b.random_mount = c.random_mount = true;
  const Simulator sa(a), sb(b), sc(c), nominal(opts("office", 5.0, 7));
  EXPECT_TRUE(sa.livoxExtrinsic().T_imu_sensor.isApprox(sb.livoxExtrinsic().T_imu_sensor));
  EXPECT_EQ(sa.velodyneTrueStartNs(0), sb.velodyneTrueStartNs(0));
  EXPECT_FALSE(sa.livoxExtrinsic().T_imu_sensor.isApprox(sc.livoxExtrinsic().T_imu_sensor));
  EXPECT_LE(sa.livoxExtrinsic().T_imu_sensor.translation().cwiseAbs().maxCoeff(), 0.1);
  EXPECT_LE(Eigen::AngleAxisd(sa.livoxExtrinsic().T_imu_sensor.linear()).angle(), (15.0 + 8.0) * M_PI / 180.0);
  const Stamp phase = sa.velodyneTrueStartNs(0) - sa.startNs();
  EXPECT_GE(phase, 0);
  EXPECT_LT(phase, 100000000LL);
  EXPECT_NEAR(nominal.livoxExtrinsic().T_imu_sensor.translation().x(), 0.05512, 1e-12);
  EXPECT_EQ(nominal.velodyneTrueStartNs(0) - nominal.startNs(), kVelodynePhaseNs);
}

TEST(Simulator, LivoxNoReturnsBecomeZeroPointsWithTheirTimesWhenAsked) {
  SimOptions with = opts("corridor", 5.0), without = opts("corridor", 5.0);
  with.livox_no_returns_as_zero = true;
  const LidarScan a = Simulator(with).livoxFrame(10), b = Simulator(without).livoxFrame(10);
  EXPECT_EQ(a.points.size(), 24000u);  // every beam, as the driver publishes them
  std::size_t zeros = 0;
  for (const Point& p : a.points) zeros += p.xyz.isZero() ? 1 : 0;
  EXPECT_EQ(a.points.size() - zeros, b.points.size());
  for (std::size_t i = 0, j = 0; i < a.points.size(); ++i) {  // the returns themselves are the same
    if (a.points[i].xyz.isZero()) continue;
    EXPECT_TRUE(a.points[i].xyz.isApprox(b.points[j].xyz));
    EXPECT_EQ(a.points[i].time_s, b.points[j++].time_s);
  }
}

TEST(Simulator, ImuNoiseAndAccelerometerBiasFollowTheOptions) {
  SimOptions quiet = opts("office", 6.0, 3), loud = opts("office", 6.0, 3);
  quiet.imu.gyro_noise_density = 1e-4;
  loud.imu.gyro_noise_density = 1e-3;
  loud.acc_bias_m_s2 = 0.05;
  const Simulator q(quiet), l(loud);
  EXPECT_DOUBLE_EQ(l.initialBias().acc_m_s2.cwiseAbs().minCoeff(), 0.05);
  double sq_q = 0, sq_l = 0;
  for (std::size_t k = 0; k < 400; ++k) {  // the first 2 s are at rest: the gyro reads bias + noise
    sq_q += (q.imu()[k].gyro_rad_s - q.initialBias().gyro_rad_s).squaredNorm();
    sq_l += (l.imu()[k].gyro_rad_s - l.initialBias().gyro_rad_s).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(sq_l / sq_q), 10.0, 1.5);
}

// The lab replays a real platform's recorded motion (levelled, smoothed): at rest, then the
// recording's own pace and turns, level within a few degrees, and always clear of the furniture.
TEST(Simulator, LabReplaysTheRecordedMotionLevelAndClearOfTheFurniture) {
  const Scenario lab = makeScenario("lab");
  ASSERT_GT(lab.recorded.size(), 800u);
  const Simulator sim(opts("lab", 0));
  const SplineMotion& m = sim.motion();
  const double rest_s = lab.walk.rest_start_s;
  EXPECT_NEAR(m.durationS(), lab.recorded.back().t_s + rest_s + lab.walk.rest_end_s, 0.1);
  EXPECT_LT(m.at(0.5 * rest_s).v_world.norm(), 1e-9);
  double max_speed = 0, max_tilt = 0, max_off = 0;
  for (const Keyframe& k : lab.recorded) {
    const MotionState s = m.at(k.t_s + rest_s);
    max_speed = std::max(max_speed, s.v_world.norm());
    const Eigen::Matrix<double, 6, 1> c = m.coordinates(k.t_s + rest_s);
    max_tilt = std::max({max_tilt, std::abs(c[4]), std::abs(c[5])});
    const Eigen::Vector3d recorded = k.p_world + Eigen::Vector3d(0, 0, lab.walk.height_m);
    if (k.t_s > 1.0) max_off = std::max(max_off, (s.p_world - recorded).norm());
    EXPECT_GT(sim.scene().distanceToSurface(s.p_world), 0.5) << k.t_s;
  }
  EXPECT_LT(max_off, 0.05);  // the recording, smoothed on 0.25 s knots
  EXPECT_GT(max_speed, 0.8);
  EXPECT_LT(max_speed, 1.6);
  EXPECT_LT(max_tilt, 2.0 * M_PI / 180);
  EXPECT_GT(sim.pathLengthM(), 45.0);
  // A shorter sequence cuts the recording and still ends at rest.
  const Simulator cut(opts("lab", 20.0));
  EXPECT_NEAR(cut.durationS(), 20.0, 0.05);
  EXPECT_LT(cut.motion().at(19.9).v_world.norm(), 1e-9);
}

}  // namespace
}  // namespace mmlio::sim
