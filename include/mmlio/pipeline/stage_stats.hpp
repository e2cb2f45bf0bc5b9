#pragma once
// Per-stage timing statistics over a run: mean, 95th and 99th percentile and maximum ms per sweep.
#include <map>
#include <string>
#include <vector>

#include "mmlio/core/timer.hpp"
#include "mmlio/pipeline/json.hpp"

namespace mmlio::pipeline {

class StageStats {
 public:
  /// Adds one sweep's stage times; a "total" entry is the sum unless `times` already has one.
  void add(const StageTimes& times);
  std::size_t sweeps() const { return sweeps_; }
  double meanMs(const std::string& stage) const;
  double p95Ms(const std::string& stage) const;
  double p99Ms(const std::string& stage) const;
  double maxMs(const std::string& stage) const;
  /// Stage names in first-seen order ("total" last).
  std::vector<std::string> stages() const;
  /// {stage: {mean_ms, p95_ms, p99_ms, max_ms, samples}} for the run report.
  Json toJson() const;
  /// Aligned text table for the terminal.
  std::string table() const;

 private:
  std::vector<std::string> order_;
  std::map<std::string, std::vector<double>> samples_;
  std::size_t sweeps_ = 0;
};

}  // namespace mmlio::pipeline
