#pragma once
// Whether a verified loop's correction is one odometry can have drifted into. A place-descriptor
// match in a repetitive or symmetric scene (a corridor's far end looking like its start, a room
// matched turned half round) passes ICP's checks and would otherwise pull the graph by metres.
// The drift that can separate a loop's ends grows with the route between them through the graph,
// which loops already closed shorten: on a survey that keeps revisiting, the distance travelled
// since the match would soon allow any correction. Core code: no I/O.
#include "mmlio/backend/loop_closer.hpp"
#include "mmlio/backend/mapping_config.hpp"
#include "mmlio/backend/pose_graph.hpp"

namespace mmlio::backend {

struct LoopCorrection {
  double route_m = 0.0;                             // PoseGraph::routeLength between the loop's ends
  double correction_m = 0.0, correction_deg = 0.0;  // how far the loop moves / turns the estimate
  double allowed_m = 0.0, allowed_deg = 0.0;        // what odometry can have drifted over route_m
  bool plausible() const { return correction_m <= allowed_m && correction_deg <= allowed_deg; }
};

/// The correction loop `r` (match -> query) asks of `graph`'s current estimate, and its bounds.
LoopCorrection loopCorrection(const PoseGraph& graph, const LoopResult& r, const MappingConfig& cfg);

/// Whether a place descriptor's heading of query seen from match (the yaw of T_match_query, rad)
/// is within the rotation bound of loopCorrection of the estimate's, give or take slack_deg (how
/// far the descriptor's heading may be off). Asked before a descriptor candidate's ICP
/// verification, so a room matched turned half round costs no ICP. Compares headings only: a
/// hand-held or stair rig's tilt is not the descriptor's to judge.
bool plausibleHeading(const PoseGraph& graph, int match, int query, double yaw_rad, double slack_deg,
                      const MappingConfig& cfg);

}  // namespace mmlio::backend
