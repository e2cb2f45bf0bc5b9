#pragma once
// report.html: one self-contained page per run that opens offline. First the answer (status,
// trust, ATE, loops, what was degenerate or dropped), then an interactive 3D view of the map with
// the trajectory, keyframes and loop edges (three.js, inlined), the plots as SVG, and every field
// of report.json collapsed below. A Content-Security-Policy forbids any request outside the file.
#include <iosfwd>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"
#include "mmlio/pipeline/run_report.hpp"

namespace mmlio::pipeline {

/// The JavaScript the 3D view runs on: Debian's libjs-three (three.min.js and OrbitControls.js),
/// read at report time. Empty: the page says how to get the 3D view and keeps everything else.
struct HtmlScripts {
  std::string three, orbit_controls;
  bool available() const { return !three.empty() && !orbit_controls.empty(); }
};

struct HtmlReportLimits {
  std::size_t max_map_points = 600000;  // the map is thinned evenly to this many points (~8 MB)
  double slice_half_height_m = 0.8;     // the top view's map slice around the trajectory's height
};

/// The page, written to `os` as it is made. `title` names the run (the bag's file name).
void writeHtml(std::ostream& os, const RunReport& report, const Trajectory& trajectory,
               const std::vector<Point>& map_world, const HtmlScripts& scripts, const std::string& title,
               const HtmlReportLimits& limits = {});
/// The same as one string (tests).
std::string toHtml(const RunReport& report, const Trajectory& trajectory, const std::vector<Point>& map_world,
                   const HtmlScripts& scripts, const std::string& title, const HtmlReportLimits& limits = {});

/// Standard base64 (RFC 4648) of raw bytes.
std::string base64(const std::uint8_t* data, std::size_t size);

}  // namespace mmlio::pipeline
