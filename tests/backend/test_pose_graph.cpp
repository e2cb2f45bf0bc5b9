#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "mmlio/backend/pose_graph.hpp"

namespace mmlio::backend {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose2d(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0);
  return T;
}

double angleOf(const Eigen::Isometry3d& T) { return Eigen::AngleAxisd(T.rotation()).angle(); }

/// True poses of a 10 m square driven counter-clockwise in 1 m steps, turning 90 deg at each corner;
/// pose 40 is back at pose 0.
std::vector<Eigen::Isometry3d> squareLoop() {
  std::vector<Eigen::Isometry3d> gt{Eigen::Isometry3d::Identity()};
  for (int side = 0; side < 4; ++side)
    for (int step = 0; step < 10; ++step) {
      Eigen::Isometry3d rel = pose2d(1.0, 0, step == 9 ? M_PI / 2 : 0.0);
      gt.push_back(gt.back() * rel);
    }
  return gt;
}

/// Odometry that integrates the true relative motions with an extra yaw of drift_rad per step.
std::vector<Eigen::Isometry3d> driftingOdometry(const std::vector<Eigen::Isometry3d>& gt, double drift_rad) {
  std::vector<Eigen::Isometry3d> odom{gt[0]};
  for (std::size_t i = 1; i < gt.size(); ++i)
    odom.push_back(odom.back() * (gt[i - 1].inverse() * gt[i]) * pose2d(0, 0, drift_rad));
  return odom;
}

PoseGraph buildGraph(const std::vector<Eigen::Isometry3d>& odom, PoseGraph::Config cfg = PoseGraph::Config()) {
  PoseGraph graph(cfg);
  for (std::size_t i = 0; i < odom.size(); ++i) {
    KeyframeNode node;
    node.stamp_ns = static_cast<Stamp>(i + 1) * 1'000'000'000;
    node.T_world_body_odom = odom[i];
    EXPECT_EQ(graph.addKeyframe(node), static_cast<int>(i));
  }
  return graph;
}

TEST(PoseGraph, SquareLoopWithYawDriftClosesToUnderOneCentimetreAfterTheLoopEdge) {
  const auto gt = squareLoop();
  ASSERT_EQ(gt.size(), 41u);
  ASSERT_LT(gt.back().translation().norm(), 1e-9);
  // 0.1 deg of yaw drift per 1 m keyframe step (4 deg over the loop), about one odometry sigma.
  const auto odom = driftingOdometry(gt, 0.1 * kDeg);
  PoseGraph::Config cfg;
  cfg.odom_sigma_rotation_rad = 0.1 * kDeg;
  PoseGraph graph = buildGraph(odom, cfg);
  const int last = static_cast<int>(graph.size()) - 1;

  const Eigen::Isometry3d T_last_first_true = gt[last].inverse() * gt[0];
  const double before_m =
      ((graph.pose(last).inverse() * graph.pose(0)).translation() - T_last_first_true.translation()).norm();
  EXPECT_GT(before_m, 0.4);  // the drift is real
  std::printf("end-to-start error before the loop: %.3f m\n", before_m);

  graph.addLoop(last, 0, T_last_first_true, isotropicInformation(0.01, 0.05 * kDeg));
  EXPECT_EQ(graph.loops(), 1u);
  ASSERT_TRUE(graph.optimize());

  const Eigen::Isometry3d err = T_last_first_true.inverse() * (graph.pose(last).inverse() * graph.pose(0));
  std::printf("after: %.4f m, %.4f deg\n", err.translation().norm(), angleOf(err) / kDeg);
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleOf(err), 0.05 * kDeg);
  // The first keyframe is the fixed anchor; the whole trajectory moves towards the truth.
  EXPECT_LT((graph.pose(0).translation() - odom[0].translation()).norm(), 1e-9);
  double worst_before = 0, worst_after = 0;
  for (int i = 0; i <= last; ++i) {
    worst_before = std::max(worst_before, (odom[i].translation() - gt[i].translation()).norm());
    worst_after = std::max(worst_after, (graph.pose(i).translation() - gt[i].translation()).norm());
  }
  EXPECT_LT(worst_after, 0.25 * worst_before);
}

