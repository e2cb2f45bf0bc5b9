#include "mmlio/backend/loop_closer.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "mmlio/core/log.hpp"
#include "mmlio/core/short_number.hpp"

namespace mmlio::backend {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
// Each of the twelve uniqueness restarts, and the refinement of one that ends elsewhere, needs only
// to tell whether another alignment fits about as well: a couple of thousand spread-out points
// decide that (a hall keyframe has ~9000 at 0.3 m, and the restarts were most of a loop check's
// 2-3 s there; a corridor refinement rarely converges within its 20 iterations).
constexpr std::size_t kMaxRestartSourcePoints = 2000;

/// The two horizontal principal axes of the points (largest spread first), unit, z = 0.
std::array<Eigen::Vector3d, 2> horizontalAxes(const std::vector<Eigen::Vector3d>& pts, const Eigen::Isometry3d& T) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pts) mean += (T * p).head<2>();
  mean /= std::max<std::size_t>(1, pts.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector2d d = (T * p).head<2>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  const Eigen::Vector2d major = es.eigenvectors().col(1), minor = es.eigenvectors().col(0);
  return {Eigen::Vector3d(major.x(), major.y(), 0), Eigen::Vector3d(minor.x(), minor.y(), 0)};
}

}  // namespace

LoopCloser::LoopCloser() : LoopCloser(Config{}) {}

IcpConfig LoopCloser::Config::icp() const {
  IcpConfig c;
  c.max_corr_coarse_m = icp_max_corr_m;
  c.max_corr_fine_m = std::min(icp_max_corr_m, 0.25);
  c.voxel_fine_m = submap_voxel_m;
  return c;
}

LoopCloser::LoopCloser(Config cfg) : cfg_(std::move(cfg)), icp_(cfg_.icp()) {}

void LoopCloser::forget(int keyframe) {
  if (keyframe >= 0 && static_cast<std::size_t>(keyframe) < descriptors_.size())
    descriptors_[static_cast<std::size_t>(keyframe)].reset();
}

const ScanContext& LoopCloser::descriptor(const PoseGraph& graph, int i) const {
  if (descriptors_.size() < graph.size()) descriptors_.resize(graph.size());
  auto& slot = descriptors_[static_cast<std::size_t>(i)];
  if (!slot) slot = makeScanContext(graph.node(i).cloud_body, cfg_.descriptor);
  return *slot;
}

AlignmentCheck LoopCloser::verify(const PoseGraph& graph, int query, int match, const Eigen::Isometry3d& prior,
                                  bool by_distance) const {
  // Target: keyframes around the match, in the match's body frame, all old enough.
  const Stamp latest = graph.node(query).stamp_ns - fromSec(cfg_.min_time_gap_s);
  const int half = std::max(0, cfg_.submap_keyframes / 2);
  const Eigen::Isometry3d T_match_world = graph.pose(match).inverse();
  std::vector<Eigen::Vector3d> submap;
  for (int i = std::max(0, match - half); i <= std::min(query - 1, match + half); ++i) {
    if (graph.node(i).stamp_ns > latest) continue;
    const Eigen::Isometry3d T_match_i = T_match_world * graph.pose(i);
    for (const auto& p : graph.node(i).cloud_body) submap.push_back(T_match_i * p);
  }
  const IcpTarget target(map::voxelCentroids(submap, cfg_.submap_voxel_m));
  return checkAlignment(graph.node(query).cloud_body, target, prior, by_distance, cfg_, icp_);
}

