#include "mmlio/pipeline/report.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mmlio/core/log.hpp"
#include "mmlio/io/trajectory_writer.hpp"
#include "mmlio/pipeline/report_html.hpp"

namespace mmlio::pipeline {
namespace {

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

HtmlScripts loadHtmlScripts() {
  const char* env = std::getenv("MMLIO_JS_DIR");
  const std::filesystem::path dir = env && *env ? env : MMLIO_JS_DIR;
  HtmlScripts scripts;
  scripts.three = readText(dir / "three/three.min.js");
  scripts.orbit_controls = readText(dir / "three/examples/js/controls/OrbitControls.js");
  // MIT: the copies travel with their copyright notice (the minified build has none).
  const std::string notice =
      "/* three.js (Debian libjs-three), Copyright (c) 2010-2017 three.js authors, MIT licence */\n";
  if (!scripts.three.empty()) scripts.three = notice + scripts.three;
  if (!scripts.orbit_controls.empty()) scripts.orbit_controls = notice + scripts.orbit_controls;
  if (!scripts.available())
    log::warn("report.html without its 3D view: three.js not found in ", dir.string(),
              " (apt-get install libjs-three, or set MMLIO_JS_DIR)");
  return scripts;
}

void writeReports(const std::string& dir, RunReport& report, const Trajectory& trajectory,
                  const std::vector<Point>& map_world, const std::string& gt_path) {
  if (!gt_path.empty()) {
    try {
      eval::EvalOptions options;
      options.align = !report.localization.enabled;  // localized poses are in the map frame the truth is given in
      report.evaluation = eval::evaluate(io::readTum(gt_path), trajectory, options);
    } catch (const std::exception& e) {
      log::warn("no evaluation against ", gt_path, ": ", e.what());
    }
  }
  if (!report.run.config_yaml.empty())
    io::writeFileAtomically(dir + "config_used.yaml", [&](std::ostream& os) {
      os << "# The effective config of this run (mmlio " << report.run.mmlio_version << ", " << report.run.commit
         << "; extrinsics from " << report.run.calibration << "): mmlio run BAG --config config_used.yaml\n"
         << report.run.config_yaml;
    });
  io::writeFileAtomically(dir + "report.json", [&](std::ostream& os) { os << toJson(report).dump(2) << '\n'; });
  io::writeFileAtomically(dir + "report.md", [&](std::ostream& os) { os << toMarkdown(report); });
  const std::string title =
      report.input.source.empty() ? "run" : std::filesystem::path(report.input.source).filename().string();
  io::writeFileAtomically(dir + "report.html", [&](std::ostream& os) {
    writeHtml(os, report, trajectory, map_world, loadHtmlScripts(), title);
  });
}

}  // namespace mmlio::pipeline
