// The yaw search of the spatial calibration on scenes built to fool it: a room that looks the same
// a quarter turn round must be refused, not guessed; a wrong mount that matches the few points it
// puts in view must lose to the right one.
#include <gtest/gtest.h>

#include <cstdio>

#include "calib_scene.hpp"
#include "mmlio/calib/spatial_calibration.hpp"

namespace mmlio::calib {
namespace {

using namespace testing;

/// A 10 x 10 x 3 m room the same after every quarter turn about its centre: pillars and cabinets
/// repeated four times round.
Scene fourFoldRoom() {
  Scene s;
  const double w = 0.2, a = 5, h = 3;
  s.push_back({{-a - w, -a - w, -w}, {a + w, a + w, 0}});
  s.push_back({{-a - w, -a - w, h}, {a + w, a + w, h + w}});
  const auto quarter = [](const Eigen::Vector3d& p, int k) {
    return Eigen::Vector3d(Eigen::AngleAxisd(k * M_PI / 2, Eigen::Vector3d::UnitZ()) * p);
  };
  const std::vector<Box> quadrant = {
      {{a, -a - w, 0}, {a + w, a + w, h}},  // wall
      {{2.4, 1.6, 0}, {3.4, 2.6, h}},       // pillar left
      {{2.4, -2.6, 0}, {3.4, -1.6, h}},     // pillar right
      {{4.4, -0.3, 0}, {a, 0.9, 1.8}},      // cabinet against the wall, off centre
  };
  for (int k = 0; k < 4; ++k) {
    for (const Box& b : quadrant) {
      const Eigen::Vector3d p = quarter(b.lo, k), q = quarter(b.hi, k);
      s.push_back({p.cwiseMin(q), p.cwiseMax(q)});
    }
  }
  return s;
}

struct Views {
  std::vector<Eigen::Vector3d> spinning, solid;
};

Views viewsFrom(const Scene& scene, const Eigen::Isometry3d& T_world_solid, const Eigen::Isometry3d& T_solid_spinning) {
  Views v;
  for (unsigned k = 0; k < 8; ++k) {
    const auto f = xyz(solidFrame(scene, T_world_solid, 10 + k, 0.005));
    v.solid.insert(v.solid.end(), f.begin(), f.end());
  }
  for (unsigned k = 0; k < 2; ++k) {
    const auto f = xyz(spinningSweep(scene, T_world_solid * T_solid_spinning, 20 + k, 0.005));
    v.spinning.insert(v.spinning.end(), f.begin(), f.end());
  }
  return v;
}

void printFinalists(const SpatialCalibrationResult& r) {
  std::printf("%s\n", r.message.c_str());
  for (const MountCandidate& c : r.candidates)
    std::printf("  yaw %.1f: %d of %d, seen through %.3f\n", c.yaw_deg, c.inliers, c.points_in_view, c.seen_through);
}

TEST(YawSearch, RefusesARoomThatLooksTheSameAQuarterTurnRound) {
  // The rig low enough for the floor to be in view (it holds the height). The spinning LiDAR right
  // above the solid-state one, both on the room's axis of symmetry: every
  // quarter turn of its mount explains the two views alike.
  const Eigen::Isometry3d truth = pose(0, 0, 0.15, 100 * kDeg);
  const Views v = viewsFrom(fourFoldRoom(), pose(0, 0, 0.6, 0), truth);
  const SpatialCalibrationResult r = calibrateSpinningToSolid(v.spinning, v.solid, std::nullopt);
  printFinalists(r);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("about equally"), std::string::npos) << r.message;
}

TEST(YawSearch, FindsTheMountOnceTheSymmetryIsBroken) {
  // The same room with a cabinet and a shelf in view that have no twins: the quarter turns no longer
  // explain it all.
  Scene scene = fourFoldRoom();
  scene.push_back({{2.2, -0.3, 0}, {2.8, 0.6, 2.0}});
  scene.push_back({{3.5, -1.3, 0}, {4.2, -0.6, 1.5}});
  const Eigen::Isometry3d truth = pose(0, 0, 0.15, 100 * kDeg);
  const Views v = viewsFrom(scene, pose(0, 0, 0.6, 0), truth);
  const SpatialCalibrationResult r = calibrateSpinningToSolid(v.spinning, v.solid, std::nullopt);
  printFinalists(r);
  ASSERT_TRUE(r.ok) << r.message;
  const Eigen::Isometry3d err = truth.inverse() * r.T_solid_spinning;
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleDeg(err), 0.1);
}

TEST(YawSearch, WhatTheStartCannotTellTheRoomAroundDoes) {
  // The four-fold room with a cabinet and a shelf behind the rig: the start's view is alike every
  // quarter turn, the solid-state LiDAR's frames once the rig has turned round (its view of the
  // first seconds of motion) are not.
  Scene scene = fourFoldRoom();
  scene.push_back({{-2.8, -0.6, 0}, {-2.2, 0.3, 2.0}});
  scene.push_back({{-4.2, 0.6, 0}, {-3.5, 1.3, 1.5}});
  const Eigen::Isometry3d truth = pose(0, 0, 0.15, 100 * kDeg);
  const Eigen::Isometry3d start = pose(0, 0, 0.6, 0);
  const Views v = viewsFrom(scene, start, truth);
  const SpatialCalibrationResult still = calibrateSpinningToSolid(v.spinning, v.solid, std::nullopt);
  EXPECT_FALSE(still.ok);
  EXPECT_EQ(still.refusal, SpatialCalibrationResult::Refusal::kAmbiguous) << still.message;

  SolidView around;
  around.frames.push_back({Eigen::Isometry3d::Identity(), v.solid});
  for (int k = 1; k < 8; ++k) {
    const Eigen::Isometry3d T_start_solid = pose(0.1 * k, 0.05 * k, 0, k * 45 * kDeg);
    around.frames.push_back({T_start_solid, xyz(solidFrame(scene, start * T_start_solid, 40 + k, 0.005))});
  }
  const SpatialCalibrationResult r = calibrateSpinningToSolid(v.spinning, around, std::nullopt);
  printFinalists(r);
  ASSERT_TRUE(r.ok) << r.message;
  const Eigen::Isometry3d err = truth.inverse() * r.T_solid_spinning;
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(angleDeg(err), 0.1);
}

TEST(YawSearch, AMountThatPutsPointsWhereTheSolidStateLidarSeesThroughIsRefused) {
  // A guess a quarter turn off, in a room without symmetry: the points it puts in view lie
  // in front of walls the solid-state LiDAR sees, so it cannot be right whatever GICP makes of it.
  const Eigen::Isometry3d truth = pose(0.05, 0.1, 0.15, 0);
  const Views v = viewsFrom(office(), pose(0, 0, 1.2, 0), truth);
  SpatialCalibrationConfig cfg;
  cfg.yaw_step_deg = 360;  // no search: only the guess
  const SpatialCalibrationResult r =
      calibrateSpinningToSolid(v.spinning, v.solid, Eigen::Isometry3d(pose(0.05, 0.1, 0.15, 90 * kDeg)), cfg);
  std::printf("%s (seen through %.3f)\n", r.message.c_str(), r.seen_through);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.seen_through, 0.3);
  const SpatialCalibrationResult right = calibrateSpinningToSolid(v.spinning, v.solid, truth, cfg);
  ASSERT_TRUE(right.ok) << right.message;
  EXPECT_LT(right.seen_through, 0.02);
}

}  // namespace
}  // namespace mmlio::calib
