#include "mmlio/estimator/odometry.hpp"

#include <ceres/ceres.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <unordered_map>

#include "mmlio/core/flat_key_index.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/so3.hpp"
#include "mmlio/core/voxel_key.hpp"
#include "mmlio/estimator/feature_budget.hpp"
#include "mmlio/estimator/imu_factor.hpp"
#include "mmlio/estimator/lidar_factors.hpp"
#include "mmlio/estimator/sliding_window.hpp"
#include "mmlio/estimator/pose_manifold.hpp"
#include "mmlio/estimator/prior_factor.hpp"
#include "mmlio/imu/imu_integrator.hpp"
#include "mmlio/imu/preintegration.hpp"
#include "mmlio/lidar/deskew.hpp"
#include "mmlio/lidar/voxel_filter.hpp"
#include "mmlio/map/geometry_fit.hpp"
#include "mmlio/map/voxel_hash_map.hpp"

namespace mmlio::estimator {
namespace {

constexpr std::size_t kMinCorrespondences = 30;

/// The de-skew motion of a sweep: `start` propagated through the IMU `samples` to 11 times from
/// max(from, sweep start) to the sweep end, as poses relative to the end pose; the end state into
/// *end if given.
lidar::SweepMotion imuMotion(const NavState& start, const std::vector<ImuSample>& samples, Stamp from,
                             const lidar::AlignedSweep& sweep, const Eigen::Vector3d& g_world,
                             NavState* end = nullptr) {
  std::vector<Stamp> query;
  const int n = 10;
  for (int k = 0; k <= n; ++k)
    query.push_back(std::max(from, sweep.start_ns + (sweep.end_ns - sweep.start_ns) * k / n));
  const std::vector<NavState> states = imu::propagate(start, samples, query, g_world);
  const Eigen::Isometry3d T_end_inv = states.back().pose().inverse();
  std::vector<double> times;
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t k = 0; k < states.size(); ++k) {
    times.push_back(toSec(query[k] - sweep.start_ns));
    poses.push_back(T_end_inv * states[k].pose());
  }
  if (end) *end = states.back();
  return lidar::SweepMotion(times, poses);
}
constexpr Stamp kMaxImuGapNs = 50000000;       // 50 ms: ten samples of a 200 Hz IMU
constexpr double kGuessedVelocitySigma = 1.0;  // m/s: a velocity guessed across a gap (walking, driving slowly)
// Registration rounds and the window find matches again once a pose moved a tenth of the plane
// voxel or a tenth of a degree from where they were found.
Reassociation reassociationFor(const OdometryConfig& c) { return {0.1 * c.plane_voxel_m, 0.1 * M_PI / 180.0}; }

// Over a gap in all data the motion is not measured: the turn the rig was in may have stopped, gone
// on, sped up, or one may have begun. Registration starts from the last turn rate and velocity
// carried over the gap, scaled by each of kGapMotionScales, and from that extrapolation turned about
// the vertical in kGapYawStepRad steps as far as kMaxTurnRate could have turned the rig; the pose
// whose sweep fits the map best is kept.
constexpr double kGapMotionScales[] = {1.0, 0.5, 0.0};
constexpr double kGapYawStepRad = 10.0 * M_PI / 180.0;  // registration converges from about twice this
constexpr double kMaxTurnRate = 90.0 * M_PI / 180.0;    // rad/s: a walker, a robot turning on the spot
constexpr double kFitInlierM = 0.1;  // fit score: matches closer than this count, the closer the more
// Matched at a pose the IMU predicted from a tracked state (centimetres off), a point farther than
// this from its map plane or line is not on it: a neighbour of another surface (the next stair
// nosing, the far side of a slab). Huber's loss would still give each such match a constant pull,
// and where the LiDARs constrain a direction weakly (height on a staircase) a few of them drag the
// pose.
constexpr double kMaxMatchResidualM = 0.1;

void integrateSamples(imu::Preintegration& pre, const std::vector<ImuSample>& samples) { pre.integrate(samples); }

}  // namespace

struct Odometry::Impl {
  OdometryConfig cfg;
  std::vector<LidarSetup> lidars;
  Eigen::Vector3d g_world;

