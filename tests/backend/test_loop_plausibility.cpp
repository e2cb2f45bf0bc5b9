// A loop's correction is bounded by what odometry can drift over the route between its ends
// through the graph: a room matched turned half round is refused at any distance, and a revisit
// whose ends earlier loops already tie is held to a tight bound. A place descriptor's heading is
// held to the same rotation bound before any ICP.
#include <gtest/gtest.h>

#include <cmath>

#include "../common/box_scene.hpp"
#include "mmlio/backend/loop_plausibility.hpp"

namespace mmlio::backend {
namespace {

constexpr double kDeg = M_PI / 180.0;

using box_scene::pose;

/// Laps of a 10 m square in 1 m steps (40 keyframes a lap), the odometry exact.
PoseGraph laps(int n) {
  PoseGraph graph;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i <= 40 * n; ++i) {
    KeyframeNode node;
    node.stamp_ns = static_cast<Stamp>(i + 1) * 1'000'000'000;
    node.T_world_body_odom = T;
    graph.addKeyframe(node);
    T = T * pose(1.0, 0, 0, i % 10 == 9 ? M_PI / 2 : 0.0);
  }
  return graph;
}

LoopResult loopAt(const PoseGraph& graph, int match, int query, const Eigen::Isometry3d& error) {
  LoopResult r;
  r.accepted = true;
  r.match = match;
  r.query = query;
  r.T_match_query = graph.pose(match).inverse() * graph.pose(query) * error;
  return r;
}

TEST(LoopPlausibility, TheOdometrysOwnRelativePoseIsPlausible) {
  const PoseGraph graph = laps(1);
  const LoopCorrection c = loopCorrection(graph, loopAt(graph, 0, 40, Eigen::Isometry3d::Identity()), MappingConfig{});
  EXPECT_NEAR(c.route_m, 40.0, 1e-9);
  EXPECT_NEAR(c.correction_m, 0.0, 1e-9);
  EXPECT_NEAR(c.correction_deg, 0.0, 1e-6);
  EXPECT_TRUE(c.plausible());
}

TEST(LoopPlausibility, ARoomMatchedTurnedHalfRoundIsRefusedAfterAnyRoute) {
  PoseGraph graph = laps(25);  // a kilometre
  const LoopResult flipped = loopAt(graph, 3, 1000, pose(0.2, 0.1, 0, M_PI));
  const LoopCorrection c = loopCorrection(graph, flipped, MappingConfig{});
  EXPECT_NEAR(c.correction_deg, 180.0, 1e-6);
  EXPECT_LT(c.correction_m, c.allowed_m);  // the shift alone would pass
  EXPECT_FALSE(c.plausible());
  // A small genuine correction over the same route passes.
  EXPECT_TRUE(loopCorrection(graph, loopAt(graph, 3, 1000, pose(0.2, 0.1, 0, 2 * kDeg)), MappingConfig{}).plausible());
}

TEST(LoopPlausibility, LoopsAlreadyClosedTightenTheBoundOfTheNextOne) {
  PoseGraph graph = laps(3);
  const LoopResult shifted = loopAt(graph, 2, 118, pose(0.6, 0, 0, 0));  // 0.6 m off, 116 m travelled
  EXPECT_TRUE(loopCorrection(graph, shifted, MappingConfig{}).plausible());
  // Each lap's start tied to the first: 2 and 118 are then 4 m apart through the graph.
  graph.addLoop(0, 40, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  graph.addLoop(40, 80, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  graph.addLoop(80, 120, Eigen::Isometry3d::Identity(), isotropicInformation(0.01, 0.001));
  const LoopCorrection c = loopCorrection(graph, shifted, MappingConfig{});
  EXPECT_NEAR(c.route_m, 4.0, 1e-9);
  EXPECT_FALSE(c.plausible());
  EXPECT_TRUE(loopCorrection(graph, loopAt(graph, 2, 118, pose(0.05, 0, 0, 0.5 * kDeg)), MappingConfig{}).plausible());
}

TEST(LoopPlausibility, ADescriptorHeadingHalfRoundIsRefusedAndATiltedRigsHeadingIsNot) {
  const PoseGraph graph = laps(25);  // keyframes 0 and 1000 at the same place, heading the same way
  const MappingConfig cfg;
  const double route_m = graph.routeLength(0, 1000);
  const double allowed_deg = cfg.max_loop_rotation_base_deg + cfg.max_rotation_drift_deg_per_m * route_m;
  EXPECT_TRUE(plausibleHeading(graph, 0, 1000, 0.0, 6.0, cfg));
  EXPECT_TRUE(plausibleHeading(graph, 0, 1000, (allowed_deg + 5.0) * kDeg, 6.0, cfg));  // within the slack
  EXPECT_FALSE(plausibleHeading(graph, 0, 1000, (allowed_deg + 7.0) * kDeg, 6.0, cfg));
  EXPECT_FALSE(plausibleHeading(graph, 0, 1000, M_PI, 6.0, cfg));
  EXPECT_FALSE(plausibleHeading(graph, 0, 1000, -M_PI + 0.01, 6.0, cfg));  // wraps round
  // The same place seen with the rig pitched 20 deg: the heading is still the same.
  PoseGraph tilted;
  KeyframeNode a, b;
  a.stamp_ns = 1'000'000'000;
  b.stamp_ns = 2'000'000'000;
  b.T_world_body_odom = pose(0.5, 0, 0, 30 * kDeg, 20 * kDeg);
  tilted.addKeyframe(a);
  tilted.addKeyframe(b);
  EXPECT_TRUE(plausibleHeading(tilted, 0, 1, 30 * kDeg, 0.0, cfg));
  EXPECT_FALSE(plausibleHeading(tilted, 0, 1, 50 * kDeg, 0.0, cfg));
}

}  // namespace
}  // namespace mmlio::backend
