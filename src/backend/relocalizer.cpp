#include "mmlio/backend/relocalizer.hpp"

#include <algorithm>
#include <cmath>

#include "mmlio/core/short_number.hpp"
#include "mmlio/map/kd_tree.hpp"

namespace mmlio::backend {
Relocalizer::Relocalizer(const Session& session, RelocalizerConfig cfg) : session_(session), cfg_(std::move(cfg)) {
  descriptors_.resize(session_.keyframes.size());
  for (std::size_t k = 0; k < session_.keyframes.size(); ++k)
    if (!session_.keyframes[k].cloud_body.empty())
      descriptors_[k] = makeScanContext(session_.keyframes[k].cloud_body, cfg_.checks.descriptor);
}

AlignmentCheck Relocalizer::verify(const std::vector<Eigen::Vector3d>& cloud_body, const Candidate& c) const {
  const int n = static_cast<int>(session_.keyframes.size());
  const int half = std::max(0, cfg_.submap_keyframes / 2);
  const Eigen::Isometry3d T_keyframe_map =
      session_.keyframes[static_cast<std::size_t>(c.keyframe)].T_map_body.inverse();
  std::vector<Eigen::Vector3d> submap;
  for (int i = std::max(0, c.keyframe - half); i <= std::min(n - 1, c.keyframe + half); ++i) {
    const SessionKeyframe& k = session_.keyframes[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d T_keyframe_i = T_keyframe_map * k.T_map_body;
    for (const Eigen::Vector3d& p : k.cloud_body) submap.push_back(T_keyframe_i * p);
  }
  const IcpTarget target(map::voxelCentroids(submap, cfg_.checks.submap_voxel_m));
  return checkAlignment(cloud_body, target, c.T_keyframe_body, false, cfg_.checks, cfg_.checks.icp());
}

Relocalization Relocalizer::locate(const std::vector<Eigen::Vector3d>& cloud_body,
                                   const std::vector<Eigen::Vector3d>& verify_body,
                                   const std::optional<Eigen::Isometry3d>& hint) const {
  Relocalization out;
  if (cloud_body.empty()) {
    out.reason = "the sweep has no points";
    return out;
  }
  std::vector<Candidate> candidates;
  if (hint) {
    std::vector<std::pair<double, int>> near;
    for (std::size_t k = 0; k < session_.keyframes.size(); ++k) {
      if (!descriptors_[k]) continue;
      const double d = (session_.keyframes[k].T_map_body.translation() - hint->translation()).norm();
      if (d <= cfg_.hint_radius_m) near.emplace_back(d, static_cast<int>(k));
    }
    std::sort(near.begin(), near.end());
    for (std::size_t i = 0; i < near.size() && static_cast<int>(i) < cfg_.descriptor_candidates; ++i)
      candidates.push_back(
          {near[i].second, session_.keyframes[static_cast<std::size_t>(near[i].second)].T_map_body.inverse() * *hint});
  } else {
    const ScanContext q = makeScanContext(cloud_body, cfg_.checks.descriptor);
    std::vector<std::pair<ScanContextMatch, int>> ranked;
    for (std::size_t k = 0; k < descriptors_.size(); ++k) {
      if (!descriptors_[k]) continue;
      const ScanContextMatch m = compareScanContexts(q, *descriptors_[k]);
      if (m.distance <= cfg_.max_descriptor_distance) ranked.emplace_back(m, static_cast<int>(k));
    }
    std::sort(ranked.begin(), ranked.end(),
              [](const auto& a, const auto& b) { return a.first.distance < b.first.distance; });
    // A rectangular room's descriptor matches itself turned half round about as well as it does
    // unturned: each candidate is tried at both headings, and the fit decides.
    for (std::size_t i = 0; i < ranked.size() && static_cast<int>(i) < cfg_.descriptor_candidates; ++i)
      for (const double turn : {0.0, M_PI}) {
        Eigen::Isometry3d prior = Eigen::Isometry3d::Identity();
        prior.linear() = Eigen::AngleAxisd(ranked[i].first.yaw_rad + turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        candidates.push_back({ranked[i].second, prior});
      }
  }
  if (candidates.empty()) {
    out.reason = hint ? "no keyframe of the session within " + shortNumber(cfg_.hint_radius_m) + " m of the hint"
                      : "no keyframe of the session looks like this place";
    return out;
  }
  struct Passed {
    Eigen::Isometry3d T_map_body;
    int keyframe;
    IcpResult icp;
  };
  std::vector<Passed> passed;
  std::string last_reason;
  for (const Candidate& c : candidates) {
    ++out.candidates_tried;
    const AlignmentCheck v = verify(verify_body, c);
    if (!v.accepted) {
      last_reason = "keyframe " + std::to_string(c.keyframe) + ": " + v.reason;
      continue;
    }
    passed.push_back({session_.keyframes[static_cast<std::size_t>(c.keyframe)].T_map_body * v.icp.T_target_source,
                      c.keyframe, v.icp});
  }
  if (passed.empty()) {
    out.reason = "no candidate verified (" + std::to_string(out.candidates_tried) + " tried; last " + last_reason + ")";
    return out;
  }
  // The alignment that explains most of the sweep wins: a wrong one in a symmetric room fits the
  // walls as closely as the right one (both to the range noise) but misses the furniture.
  const auto best = std::max_element(passed.begin(), passed.end(), [](const Passed& a, const Passed& b) {
    return a.icp.overlap < b.icp.overlap || (a.icp.overlap == b.icp.overlap && a.icp.fitness_m > b.icp.fitness_m);
  });
  for (const Passed& p : passed) {
    const double separation = (p.T_map_body.translation() - best->T_map_body.translation()).norm();
    const double turn = Eigen::AngleAxisd(p.T_map_body.rotation().transpose() * best->T_map_body.rotation()).angle();
    if ((separation >= cfg_.ambiguity_min_separation_m || turn >= cfg_.ambiguity_min_turn_rad) &&
        p.icp.overlap >= best->icp.overlap - cfg_.ambiguity_overlap_margin &&
        p.icp.fitness_m <= cfg_.ambiguity_fitness_ratio * best->icp.fitness_m) {
      out.reason = "ambiguous: keyframes " + std::to_string(best->keyframe) + " and " + std::to_string(p.keyframe) +
                   " place the sweep " + shortNumber(separation) + " m and " + shortNumber(turn * 180.0 / M_PI) +
                   " deg apart and fit alike (overlap " + shortNumber(best->icp.overlap) + " and " +
                   shortNumber(p.icp.overlap) + ", fitness " + shortNumber(best->icp.fitness_m) + " and " +
                   shortNumber(p.icp.fitness_m) + " m)";
      return out;
    }
  }
  out.localized = true;
  out.T_map_body = best->T_map_body;
  out.keyframe = best->keyframe;
  out.fitness_m = best->icp.fitness_m;
  out.overlap = best->icp.overlap;
  out.reason = "verified against keyframe " + std::to_string(best->keyframe) + " (fitness " +
               shortNumber(out.fitness_m) + " m, overlap " + shortNumber(out.overlap) + "; " +
               std::to_string(passed.size()) + " of " + std::to_string(out.candidates_tried) +
               " candidates agree or fit worse)";
  return out;
}

}  // namespace mmlio::backend
