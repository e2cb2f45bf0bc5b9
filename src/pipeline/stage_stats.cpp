#include "mmlio/pipeline/stage_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace mmlio::pipeline {
namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  // Nearest-rank: the smallest value with at least q of the samples at or below it.
  const std::size_t rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace

void StageStats::add(const StageTimes& times) {
  double total = 0.0;
  bool has_total = false;
  for (const auto& [stage, ms] : times) {
    if (stage == "total")
      has_total = true;
    else
      total += ms;
    if (!samples_.count(stage) && stage != "total") order_.push_back(stage);
    samples_[stage].push_back(ms);
  }
  if (!has_total) samples_["total"].push_back(total);
  ++sweeps_;
}

double StageStats::meanMs(const std::string& stage) const {
  const auto it = samples_.find(stage);
  if (it == samples_.end() || it->second.empty()) return 0.0;
  return std::accumulate(it->second.begin(), it->second.end(), 0.0) / it->second.size();
}

double StageStats::p95Ms(const std::string& stage) const {
  const auto it = samples_.find(stage);
  return it == samples_.end() ? 0.0 : percentile(it->second, 0.95);
}

double StageStats::p99Ms(const std::string& stage) const {
  const auto it = samples_.find(stage);
  return it == samples_.end() ? 0.0 : percentile(it->second, 0.99);
}

double StageStats::maxMs(const std::string& stage) const {
  const auto it = samples_.find(stage);
  return it == samples_.end() || it->second.empty() ? 0.0 : *std::max_element(it->second.begin(), it->second.end());
}

std::vector<std::string> StageStats::stages() const {
  std::vector<std::string> out = order_;
  if (samples_.count("total")) out.emplace_back("total");
  return out;
}

Json StageStats::toJson() const {
  Json j = Json::object();
  for (const auto& stage : stages()) {
    const auto& v = samples_.at(stage);
    Json s = Json::object();
    s["mean_ms"] = meanMs(stage);
    s["p95_ms"] = p95Ms(stage);
    s["p99_ms"] = p99Ms(stage);
    s["max_ms"] = maxMs(stage);
    s["samples"] = v.size();
    j[stage] = s;
  }
  return j;
}

std::string StageStats::table() const {
  std::string out;
  char line[160];
  std::snprintf(line, sizeof(line), "%-16s %9s %9s %9s %9s %8s\n", "stage", "mean ms", "p95 ms", "p99 ms", "max ms",
                "sweeps");
  out += line;
  for (const auto& stage : stages()) {
    std::snprintf(line, sizeof(line), "%-16s %9.2f %9.2f %9.2f %9.2f %8zu\n", stage.c_str(), meanMs(stage),
                  p95Ms(stage), p99Ms(stage), maxMs(stage), samples_.at(stage).size());
    out += line;
  }
  return out;
}

}  // namespace mmlio::pipeline
