#include <gtest/gtest.h>

#include <functional>
#include <limits>

#include "mmlio/pipeline/report_html.hpp"
#include "mmlio/pipeline/run_report.hpp"

namespace mmlio::pipeline {
namespace {

RunReport sampleReport() {
  RunReport r;
  r.status = "degraded: input dropped";
  r.input.source = "office.bag";
  r.input.config = "config/hvi.yaml";
  r.input.mode = "hvi";
  r.input.duration_s = 43.025;
  r.input.imu_messages = 8606;
  r.input.imu_dropped.non_finite = 3;
  r.input.decoded["velodyne"].kept = 1200;
  r.imu_init.ok = true;
  r.imu_init.message = "|g|=9.802 m/s^2";
  r.sweeps.tracked = 420;
  r.features["livox"].sweeps = 2;
  r.features["livox"].edges = 30;
  r.timing.add({{"features", 1.5}, {"registration", 2.5}});
  r.wall_time_s = std::numeric_limits<double>::quiet_NaN();
  return r;
}

TEST(RunReport, JsonKeepsSectionOrderAndWritesNonFiniteAsNull) {
  const Json j = toJson(sampleReport());
  std::vector<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.push_back(k);
  ASSERT_GE(keys.size(), 4u);
  EXPECT_EQ(keys[0], "status");
  EXPECT_EQ(keys[1], "trustworthy");
  EXPECT_EQ(keys[2], "run");  // which mmlio, which settings: what reproduces the run
  EXPECT_EQ(keys[3], "input");
  EXPECT_EQ(j["run"]["schema_version"], 2);
  EXPECT_EQ(j["input"]["source"], "office.bag");
  EXPECT_EQ(j["input"]["imu_dropped"]["non_finite"], 3);
  EXPECT_EQ(j["features"]["livox"]["mean_edges"], 15.0);
  EXPECT_NE(j.dump().find("\"wall_time_s\":null"), std::string::npos);
}

TEST(RunReport, MarkdownSummarisesAndPointsToThePage) {
  RunReport r = sampleReport();
  r.untrusted = "drift sigma 0.48 m";
  eval::EvalResult e;
  e.ate_rmse_m = 0.0061;
  e.path_length_m = 42.0;
  r.evaluation = e;
  const std::string md = toMarkdown(r);
  EXPECT_NE(md.find("# mmlio run: office.bag"), std::string::npos);
  EXPECT_NE(md.find("**degraded: input dropped**, **untrusted**: drift sigma 0.48 m"), std::string::npos);
  EXPECT_NE(md.find("| ATE | 0.61 cm"), std::string::npos);
  EXPECT_NE(md.find("| sweeps | 420 tracked"), std::string::npos);
  EXPECT_NE(md.find("[report.html](report.html)"), std::string::npos);
}

TEST(RunReport, HtmlHoldsEveryFieldOfTheJson) {
  RunReport r = sampleReport();
  r.timeline.push_back({fromSec(1.0), 10.f, 200.f, 25.f, 3.f, true, false, true});
  r.timeline.push_back({fromSec(1.1), 12.f, 210.f, 80.f, 3.5f, false, false, false});
  Trajectory trajectory = {{fromSec(1.0), Eigen::Isometry3d::Identity()},
                           {fromSec(1.1), Eigen::Isometry3d(Eigen::Translation3d(1.0, 0.0, 0.0))}};
  std::vector<Point> map(3);
  map[1].xyz = Eigen::Vector3f(1.f, 2.f, 3.f);
  const std::string html = toHtml(r, trajectory, map, HtmlScripts{}, "office.bag");
  std::function<void(const Json&, const std::string&)> check = [&](const Json& node, const std::string& path) {
    for (const auto& [k, v] : node.items()) {
      if (v.is_object() && !v.empty()) {
        check(v, path + k + ".");
        continue;
      }
      EXPECT_NE(html.find(">" + k + "<"), std::string::npos) << path + k << " missing from report.html";
    }
  };
  check(toJson(r), "");
  EXPECT_NE(html.find("data-figure=\"path_m\""), std::string::npos);
  EXPECT_NE(html.find(">1.0 m<"), std::string::npos);  // the path length
  // Without three.js the page says how to get the 3D view and keeps the plots.
  EXPECT_NE(html.find("apt-get install libjs-three"), std::string::npos);
  EXPECT_NE(html.find("Features per sweep"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_NE(html.find("Content-Security-Policy"), std::string::npos);
}

TEST(RunReport, HtmlEmbedsTheMapForTheViewer) {
  RunReport r = sampleReport();
  Trajectory trajectory = {{fromSec(1.0), Eigen::Isometry3d(Eigen::Translation3d(100.0, 0.0, 0.0))}};
  std::vector<Point> map(10);
  for (int i = 0; i < 10; ++i) map[i].xyz = Eigen::Vector3f(100.f + i, 0.f, 0.f);
  HtmlReportLimits limits;
  limits.max_map_points = 4;  // every third point
  const std::string html = toHtml(r, trajectory, map, HtmlScripts{"/*three*/", "/*orbit*/"}, "x", limits);
  EXPECT_NE(html.find("\"points\":4,\"poses\":1,\"keyframes\":0,\"loops\":0,\"x_low\":0.000,\"x_high\":9.000"),
            std::string::npos);  // relative to the trajectory's start, thinned
  EXPECT_NE(html.find("<script>/*three*/</script>"), std::string::npos);
  EXPECT_NE(html.find("4 of 10 map points"), std::string::npos);
}

TEST(RunReport, Base64MatchesRfc4648) {
  const std::string text = "foobar";
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(text.data());
  EXPECT_EQ(base64(bytes, 0), "");
  EXPECT_EQ(base64(bytes, 1), "Zg==");
  EXPECT_EQ(base64(bytes, 2), "Zm8=");
  EXPECT_EQ(base64(bytes, 3), "Zm9v");
  EXPECT_EQ(base64(bytes, 6), "Zm9vYmFy");
}

TEST(RunReport, MappingStatesLoopClosureAndABackEndFailure) {
  RunReport r = sampleReport();
  r.mapping.enabled = true;
  r.mapping.keyframes = 43;
  r.mapping.attempts = 11;
  r.mapping.accepted = 1;
  r.mapping.candidates_rejected = 2;
  r.mapping.loops.push_back({40.5, 1.25, 0.031, 0.82});
  Json j = toJson(r);
  const Json& m = j["mapping"];
  EXPECT_EQ(m["enabled"], true);
  EXPECT_EQ(m["keyframes"], 43);
  EXPECT_EQ(m["loop_attempts"], 11);
  EXPECT_EQ(m["loops_accepted"], 1);
  EXPECT_EQ(m["candidates_rejected"], 2);
  ASSERT_EQ(m["loops"].size(), 1u);
  EXPECT_EQ(m["loops"][0]["query_s"], 40.5);
  EXPECT_EQ(m["loops"][0]["match_s"], 1.25);
  EXPECT_EQ(m["loops"][0]["fitness_m"], 0.031);
  EXPECT_EQ(m["loops"][0]["overlap"], 0.82);
  EXPECT_FALSE(m.contains("error"));
  r.mapping_error = "out of memory";
  j = toJson(r);
  EXPECT_EQ(j["mapping"]["error"], "out of memory");
  EXPECT_NE(toMarkdown(r).find("out of memory"), std::string::npos);
}

// The status names each cause of a degraded input, with its count and where to look, and none
// that did not happen (an IMU driver that restarted and a node behind its sensors, here).
TEST(RunReport, InputStatusNamesEachCauseItHas) {
  RunReport r;
  EXPECT_EQ(r.inputStatus(), "complete");
  r.input.imu_dropped.jumped = 1;
  r.input.imu_stream.missing = 1019;
  r.input.queue_dropped_scans = 3;
  const std::string status = r.inputStatus();
  EXPECT_EQ(status.rfind("degraded: ", 0), 0u) << status;
  EXPECT_NE(status.find("1 IMU samples dropped (input.imu_dropped), 1019 missing"), std::string::npos) << status;
  EXPECT_NE(status.find("3 messages dropped by the node's queue"), std::string::npos) << status;
  for (const char* absent : {"truncated", "damaged", "time base", "decode", "scans missing", "out of order"})
    EXPECT_EQ(status.find(absent), std::string::npos) << absent << ": " << status;
}

// An IMU that went silent for a while (its driver restarted) degrades the run without a sample
// dropped; one sample lost now and then does not.
TEST(RunReport, AnImuSilentForAWhileDegradesTheRunALoneLostSampleDoesNot) {
  RunReport r;
  r.input.imu_stream.period_s = 0.005;
  r.input.imu_stream.missing = 3;
  r.input.imu_stream.gaps = {{fromSec(1.0), 1}, {fromSec(7.0), 2}};
  EXPECT_EQ(r.inputStatus(), "complete");
  r.input.imu_stream.missing += 399;
  r.input.imu_stream.gaps.push_back({fromSec(22.0), 399});
  const std::string status = r.inputStatus();
  EXPECT_NE(status.find("degraded: 399 IMU samples missing in gaps"), std::string::npos) << status;
}

}  // namespace
}  // namespace mmlio::pipeline
