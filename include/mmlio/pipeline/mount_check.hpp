#pragma once
// What `mmlio run` found when it checked a rig file's spinning-LiDAR mount on the bag's still start
// (pipeline::checkMountAtStart), for the run's report.
#include <string>

namespace mmlio::pipeline {

/// Whether the spinning LiDAR's mount given in a rig file agrees with the solid-state LiDAR's view
/// at the bag's still start: GICP from it (no search), then the seen-through, overlap and fitness
/// tests of the calibration. A start that cannot tell (moving, a single wall, no overlap, a view
/// alike turned) leaves it unchecked.
struct MountCheck {
  std::string lidar;     // the spinning LiDAR ("" when the rig has no spinning and solid-state pair)
  bool checked = false;  // the start could tell
  bool agrees = true;
  double moved_m = 0;    // what GICP moved the given mount by, along the directions the start constrains
  double moved_deg = 0;  // ... and turned it by
  double seen_through = 0, overlap = 0;
  std::string message;
};
constexpr double kMountCheckMaxMoveM = 0.15;    // a given mount GICP moves further than this ...
constexpr double kMountCheckMaxTurnDeg = 10.0;  // ... or turns by more is grossly wrong
constexpr double kMountCheckConstrained = 0.2;  // a direction whose information is this fraction of the
                                                // strongest one's is constrained

}  // namespace mmlio::pipeline
