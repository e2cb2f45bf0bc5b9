// Relocalization in a saved session with no initial pose: found to centimetres between and across
// the session's keyframes, refused in another room, and "ambiguous" (never a confident guess) in a
// corridor whose doors repeat.
#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/backend/relocalizer.hpp"
#include "session_scene.hpp"

namespace mmlio::backend {
namespace {

using testing::pose;
constexpr double kDeg = M_PI / 180.0;

std::vector<Eigen::Vector3d> sweep(const testing::Scene& scene, const Eigen::Isometry3d& T_map_body, unsigned seed) {
  return testing::keyframeCloud(scene, T_map_body, seed);
}

using testing::sessionOf;

Session roomASession() { return sessionOf(testing::roomA(), testing::roomARoute()); }

double angleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd((a.inverse() * b).rotation()).angle() / kDeg;
}

TEST(Relocalizer, FindsASweepBetweenTheKeyframesFacingAnotherWay) {
  const Session session = roomASession();
  const Relocalizer relocalizer(session);
  // Within a metre of the route, headings the walk never had (one of them the rectangular room's
  // half-turn twin of a keyframe's).
  for (const Eigen::Isometry3d& truth :
       {pose(1.2, -2.7, 1, 100 * kDeg), pose(-4.2, 0.5, 1.1, -60 * kDeg), pose(4.0, 0.0, 1.2, 180 * kDeg)}) {
    const Relocalization r = relocalizer.locate(sweep(testing::roomA(), truth, 99));
    ASSERT_TRUE(r.localized) << r.reason;
    EXPECT_LT((r.T_map_body.translation() - truth.translation()).norm(), 0.05) << r.reason;
    EXPECT_LT(angleDeg(r.T_map_body, truth), 1.0) << r.reason;
    EXPECT_GE(r.keyframe, 0);
  }
}

TEST(Relocalizer, AHintOfAMetreAndTwentyDegreesIsEnough) {
  const Session session = roomASession();
  const Relocalizer relocalizer(session);
  const Eigen::Isometry3d truth = pose(0.5, 2.0, 1, 200 * kDeg);
  const Relocalization r = relocalizer.locate(sweep(testing::roomA(), truth, 98), pose(1.3, 2.0, 1, 220 * kDeg));
  ASSERT_TRUE(r.localized) << r.reason;
  EXPECT_LT((r.T_map_body.translation() - truth.translation()).norm(), 0.05) << r.reason;
  EXPECT_LT(angleDeg(r.T_map_body, truth), 1.0) << r.reason;
}

TEST(Relocalizer, ASweepFromAnotherRoomIsNotLocalized) {
  const Session session = roomASession();
  const Relocalizer relocalizer(session);
  for (const Eigen::Isometry3d& where : {pose(0, 0, 1, 0), pose(2, -1, 1, 45 * kDeg)}) {
    const Relocalization r = relocalizer.locate(sweep(testing::roomB(), where, 97));
    EXPECT_FALSE(r.localized) << "claimed " << r.T_map_body.translation().transpose() << ": " << r.reason;
    EXPECT_FALSE(r.reason.empty());
  }
}

TEST(Relocalizer, ACorridorWhoseDoorsRepeatIsAmbiguousNotAGuess) {
  const testing::Scene corridor = testing::corridor(60.0, 4.0);
  std::vector<Eigen::Isometry3d> poses;
  for (double x = -20; x <= 20; x += 2.5) poses.push_back(pose(x, 0, 1, 0));
  const Session session = sessionOf(corridor, poses);
  const Relocalizer relocalizer(session);
  const Eigen::Isometry3d truth = pose(3.3, 0.1, 1, 5 * kDeg);
  const Relocalization r = relocalizer.locate(sweep(corridor, truth, 96));
  // Either it says it cannot tell, or it is right: never a pose a door period away.
  if (r.localized)
    EXPECT_LT((r.T_map_body.translation() - truth.translation()).norm(), 0.1) << r.reason;
  else
    EXPECT_FALSE(r.reason.empty());
  std::printf("%s\n", r.reason.c_str());
}

}  // namespace
}  // namespace mmlio::backend