AlignmentCheck checkAlignment(const std::vector<Eigen::Vector3d>& source, const IcpTarget& target,
                              const Eigen::Isometry3d& prior, bool by_distance, const LoopCloser::Config& cfg,
                              const IcpConfig& icp) {
  AlignmentCheck v;
  // A distance candidate's prior is close to the alignment, which changes the weakest direction's
  // information only a little: a place that is clearly degenerate at the prior is rejected
  // without the ICP (in a corridor, most candidates). Descriptor priors (yaw only) are not.
  IcpConfig at_pose = icp;
  at_pose.levels = 1;
  at_pose.max_iterations_per_level = 0;  // only the final statistics (at the finest gate), at the pose given
  const auto clearlyDegenerate = [&cfg](const IcpResult& probe, double fraction) {
    return probe.converged && probe.min_translation_eigenvalue < fraction * cfg.min_translation_eigenvalue;
  };
  if (by_distance && cfg.prior_eigenvalue_fraction > 0) {
    const IcpResult probe = alignPointToPlane(source, target, prior, at_pose);
    if (clearlyDegenerate(probe, cfg.prior_eigenvalue_fraction)) {
      v.icp = probe;
      v.reason = "degenerate geometry at the prior (translation eigenvalue " +
                 shortNumber(probe.min_translation_eigenvalue) + ")";
      return v;
    }
  }
  // The prior can be a metre off, but after the ICP's coarsest level the pose is close to the final
  // one and so is the weakest direction's information: a place still clearly short of it there is
  // rejected before the finer levels, which cost the most.
  IcpConfig staged = icp;
  IcpResult after_coarse;
  bool degenerate_after_coarse = false;
  if (by_distance && cfg.coarse_eigenvalue_fraction > 0)
    staged.continue_after_level = [&](int level, const Eigen::Isometry3d& T) {
      if (level > 0) return true;
      after_coarse = alignPointToPlane(source, target, T, at_pose);
      degenerate_after_coarse = clearlyDegenerate(after_coarse, cfg.coarse_eigenvalue_fraction);
      return !degenerate_after_coarse;
    };
  v.icp = alignPointToPlane(source, target, prior, staged);
  if (degenerate_after_coarse) {
    v.icp = after_coarse;
    v.reason = "degenerate geometry after the coarse alignment (translation eigenvalue " +
               shortNumber(after_coarse.min_translation_eigenvalue) + ")";
    return v;
  }
  const IcpResult& r = v.icp;
  if (!r.converged) {
    v.reason = "ICP did not converge (" + std::to_string(r.correspondences) + " correspondences)";
    return v;
  }
  if (r.fitness_m > cfg.max_fitness_m) {
    v.reason = "fitness " + shortNumber(r.fitness_m) + " m > " + shortNumber(cfg.max_fitness_m);
    return v;
  }
  if (r.overlap < cfg.min_overlap) {
    v.reason = "overlap " + shortNumber(r.overlap) + " < " + shortNumber(cfg.min_overlap);
    return v;
  }
  if (r.min_translation_eigenvalue < cfg.min_translation_eigenvalue) {
    v.reason = "degenerate geometry (translation eigenvalue " + shortNumber(r.min_translation_eigenvalue) + ")";
    return v;
  }
  if (by_distance) {
    const Eigen::Isometry3d correction = prior.inverse() * r.T_target_source;
    const double angle_deg = Eigen::AngleAxisd(correction.rotation()).angle() * kRadToDeg;
    if (correction.translation().norm() > cfg.max_correction_m || angle_deg > cfg.max_correction_deg) {
      v.reason = "correction " + shortNumber(correction.translation().norm()) + " m / " + shortNumber(angle_deg) +
                 " deg from the prior exceeds the bound";
      return v;
    }
  }
  // Uniqueness: restart from the solution shifted along the horizontal principal axes.
  // Restarts run coarse (cheap); one that ends at a distinct place is refined at full resolution
  // before its fitness and overlap are compared with the solution's.
  IcpConfig restart = icp;
  restart.levels = 2;
  restart.voxel_fine_m = std::max(icp.voxel_fine_m, 0.3);
  restart.max_corr_fine_m = std::max(icp.max_corr_fine_m, 0.5);
  restart.max_iterations_per_level = 10;
  restart.max_source_points = kMaxRestartSourcePoints;
  const auto axes = horizontalAxes(map::voxelCentroids(source, 0.5), r.T_target_source);
  for (const auto& axis : axes)
    for (double shift : cfg.ambiguity_shifts_m)
      for (double sign : {-1.0, 1.0}) {
        Eigen::Isometry3d guess = r.T_target_source;
        guess.pretranslate(sign * shift * axis);
        const IcpResult coarse = alignPointToPlane(source, target, guess, restart);
        if (!coarse.converged) continue;
        if ((coarse.T_target_source.translation() - r.T_target_source.translation()).norm() <
            cfg.ambiguity_min_separation_m)
          continue;
        // The coarse overlap (wider gate) bounds the fine one from above, roughly: skip hopeless ones.
        if (coarse.overlap < cfg.ambiguity_overlap_ratio * r.overlap) continue;
        IcpConfig fine = icp;
        fine.levels = 1;
        fine.max_corr_coarse_m = icp.max_corr_fine_m;
        fine.voxel_coarse_m = icp.voxel_fine_m;
        fine.max_source_points = kMaxRestartSourcePoints;
        const IcpResult alt = alignPointToPlane(source, target, coarse.T_target_source, fine);
        if (!alt.converged) continue;
        const double separation = (alt.T_target_source.translation() - r.T_target_source.translation()).norm();
        if (separation < cfg.ambiguity_min_separation_m) continue;
        if (alt.fitness_m <= cfg.ambiguity_fitness_ratio * r.fitness_m &&
            alt.overlap >= cfg.ambiguity_overlap_ratio * r.overlap && alt.fitness_m <= cfg.max_fitness_m &&
            alt.overlap >= cfg.min_overlap) {
          v.reason = "ambiguous: an alignment " + shortNumber(separation) + " m away fits as well (fitness " +
                     shortNumber(alt.fitness_m) + " vs " + shortNumber(r.fitness_m) + ", overlap " +
                     shortNumber(alt.overlap) + " vs " + shortNumber(r.overlap) + ")";
          return v;
        }
      }
  v.accepted = true;
  v.reason = "accepted: fitness " + shortNumber(r.fitness_m) + " m, overlap " + shortNumber(r.overlap);
  return v;
}

