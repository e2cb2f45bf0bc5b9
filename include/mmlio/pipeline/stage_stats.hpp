#pragma once
// Per-stage timing statistics over a run: mean, 95th and 99th percentile and maximum ms per sweep.
// A run of any length keeps the same few kilobytes: percentiles come from bins 1 % wide.
#include <cstdint>
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
  /// Nearest-rank percentiles, to within 1 % (the upper edge of the sample's bin, at most the maximum).
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
  /// One stage's times: count, sum and maximum exact, the distribution in bins whose edges grow
  /// by 1 % from 1 us to 1000 s.
  struct Histogram {
    std::size_t count = 0;
    double sum_ms = 0.0, max_ms = 0.0;
    std::vector<std::uint32_t> bins;  // allocated by the first sample
    void add(double ms);
    double quantile(double q) const;
  };
  const Histogram* find(const std::string& stage) const;

  std::vector<std::string> order_;
  std::map<std::string, Histogram> stages_;
  std::size_t sweeps_ = 0;
};

}  // namespace mmlio::pipeline