  std::deque<ImuSample> imu;
  imu::ImuInitializer initializer;
  imu::ImuInitResult init_result;
  bool initialized = false;

  NavState last;  // at the end of the last processed sweep
  map::VoxelHashMap edge_map, plane_map;
  SlidingWindow window;
  std::shared_ptr<imu::Preintegration> pre_since_keyframe;
  std::size_t keyframes = 0;
  std::vector<char> rejected_sources;  // of the last registration, by LiDAR index
  std::vector<char> edge_poor;         // this sweep's solid-state frames the edge count marks bad
  PredictionDrift drift;               // how far the IMU prediction may have drifted, per direction
  FreeSpaceMemory free_space;
  MoverWatch mover_watch;
  std::shared_ptr<SweepView> view;                       // this sweep's, while it is processed
  bool in_imu_gap = false;                               // the last sweep had no usable IMU
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();  // last sweep's turn rate, rad/s
  ceres::Manifold* pose_manifold = nullptr;              // owned by the problems (kept alive separately)

  Impl(OdometryConfig c, std::vector<LidarSetup> l)
      : cfg(std::move(c)),
        lidars(std::move(l)),
        g_world(0, 0, -cfg.gravity_m_s2),
        initializer(cfg.imu_init),
        // Hash cells 2.5x the map resolution: the 1 m kNN radius spans 2 rings instead of 5, which
        // matters where features are far and sparse (hall registration 231 -> 47 ms/sweep with the
        // same accuracy: ATE 1.37 -> 1.43 cm hall, 1.01 -> 1.00 cm office).
        edge_map(2.5 * cfg.map_voxel_m, 60),
        plane_map(2.5 * cfg.map_voxel_m, 60, cfg.voxel_planes),
        window(windowConfig(cfg), g_world),
        free_space(cfg.dynamic),
        mover_watch(cfg.dynamic) {}

  static SlidingWindowConfig windowConfig(const OdometryConfig& c) {
    SlidingWindowConfig w;
    w.size = c.window_size;
    w.max_iterations = c.max_iterations;
    w.lidar_sigma_m = c.lidar_sigma_m;
    w.huber_loss_m = c.huber_loss_m;
    w.reassociation = reassociationFor(c);
    return w;
  }

  std::vector<ImuSample> imuBuffer() const { return {imu.begin(), imu.end()}; }

  /// The residual gate of a pose predicted by the IMU from a tracked state; none otherwise.
  static double matchGate(bool imu_predicted, bool prev_velocity_guessed) {
    return imu_predicted && !prev_velocity_guessed ? kMaxMatchResidualM : std::numeric_limits<double>::infinity();
  }

  std::size_t indexOf(const std::string& name) const {
    for (std::size_t i = 0; i < lidars.size(); ++i)
      if (lidars[i].extrinsic.name == name) return i;
    return 0;
  }

  const LidarSetup* setupOf(const std::string& name) const {
    for (const auto& s : lidars)
      if (s.extrinsic.name == name) return &s;
    return nullptr;
  }

  bool usesSurfacePoints(const std::string& sensor) const {
    if (cfg.surface_points == SurfacePoints::kAll) return true;
    return cfg.surface_points == SurfacePoints::kSolidState &&
           setupOf(sensor)->extrinsic.kind == LidarKind::kSolidState;
  }

