#pragma once
// The built-in scenarios: a box scene and a walk through it that starts and ends at rest at the
// same pose. Sizes (x by y by height):
//   office   12 x 3.7 x 2.8 m: desks, cabinets, a thin TV, a door recess; two fast U-turns.
//   corridor 60 x 2.4 x 2.8 m: door recesses at irregular spacing, a 6 m wide end area for the U-turn.
//   corridor_blind  the corridor from a blind start: 0.6 m in front of the start wall, swaying
//            +-15 deg for ~4 s, then the corridor walk, ending in the same dead end.
//   hall     127 x 35 x 8 m with 4 rows of pillars, entered through a 3 m wide, 12 m long passage;
//            the walk starts and ends 1.5 m in front of the passage's end wall (the solid-state
//            LiDAR sees only that wall there).

#include <string>
#include <vector>

#include "mmlio/sim/motion.hpp"
#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

struct Scenario {
  std::string name;
  std::vector<Box> boxes;
  std::vector<Waypoint> waypoints;  // first == last (up to whole turns of yaw)
  WalkConfig walk;
};

/// "office", "corridor", "corridor_blind", "hall".
std::vector<std::string> scenarioNames();
/// Throws mmlio::Error naming the valid scenarios for an unknown name.
Scenario makeScenario(const std::string& name);

}  // namespace mmlio::sim
