// Helpers of mmlio_node that need no ROS master: the hand-off queue, the IMU unit gate and the
// published cloud.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "bounded_queue.hpp"
#include "imu_unit_gate.hpp"
#include "ros_messages.hpp"
#include "mmlio/core/error.hpp"

namespace mmlio::live {
namespace {

TEST(BoundedQueue, AFullClassDropsItsNewItemsButNotTheOtherClass) {
  BoundedQueue<int, 2> q({3, 1});
  EXPECT_TRUE(q.push(1, 100));
  EXPECT_FALSE(q.push(1, 101));  // scan class full
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(q.push(0, i));
  EXPECT_FALSE(q.push(0, 3));  // imu class full
  EXPECT_EQ(q.dropped(0), 1u);
  EXPECT_EQ(q.dropped(1), 1u);
  EXPECT_EQ(q.size(), 4u);
}

// LiDAR messages, behind: the oldest waiting one goes for the newest (a bounded lag), and IMU
// samples are neither evicted for it nor evicted themselves.
TEST(BoundedQueue, AClassThatEvictsDropsItsOldestWaitingItemForTheNewOne) {
  BoundedQueue<int, 2> q({2, 2}, {false, true});
  q.push(0, 1);
  q.push(1, 10);
  q.push(0, 2);
  q.push(1, 11);
  EXPECT_TRUE(q.push(1, 12));  // 10 goes
  EXPECT_FALSE(q.push(0, 3));  // IMU full: the new one is dropped
  EXPECT_EQ(q.dropped(1), 1u);
  EXPECT_EQ(q.dropped(0), 1u);
  std::vector<int> order;
  q.close();
  for (int v = 0; q.pop(&v);) order.push_back(v);
  EXPECT_EQ(order, (std::vector<int>{1, 2, 11, 12}));
}

TEST(BoundedQueue, PopsInArrivalOrderAndFreesTheSlotOfItsClass) {
  BoundedQueue<int, 2> q({2, 1});
  q.push(0, 1);
  q.push(1, 2);
  q.push(0, 3);
  int v = 0;
  ASSERT_TRUE(q.pop(&v));
  EXPECT_EQ(v, 1);
  ASSERT_TRUE(q.pop(&v));
  EXPECT_EQ(v, 2);
  EXPECT_TRUE(q.push(1, 4));  // the scan slot is free again
  ASSERT_TRUE(q.pop(&v));
  EXPECT_EQ(v, 3);
  ASSERT_TRUE(q.pop(&v));
  EXPECT_EQ(v, 4);
}

TEST(BoundedQueue, CloseDrainsWhatIsQueuedThenStopsAndRefusesPushes) {
  BoundedQueue<int, 1> q({5});
  q.push(0, 7);
  q.close();
  EXPECT_FALSE(q.push(0, 8));
  EXPECT_EQ(q.dropped(0), 0u);  // arrived after the stop: not lost by the node
  int v = 0;
  ASSERT_TRUE(q.pop(&v));
  EXPECT_EQ(v, 7);
  EXPECT_FALSE(q.pop(&v));
}

sensor_msgs::Imu imuMsg(double t_s, double acc_z) {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(t_s);
  m.linear_acceleration.z = acc_z;
  m.angular_velocity.x = 0.01;
  return m;
}

TEST(ImuUnitGate, AutoHoldsTheFirstSamplesThenReleasesThemScaledFromG) {
  ImuUnitGate gate("/imu", "auto", 5);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(gate.add(imuMsg(100 + 0.01 * i, 1.0)).empty());
  EXPECT_FALSE(gate.decided());
  const auto out = gate.add(imuMsg(100.04, 1.0));
  ASSERT_EQ(out.size(), 5u);
  EXPECT_TRUE(gate.decided());
  EXPECT_DOUBLE_EQ(gate.accScale(), 9.80665);
  EXPECT_DOUBLE_EQ(out[0].acc_m_s2.z(), 9.80665);
  EXPECT_EQ(out[0].stamp_ns, 100'000'000'000);
  EXPECT_EQ(out[4].stamp_ns, 100'040'000'000);
  const auto next = gate.add(imuMsg(100.05, 1.0));  // passes straight through now
  ASSERT_EQ(next.size(), 1u);
  EXPECT_DOUBLE_EQ(next[0].acc_m_s2.z(), 9.80665);
}

TEST(ImuUnitGate, AutoKeepsMetresPerSecondSquared) {
  ImuUnitGate gate("/imu", "auto", 3);
  gate.add(imuMsg(1.0, 9.81));
  gate.add(imuMsg(1.01, 9.81));
  const auto out = gate.add(imuMsg(1.02, 9.81));
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[2].acc_m_s2.z(), 9.81);
}

TEST(ImuUnitGate, ReleaseAtEndOfStreamDecidesFromFewerSamples) {
  ImuUnitGate gate("/imu", "auto", 50);
  gate.add(imuMsg(1.0, 1.0));
  gate.add(imuMsg(1.01, 1.0));
  const auto out = gate.release();
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out[1].acc_m_s2.z(), 9.80665);
  EXPECT_TRUE(gate.release().empty());
}

TEST(ImuUnitGate, AConfiguredUnitPassesEverySampleAtOnce) {
  ImuUnitGate g("/imu", "g"), mps2("/imu", "m/s2");
  ASSERT_EQ(g.add(imuMsg(1.0, 1.0)).size(), 1u);
  EXPECT_DOUBLE_EQ(g.add(imuMsg(1.01, 2.0))[0].acc_m_s2.z(), 2 * 9.80665);
  EXPECT_DOUBLE_EQ(mps2.add(imuMsg(1.0, 9.7))[0].acc_m_s2.z(), 9.7);
}

TEST(ImuUnitGate, AnUnknownUnitIsAnError) { EXPECT_THROW(ImuUnitGate("/imu", "ft/s2"), Error); }

TEST(RosMessages, CloudIsMovedIntoTheTargetFrameWithIntensity) {
  Point p;
  p.xyz = {1.f, 0.f, 0.f};
  p.intensity = 42.f;
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  T_world_body.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_world_body.translation() = Eigen::Vector3d(10, 20, 30);
  const auto msg = toPointCloud2({p, p}, T_world_body, 1'500'000'000'123, "map");
  EXPECT_EQ(msg.header.frame_id, "map");
  EXPECT_EQ(msg.header.stamp.sec, 1500u);
  EXPECT_EQ(msg.header.stamp.nsec, 123u);
  ASSERT_EQ(msg.width, 2u);
  ASSERT_EQ(msg.fields.size(), 4u);
  EXPECT_EQ(msg.fields[3].name, "intensity");
  ASSERT_EQ(msg.data.size(), 32u);
  float v[4];
  std::memcpy(v, msg.data.data() + 16, sizeof v);
  EXPECT_NEAR(v[0], 10.f, 1e-5);  // x rotated onto +y, then translated
  EXPECT_NEAR(v[1], 21.f, 1e-5);
  EXPECT_NEAR(v[2], 30.f, 1e-5);
  EXPECT_EQ(v[3], 42.f);
}

TEST(RosMessages, OdometryCarriesPoseInItsFrameAndTwistInTheBodyFrame) {
  NavState s;
  s.stamp_ns = 2'000'000'001;
  s.p_world = {1, 2, 3};
  s.q_world_body = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  s.v_world = {0, 1, 0};  // along the body's x axis (yawed 90 deg)
  std::array<double, 36> cov{};
  cov[0] = 0.25;
  const auto odom = toOdometry(s, s.pose(), {0, 0, 0.5}, cov, "odom", "imu");
  EXPECT_EQ(odom.header.frame_id, "odom");
  EXPECT_EQ(odom.child_frame_id, "imu");
  EXPECT_EQ(odom.header.stamp.toNSec(), 2'000'000'001u);
  EXPECT_DOUBLE_EQ(odom.pose.pose.position.z, 3.0);
  EXPECT_NEAR(odom.pose.pose.orientation.z, std::sin(M_PI / 4), 1e-12);
  EXPECT_NEAR(odom.twist.twist.linear.x, 1.0, 1e-12);
  EXPECT_NEAR(odom.twist.twist.linear.y, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(odom.twist.twist.angular.z, 0.5);
  EXPECT_DOUBLE_EQ(odom.pose.covariance[0], 0.25);
  EXPECT_DOUBLE_EQ(odom.twist.covariance[0], -1.0);  // not estimated
}

TEST(RosMessages, CovarianceIsLargeAlongWhatTheLidarsDoNotObserve) {
  // A corridor along world x: translation information tiny along x, strong across; rotation strong.
  estimator::Degeneracy d;
  d.translation_basis = Eigen::Matrix3d::Identity();  // columns: x, y, z
  d.translation_eigenvalues = {1e-9, 400.0, 900.0};
  d.rotation_eigenvalues = {100.0, 100.0, 100.0};
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  const auto c = poseCovariance(d, yaw, 0.02, 1e4);
  EXPECT_DOUBLE_EQ(c[0], 1e4);                    // unobserved: capped
  EXPECT_NEAR(c[7], 0.02 * 0.02 / 400.0, 1e-15);  // sigma^2 / eigenvalue
  EXPECT_NEAR(c[14], 0.02 * 0.02 / 900.0, 1e-15);
  EXPECT_NEAR(c[21], 0.02 * 0.02 / 100.0, 1e-15);  // isotropic rotation stays so in any frame
  EXPECT_NEAR(c[1], 0.0, 1e-15);
  EXPECT_NEAR(c[3], 0.0, 1e-15);  // no translation-rotation coupling given
}

TEST(RosMessages, TransformAndPathCarryPosesInTheirFrames) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1, 2, 3);
  const auto tf = toTransform(T, 5'000'000'000, "map", "odom");
  EXPECT_EQ(tf.header.frame_id, "map");
  EXPECT_EQ(tf.child_frame_id, "odom");
  EXPECT_DOUBLE_EQ(tf.transform.translation.y, 2.0);
  EXPECT_NEAR(std::abs(tf.transform.rotation.x), std::sin(0.15), 1e-12);
  const auto path = toPath({{1'000'000'000, Eigen::Isometry3d::Identity()}, {2'000'000'000, T}}, "map");
  ASSERT_EQ(path.poses.size(), 2u);
  EXPECT_EQ(path.header.frame_id, "map");
  EXPECT_EQ(path.header.stamp.toNSec(), 2'000'000'000u);
  EXPECT_EQ(path.poses[1].header.frame_id, "map");
  EXPECT_DOUBLE_EQ(path.poses[1].pose.position.x, 1.0);
}

TEST(RosMessages, APoseReadsBackAsTheTransformItCameFrom) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(-1.2, Eigen::Vector3d(0.2, 0.1, 1).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4, -5, 0.5);
  EXPECT_TRUE(fromPose(toPose(T)).isApprox(T, 1e-12));
  geometry_msgs::Pose zero;  // an all-zero quaternion (a hand-typed message): no rotation
  zero.orientation.w = 0.0;
  EXPECT_TRUE(fromPose(zero).isApprox(Eigen::Isometry3d::Identity()));
}

TEST(RosMessages, DiagnosticsSayOkWhenLocalizedWarnBeforeAndErrorWhenLost) {
  backend::LocalizationStatus s;
  s.last_reason = "ambiguous";
  const auto level = [&](Stamp now) { return localizationStatus(s, now, "mmlio: localization").level; };
  EXPECT_EQ(level(1'000'000'000), diagnostic_msgs::DiagnosticStatus::WARN);
  s.localized = true;
  s.first_localized_ns = 1'000'000'000;
  EXPECT_EQ(level(2'000'000'000), diagnostic_msgs::DiagnosticStatus::OK);
  s.localized = false;
  s.lost_spells.emplace_back(3'000'000'000, 0);
  const diagnostic_msgs::DiagnosticArray lost =
      toDiagnostics({localizationStatus(s, 10'000'000'000, "mmlio: localization")}, 10'000'000'000);
  EXPECT_EQ(lost.status.at(0).level, diagnostic_msgs::DiagnosticStatus::ERROR);
  EXPECT_EQ(lost.status.at(0).name, "mmlio: localization");
  EXPECT_NE(lost.status.at(0).message.find("lost for 7 s"), std::string::npos) << lost.status.at(0).message;
  EXPECT_EQ(lost.header.stamp.toNSec(), 10'000'000'000u);
}

TEST(RosMessages, TheInputStatusSaysWhatTheNodeGivesUpNowAndWhatItGaveUpEarlier) {
  InputFigures f;
  f.imu_messages = 2000;
  f.sweeps = 100;
  EXPECT_EQ(inputStatus(f, "mmlio: input").level, diagnostic_msgs::DiagnosticStatus::OK);
  f.sweeps_degraded = 3;
  EXPECT_EQ(inputStatus(f, "mmlio: input").level, diagnostic_msgs::DiagnosticStatus::WARN);
  f.dropped_scans = 7;
  const diagnostic_msgs::DiagnosticStatus behind = inputStatus(f, "mmlio: input");
  EXPECT_EQ(behind.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_NE(behind.message.find("7 LiDAR messages dropped"), std::string::npos) << behind.message;
  f.dropped_imu = 1;
  EXPECT_EQ(inputStatus(f, "mmlio: input").level, diagnostic_msgs::DiagnosticStatus::ERROR);
  // Caught up: OK again, with what was given up.
  f.quiet_s = 42.0;
  const diagnostic_msgs::DiagnosticStatus caught_up = inputStatus(f, "mmlio: input");
  EXPECT_EQ(caught_up.level, diagnostic_msgs::DiagnosticStatus::OK);
  EXPECT_EQ(caught_up.message,
            "keeping up (earlier: 1 IMU and 7 LiDAR messages dropped, 3 sweeps degraded; the last 42 s ago)");
}

}  // namespace
}  // namespace mmlio::live