  // ---- stage: de-skew, features, bad frame, merge ----
  // The sweep's scans are moved into their de-skewed copies. with_view: also this sweep's view of
  // free space (a range image per LiDAR).
  Features extract(lidar::AlignedSweep& sweep, const lidar::SweepMotion& motion, bool with_view, SweepResult* out) {
    const double end_s = toSec(sweep.end_ns - sweep.start_ns);
    edge_poor.assign(lidars.size(), 0);
    std::vector<LidarScan*> scans;
    for (auto& scan : sweep.scans)
      if (setupOf(scan.sensor)) scans.push_back(&scan);
    std::vector<lidar::FeatureCloud> clouds(scans.size());
    std::vector<LidarScan> deskewed(scans.size());
    std::vector<LidarFrameStats> stats(scans.size());
    std::vector<char> surface_points(scans.size(), 0);  // every return is matched as a plane point
    std::vector<SensorView> views(with_view ? scans.size() : 0);
    tbb::parallel_for(std::size_t(0), scans.size(), [&](std::size_t i) {
      const LidarSetup& setup = *setupOf(scans[i]->sensor);
      deskewed[i] = std::move(*scans[i]);
      lidar::deskewToEnd(deskewed[i], setup.extrinsic.T_imu_sensor, motion, end_s);
      if (!views.empty()) {
        views[i].source = static_cast<std::uint8_t>(indexOf(setup.extrinsic.name));
        views[i].T_body_sensor = setup.extrinsic.T_imu_sensor;
        views[i].image = map::RangeImage(deskewed[i].points, cfg.dynamic.image);
      }
      // Where every return is a surface point, scan-line plane features would go unused.
      surface_points[i] = usesSurfacePoints(setup.extrinsic.name);
      lidar::FeatureConfig features = cfg.features;
      features.planes = !surface_points[i];
      clouds[i] = lidar::extractFeatures(deskewed[i], setup.extrinsic.kind, setup.num_rings, features);
      stats[i].sensor = setup.extrinsic.name;
      stats[i].points = deskewed[i].points.size();
      stats[i].edges = clouds[i].edges.size();
      stats[i].planes = surface_points[i] ? deskewed[i].points.size() : clouds[i].planes.size();
      if (setup.extrinsic.kind == LidarKind::kSolidState) {
        const lidar::BadFrameResult bad = lidar::checkSolidStateFrame(clouds[i], cfg.bad_frame);
        stats[i].bad_frame = bad.bad;
        stats[i].counted_edges = bad.counted_edges;
      }
    });

    // A frame kept for judgement is thinned on its own: should registration reject it, the other
    // LiDARs' features are then exactly those they have without it (a shared voxel would otherwise
    // carry its centroid, or go with it).
    std::vector<Point> edges, planes;
    std::vector<std::vector<Point>> judged_edges(lidars.size()), judged_planes(lidars.size());
    std::size_t n_edges = 0, n_planes = 0, n_points = 0;
    for (const LidarFrameStats& s : stats) {
      n_edges += s.edges;
      n_planes += s.planes;
      n_points += s.points;
    }
    edges.reserve(n_edges);
    planes.reserve(n_planes);
    if (cfg.keep_points) out->points_body.reserve(n_points);
    std::vector<char> dropped(scans.size(), 0);  // bad frames that leave the sweep before registration
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const Eigen::Isometry3f T = setupOf(deskewed[i].sensor)->extrinsic.T_imu_sensor.cast<float>();
      const auto source = static_cast<std::uint8_t>(indexOf(deskewed[i].sensor));
      auto toBody = [&T, source](const std::vector<Point>& pts, std::vector<Point>* dst) {
        for (Point p : pts) {
          p.xyz = T * p.xyz;
          p.source = source;
          dst->push_back(p);
        }
      };
      // Judged by information, an edge-poor frame stays in until registration has seen what it constrains.
      const bool keep_for_judgement = stats[i].bad_frame && cfg.bad_frame.by_information;
      if (keep_for_judgement) edge_poor[source] = 1;
      dropped[i] = stats[i].bad_frame && !keep_for_judgement;
      if (!dropped[i]) {
        toBody(clouds[i].edges, keep_for_judgement ? &judged_edges[source] : &edges);
        toBody(surface_points[i] ? deskewed[i].points : clouds[i].planes,
               keep_for_judgement ? &judged_planes[source] : &planes);
      }
      if (cfg.keep_points) toBody(deskewed[i].points, &out->points_body);
    }
    out->lidars = std::move(stats);
    view.reset();
    if (!views.empty()) {
      view = std::make_shared<SweepView>();
      view->stamp_ns = sweep.end_ns;
      for (std::size_t i = 0; i < views.size(); ++i)
        if (!dropped[i]) view->sensors.push_back(std::move(views[i]));
    }

