#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/estimator/degeneracy.hpp"

namespace mmlio::estimator {
namespace {

// Plane matches of a 2.4 m wide, 2.8 m high corridor along x, seen from a body at the origin:
// walls y = +-1.2, floor z = -1.2, ceiling z = 1.6, points spread from x = -10 to 10 m.
std::vector<MapMatch> corridorMatches(std::uint8_t source = 0) {
  std::vector<MapMatch> m;
  for (int i = 0; i < 200; ++i) {
    const double x = -10.0 + 0.1 * i, s = 0.3 * std::sin(0.7 * i);
    const auto plane = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
      MapMatch match;
      match.kind = MapMatch::Kind::kPlane;
      match.source = source;
      match.p_body = p;
      match.a = n;
      match.b = Eigen::Vector3d(-n.dot(p), 0, 0);
      m.push_back(match);
    };
    plane({x, 1.2, s}, Eigen::Vector3d::UnitY());
    plane({x, -1.2, s}, -Eigen::Vector3d::UnitY());
    plane({x, s, -1.2}, Eigen::Vector3d::UnitZ());
    plane({x, s, 1.6}, -Eigen::Vector3d::UnitZ());
  }
  return m;
}

std::vector<MapMatch> endWall(int points, std::uint8_t source = 0) {
  std::vector<MapMatch> m;
  for (int i = 0; i < points; ++i) {
    MapMatch match;
    match.kind = MapMatch::Kind::kPlane;
    match.source = source;
    match.p_body = Eigen::Vector3d(50.0, -1.0 + 2.0 * i / points, 0.5 * std::cos(i));
    match.a = -Eigen::Vector3d::UnitX();
    match.b = Eigen::Vector3d(50.0, 0, 0);
    m.push_back(match);
  }
  return m;
}

TEST(Degeneracy, ACorridorLeavesItsAxisUnobservedAndNamesIt) {
  const Degeneracy d =
      analyseDegeneracy(matchInformation(corridorMatches(), Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig());
  EXPECT_TRUE(d.translation_degenerate);
  EXPECT_LT(d.translation_points, 1e-6);
  EXPECT_GT(std::abs(d.weak_translation.x()), 0.999);
  EXPECT_STREQ(bodyAxisName(d.weak_translation), "forward");
  EXPECT_GT(d.translation_eigenvalues(1), 100.0);  // across and up: hundreds of points
  EXPECT_FALSE(d.rotation_degenerate);
}

TEST(Degeneracy, AFarEndWallMakesTheAxisObservedInProportionToItsPoints) {
  std::vector<MapMatch> few = corridorMatches(), many = corridorMatches();
  for (const MapMatch& m : endWall(10)) few.push_back(m);
  for (const MapMatch& m : endWall(80)) many.push_back(m);
  const Degeneracy d_few =
      analyseDegeneracy(matchInformation(few, Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig());
  const Degeneracy d_many =
      analyseDegeneracy(matchInformation(many, Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig());
  EXPECT_NEAR(d_few.translation_points, 10.0, 1.0);  // an end wall point is worth one point along x
  EXPECT_TRUE(d_few.translation_degenerate);
  EXPECT_NEAR(d_many.translation_points, 80.0, 8.0);
  EXPECT_FALSE(d_many.translation_degenerate);
}

TEST(Degeneracy, OutliersAndOtherLidarsAreLeftOutOfALidarsInformation) {
  std::vector<MapMatch> m = corridorMatches(0);
  for (MapMatch w : endWall(80, 1)) m.push_back(w);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(analyseDegeneracy(matchInformation(m, I, 0.1, 0), DegeneracyConfig()).translation_degenerate);
  EXPECT_FALSE(analyseDegeneracy(matchInformation(m, I, 0.1, -1), DegeneracyConfig()).translation_degenerate);
  // Seen from 0.5 m farther along x, the end wall's residuals are 0.5 m: outliers, no information.
  Eigen::Isometry3d shifted = I;
  shifted.translation().x() = 0.5;
  EXPECT_TRUE(analyseDegeneracy(matchInformation(m, shifted, 0.1), DegeneracyConfig()).translation_degenerate);
}

TEST(Degeneracy, RemappingKeepsThePredictionAlongTheWeakAxisAndTheSolutionAcrossIt) {
  const Degeneracy d =
      analyseDegeneracy(matchInformation(corridorMatches(), Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig());
  const Eigen::Vector3d p_pred(1.0, 0.0, 0.0), v_pred(1.0, 0.0, 0.0);
  const Eigen::Quaterniond q_pred = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p(0.9, 0.05, -0.02), v(0.8, 0.1, 0.0);
  Eigen::Quaterniond q(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond q_solved = q;
  const int n = remapDegenerateDirections(d, DegeneracyConfig(), p_pred, q_pred, v_pred, &p, &q, &v);
  EXPECT_EQ(n, 1);
  EXPECT_NEAR(p.x(), 1.0, 1e-9);   // along the corridor: the IMU's prediction
  EXPECT_NEAR(p.y(), 0.05, 1e-9);  // across: the LiDARs' solution
  EXPECT_NEAR(p.z(), -0.02, 1e-9);
  EXPECT_NEAR(v.x(), 1.0, 1e-9);
  EXPECT_NEAR(v.y(), 0.1, 1e-9);
  EXPECT_TRUE(q.isApprox(q_solved));  // rotation is observed: untouched
}

// The drift model: unobserved, the position variance grows as a white acceleration's (q^2 t^3 / 3);
// observed along x, only x shrinks.
TEST(PredictionDrift, GrowsWhereUnobservedAndShrinksOnlyAlongWhatTheLidarsObserve) {
  PredictionDrift drift;
  const double q = 0.05;
  for (int k = 0; k < 20; ++k) drift.predict(0.1, q);
  const double expected = q * q * 8.0 / 3.0;  // t = 2 s
  EXPECT_NEAR(drift.positionCovariance()(0, 0), expected, 1e-3 * expected);
  EXPECT_NEAR(drift.positionCovariance()(2, 2), expected, 1e-3 * expected);
  EXPECT_NEAR(drift.positionCovariance()(0, 1), 0.0, 1e-12);

  std::vector<MapMatch> wall = endWall(400);  // a wall across x: x observed, y and z not
  const Degeneracy d =
      analyseDegeneracy(matchInformation(wall, Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig());
  drift.update(d, 0.05);
  EXPECT_LT(drift.positionCovariance()(0, 0), 0.05 * 0.05 / 300.0);
  EXPECT_NEAR(drift.positionCovariance()(1, 1), expected, 1e-3 * expected);
  EXPECT_NEAR(drift.positionCovariance()(2, 2), expected, 1e-3 * expected);
}

// Fifteen end-wall points do not beat a fresh prediction; after seconds without them they do.
// Five never do: too few to tell a surface from a wrong association.
TEST(Degeneracy, WeakEvidenceCountsOnceThePredictionHasDrifted) {
  std::vector<MapMatch> m = corridorMatches(), five = corridorMatches();
  for (const MapMatch& w : endWall(15)) m.push_back(w);
  for (const MapMatch& w : endWall(5)) five.push_back(w);
  const Matrix6d info = matchInformation(m, Eigen::Isometry3d::Identity(), 0.1);
  const double sigma = 0.05;
  PredictionDrift drift;
  drift.predict(0.1, 0.05);
  const Eigen::Matrix3d fresh = drift.positionCovariance();
  EXPECT_TRUE(analyseDegeneracy(info, DegeneracyConfig(), &fresh, sigma).translation_degenerate);
  for (int k = 0; k < 20; ++k) drift.predict(0.1, 0.05);
  const Eigen::Matrix3d drifted = drift.positionCovariance();
  const Degeneracy d = analyseDegeneracy(info, DegeneracyConfig(), &drifted, sigma);
  EXPECT_FALSE(d.translation_degenerate);
  EXPECT_LE(d.translation_thresholds(0), 10.0);
  EXPECT_TRUE(
      analyseDegeneracy(matchInformation(five, Eigen::Isometry3d::Identity(), 0.1), DegeneracyConfig(), &drifted, sigma)
          .translation_degenerate);
  // Without any evidence along the axis, the drifted prediction is still all there is.
  const Degeneracy none = analyseDegeneracy(matchInformation(corridorMatches(), Eigen::Isometry3d::Identity(), 0.1),
                                            DegeneracyConfig(), &drifted, sigma);
  EXPECT_TRUE(none.translation_degenerate);
  EXPECT_GT(std::abs(none.weak_translation.x()), 0.999);
}

}  // namespace
}  // namespace mmlio::estimator
