// Odometry stage: scan-to-map registration of a sweep (with an IMU factor to the previous sweep,
// or from several starts across a gap in the data), solid-state frames judged by what their
// matches constrain, degenerate directions kept at the IMU prediction.
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

#include "mmlio/core/so3.hpp"
#include "mmlio/estimator/imu_factor.hpp"
#include "mmlio/estimator/pose_manifold.hpp"
#include "mmlio/estimator/prior_factor.hpp"
#include "odometry_impl.hpp"

namespace mmlio::estimator {
namespace {

constexpr double kGuessedVelocitySigma = 1.0;  // m/s: a velocity guessed across a gap (walking, driving slowly)
// Over a gap in all data the motion is not measured: the turn the rig was in may have stopped, gone
// on, sped up, or one may have begun. Registration starts from the last turn rate and velocity
// carried over the gap, scaled by each of kGapMotionScales, and from that extrapolation turned about
// the vertical in kGapYawStepRad steps as far as kMaxTurnRate could have turned the rig; the pose
// whose sweep fits the map best is kept.
constexpr double kGapMotionScales[] = {1.0, 0.5, 0.0};
constexpr double kGapYawStepRad = 10.0 * M_PI / 180.0;  // registration converges from about twice this
constexpr double kMaxTurnRate = 90.0 * M_PI / 180.0;    // rad/s: a walker, a robot turning on the spot
constexpr double kFitInlierM = 0.1;  // fit score: matches closer than this count, the closer the more

void dropSources(const std::vector<char>& rejected, std::vector<Eigen::Vector3d>* pts, std::vector<std::uint8_t>* src) {
  if (src->size() != pts->size()) return;
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts->size(); ++i)
    if (!rejected[(*src)[i]]) {
      (*pts)[k] = (*pts)[i];
      (*src)[k++] = (*src)[i];
    }
  pts->resize(k);
  src->resize(k);
}

}  // namespace

// ---- the stage: registration of a budget of the features, if one is set (the window and the map take all) ----
NavState Odometry::Impl::registration(const Features& features, const Prediction& p, Stamp sweep_end_ns, bool* tracked,
                                      SweepResult* out) {
  const bool budgeted = cfg.registration_max_edges > 0 || cfg.registration_max_planes > 0;
  Features thinned;
  if (budgeted) thinned = thinToBudget(features, registrationBudget());
  const Features& matched = budgeted ? thinned : features;
  NavState state = p.predicted;
  *tracked = true;
  rejected_sources = edge_poor;  // unless registration judges them by their information
  drift.predict(toSec(sweep_end_ns - p.prev.stamp_ns), cfg.degeneracy.drift_m_s2);
  if (plane_map.empty()) return state;
  out->correspondences = p.imu_ok
                             ? registerSweep(matched, p.pre, p.prev, p.prev_velocity_guessed, &state, out)
                             : registerAcrossGap(matched, p.prev, p.prev_velocity_guessed, p.unobserved_s, &state, out);
  if (out->registered && out->correspondences >= kMinCorrespondences) drift.update(out->degeneracy, cfg.lidar_sigma_m);
  out->drift_sigma_m = drift.largestSigmaM();
  if (out->correspondences < kMinCorrespondences) {
    *tracked = false;
    state = p.predicted;
    out->note = "only " + std::to_string(out->correspondences) + " map correspondences: IMU prediction kept";
  } else if (!p.imu_ok && sweep_end_ns > p.prev.stamp_ns) {
    state.v_world = (state.p_world - p.prev.p_world) / toSec(sweep_end_ns - p.prev.stamp_ns);  // what the LiDARs moved
  }
  return state;
}

