#pragma once
// Degeneracy over a run, for the report and the progress line: how many registered sweeps left a
// direction to the IMU, which body axis was weak, when (spells of consecutive degenerate sweeps),
// and what each LiDAR constrained on its own.
#include <map>
#include <string>
#include <vector>

#include "mmlio/estimator/odometry.hpp"
#include "mmlio/pipeline/json.hpp"

namespace mmlio::pipeline {

class DegeneracyTally {
 public:
  /// min_points / remap: the odometry's odometry.degenerate_min_points and remap_degenerate.
  DegeneracyTally(double min_points, bool remap) : min_points_(min_points), remap_(remap) {}
  void add(const estimator::SweepResult& r);
  std::size_t degenerateSweeps() const { return degenerate_; }
  /// report.json "degeneracy"; times in s since begin_ns.
  Json toJson(Stamp begin_ns) const;

 private:
  struct Spell {
    Stamp start_ns = 0, end_ns = 0;
    std::size_t sweeps = 0;
    std::map<std::string, std::size_t> axes;
    double max_drift_sigma_m = 0.0;
  };
  struct PerLidar {
    std::size_t judged = 0, degenerate_alone = 0;
    std::vector<double> points;
  };
  double min_points_;
  bool remap_;
  std::size_t registered_ = 0, degenerate_ = 0, translation_ = 0, rotation_ = 0, remapped_ = 0;
  std::map<std::string, std::size_t> weak_axis_;
  std::vector<double> weakest_points_;
  std::vector<Spell> spells_;
  double max_drift_sigma_m_ = 0.0;
  Stamp max_drift_at_ns_ = 0;
  bool in_spell_ = false, recording_ = false;
  std::map<std::string, PerLidar> lidars_;
};

}  // namespace mmlio::pipeline