    Features f;
    // A voxel shared by two LiDARs keeps its first point's source.
    auto toVec = [](const std::vector<Point>& pts, std::vector<Eigen::Vector3d>* dst, std::vector<std::uint8_t>* src) {
      dst->reserve(dst->size() + pts.size());
      src->reserve(src->size() + pts.size());
      for (const Point& p : pts) {
        dst->push_back(p.xyz.cast<double>());
        src->push_back(p.source);
      }
    };
    toVec(lidar::voxelDownsample(edges, cfg.edge_voxel_m), &f.edges, &f.edge_source);
    toVec(lidar::voxelDownsample(planes, cfg.plane_voxel_m), &f.planes, &f.plane_source);
    for (std::size_t s = 0; s < lidars.size(); ++s) {
      toVec(lidar::voxelDownsample(judged_edges[s], cfg.edge_voxel_m), &f.edges, &f.edge_source);
      toVec(lidar::voxelDownsample(judged_planes[s], cfg.plane_voxel_m), &f.planes, &f.plane_source);
    }
    return f;
  }

  // ---- stage: scan-to-map registration of one sweep with an IMU factor to the previous one ----
  std::size_t registerSweep(const Features& f, const std::shared_ptr<imu::Preintegration>& pre, const NavState& prev,
                            bool prev_velocity_guessed, NavState* state, SweepResult* out) {
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
      matches.erase(
          std::remove_if(matches.begin(), matches.end(), [&](const MapMatch& m) { return rejected[m.source]; }),
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

  // ---- stage: LiDAR-only registration across a gap in the data ----
  // `unobserved_s` of the motion since `prev` were extrapolated (last turn rate and velocity) into
  // *state. A single start converges to a wrong minimum once that guess is off by more than about
  // 10 deg (office, a U-turn ending during 0.3 s of lost data: 52 cm ATE), so registration is
  // started from several guesses (see kGapMotionScales) and the best-fitting result is kept.
  std::size_t registerAcrossGap(const Features& f, const NavState& prev, bool prev_velocity_guessed,
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
  double fitScore(const Features& f, const Eigen::Isometry3d& T) const {
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
  void judgeLidars(const std::vector<MapMatch>& matches, const Eigen::Isometry3d& T, std::vector<char>* rejected,
                   SweepResult* out) const {
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

  static void dropSources(const std::vector<char>& rejected, std::vector<Eigen::Vector3d>* pts,
                          std::vector<std::uint8_t>* src) {
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

  FeatureBudget registrationBudget() const {
    const auto count = [](int n) { return static_cast<std::size_t>(std::max(0, n)); };
    return {count(cfg.registration_max_edges), count(cfg.registration_max_planes), cfg.edge_voxel_m, cfg.plane_voxel_m};
  }

  /// Bad frames found during registration leave the sweep's features (window and map) and its
  /// view of free space: the estimate goes on as without that LiDAR.
  void dropRejected(Features* f) const {
    if (std::none_of(rejected_sources.begin(), rejected_sources.end(), [](char c) { return c != 0; })) return;
    dropSources(rejected_sources, &f->edges, &f->edge_source);
    dropSources(rejected_sources, &f->planes, &f->plane_source);
    if (view)
      view->sensors.erase(std::remove_if(view->sensors.begin(), view->sensors.end(),
                                         [&](const SensorView& s) { return rejected_sources[s.source] != 0; }),
                          view->sensors.end());
  }

  // ---- stage: returns on things that moved in (space an earlier sweep saw through) ----
  // Returns whether they include a mover (moverFound), not only the odd false return.
  bool rejectMovedIn(Features* f, const Eigen::Isometry3d& T_world_body, Stamp now, SweepResult* out) const {
    std::vector<Eigen::Vector3d> world;
    world.reserve(f->edges.size() + f->planes.size());
    for (const auto& p : f->edges) world.push_back(T_world_body * p);
    for (const auto& p : f->planes) world.push_back(T_world_body * p);
    std::vector<std::uint8_t> moved = free_space.movedIn(world, now);
    const bool mover = moverFound(world, moved);
    // Raw points follow their feature's voxel (features are voxel centroids of the raw points).
    const double inv = 1.0 / cfg.plane_voxel_m;
    const auto key = [inv](const Eigen::Vector3d& p, int dx = 0, int dy = 0, int dz = 0) {
      return scaledVoxelKeyOf(p, inv, dx, dy, dz);
    };
    // A mover is found where part of it entered free space (its leading side); its other returns
    // lie next to those: every feature in a voxel touching a flagged one goes with them.
    // The flagged voxels are few: their neighbourhoods go in one set, looked up once per feature.
    FlatKeySet near_flagged;
    const auto bodyPoint = [&](std::size_t i) {
      return i < f->edges.size() ? f->edges[i] : f->planes[i - f->edges.size()];
    };
    // Not from a frame still under judgement: rejected, it must leave the other LiDARs' features as they were.
    const auto judged = [&](std::size_t i) {
      const std::vector<std::uint8_t>& src = i < f->edges.size() ? f->edge_source : f->plane_source;
      const std::size_t k = i < f->edges.size() ? i : i - f->edges.size();
      return k < src.size() && edge_poor[src[k]] != 0;
    };
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (moved[i] && !judged(i))
        for (int n = 0; n < 27; ++n) near_flagged.insert(key(bodyPoint(i), n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1));
    if (!near_flagged.empty())
      for (std::size_t i = 0; i < moved.size(); ++i)
        if (!moved[i]) moved[i] = near_flagged.contains(key(bodyPoint(i))) ? 1 : 0;
    FlatKeySet moved_voxels;
    std::size_t index = 0;
    const auto keep = [&](std::vector<Eigen::Vector3d>* pts, std::vector<std::uint8_t>* src) {
      std::size_t k = 0;
      for (std::size_t i = 0; i < pts->size(); ++i, ++index) {
        if (moved[index]) {
          moved_voxels.insert(key((*pts)[i]));
          continue;
        }
        (*pts)[k] = (*pts)[i];
        if (src->size() == pts->size()) (*src)[k] = (*src)[i];
        ++k;
      }
      if (src->size() == pts->size()) src->resize(k);
      pts->resize(k);
    };
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (moved[i]) out->moved_world.push_back(world[i]);
    keep(&f->edges, &f->edge_source);
    keep(&f->planes, &f->plane_source);
    out->dynamic_points = static_cast<std::size_t>(std::count(moved.begin(), moved.end(), 1));
    if (moved_voxels.empty() || out->points_body.empty()) return mover;
    std::size_t k = 0;
    for (const Point& p : out->points_body) {
      if (moved_voxels.contains(key(p.xyz.cast<double>())))
        out->points_dynamic_body.push_back(p);
      else
        out->points_body[k++] = p;
    }
    out->points_body.resize(k);
    return mover;
  }

  /// Local map points the keyframe's sweep saw through were left by something that has gone.
  std::size_t carveMap(const Eigen::Vector3d& center, std::vector<Eigen::Vector3d>* carved) {
    if (!view) return 0;
    const auto seen_through = [this](const Eigen::Vector3d& p) { return view->seesThrough(p); };
    return plane_map.removeIf(center, cfg.dynamic.carve_radius_m, seen_through, carved) +
           edge_map.removeIf(center, cfg.dynamic.carve_radius_m, seen_through, carved);
  }

  bool isKeyframe(const NavState& s) const {
    if (window.empty()) return true;
    const NavState k = fromBlocks(window.back().x, window.back().stamp);
    const double angle_deg = Eigen::AngleAxisd(k.q_world_body.inverse() * s.q_world_body).angle() * 180.0 / M_PI;
    return angle_deg > cfg.keyframe_rotation_deg || (s.p_world - k.p_world).norm() > cfg.keyframe_translation_m ||
           toSec(s.stamp_ns - k.stamp_ns) > cfg.keyframe_interval_s;
  }

  // The map keeps the features' resolution: denser map clouds (0.1-0.2 m) were measured to fit
  // noisier local planes (office HVI ATE 1.2 -> 1.8-2.0 cm) although they are faster to search.
  void addToMap(const WindowKeyframe& kf) {
    const Eigen::Isometry3d T = poseOf(kf.x.pose);
    std::vector<Eigen::Vector3d> e, p;
    e.reserve(kf.features.edges.size());
    p.reserve(kf.features.planes.size());
    for (const auto& v : kf.features.edges) e.push_back(T * v);
    for (const auto& v : kf.features.planes) p.push_back(T * v);
    edge_map.add(e);
    plane_map.add(p);
    edge_map.removeFarFrom(T.translation(), cfg.local_map_radius_m);
    plane_map.removeFarFrom(T.translation(), cfg.local_map_radius_m);
  }

  void trimImu() {
    while (imu.size() > 2 && imu[1].stamp_ns < last.stamp_ns - fromSec(1.0)) imu.pop_front();
  }
};

Odometry::Odometry(OdometryConfig cfg, std::vector<LidarSetup> lidars)
    : impl_(std::make_unique<Impl>(std::move(cfg), std::move(lidars))) {}
Odometry::~Odometry() = default;

void Odometry::addImu(const ImuSample& sample) {
  auto& d = *impl_;
  if (!d.imu.empty() && sample.stamp_ns <= d.imu.back().stamp_ns) {
    log::emit(log::Level::kWarn, "IMU sample out of order or duplicated at ", log::stampText(sample.stamp_ns),
              " s: dropped");
    return;
  }
  d.imu.push_back(sample);
  if (!d.initialized) {
    d.initializer.add(sample);
    while (d.imu.size() > 4000) d.imu.pop_front();
  }
}

bool Odometry::initialized() const { return impl_->initialized; }
const imu::ImuInitResult& Odometry::imuInit() const { return impl_->init_result; }
std::size_t Odometry::keyframes() const { return impl_->keyframes; }
Stamp Odometry::lastImuNs() const { return impl_->imu.empty() ? 0 : impl_->imu.back().stamp_ns; }

SweepResult Odometry::process(lidar::AlignedSweep sweep) {
  auto& d = *impl_;
  SweepResult out;
  Stopwatch watch;

  if (!d.initialized) {
    if (!d.initializer.ready()) {
      d.init_result = d.initializer.result();
      return out;
    }
    d.init_result = d.initializer.result();
    if (!d.init_result.ok) return out;
    d.initialized = true;
    d.last = NavState{};
    d.last.stamp_ns = sweep.start_ns;
    d.last.q_world_body = d.init_result.q_world_imu;
    d.last.bias.gyro_rad_s = d.init_result.gyro_bias;
    log::emit(
        d.init_result.forced ? log::Level::kWarn : log::Level::kInfo, "IMU initialised: ", d.init_result.message,
        d.init_result.forced ? " (no standstill: gyro bias starts at 0, roll/pitch from the mean acceleration)" : "");
  }

  // ---- IMU prediction over the sweep, motion for de-skew ----
  const NavState prev = d.last;
  const Stamp t0 = std::max(prev.stamp_ns, sweep.start_ns - fromSec(0.2));
  std::vector<ImuSample> samples = imu::imuBetween(d.imuBuffer(), prev.stamp_ns, sweep.end_ns);
  NavState predicted = prev;
  predicted.stamp_ns = sweep.end_ns;
  auto pre = std::make_shared<imu::Preintegration>(prev.bias, d.cfg.imu_noise);
  lidar::SweepMotion motion;
  double unobserved_s = 0.0;  // of the motion since prev: extrapolated, not measured
  // A gap in the IMU stream must not be bridged by interpolating across it (a straight line through
  // two seconds of walking): the sweeps it spans are registered by their LiDARs alone.
  Stamp widest_gap = 0;
  for (std::size_t k = 1; k < d.imu.size(); ++k)
    if (d.imu[k].stamp_ns > prev.stamp_ns && d.imu[k - 1].stamp_ns < sweep.end_ns)
      widest_gap = std::max(widest_gap, d.imu[k].stamp_ns - d.imu[k - 1].stamp_ns);
  const bool imu_ok = samples.size() >= 2 && samples.front().stamp_ns <= prev.stamp_ns + fromSec(0.02) &&
                      samples.back().stamp_ns >= sweep.end_ns - fromSec(0.02) && widest_gap <= kMaxImuGapNs;
  if (imu_ok) {
    integrateSamples(*pre, samples);
    if (!d.pre_since_keyframe) d.pre_since_keyframe = std::make_shared<imu::Preintegration>(prev.bias, d.cfg.imu_noise);
    integrateSamples(*d.pre_since_keyframe, samples);
    predicted = pre->predict(prev, d.g_world);
    predicted.stamp_ns = sweep.end_ns;
    motion = imuMotion(prev, samples, t0, sweep, d.g_world);
  } else {
    // No IMU across this sweep (gap or IMU stopped): the last motion goes on (velocity and turn
    // rate), for the prediction and the de-skew, logged.
    const double dt = toSec(sweep.end_ns - prev.stamp_ns);
    unobserved_s = dt;
    predicted.p_world += prev.v_world * dt;
    predicted.q_world_body = (prev.q_world_body * so3::exp(d.omega_body * dt)).normalized();
    motion = lidar::SweepMotion::constantTwist(prev.q_world_body.inverse() * prev.v_world, d.omega_body,
                                               toSec(sweep.end_ns - sweep.start_ns));
    // The IMU may be back within this sweep (a gap of all data just ended): its gyroscope then
    // de-skews the sweep instead of the turn rate from before the gap (a walker who stopped turning
    // during the gap would be de-skewed by a turn that did not happen).
    const std::vector<ImuSample> within = imu::imuBetween(d.imuBuffer(), sweep.start_ns, sweep.end_ns);
    Stamp within_gap = 0;
    for (std::size_t k = 1; k < within.size(); ++k)
      within_gap = std::max(within_gap, within[k].stamp_ns - within[k - 1].stamp_ns);
    if (within.size() >= 2 && within.front().stamp_ns <= sweep.start_ns + fromSec(0.005) &&
        within.back().stamp_ns >= sweep.end_ns - fromSec(0.005) && within_gap <= kMaxImuGapNs) {
      NavState start = prev;
      start.stamp_ns = sweep.start_ns;
      start.p_world = prev.p_world + prev.v_world * toSec(sweep.start_ns - prev.stamp_ns);
      start.q_world_body =
          (prev.q_world_body * so3::exp(d.omega_body * toSec(sweep.start_ns - prev.stamp_ns))).normalized();
      NavState end;
      motion = imuMotion(start, within, sweep.start_ns, sweep, d.g_world, &end);
      unobserved_s = toSec(sweep.start_ns - prev.stamp_ns);
      predicted.q_world_body = end.q_world_body;
      predicted.p_world = end.p_world;
    }
    out.note = "no IMU over the sweep: constant-velocity prediction, LiDAR-only registration";
    // The keyframe preintegration now misses an interval: restart the window (the map stays).
    d.window.clear();
    d.pre_since_keyframe.reset();
    // Moved-in tests place points at predictions that may be centimetres off after a gap: static
    // surfaces then seem to stand where earlier views saw through, and whole walls are rejected as
    // movers (measured: 40 % of the features), so the LiDARs cannot pull the pose back. The views
    // restart with the data.
    d.free_space.clear();
    if (!d.in_imu_gap)
      log::emit(log::Level::kWarn, "no IMU data over the sweep ending at ", log::stampText(sweep.end_ns),
                " s: LiDAR-only registration until it returns (the report counts degraded sweeps)");
  }
  const bool prev_velocity_guessed = d.in_imu_gap;  // the previous sweep had no IMU
  d.in_imu_gap = !imu_ok;
  out.times_ms.emplace_back("imu_predict", watch.lapMs());

  // Movers are looked for where they were lately, and at intervals elsewhere (MoverWatch); a
  // keyframe's view carves the local map and goes to the back end's ghost removal.
  out.judged_for_movers = d.cfg.dynamic.enabled && imu_ok && d.mover_watch.shouldJudge(sweep.end_ns);
  const bool with_view = d.cfg.dynamic.enabled && (out.judged_for_movers || !imu_ok || d.isKeyframe(predicted));
  Features features = d.extract(sweep, motion, with_view, &out);
  out.times_ms.emplace_back("deskew_features", watch.lapMs());
  if (out.judged_for_movers)
    d.mover_watch.judged(sweep.end_ns, d.rejectMovedIn(&features, predicted.pose(), sweep.end_ns, &out));
  out.times_ms.emplace_back("dynamic", watch.lapMs());

  // ---- registration (of a budget of the features, if one is set; the window and the map take all) ----
  const bool budgeted = d.cfg.registration_max_edges > 0 || d.cfg.registration_max_planes > 0;
  Features thinned;
  if (budgeted) thinned = thinToBudget(features, d.registrationBudget());
  const Features& matched = budgeted ? thinned : features;
  NavState state = predicted;
  bool tracked = true;
  d.rejected_sources = d.edge_poor;  // unless registration judges them by their information
  d.drift.predict(toSec(sweep.end_ns - prev.stamp_ns), d.cfg.degeneracy.drift_m_s2);
  if (!d.plane_map.empty()) {
    out.correspondences = imu_ok
                              ? d.registerSweep(matched, pre, prev, prev_velocity_guessed, &state, &out)
                              : d.registerAcrossGap(matched, prev, prev_velocity_guessed, unobserved_s, &state, &out);
    if (out.registered && out.correspondences >= kMinCorrespondences)
      d.drift.update(out.degeneracy, d.cfg.lidar_sigma_m);
    out.drift_sigma_m = d.drift.largestSigmaM();
    if (out.correspondences < kMinCorrespondences) {
      tracked = false;
      state = predicted;
      out.note = "only " + std::to_string(out.correspondences) + " map correspondences: IMU prediction kept";
    } else if (!imu_ok && sweep.end_ns > prev.stamp_ns) {
      state.v_world = (state.p_world - prev.p_world) / toSec(sweep.end_ns - prev.stamp_ns);  // what the LiDARs moved
    }
  }
  d.dropRejected(&features);
  out.times_ms.emplace_back("registration", watch.lapMs());

  // ---- keyframe, sliding window, map ----
  out.keyframe = d.isKeyframe(state) || d.plane_map.empty();
  if (out.keyframe && tracked && (imu_ok || d.window.empty())) {
    WindowKeyframe kf;
    kf.stamp = state.stamp_ns;
    kf.x = toBlocks(state);
    kf.features = std::move(features);
    kf.pre = d.pre_since_keyframe;
    if (!d.window.empty() && !kf.pre) kf.pre = pre;
    kf.max_match_residual_m = Impl::matchGate(imu_ok, prev_velocity_guessed);
    d.window.push(std::move(kf));
    d.window.optimize(d.edge_map, d.plane_map);
    out.times_ms.emplace_back("window", watch.lapMs());
    d.window.marginalizeOldest(d.edge_map, d.plane_map);
    out.times_ms.emplace_back("marginalize", watch.lapMs());
    d.addToMap(d.window.back());
    state = fromBlocks(d.window.back().x, state.stamp_ns);
    if (d.view) d.view->place(state.pose());
    // What the keyframe sees through in the local map was left by a mover: where none was found
    // lately, only the odd mixed pixel, which would cost static points.
    if (d.view && d.mover_watch.moversLately(state.stamp_ns))
      out.carved_points = d.carveMap(state.p_world, &out.moved_world);
    d.plane_map.refitPlanes();  // once, after this keyframe's additions, trim and carving
    d.pre_since_keyframe = std::make_shared<imu::Preintegration>(state.bias, d.cfg.imu_noise);
    ++d.keyframes;
  } else {
    out.keyframe = false;
    out.times_ms.emplace_back("window", 0.0);
    out.times_ms.emplace_back("marginalize", 0.0);
  }
  out.times_ms.emplace_back("map_update", watch.lapMs());

  if (d.view && tracked) {
    d.view->place(state.pose());
    if (imu_ok) d.free_space.remember(d.view);  // a sweep without IMU is de-skewed and placed by a guess
    out.view = d.view;
  }
  if (tracked && state.stamp_ns > prev.stamp_ns)  // the body's turn rate, for sweeps without IMU
    d.omega_body = so3::log(prev.q_world_body.inverse() * state.q_world_body) / toSec(state.stamp_ns - prev.stamp_ns);
  d.last = state;
  d.trimImu();
  out.state = state;
  out.status = tracked && imu_ok ? SweepResult::Status::kTracking : SweepResult::Status::kDegraded;
  return out;
}

}  // namespace mmlio::estimator
