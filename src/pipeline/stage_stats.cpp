#include "mmlio/pipeline/stage_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mmlio::pipeline {
namespace {

constexpr double kFirstEdgeMs = 1e-3;  // bin 0 holds everything up to 1 us
constexpr double kGrowth = 1.01;       // each bin's upper edge 1 % above the previous one's
const double kLogGrowth = std::log(kGrowth);
const auto kBins = static_cast<std::size_t>(std::ceil(std::log(1e6 / kFirstEdgeMs) / kLogGrowth)) + 1;

std::size_t binOf(double ms) {
  if (!(ms > kFirstEdgeMs)) return 0;  // also NaN
  const double i = std::ceil(std::log(ms / kFirstEdgeMs) / kLogGrowth);
  return std::min(kBins - 1, static_cast<std::size_t>(i));
}

double upperEdgeMs(std::size_t bin) { return kFirstEdgeMs * std::pow(kGrowth, static_cast<double>(bin)); }

}  // namespace

void StageStats::Histogram::add(double ms) {
  if (bins.empty()) bins.assign(kBins, 0);
  ++bins[binOf(ms)];
  ++count;
  sum_ms += ms;
  max_ms = std::max(max_ms, ms);
}

double StageStats::Histogram::quantile(double q) const {
  if (count == 0) return 0.0;
  // Nearest rank: the smallest value with at least q of the samples at or below it.
  const auto rank = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(count))));
  std::size_t seen = 0;
  for (std::size_t i = 0; i < bins.size(); ++i) {
    seen += bins[i];
    if (seen >= rank) return std::min(max_ms, upperEdgeMs(i));
  }
  return max_ms;
}

void StageStats::add(const StageTimes& times) {
  double total = 0.0;
  bool has_total = false;
  for (const auto& [stage, ms] : times) {
    if (stage == "total")
      has_total = true;
    else
      total += ms;
    if (!stages_.count(stage) && stage != "total") order_.push_back(stage);
    stages_[stage].add(ms);
  }
  if (!has_total) stages_["total"].add(total);
  ++sweeps_;
}

const StageStats::Histogram* StageStats::find(const std::string& stage) const {
  const auto it = stages_.find(stage);
  return it == stages_.end() || it->second.count == 0 ? nullptr : &it->second;
}

double StageStats::meanMs(const std::string& stage) const {
  const Histogram* h = find(stage);
  return h ? h->sum_ms / static_cast<double>(h->count) : 0.0;
}

double StageStats::p95Ms(const std::string& stage) const {
  const Histogram* h = find(stage);
  return h ? h->quantile(0.95) : 0.0;
}

double StageStats::p99Ms(const std::string& stage) const {
  const Histogram* h = find(stage);
  return h ? h->quantile(0.99) : 0.0;
}

double StageStats::maxMs(const std::string& stage) const {
  const Histogram* h = find(stage);
  return h ? h->max_ms : 0.0;
}

std::vector<std::string> StageStats::stages() const {
  std::vector<std::string> out = order_;
  if (stages_.count("total")) out.emplace_back("total");
  return out;
}

Json StageStats::toJson() const {
  Json j = Json::object();
  for (const auto& stage : stages()) {
    Json s = Json::object();
    s["mean_ms"] = meanMs(stage);
    s["p95_ms"] = p95Ms(stage);
    s["p99_ms"] = p99Ms(stage);
    s["max_ms"] = maxMs(stage);
    s["samples"] = stages_.at(stage).count;
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
                  p95Ms(stage), p99Ms(stage), maxMs(stage), stages_.at(stage).count);
    out += line;
  }
  return out;
}

}  // namespace mmlio::pipeline