TEST(PoseGraph, ConsistentConstraintsLeaveTheGraphUnchanged) {
  const auto gt = squareLoop();
  PoseGraph graph = buildGraph(gt);
  const int last = static_cast<int>(graph.size()) - 1;
  graph.addLoop(last, 0, gt[last].inverse() * gt[0], isotropicInformation(0.01, 0.001));
  graph.addLoop(20, 5, gt[20].inverse() * gt[5], isotropicInformation(0.01, 0.001));
  ASSERT_TRUE(graph.optimize());
  for (int i = 0; i <= last; ++i) {
    EXPECT_LT((graph.pose(i).translation() - gt[i].translation()).norm(), 1e-6) << i;
    EXPECT_LT(angleOf(graph.pose(i).inverse() * gt[i]), 1e-6) << i;
  }
}

TEST(PoseGraph, CorrectAppliesTheCorrectionOfTheLastKeyframeAtOrBeforeTheStamp) {
  const auto gt = squareLoop();
  const auto odom = driftingOdometry(gt, 0.3 * kDeg);
  PoseGraph graph = buildGraph(odom);  // keyframe i stamped (i + 1) s
  const int last = static_cast<int>(graph.size()) - 1;
  graph.addLoop(last, 0, gt[last].inverse() * gt[0], isotropicInformation(0.01, 0.001));
  ASSERT_TRUE(graph.optimize());

  const Eigen::Isometry3d T_odom = pose2d(3.0, -2.0, 0.7);
  // Before the first keyframe: unchanged.
  EXPECT_TRUE(graph.correct(500'000'000, T_odom).isApprox(T_odom, 1e-12));
  // Exactly at a keyframe's stamp, its own odometry pose maps to its optimised pose.
  EXPECT_TRUE(graph.correct(11'000'000'000, odom[10]).isApprox(graph.pose(10), 1e-9));
  // Between keyframes 10 (11 s) and 11 (12 s): keyframe 10's correction, not an interpolation.
  const Eigen::Isometry3d C10 = graph.pose(10) * odom[10].inverse();
  const Eigen::Isometry3d C11 = graph.pose(11) * odom[11].inverse();
  ASSERT_FALSE(C10.isApprox(C11, 1e-6));
  EXPECT_TRUE(graph.correct(11'999'999'999, T_odom).isApprox(C10 * T_odom, 1e-9));
  // After the last keyframe: the last correction.
  const Eigen::Isometry3d Clast = graph.pose(last) * odom[last].inverse();
  EXPECT_TRUE(graph.correct(1000'000'000'000, T_odom).isApprox(Clast * T_odom, 1e-9));
}

TEST(PoseGraph, KeyframeAddedAfterOptimisationChainsOntoTheCorrectedEstimate) {
  const auto gt = squareLoop();
  const auto odom = driftingOdometry(gt, 0.3 * kDeg);
  PoseGraph graph = buildGraph(odom);
  const int last = static_cast<int>(graph.size()) - 1;
  graph.addLoop(last, 0, gt[last].inverse() * gt[0], isotropicInformation(0.01, 0.001));
  ASSERT_TRUE(graph.optimize());
  KeyframeNode next;
  next.stamp_ns = 100'000'000'000;
  next.T_world_body_odom = odom[last] * pose2d(1.0, 0, 0);
  const int k = graph.addKeyframe(next);
  EXPECT_TRUE(graph.pose(k).isApprox(graph.pose(last) * pose2d(1.0, 0, 0), 1e-9));
  EXPECT_TRUE(graph.pose(k).isApprox(graph.correct(next.stamp_ns, next.T_world_body_odom), 1e-9));
}

/// Angle between a pose's body z axis and the world vertical.
double tiltOf(const Eigen::Isometry3d& T) { return std::acos(std::clamp(T.linear()(2, 2), -1.0, 1.0)); }

TEST(PoseGraph, ALoopClosingVerticalDriftMovesHeightsNotTilt) {
  // Odometry that climbs 1 cm per 1 m step with a level attitude (the IMU observes roll and
  // pitch): after the square the loop says the end is 40 cm lower. The correction must come from
  // the heights; without the tilt factor the graph pitches the keyframes instead.
  const auto gt = squareLoop();
  std::vector<Eigen::Isometry3d> odom{gt[0]};
  for (std::size_t i = 1; i < gt.size(); ++i) {
    Eigen::Isometry3d rel = gt[i - 1].inverse() * gt[i];
    rel.translation().z() += 0.01;
    odom.push_back(odom.back() * rel);
  }
  const auto solve = [&](double tilt_sigma_rad, double* worst_tilt, double* end_error) {
    PoseGraph::Config cfg;
    cfg.tilt_sigma_rad = tilt_sigma_rad;
    PoseGraph graph = buildGraph(odom, cfg);
    const int last = static_cast<int>(graph.size()) - 1;
    graph.addLoop(last, 0, gt[last].inverse() * gt[0], isotropicInformation(0.01, 0.001));
    ASSERT_TRUE(graph.optimize());
    *worst_tilt = 0;
    for (int i = 0; i <= last; ++i) *worst_tilt = std::max(*worst_tilt, tiltOf(graph.pose(i)));
    *end_error = (graph.pose(last).translation() - gt[last].translation()).norm();
  };
  double tilt_with = 0, end_with = 0, tilt_without = 0, end_without = 0;
  solve(0.003, &tilt_with, &end_with);
  solve(0.0, &tilt_without, &end_without);
  std::printf("worst tilt with the factor %.2f mrad (end %.3f m), without %.2f mrad (end %.3f m)\n", 1e3 * tilt_with,
              end_with, 1e3 * tilt_without, end_without);
  EXPECT_LT(end_with, 0.05);
  EXPECT_LT(tilt_with, 0.003);
  EXPECT_GT(tilt_without, 3.0 * tilt_with);
}

TEST(PoseGraph, RouteLengthFollowsTheOdometryUntilALoopShortensIt) {
  PoseGraph graph = buildGraph(squareLoop());  // 40 one-metre steps, pose 40 back at pose 0
  EXPECT_NEAR(graph.routeLength(0, 40), 40.0, 1e-9);
  EXPECT_NEAR(graph.routeLength(35, 5), 30.0, 1e-9);
  EXPECT_EQ(graph.routeLength(7, 7), 0.0);
  graph.addLoop(0, 40, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  EXPECT_NEAR(graph.routeLength(0, 40), 0.0, 1e-9);
  EXPECT_NEAR(graph.routeLength(35, 5), 10.0, 1e-9);  // 35 -> 40 = 0 -> 5
  EXPECT_NEAR(graph.routeLength(5, 35), 10.0, 1e-9);
  EXPECT_NEAR(graph.routeLength(10, 30), 20.0, 1e-9);  // either way round
  EXPECT_THROW(graph.routeLength(0, 41), std::invalid_argument);
}

TEST(PoseGraph, AGraphOfTheCornersAloneClosesTheLoopAndCorrectsTheFoldedKeyframes) {
  // The square with yaw drift, solved twice: every keyframe optimised, and only the corners kept
  // (the other 36 folded as they arrive, as the back end folds revisits). The folded graph's
  // composed edges carry the steps' noise exactly; the two solutions differ by the problem's
  // nonlinearity (4 deg of drift) within the corners' posterior spread (2 cm per step).
  const auto gt = squareLoop();
  const auto odom = driftingOdometry(gt, 0.1 * kDeg);
  PoseGraph::Config cfg;
  cfg.odom_sigma_rotation_rad = 0.1 * kDeg;
  PoseGraph full = buildGraph(odom, cfg);
  PoseGraph folded(cfg);
  for (std::size_t i = 0; i < odom.size(); ++i) {
    KeyframeNode node;
    node.stamp_ns = static_cast<Stamp>(i + 1) * 1'000'000'000;
    node.T_world_body_odom = odom[i];
    folded.addKeyframe(node);
    if (i >= 2 && (i - 1) % 10 != 0) {
      EXPECT_TRUE(folded.fold(static_cast<int>(i) - 1));
    }
  }
  EXPECT_EQ(folded.optimised(), 5u);  // 0, 10, 20, 30, 40
  const int last = static_cast<int>(odom.size()) - 1;
  // Folding changes nothing before an optimisation.
  for (int i = 0; i <= last; ++i) EXPECT_LT((folded.pose(i).translation() - odom[i].translation()).norm(), 1e-9);
  const Eigen::Isometry3d T_last_first = gt[last].inverse() * gt[0];
  for (PoseGraph* g : {&full, &folded}) {
    g->addLoop(last, 0, T_last_first, isotropicInformation(0.01, 0.05 * kDeg));
    ASSERT_TRUE(g->optimize());
  }
  double worst_full = 0, worst_folded = 0, worst_odom = 0;
  for (int i = 0; i <= last; ++i) {
    worst_odom = std::max(worst_odom, (odom[i].translation() - gt[i].translation()).norm());
    worst_full = std::max(worst_full, (full.pose(i).translation() - gt[i].translation()).norm());
    worst_folded = std::max(worst_folded, (folded.pose(i).translation() - gt[i].translation()).norm());
  }
  std::printf("worst position error: odometry %.3f m, full graph %.3f m, folded %.3f m\n", worst_odom, worst_full,
              worst_folded);
  EXPECT_LT(worst_folded, 0.2 * worst_odom);
  const Eigen::Isometry3d err = T_last_first.inverse() * (folded.pose(last).inverse() * folded.pose(0));
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleOf(err), 0.05 * kDeg);
  // Folded keyframes lie on the corrected path: no jump at a kept neighbour.
  for (int i = 1; i <= last; ++i) {
    const double step = (folded.pose(i).translation() - folded.pose(i - 1).translation()).norm();
    EXPECT_NEAR(step, 1.0, 0.02) << i;
  }
}

TEST(PoseGraph, FoldsNeitherTheAnchorNorTheNewestNorALoopsEnd) {
  PoseGraph graph = buildGraph(squareLoop());
  graph.addLoop(40, 0, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  graph.addLoop(20, 5, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  EXPECT_FALSE(graph.fold(0));
  EXPECT_FALSE(graph.fold(40));
  EXPECT_FALSE(graph.fold(5));
  EXPECT_FALSE(graph.fold(20));
  EXPECT_FALSE(graph.fold(41));
  EXPECT_TRUE(graph.fold(6));
  EXPECT_FALSE(graph.fold(6));  // once
  EXPECT_EQ(graph.optimised(), 40u);
  EXPECT_THROW(graph.addLoop(6, 30, Eigen::Isometry3d::Identity(), Matrix6d::Identity()), std::invalid_argument);
}

TEST(PoseGraph, PriorsFromAMapPullADriftedSideOntoItAndAreNotFolded) {
  // The square driven with drift, its third side's keyframes measured where a map places them (the
  // truth): they end on it, and the keyframes between follow.
  const auto gt = squareLoop();
  const auto odom = driftingOdometry(gt, 0.5 * kDeg);
  PoseGraph graph = buildGraph(odom);
  for (int k = 20; k <= 30; k += 5)
    graph.addPrior(k, gt[static_cast<std::size_t>(k)], isotropicInformation(0.003, 0.001));
  EXPECT_EQ(graph.priors(), 3u);
  const double before = (graph.pose(25).translation() - gt[25].translation()).norm();
  ASSERT_TRUE(graph.optimize());
  const double after = (graph.pose(25).translation() - gt[25].translation()).norm();
  std::printf("keyframe 25: %.3f m off before, %.4f m after\n", before, after);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(after, 0.01);
  EXPECT_LT((graph.pose(27).translation() - gt[27].translation()).norm(), 0.05);
  EXPECT_FALSE(graph.fold(25));
  EXPECT_TRUE(graph.fold(26));
  EXPECT_THROW(graph.addPrior(26, gt[26], isotropicInformation(0.003, 0.001)), std::invalid_argument);
}

TEST(PoseGraph, RejectsBadInput) {
  PoseGraph graph;
  KeyframeNode a;
  a.stamp_ns = 10;
  graph.addKeyframe(a);
  KeyframeNode b;
  b.stamp_ns = 5;
  EXPECT_THROW(graph.addKeyframe(b), std::invalid_argument);
  EXPECT_THROW(graph.addLoop(0, 3, Eigen::Isometry3d::Identity(), Matrix6d::Identity()), std::invalid_argument);
  EXPECT_TRUE(graph.optimize());  // one keyframe: nothing to do
}

}  // namespace
}  // namespace mmlio::backend
