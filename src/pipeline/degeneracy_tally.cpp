#include "mmlio/pipeline/degeneracy_tally.hpp"

#include <algorithm>

namespace mmlio::pipeline {
namespace {

constexpr std::size_t kMaxSpells = 50;  // the report lists the first spells; the counts cover all

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

void DegeneracyTally::add(const estimator::SweepResult& r) {
  for (const auto& l : r.lidars) {
    if (l.translation_points < 0) continue;
    PerLidar& p = lidars_[l.sensor];
    ++p.judged;
    p.points.push_back(l.translation_points);
    // The same threshold as the sweep's: this LiDAR alone would have left a direction unobserved.
    if (l.translation_points < min_points_) ++p.degenerate_alone;
  }
  if (r.status != estimator::SweepResult::Status::kInitializing && r.drift_sigma_m > max_drift_sigma_m_) {
    max_drift_sigma_m_ = r.drift_sigma_m;
    max_drift_at_ns_ = r.state.stamp_ns;
  }
  if (!r.registered) {
    in_spell_ = false;
    return;
  }
  ++registered_;
  weakest_points_.push_back(r.degeneracy.translation_points);
  if (!r.degeneracy.any()) {
    in_spell_ = false;
    return;
  }
  ++degenerate_;
  translation_ += r.degeneracy.translation_degenerate ? 1 : 0;
  rotation_ += r.degeneracy.rotation_degenerate ? 1 : 0;
  remapped_ += r.remapped_directions > 0 ? 1 : 0;
  const Eigen::Vector3d weak_body = r.state.q_world_body.conjugate() * r.degeneracy.weak_translation;
  const std::string axis = r.degeneracy.translation_degenerate ? estimator::bodyAxisName(weak_body) : "rotation";
  ++weak_axis_[axis];
  if (!in_spell_) {
    in_spell_ = true;
    recording_ = spells_.size() < kMaxSpells;
    if (recording_) spells_.push_back({r.state.stamp_ns, r.state.stamp_ns, 0, {}});
  }
  if (recording_) {
    Spell& s = spells_.back();
    s.end_ns = r.state.stamp_ns;
    ++s.sweeps;
    ++s.axes[axis];
    s.max_drift_sigma_m = std::max(s.max_drift_sigma_m, r.drift_sigma_m);
  }
}

Json DegeneracyTally::toJson(Stamp begin_ns) const {
  Json j = Json::object();
  j["min_points"] = min_points_;
  j["remap_to_imu"] = remap_;
  j["registered_sweeps"] = registered_;
  j["degenerate_sweeps"] = degenerate_;
  j["translation_degenerate"] = translation_;
  j["rotation_degenerate"] = rotation_;
  j["remapped_sweeps"] = remapped_;
  Json axes = Json::object();
  for (const auto& [name, n] : weak_axis_) axes[name] = n;
  j["weak_direction"] = axes;
  j["median_weakest_translation_points"] = median(weakest_points_);
  j["max_drift_sigma_m"] = max_drift_sigma_m_;
  j["max_drift_at_s"] = max_drift_at_ns_ > 0 ? toSec(max_drift_at_ns_ - begin_ns) : 0.0;
  Json spells = Json::array();
  for (const Spell& s : spells_) {
    Json e = Json::object();
    e["start_s"] = toSec(s.start_ns - begin_ns);
    e["end_s"] = toSec(s.end_ns - begin_ns);
    e["sweeps"] = s.sweeps;
    std::string axis;
    std::size_t most = 0;
    for (const auto& [name, n] : s.axes)
      if (n > most) most = n, axis = name;
    e["weak_direction"] = axis;
    e["max_drift_sigma_m"] = s.max_drift_sigma_m;
    spells.push_back(e);
  }
  j["spells"] = spells;
  Json per = Json::object();
  for (const auto& [name, p] : lidars_) {
    Json l = Json::object();
    l["judged_sweeps"] = p.judged;
    l["degenerate_alone"] = p.degenerate_alone;
    l["median_weakest_translation_points"] = median(p.points);
    per[name] = l;
  }
  j["lidars"] = per;
  return j;
}

}  // namespace mmlio::pipeline
