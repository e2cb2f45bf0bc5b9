#include <gtest/gtest.h>

#include <functional>
#include <limits>

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
  EXPECT_EQ(j["run"]["schema_version"], 1);
  EXPECT_EQ(j["input"]["source"], "office.bag");
  EXPECT_EQ(j["input"]["imu_dropped"]["non_finite"], 3);
  EXPECT_EQ(j["features"]["livox"]["mean_edges"], 15.0);
  EXPECT_NE(j.dump().find("\"wall_time_s\":null"), std::string::npos);
}

TEST(RunReport, MarkdownShowsEveryFieldWithItsValue) {
  const RunReport r = sampleReport();
  const Json j = toJson(r);
  const std::string md = toMarkdown(r);
  // Every leaf of report.json appears in report.md under its own name, with a non-empty value.
  std::function<void(const Json&, const std::string&)> check = [&](const Json& node, const std::string& path) {
    for (const auto& [k, v] : node.items()) {
      if (v.is_object() && !v.empty()) {
        check(v, path + k + ".");
        continue;
      }
      if (k == "figures") continue;      // pictures, shown as images
      if (k == "config_yaml") continue;  // a file of its own, config_used.yaml, named in the run section
      const std::size_t at = md.find(k);
      ASSERT_NE(at, std::string::npos) << path + k << " missing from report.md";
    }
  };
  check(j, "");
  EXPECT_NE(md.find("| source | office.bag |"), std::string::npos);
  EXPECT_NE(md.find("| config | config/hvi.yaml |"), std::string::npos);
  EXPECT_NE(md.find("| mode | hvi |"), std::string::npos);
  EXPECT_NE(md.find("| config | config_used.yaml |"), std::string::npos);
  EXPECT_NE(md.find("| duration_s | 43.025 |"), std::string::npos);
  // A '|' in a value must not split the table row.
  EXPECT_NE(md.find("| message | \\|g\\|=9.802 m/s^2 |"), std::string::npos);
  // Per-LiDAR figures: one row per LiDAR, one column per figure.
  EXPECT_NE(md.find("| livox | 2 | 0 | 15 | 0 | 0 |"), std::string::npos);
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

}  // namespace
}  // namespace mmlio::pipeline
