#pragma once
// What loop closure did in a run: the mapping back end's figures, as the run report states them.
#include <cstddef>
#include <vector>

namespace mmlio::backend {

/// A loop closed into the pose graph; times in seconds since the first keyframe.
struct ClosedLoop {
  double query_s = 0.0, match_s = 0.0;
  double fitness_m = 0.0;  // the verification's mean |point-to-plane residual|
  double overlap = 0.0;    // fraction of the query keyframe's points near the matched submap
};

struct LoopFigures {
  bool enabled = false;
  std::size_t keyframes = 0, attempts = 0, accepted = 0;
  std::size_t candidates_rejected = 0;  // by the verification or as an implausible correction
  std::vector<ClosedLoop> loops;
};

}  // namespace mmlio::backend