// Scan-to-map registration of one sweep with an IMU factor to the previous one.
std::size_t Odometry::Impl::registerSweep(const Features& f, const std::shared_ptr<imu::Preintegration>& pre,
                                          const NavState& prev, bool prev_velocity_guessed, NavState* state,
                                          SweepResult* out) {
  const NavState predicted = *state;
  std::vector<MapMatch> matches;
  std::vector<char> rejected(lidars.size(), 0);  // solid-state frames judged bad by their information
  StateBlocks xi = toBlocks(prev), xj = toBlocks(*state);
  double prev_sb[9];
  std::copy(xi.speed_bias, xi.speed_bias + 9, prev_sb);
  std::size_t used = 0;
  const auto solve = [&](const std::vector<MapMatch>& with, int iterations) {
    ceres::Problem::Options po;
    po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    PoseManifold manifold;
    problem.AddParameterBlock(xj.pose, 7, &manifold);
    if (pre) {
      problem.AddParameterBlock(xi.pose, 7, &manifold);
      problem.AddParameterBlock(xi.speed_bias, 9);
      problem.AddParameterBlock(xj.speed_bias, 9);
      problem.SetParameterBlockConstant(xi.pose);
      // The previous velocity may move a little, so a position correction also corrects it. After
      // sweeps without IMU it was only guessed (LiDAR displacement across the gap): held to it, the
      // stiff IMU factor would carry its error on, the LiDARs correcting only the slack.
      const double sigma_v = prev_velocity_guessed ? kGuessedVelocitySigma : cfg.prior_sigma_v_m_s;
      problem.AddResidualBlock(new SpeedBiasPrior(prev_sb, sigma_v, cfg.prior_sigma_ba, cfg.prior_sigma_bg), nullptr,
                               xi.speed_bias);
      problem.AddResidualBlock(new ImuFactor(pre, g_world), nullptr, xi.pose, xi.speed_bias, xj.pose, xj.speed_bias);
    }
    addMapResiduals(problem, xj.pose, with, cfg.lidar_sigma_m, cfg.huber_loss_m);
    ceres::Solver::Summary summary;
    ceres::Solve(odometrySolverOptions(iterations), &problem, &summary);
  };
  // The first round starts from the prediction and takes every match: the prediction may be off
  // by more than the gate (a velocity carried over a gap). What the last round solves with lies
  // within the gate of the pose the rounds before it found.
  const double gate = matchGate(pre != nullptr, prev_velocity_guessed);
  const int rounds = std::max(1, cfg.match_rounds);
  const int iterations = std::max(2, cfg.max_iterations / rounds);
  bool gate_applied = !std::isfinite(gate);
  for (int round = 0; round < rounds; ++round) {
    const Eigen::Isometry3d T_before = poseOf(xj.pose);
    MapMatchConfig matching;
    if (round > 0) matching.max_residual_m = gate;
    gate_applied = gate_applied || round > 0;
    matches = findMapMatches(f, T_before, edge_map, plane_map, matching);
    if (round == 0) judgeLidars(matches, T_before, &rejected, out);
    matches.erase(std::remove_if(matches.begin(), matches.end(), [&](const MapMatch& m) { return rejected[m.source]; }),
                  matches.end());
    used = matches.size();
    if (used < kMinCorrespondences) return used;
    solve(matches, iterations);
    // Associations are redone to follow the pose; a pose that barely moved would find the same ones.
    if (!reassociationFor(cfg).needed(T_before, poseOf(xj.pose))) break;
  }
  if (!gate_applied) {
    // The same associations, less those beyond the gate at the pose found.
    const Eigen::Isometry3d T = poseOf(xj.pose);
    const std::size_t found = matches.size();
    matches.erase(
        std::remove_if(matches.begin(), matches.end(), [&](const MapMatch& m) { return matchDistance(m, T) > gate; }),
        matches.end());
    used = matches.size();
    if (used < kMinCorrespondences) return used;
    if (used < found) solve(matches, iterations);
  }
  *state = fromBlocks(xj, state->stamp_ns);
  // What did the LiDARs constrain? Along what they could not, nearest-neighbour associations only
  // drag the pose: keep the IMU prediction there.
  const Eigen::Matrix3d prediction_covariance = drift.positionCovariance();
  out->degeneracy = analyseDegeneracy(matchInformation(matches, state->pose(), cfg.huber_loss_m), cfg.degeneracy,
                                      &prediction_covariance, cfg.lidar_sigma_m);
  out->registered = true;
  rejected_sources = rejected;
  if (cfg.remap_degenerate && out->degeneracy.any())
    out->remapped_directions =
        remapDegenerateDirections(out->degeneracy, cfg.degeneracy, predicted.p_world, predicted.q_world_body,
                                  predicted.v_world, &state->p_world, &state->q_world_body, &state->v_world);
  return used;
}

