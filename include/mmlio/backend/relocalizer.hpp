#pragma once
// Finds where a sweep was taken in a saved session's map, with no initial pose: the session's
// keyframes most alike by place descriptor (Scan Context, which also gives the heading) are the
// candidates; each is verified as a loop closure is (ICP of the sweep onto the keyframes around the
// candidate, fitness, overlap, conditioning, uniqueness). Where candidates at different places pass
// about equally well (a hall whose pillars repeat), it answers "ambiguous" rather than a guess.
// With a pose hint only the keyframes near the hint are candidates.
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "mmlio/backend/loop_closer.hpp"
#include "mmlio/backend/scan_context.hpp"
#include "mmlio/core/session.hpp"

namespace mmlio::backend {

/// A loop's checks, but a sweep must explain three quarters of its points in the map (a loop's
/// keyframe one half): from another room of like shape 0.68 fitted. The weakest direction may be
/// four times weaker than a loop's: a corridor's end walls and doors fix the sweep along it (the
/// uniqueness restarts still refuse a door period's twin), and a wrong finding is caught by the
/// tracking that follows, where a wrong loop would bend the pose graph for good.
inline LoopCloser::Config relocalizationChecks() {
  LoopCloser::Config c;
  c.min_overlap = 0.75;
  c.min_translation_eigenvalue = 0.02;
  return c;
}

struct RelocalizerConfig {
  int descriptor_candidates = 10;        // best descriptor matches verified (each at two headings)
  double max_descriptor_distance = 0.3;  // Scan-Context distance (0..1) of a candidate at most
  double hint_radius_m = 5.0;            // with a hint: keyframes within this of it are candidates
  int submap_keyframes = 5;              // keyframes around a candidate merged into the target
  // The verified alignment with the largest overlap wins. Another one at least this far away (or
  // turned this far), explaining nearly as much of the sweep (overlap within the margin) and
  // fitting within the ratio, makes the answer ambiguous. The margin is several times the overlap's
  // spread between two sweeps of one place (about 0.01).
  double ambiguity_min_separation_m = 1.0;
  double ambiguity_min_turn_rad = 0.2;
  double ambiguity_overlap_margin = 0.03;
  double ambiguity_fitness_ratio = 1.5;
  LoopCloser::Config checks = relocalizationChecks();  // the verification's thresholds, the descriptor
};

struct Relocalization {
  bool localized = false;
  Eigen::Isometry3d T_map_body = Eigen::Isometry3d::Identity();
  int keyframe = -1;  // the session keyframe it was verified against
  double fitness_m = 0, overlap = 0;
  int candidates_tried = 0;
  std::string reason;  // why localized, or why not
};

class Relocalizer {
 public:
  /// Keeps a reference to the session (keyframe clouds and poses): it must outlive the Relocalizer.
  explicit Relocalizer(const Session& session, RelocalizerConfig cfg = RelocalizerConfig());

  /// cloud_body: the sweep's points in the body frame (as keyframe clouds are kept), e.g. voxel
  /// centroids at the session's cloud_voxel_m. `hint`: T_map_body roughly (within hint_radius_m and
  /// 30 deg), or none.
  Relocalization locate(const std::vector<Eigen::Vector3d>& cloud_body,
                        const std::optional<Eigen::Isometry3d>& hint = std::nullopt) const {
    return locate(cloud_body, cloud_body, hint);
  }
  /// The same, with the candidates found by the sweep's descriptor (`cloud_body`, as keyframes'
  /// descriptors are made) but verified with `verify_body`: the sweep and the ones before it, in
  /// its body frame. One sweep down a corridor does not fix where along it the rig is; the last few
  /// metres walked, with a door or a corner, can.
  Relocalization locate(const std::vector<Eigen::Vector3d>& cloud_body, const std::vector<Eigen::Vector3d>& verify_body,
                        const std::optional<Eigen::Isometry3d>& hint = std::nullopt) const;

 private:
  struct Candidate {
    int keyframe;
    Eigen::Isometry3d T_keyframe_body;  // the prior
  };
  AlignmentCheck verify(const std::vector<Eigen::Vector3d>& cloud_body, const Candidate& c) const;

  const Session& session_;
  RelocalizerConfig cfg_;
  std::vector<std::optional<ScanContext>> descriptors_;  // per keyframe with a cloud
};

}  // namespace mmlio::backend
