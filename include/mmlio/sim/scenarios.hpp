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
//   stairs   two storeys 3 m apart (20 x 6.4 m each, a corridor and a room off it, the same plan,
//            different furniture), a switch-back staircase (0.167 m risers, 0.28 m treads, a
//            landing); carried by hand up, through the upper floor, down and back.
//   ramp     30 x 8 x 4.5 m with a 12 m ramp (1:12) up to a 1 m platform, driven like a robot that
//            pitches with the slope: up, round on the platform, down and home.
//   lab      14.5 x 7.2 x 3 m, benches, shelves, pillars; driven along a real platform's recorded
//            6-DoF motion (TIERS dataset, indoor08: 90 s, 52 m, back and forth), not a planned walk.

#include <string>
#include <vector>

#include "mmlio/sim/motion.hpp"
#include "mmlio/sim/scene.hpp"

namespace mmlio::sim {

struct Scenario {
  std::string name;
  std::vector<Box> boxes;
  std::vector<Waypoint> waypoints;  // first == last (up to whole turns of yaw)
  std::vector<Keyframe> recorded;   // when set, the motion as recorded (waypoints then only trace it)
  WalkConfig walk;
};

/// "office", "corridor", "corridor_blind", "hall", "stairs", "ramp", "lab".
std::vector<std::string> scenarioNames();
/// Throws mmlio::Error naming the valid scenarios for an unknown name.
Scenario makeScenario(const std::string& name);

/// A walker's hand-held gait: ~3 cm bounce at 1.9 steps/s, 3 deg sway and nod, 2 deg yaw wobble,
/// turns up to 150 deg/s.
WalkConfig handheldWalk();
/// The same closed route walked from waypoint `first` on (0: as designed), e.g. a localization that
/// starts where the mapping walk did not. Throws mmlio::Error for a recorded motion (lab) or a
/// waypoint the route does not have.
Scenario startingAt(Scenario s, int first);
/// The scenario's route carried by hand: the hand-held gait at the route's speed, and deliberate
/// looks 25 deg down and 20 deg up between waypoints (a recorded motion gets the gait only).
Scenario carriedByHand(Scenario s);

}  // namespace mmlio::sim
