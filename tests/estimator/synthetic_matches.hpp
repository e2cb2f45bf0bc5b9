#pragma once
// Random point-to-plane and point-to-edge map matches near a pose, for the map-match residual's
// tests and benchmark.
#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "mmlio/estimator/map_matching.hpp"

namespace mmlio::estimator::testing {

struct MatchSpread {
  int count = 30;
  int edge_every = 3;      // every edge_every-th match is an edge, the others planes
  double extent_m = 3.0;   // body-frame points within +-extent_m on each axis
  double offset_m = 0.25;  // planes and lines up to this far from where the pose puts their points
  unsigned seed = 3;
};

inline std::vector<MapMatch> randomMatches(const Eigen::Isometry3d& T_world_body, const MatchSpread& s) {
  std::mt19937 rng(s.seed);
  std::uniform_real_distribution<double> U(-s.extent_m, s.extent_m), offset(-s.offset_m, s.offset_m);
  std::vector<MapMatch> matches;
  for (int i = 0; i < s.count; ++i) {
    MapMatch m;
    m.kind = i % s.edge_every == s.edge_every - 1 ? MapMatch::Kind::kEdge : MapMatch::Kind::kPlane;
    m.p_body = {U(rng), U(rng), U(rng)};
    const Eigen::Vector3d q = T_world_body * m.p_body;
    if (m.kind == MapMatch::Kind::kPlane) {
      m.a = Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized();
      m.b = Eigen::Vector3d(-m.a.dot(q) + offset(rng), 0, 0);
    } else {
      m.a = q + Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
      m.b = Eigen::Vector3d(U(rng), U(rng), 1.0);
    }
    matches.push_back(m);
  }
  return matches;
}

}  // namespace mmlio::estimator::testing
