#pragma once
// Loop detection and verification over a PoseGraph's keyframes.
//
// Candidates: (1) past keyframes within search_radius_m of the query in the current estimate and at
// least min_time_gap_s older, nearest first; (2) the best Scan-Context match among the old-enough
// keyframes (for when drift has moved the estimate away from the true place), its prior being the
// descriptor's yaw at zero offset, unless the caller's HeadingCheck says drift cannot have turned
// the estimate that far (a room matched turned half round). Each is verified by point-to-plane
// ICP of the query cloud against a submap of keyframes around the candidate, and accepted only if
//   fitness <= max_fitness_m, overlap >= min_overlap, the geometry constrains every horizontal
//   direction (smallest normalised Hessian eigenvalue; a distance candidate clearly short of it
//   already at its prior is rejected before the ICP), a distance candidate's correction from its
//   prior stays within a bound, and the match is unique: ICP restarted from priors shifted along the
//   scene's horizontal principal axes must not find a distinct, equally good alignment. The last test
//   is what rejects a repetitive corridor, where every door period aligns as well as the true one.

#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "mmlio/backend/point_to_plane_icp.hpp"
#include "mmlio/backend/pose_graph.hpp"
#include "mmlio/backend/scan_context.hpp"

namespace mmlio::backend {

struct LoopResult {
  bool accepted = false;
  int query = -1, match = -1;                                       // keyframe indices
  Eigen::Isometry3d T_match_query = Eigen::Isometry3d::Identity();  // for PoseGraph::addLoop(match, query, ...)
  Matrix6d information = Matrix6d::Identity();                      // of T_match_query (dp, dtheta)
  double fitness_m = 0, overlap = 0;
  int candidates_tried = 0;    // verified by ICP
  int candidates_refused = 0;  // refused before their verification (HeadingCheck)
  std::string reason;          // why accepted / why the last candidate was rejected
};

struct AlignmentCheck {
  bool accepted = false;
  IcpResult icp;
  std::string reason;  // why accepted / rejected
};

class LoopCloser {
 public:
  struct Config {
    double search_radius_m = 10.0;         // distance candidates: within this in the current estimate ...
    double min_time_gap_s = 20.0;          // ... and at least this much older than the query
    double max_fitness_m = 0.1;            // accept: mean |point-to-plane residual| at most this
    double min_overlap = 0.5;              // accept: fraction of query points near the submap (0..1)
    double icp_max_corr_m = 1.0;           // ICP correspondence gate at the coarsest level
    int submap_keyframes = 5;              // keyframes around the candidate merged into the target
    int max_distance_candidates = 3;       // nearest distance candidates verified per query
    bool use_descriptor = true;            // also try the best Scan-Context match
    double max_descriptor_distance = 0.2;  // Scan-Context distance (0..1) below which it is a candidate
    // How far a descriptor's heading may be off the truth: its 6 deg sectors, and the columns a
    // place seen from a metre away shifts (8 deg in the descriptor test). Slack of HeadingCheck.
    double descriptor_heading_tolerance_deg = 30.0;
    double submap_voxel_m = 0.1;  // target downsampling
    // Reject below: degenerate direction (see IcpResult). Corridor-like places (weak along one
    // axis) give loops that slide: on the simulated corridor 0.03 raised the ATE 5.2 -> 10.7 cm.
    double min_translation_eigenvalue = 0.08;
    // Distance candidates whose geometry at the prior gives less than this fraction of
    // min_translation_eigenvalue are rejected before the ICP (0: never). The alignment changes it
    // by a few percent (docs/speed_history.md), so only clear cases are cut short.
    double prior_eigenvalue_fraction = 0.67;
    // ... and those below this fraction after the ICP's coarsest level, at the finest gate, before
    // the finer levels (0: never): from there the final value is within a few percent (0.98-1.04x
    // near the threshold over 62 candidates of four scenes, docs/speed_history.md).
    double coarse_eigenvalue_fraction = 0.9;
    double max_correction_m = 5.0;     // distance candidates: ICP may move the prior at most this ...
    double max_correction_deg = 30.0;  // ... and rotate it at most this
    std::vector<double> ambiguity_shifts_m{1.5, 3.0, 4.5};  // restarts at +-these along both principal axes
    double ambiguity_min_separation_m = 1.0;                // a restart ending this far from the solution is distinct
    double ambiguity_fitness_ratio = 1.5;                   // distinct and fitness within this factor ...
    double ambiguity_overlap_ratio = 0.8;                   // ... and overlap within this fraction: ambiguous
    // Information of an accepted loop: a verified submap ICP is good to millimetres (5 mm /
    // 0.05 deg on the synthetic revisit test); 1 cm / 1 mrad keeps it a little softer than that
    // but stiffer than a few odometry edges (PoseGraph: 2 cm / 2 mrad each), so a loop corrects.
    double loop_sigma_translation_m = 0.01;
    double loop_sigma_rotation_rad = 0.001;
    ScanContextConfig descriptor;
    /// The ICP settings of a verification (from icp_max_corr_m and submap_voxel_m).
    IcpConfig icp() const;
  };

  LoopCloser();
  explicit LoopCloser(Config cfg);

  /// Whether the estimate can have drifted into a descriptor candidate's heading (the yaw of its
  /// T_match_query prior, rad) within `slack_deg`; a candidate it refuses is not verified.
  using HeadingCheck = std::function<bool(int match, double yaw_rad, double slack_deg)>;

  /// Looks for a loop from keyframe `query` to an older keyframe of `graph`. Caches descriptors by
  /// keyframe index, so one LoopCloser serves one graph (not thread-safe).
  LoopResult detect(const PoseGraph& graph, int query, const HeadingCheck& plausible_heading = {}) const;
  /// Frees the cached descriptor of a keyframe that is no loop candidate any more (its cloud dropped).
  void forget(int keyframe);

  const Config& config() const { return cfg_; }

 private:
  AlignmentCheck verify(const PoseGraph& graph, int query, int match, const Eigen::Isometry3d& prior,
                        bool by_distance) const;
  const ScanContext& descriptor(const PoseGraph& graph, int i) const;

  Config cfg_;
  IcpConfig icp_;
  mutable std::vector<std::optional<ScanContext>> descriptors_;
};

/// The checks a loop closure (and a relocalization) must pass: `source` aligned onto `target` by
/// ICP from `prior`, then fitness, overlap, the weakest horizontal direction's information, a
/// bounded correction from the prior when `by_distance` (a degenerate prior is also rejected before
/// the ICP then), and uniqueness (restarts shifted along the scene's horizontal axes find no other
/// alignment as good).
AlignmentCheck checkAlignment(const std::vector<Eigen::Vector3d>& source, const IcpTarget& target,
                              const Eigen::Isometry3d& prior, bool by_distance, const LoopCloser::Config& cfg,
                              const IcpConfig& icp);

}  // namespace mmlio::backend