// LiDAR-only registration across a gap in the data:
// `unobserved_s` of the motion since `prev` were extrapolated (last turn rate and velocity) into
// *state. A single start converges to a wrong minimum once that guess is off by more than about
// 10 deg (office, a U-turn ending during 0.3 s of lost data: 52 cm ATE), so registration is
// started from several guesses (see kGapMotionScales) and the best-fitting result is kept.
std::size_t Odometry::Impl::registerAcrossGap(const Features& f, const NavState& prev, bool prev_velocity_guessed,
                                              double unobserved_s, NavState* state, SweepResult* out) {
  const Eigen::Vector3d carried = omega_body * unobserved_s;
  const int yaw_steps = static_cast<int>(kMaxTurnRate * unobserved_s / kGapYawStepRad);
  if (yaw_steps == 0 && carried.norm() < 0.5 * kGapYawStepRad)
    return registerSweep(f, nullptr, prev, prev_velocity_guessed, state, out);
  const NavState predicted = *state;
  // The predicted rotation with the gap's part taken out: what the IMU or the sweep itself adds.
  const Eigen::Quaterniond after_gap = (prev.q_world_body * so3::exp(carried)).inverse() * predicted.q_world_body;
  struct Trial {
    NavState state;
    SweepResult out;
    std::vector<char> rejected;
    std::size_t used = 0;
    double score = -1.0;
  };
  Trial best;
  const auto tryStart = [&](double scale, double yaw_rad) {
    Trial t{predicted, *out, {}, 0, -1.0};
    const Eigen::Quaterniond yaw(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
    t.state.q_world_body = (yaw * prev.q_world_body * so3::exp(carried * scale) * after_gap).normalized();
    t.state.p_world = prev.p_world + (predicted.p_world - prev.p_world) * scale;
    t.state.v_world = prev.v_world * scale;
    t.used = registerSweep(f, nullptr, prev, prev_velocity_guessed, &t.state, &t.out);
    t.rejected = rejected_sources;
    if (t.used >= kMinCorrespondences) t.score = fitScore(f, t.state.pose());
    if (t.score > best.score) best = std::move(t);
  };
  for (double scale : kGapMotionScales) tryStart(scale, 0.0);
  for (int k = 1; k <= yaw_steps; ++k) {
    tryStart(1.0, k * kGapYawStepRad);
    tryStart(1.0, -k * kGapYawStepRad);
  }
  if (best.score < 0) return registerSweep(f, nullptr, prev, prev_velocity_guessed, state, out);
  *state = best.state;
  *out = std::move(best.out);
  rejected_sources = std::move(best.rejected);
  return best.used;
}

/// How well the sweep's features fit the local map at T: each match within kFitInlierM adds
/// 1 - (distance / kFitInlierM)^2.
double Odometry::Impl::fitScore(const Features& f, const Eigen::Isometry3d& T) const {
  double score = 0.0;
  for (const MapMatch& m : findMapMatches(f, T, edge_map, plane_map)) {
    const double r = matchDistance(m, T) / kFitInlierM;
    if (r < 1.0) score += 1.0 - r * r;
  }
  return score;
}

// Per LiDAR: what its own matches constrain at the predicted pose. A solid-state frame the edge
// count marks bad (edge_poor) whose matches also leave a translation direction unobserved (a
// wall filling its view, nothing in range) is a bad frame: its points leave the sweep, unless
// no other LiDAR has matches. Then it is all the sweep has: rejected, the sweep would ride on
// the IMU in every direction; kept, only along what it leaves unobserved (degeneracy remapping).
void Odometry::Impl::judgeLidars(const std::vector<MapMatch>& matches, const Eigen::Isometry3d& T,
                                 std::vector<char>* rejected, SweepResult* out) const {
  for (LidarFrameStats& st : out->lidars) {
    const std::size_t s = indexOf(st.sensor);
    const Degeneracy d =
        analyseDegeneracy(matchInformation(matches, T, cfg.huber_loss_m, static_cast<int>(s)), cfg.degeneracy);
    st.translation_points = d.translation_points;
    (*rejected)[s] = edge_poor[s] && d.translation_degenerate;
  }
  const bool others_matched =
      std::any_of(matches.begin(), matches.end(), [&](const MapMatch& m) { return !(*rejected)[m.source]; });
  if (!others_matched) std::fill(rejected->begin(), rejected->end(), 0);
  for (LidarFrameStats& st : out->lidars) {
    const std::size_t s = indexOf(st.sensor);
    if (edge_poor[s]) st.bad_frame = (*rejected)[s] != 0;  // the others' verdicts were final
  }
}

FeatureBudget Odometry::Impl::registrationBudget() const {
  const auto count = [](int n) { return static_cast<std::size_t>(std::max(0, n)); };
  return {count(cfg.registration_max_edges), count(cfg.registration_max_planes), cfg.edge_voxel_m, cfg.plane_voxel_m};
}

/// Bad frames found during registration leave the sweep's features (window and map) and its
/// view of free space: the estimate goes on as without that LiDAR.
void Odometry::Impl::dropRejected(Features* f) const {
  if (std::none_of(rejected_sources.begin(), rejected_sources.end(), [](char c) { return c != 0; })) return;
  dropSources(rejected_sources, &f->edges, &f->edge_source);
  dropSources(rejected_sources, &f->planes, &f->plane_source);
  if (view)
    view->sensors.erase(std::remove_if(view->sensors.begin(), view->sensors.end(),
                                       [&](const SensorView& s) { return rejected_sources[s.source] != 0; }),
                        view->sensors.end());
}

}  // namespace mmlio::estimator