LoopResult LoopCloser::detect(const PoseGraph& graph, int query, const HeadingCheck& plausible_heading) const {
  LoopResult result;
  result.query = query;
  if (query < 0 || query >= static_cast<int>(graph.size())) {
    result.reason = "no such keyframe";
    return result;
  }
  if (graph.node(query).cloud_body.empty()) {
    result.reason = "query keyframe has no points";
    return result;
  }
  const Stamp latest = graph.node(query).stamp_ns - fromSec(cfg_.min_time_gap_s);
  const Eigen::Isometry3d T_world_query = graph.pose(query);

  struct Candidate {
    int index;
    Eigen::Isometry3d prior;  // T_match_query
    bool by_distance;
  };
  std::vector<Candidate> candidates;
  {
    std::vector<std::pair<double, int>> near;
    for (int i = 0; i < query; ++i) {
      if (graph.node(i).stamp_ns > latest || graph.node(i).cloud_body.empty()) continue;
      const double d = (graph.pose(i).translation() - T_world_query.translation()).norm();
      if (d <= cfg_.search_radius_m) near.emplace_back(d, i);
    }
    std::sort(near.begin(), near.end());
    for (std::size_t k = 0; k < near.size() && static_cast<int>(k) < cfg_.max_distance_candidates; ++k)
      candidates.push_back({near[k].second, graph.pose(near[k].second).inverse() * T_world_query, true});
  }
  if (cfg_.use_descriptor) {
    const ScanContext& q = descriptor(graph, query);
    int best = -1;
    ScanContextMatch best_match;
    for (int i = 0; i < query; ++i) {
      if (graph.node(i).stamp_ns > latest || graph.node(i).cloud_body.empty()) continue;
      const ScanContext& c = descriptor(graph, i);
      // Cheap rotation-invariant pre-check before the shift search.
      if ((c.ring_key - q.ring_key).norm() > 0.5 * q.ring_key.norm() + 1e-9) continue;
      const ScanContextMatch m = compareScanContexts(q, c);
      if (m.distance < best_match.distance) {
        best_match = m;
        best = i;
      }
    }
    const bool already =
        std::any_of(candidates.begin(), candidates.end(), [&](const Candidate& c) { return c.index == best; });
    if (best >= 0 && !already && best_match.distance <= cfg_.max_descriptor_distance) {
      if (!plausible_heading || plausible_heading(best, best_match.yaw_rad, cfg_.descriptor_heading_tolerance_deg)) {
        Eigen::Isometry3d prior = Eigen::Isometry3d::Identity();
        prior.linear() = Eigen::AngleAxisd(best_match.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        candidates.push_back({best, prior, false});
      } else {
        ++result.candidates_refused;
        result.reason = "descriptor candidate " + std::to_string(best) + " refused: its heading (" +
                        shortNumber(best_match.yaw_rad * kRadToDeg) +
                        " deg) is not one the estimate can have drifted into";
      }
    }
  }
  if (candidates.empty()) {
    if (result.reason.empty()) result.reason = "no candidate";
    return result;
  }
  for (const Candidate& c : candidates) {
    ++result.candidates_tried;
    const AlignmentCheck v = verify(graph, query, c.index, c.prior, c.by_distance);
    result.match = c.index;
    result.T_match_query = v.icp.T_target_source;
    result.fitness_m = v.icp.fitness_m;
    result.overlap = v.icp.overlap;
    result.reason = std::string(c.by_distance ? "distance" : "descriptor") + " candidate " + std::to_string(c.index) +
                    ": " + v.reason;
    log::debug("loop ", query, " -> ", result.reason);
    if (v.accepted) {
      result.accepted = true;
      result.information = isotropicInformation(cfg_.loop_sigma_translation_m, cfg_.loop_sigma_rotation_rad);
      return result;
    }
  }
  return result;
}

}  // namespace mmlio::backend
