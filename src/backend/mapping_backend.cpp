#include "mmlio/backend/mapping_backend.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "mmlio/backend/loop_plausibility.hpp"
#include "mmlio/backend/point_to_plane_icp.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/core/voxel_key.hpp"

namespace mmlio::backend {
namespace {

constexpr double kMovedCellM = 0.5;
// A keyframe placed by a saved session's map (MapLocalizer's tracking: point-to-plane ICP onto it).
constexpr double kSessionTieSigmaM = 0.003;
constexpr double kSessionTieSigmaRad = 0.05 * M_PI / 180.0;
constexpr int kTiesPerSolve = 5;
// A cell the odometry reported this many moved-in returns in held a mover (a walker leaves dozens);
// fewer are the odd false detection on a static surface, which must not cost it points.
constexpr std::uint32_t kMinMoverReturns = 8;

std::uint64_t cellKey(const Eigen::Vector3d& p, int dx = 0, int dy = 0, int dz = 0) {
  return voxelKeyOf(p, kMovedCellM, dx, dy, dz);
}

estimator::SweepView withoutWindows(const estimator::SweepView& view) {
  estimator::SweepView kept;
  kept.stamp_ns = view.stamp_ns;
  kept.sensors.reserve(view.sensors.size());
  for (const estimator::SensorView& s : view.sensors)
    kept.sensors.push_back({s.source, s.T_body_sensor, s.T_sensor_world, s.image.withoutWindows()});
  return kept;
}

}  // namespace

MappingBackend::MappingBackend(Config cfg) : cfg_(std::move(cfg)), dynamic_(cfg_.map_leaf_m) {
  if (cfg_.loop_enabled) closer_ = std::make_unique<backend::LoopCloser>(cfg_.loop);
}

MappingBackend::~MappingBackend() = default;

bool MappingBackend::plausibleCorrection(const backend::LoopResult& r) const {
  const LoopCorrection c = loopCorrection(graph_, r, cfg_);
  if (c.plausible()) return true;
  log::emit(log::Level::kInfo, "loop ", r.query, " -> ", r.match, " rejected: it would move the pose by ",
            c.correction_m, " m and turn it by ", c.correction_deg, " deg, more than odometry can drift over the ",
            c.route_m, " m between them (", c.allowed_m, " m, ", c.allowed_deg, " deg)");
  return false;
}

void MappingBackend::tryLoop(int k) {
  last_checked_ = k;
  ++loop_attempts_;
  const auto heading = [this, k](int match, double yaw_rad, double slack_deg) {
    return backend::plausibleHeading(graph_, match, k, yaw_rad, slack_deg, cfg_);
  };
  backend::LoopResult r = closer_->detect(graph_, k, heading);
  if (r.accepted && !plausibleCorrection(r)) {
    r.accepted = false;
    ++rejected_;
  }
  if (r.accepted) {
    const Eigen::Isometry3d d = (graph_.pose(r.match).inverse() * graph_.pose(k)).inverse() * r.T_match_query;
    log::debug("loop ", k, " -> ", r.match, " corrects the estimate by (", d.translation().transpose(), ") m, (",
               Eigen::AngleAxisd(d.rotation()).angle() * Eigen::AngleAxisd(d.rotation()).axis().transpose(), ") rad");
    graph_.addLoop(r.match, r.query, r.T_match_query, r.information);
    graph_.optimize();
    const Stamp t0 = graph_.node(0).stamp_ns;  // seconds since the first keyframe: readable
    loops_.push_back(
        {toSec(graph_.node(r.query).stamp_ns - t0), toSec(graph_.node(r.match).stamp_ns - t0), r.fitness_m, r.overlap});
    log::emit(log::Level::kInfo, "loop closed: keyframe ", r.query, " -> ", r.match, " (fitness ", r.fitness_m,
              " m, overlap ", r.overlap, ")");
  } else if (r.candidates_tried + r.candidates_refused > 0) {
    ++rejected_;
    log::emit(log::Level::kDebug, "loop candidate rejected for keyframe ", k, ": ", r.reason);
  }
}

void MappingBackend::tieToSession(int k, const Eigen::Isometry3d& T_world_body) {
  graph_.addPrior(k, T_world_body, isotropicInformation(kSessionTieSigmaM, kSessionTieSigmaRad));
  // Each tie pulls little: the graph is solved every few of them, not at each.
  if (++ties_unsolved_ >= kTiesPerSolve) {
    graph_.optimize();
    ties_unsolved_ = 0;
  }
}

void MappingBackend::finish() {
  // The end of a run is where a loop matters most (a sequence that returns to its start), but it
  // is rarely a multiple of loop_check_every: check the last keyframe once more.
  const int last = static_cast<int>(graph_.size()) - 1;
  if (closer_ && last > 0 && last != last_checked_) tryLoop(last);
  if (ties_unsolved_ > 0) {
    graph_.optimize();
    ties_unsolved_ = 0;
  }
  closeSubmap();  // the newest keyframe's submap is complete now
  judgeSubmaps(true);
}

bool MappingBackend::mappedBefore(const Eigen::Vector3d& world) const {
  if (covered_before_.empty()) return false;
  // The session's surface, placed by a localization a centimetre off, sits in the neighbouring
  // voxel as often as not: any of the 27 around the point counts.
  for (int n = 0; n < 27; ++n)
    if (covered_before_.contains(voxelKeyOf(world, cfg_.map_leaf_m, n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1)))
      return true;
  return false;
}

void MappingBackend::coverAlready(const std::vector<Point>& points, const Eigen::Isometry3d& T_world_points) {
  if (!cfg_.dedupe_revisits || cfg_.map_leaf_m <= 0.0) return;
  for (const Point& p : points)
    covered_before_.insert(voxelKeyOf(T_world_points * p.xyz.cast<double>(), cfg_.map_leaf_m));
}

void MappingBackend::addSweep(const estimator::SweepResult& sweep) {
  const Eigen::Isometry3d T_world_body = sweep.state.pose();
  newest_ = {sweep.state.stamp_ns, T_world_body};
  if (sweep.keyframe || submaps_.empty()) {
    backend::KeyframeNode node;
    node.stamp_ns = sweep.state.stamp_ns;
    node.T_world_body_odom = T_world_body;
    if (cfg_.loop_enabled || cfg_.keep_keyframe_clouds) {
      std::vector<Eigen::Vector3d> pts;
      pts.reserve(sweep.points_body.size());
      for (const Point& p : sweep.points_body) pts.emplace_back(p.xyz.cast<double>());
      node.cloud_body = map::voxelCentroids(pts, cfg_.loop_cloud_voxel_m);
      node.cloud_body.shrink_to_fit();  // kept for the run: without the slack of its growth
    }
    const int k = graph_.addKeyframe(std::move(node));
    if (cfg_.clean_map && sweep.view) views_[static_cast<std::size_t>(k)] = withoutWindows(*sweep.view);
    closeSubmap();
    judgeSubmaps(false);
    submaps_.emplace_back();
    T_world_keyframe_ = T_world_body;

    if (sweep.T_world_body_measured && k > 0) tieToSession(k, *sweep.T_world_body_measured);
    if (closer_ && k > 0 && k % std::max(1, cfg_.loop_check_every) == 0) tryLoop(k);
  }
  if (cfg_.dynamic_map && !sweep.points_dynamic_body.empty()) dynamic_.add(sweep.points_dynamic_body, T_world_body);
  if (cfg_.clean_map)
    for (const Eigen::Vector3d& p : sweep.moved_world) {
      const auto [c, added] = mover_index_.insert(cellKey(p), static_cast<std::uint32_t>(mover_returns_.size()));
      if (added) {  // a cell first seen with a mover: it and its neighbours are judged
        mover_returns_.push_back(0);
        for (int n = 0; n < 27; ++n) moved_cells_.insert(cellKey(p, n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1));
      }
      ++mover_returns_[c];
    }
  // Points go into the current keyframe's submap, in that keyframe's frame. The odometry lists
  // points_body LiDAR by LiDAR, in the order of sweep.lidars.
  const std::size_t map_stride = static_cast<std::size_t>(std::max(1, cfg_.map_point_stride));
  const std::size_t map_phase = sweeps_++ % map_stride;
  // A thinned sweep holds just these points already (keepWhatTheMapTakes).
  const std::size_t stride = sweep.points_body_thinned ? 1 : map_stride;
  const std::size_t phase = sweep.points_body_thinned ? 0 : map_phase;
  const Eigen::Isometry3d T_keyframe_body = T_world_keyframe_.inverse() * T_world_body;
  std::size_t listed = 0;
  for (const auto& l : sweep.lidars) listed += l.points;
  const bool split = cfg_.per_lidar_maps && listed == sweep.points_body.size();
  std::size_t begin = 0;
  for (std::size_t l = 0; l < (split ? sweep.lidars.size() : 1); ++l) {
    const std::size_t end = split ? begin + sweep.lidars[l].points : sweep.points_body.size();
    strided_.clear();
    for (std::size_t i = begin + phase; i < end; i += stride) strided_.push_back(sweep.points_body[i]);
    const std::string key = split ? sweep.lidars[l].sensor : std::string();
    openAccumulator(key).add(strided_, T_keyframe_body);
    begin = end;
  }
}

void MappingBackend::keepWhatTheMapTakes(estimator::SweepResult* sweep, std::size_t index, const Config& cfg) {
  const std::size_t stride = static_cast<std::size_t>(std::max(1, cfg.map_point_stride));
  // Per-LiDAR maps take each LiDAR's part of the points from its own offset: left whole.
  if (sweep->keyframe || index == 0 || stride == 1 || cfg.per_lidar_maps || sweep->points_body_thinned) return;
  const std::vector<Point>& all = sweep->points_body;
  std::vector<Point> taken;
  taken.reserve(all.size() / stride + 1);
  for (std::size_t i = index % stride; i < all.size(); i += stride) taken.push_back(all[i]);
  sweep->points_body = std::move(taken);
  sweep->points_body_thinned = true;
  sweep->view.reset();
}

MapAccumulator& MappingBackend::openAccumulator(const std::string& key) {
  auto it = open_.find(key);
  if (it != open_.end()) return it->second;
  if (auto reused = emptied_.extract(key)) return open_.insert(std::move(reused)).position->second;
  return open_.try_emplace(key, cfg_.map_leaf_m).first->second;
}

Trajectory MappingBackend::corrected(const PoseLog& odometry) const {
  if (!corrects()) return odometry.trajectory();
  Trajectory out;
  out.reserve(odometry.size());
  odometry.forEach([&](const StampedPose& p) {
    out.push_back({p.stamp_ns, graph_.correct(p.stamp_ns, p.T_world_body)});
  });
  return out;
}

Trajectory MappingBackend::corrected(Trajectory odometry) const {
  if (!corrects()) return odometry;
  for (StampedPose& p : odometry) p.T_world_body = graph_.correct(p.stamp_ns, p.T_world_body);
  return odometry;
}

Eigen::Isometry3d MappingBackend::correction() const {
  if (!corrects()) return Eigen::Isometry3d::Identity();  // (a loop or a tie implies newest_ is set)
  return graph_.correct(newest_.stamp_ns, newest_.T_world_body) * newest_.T_world_body.inverse();
}

void MappingBackend::closeSubmap() {
  if (submaps_.empty()) return;
  const Eigen::Isometry3d T_world_keyframe = graph_.pose(static_cast<int>(submaps_.size()) - 1);
  const double leaf = cfg_.map_leaf_m;
  std::size_t seen = 0, new_voxels = 0;
  for (auto& [lidar, acc] : open_) {
    std::vector<Point> pts = acc.points();
    seen += pts.size();
    if (cfg_.dedupe_revisits && leaf > 0.0) {
      // Revisits add nothing new: drop voxels an earlier keyframe already holds. Loops corrected
      // later move each point with the keyframe that kept it, so the map stays consistent.
      auto& covered = covered_[lidar];
      // The set holds a key per 5 cm of mapped surface (millions in a hall): keys are computed and
      // their slots prefetched a block ahead of the inserts, which then wait on fewer cache misses.
      constexpr std::size_t kBlock = 16;
      std::uint64_t keys[kBlock];
      Eigen::Vector3d world[kBlock];
      std::size_t kept = 0;
      for (std::size_t begin = 0; begin < pts.size(); begin += kBlock) {
        const std::size_t n = std::min(kBlock, pts.size() - begin);
        for (std::size_t j = 0; j < n; ++j) {
          world[j] = T_world_keyframe * pts[begin + j].xyz.cast<double>();
          keys[j] = voxelKeyOf(world[j], leaf);
          covered.prefetch(keys[j]);
        }
        for (std::size_t j = 0; j < n; ++j)
          if (!mappedBefore(world[j]) && covered.insert(keys[j])) pts[kept++] = pts[begin + j];
      }
      pts.resize(kept);
    }
    new_voxels += pts.size();
    pts.shrink_to_fit();
    submaps_.back()[lidar] = std::move(pts);
  }
  // Each keyframe's accumulators are filled with about as many points as the last ones: their
  // storage is reused rather than grown and page-faulted anew.
  for (auto& [lidar, acc] : open_) acc.clear();
  emptied_.merge(open_);
  open_.clear();
  // A keyframe that added almost nothing new to the map revisits a place older keyframes cover:
  // its loop cloud would only duplicate theirs as a candidate, so it is freed (the last keyframe,
  // still open, keeps its cloud for the end-of-run loop check), and unless a loop ends at it, it
  // leaves the optimised graph (PoseGraph::fold): the problem each loop solves then grows with the
  // places mapped, not with the time spent revisiting them.
  const int k = static_cast<int>(submaps_.size()) - 1;
  if (cfg_.dedupe_revisits && leaf > 0.0 && k > 0 && seen > 0 && new_voxels < cfg_.revisit_new_fraction * seen) {
    graph_.dropCloud(k);
    if (closer_) closer_->forget(k);
    graph_.fold(k);
  }
}

std::vector<Point> MappingBackend::mergedMap(const std::string* only_lidar) const {
  std::vector<PosedPoints> clouds;
  for (std::size_t k = 0; k < submaps_.size(); ++k)
    for (const auto& [lidar, pts] : submaps_[k])
      if (!only_lidar || lidar == *only_lidar) clouds.push_back({&pts, graph_.pose(static_cast<int>(k))});
  std::vector<std::vector<Point>> open;  // the newest keyframe's submap, if still open
  open.reserve(open_.size());
  if (!submaps_.empty())
    for (const auto& [lidar, acc] : open_)
      if (!only_lidar || lidar == *only_lidar) {
        open.push_back(acc.points());
        clouds.push_back({&open.back(), graph_.pose(static_cast<int>(submaps_.size()) - 1)});
      }
  return mergeIntoVoxels(clouds, cfg_.map_leaf_m);
}

std::vector<Point> MappingBackend::map() const { return mergedMap(nullptr); }

Session MappingBackend::session() const {
  Session s;
  s.map_voxel_m = cfg_.map_leaf_m;
  s.cloud_voxel_m = cfg_.loop_cloud_voxel_m;
  s.keyframes.reserve(graph_.size());
  for (int k = 0; k < static_cast<int>(graph_.size()); ++k) {
    const KeyframeNode& node = graph_.node(k);
    s.keyframes.push_back({node.stamp_ns, graph_.pose(k), node.T_world_body_odom, node.cloud_body});
  }
  for (const PoseGraph::LoopEdge& e : graph_.loopEdges()) s.loops.push_back({e.from, e.to, e.T_from_to, e.information});
  return s;
}

std::vector<Point> MappingBackend::dynamicMap() const { return dynamic_.points(); }

void MappingBackend::judgeSubmaps(bool all) {
  if (!cfg_.clean_map) return;
  // Closed submaps are those before the newest keyframe (whose submap is still filling), all of
  // them after finish() closed the last one.
  const std::size_t closed = all ? submaps_.size() : (submaps_.empty() ? 0 : submaps_.size() - 1);
  const std::size_t after = static_cast<std::size_t>(std::max(0, cfg_.ghost_keyframes));
  for (; judged_ < closed && (all || judged_ + after < submaps_.size()); ++judged_) removeGhosts(judged_);
  // Views no later submap can use any more.
  while (!views_.empty() && views_.begin()->first + after < judged_) views_.erase(views_.begin());
}

bool MappingBackend::nearMoved(const Eigen::Vector3d& world) const { return moved_cells_.contains(cellKey(world)); }

bool MappingBackend::nearAMover(std::size_t submap) const {
  if (moved_cells_.empty()) return false;
  const Eigen::Isometry3d T_world_keyframe = graph_.pose(static_cast<int>(submap));
  for (const auto& [lidar, points] : submaps_[submap])
    for (const Point& p : points)
      if (nearMoved(T_world_keyframe * p.xyz.cast<double>())) return true;
  return false;
}

std::uint32_t MappingBackend::moverReturns(const Eigen::Vector3d& world) const {
  const std::uint32_t c = mover_index_.find(cellKey(world));
  return c == FlatKeyIndex::kNone ? 0 : mover_returns_[c];
}

void MappingBackend::removeGhosts(std::size_t submap) {
  // One vote per keyframe (its LiDARs together): seen through by any of them, else seen on.
  struct Eye {
    const map::RangeImage* image;
    Eigen::Isometry3d T_sensor_world;
    Eigen::Vector3d origin;
  };
  struct Group {  // a keyframe's eyes: eyes[begin, end)
    std::size_t begin, end, keyframe;
  };
  // Only points near a mover are judged: a submap with none needs no view.
  if (!nearAMover(submap)) return;
  const std::size_t reach = static_cast<std::size_t>(std::max(0, cfg_.ghost_keyframes));
  std::vector<Eye> eyes;
  std::vector<Group> groups;
  for (auto it = views_.lower_bound(submap > reach ? submap - reach : 0);
       it != views_.end() && it->first <= submap + reach; ++it) {
    if (static_cast<int>(it->first) >= static_cast<int>(graph_.size())) continue;
    const Eigen::Isometry3d T_world_body = graph_.pose(static_cast<int>(it->first));
    const std::size_t begin = eyes.size();
    for (const estimator::SensorView& s : it->second.sensors) {
      const Eigen::Isometry3d T_world_sensor = T_world_body * s.T_body_sensor;
      eyes.push_back({&s.image, T_world_sensor.inverse(), T_world_sensor.translation()});
    }
    if (eyes.size() > begin) groups.push_back({begin, eyes.size(), it->first});
  }
  if (eyes.empty()) return;
  const Eigen::Isometry3d T_world_keyframe = graph_.pose(static_cast<int>(submap));
  const double r2 = cfg_.ghost_range_m * cfg_.ghost_range_m;
  for (auto& lidar_points : submaps_[submap]) {
    std::vector<Point>& points = lidar_points.second;  // a reference the lambda below may capture (C++17)
    std::vector<std::uint8_t> ghost(points.size(), 0), judged(points.size(), 0);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const tbb::blocked_range<std::size_t>& r) {
          // A group's vote on the current point, once asked: the second, full round reuses the first's.
          enum Vote : std::uint8_t { kNotAsked, kNone, kFree, kHit };
          std::vector<std::uint8_t> votes(groups.size());
          for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const Eigen::Vector3d p = T_world_keyframe * points[i].xyz.cast<double>();
            if (!nearMoved(p)) continue;
            std::fill(votes.begin(), votes.end(), kNotAsked);
            const auto voteOf = [&](const Group& g) {
              bool view_hit = false;
              for (std::size_t e = g.begin; e < g.end; ++e) {
                if ((p - eyes[e].origin).squaredNorm() > r2) continue;
                const map::Visibility v = eyes[e].image->classify(eyes[e].T_sensor_world * p);
                if (v == map::Visibility::kFree) return kFree;  // seen through by one of them settles it
                view_hit = view_hit || v == map::Visibility::kHit;
              }
              return view_hit ? kHit : kNone;
            };
            // Votes of the keyframes whose index modulo `stride` is `phase` (stride 1: all of them).
            const auto vote = [&](std::size_t stride, int* free, int* hit) {
              for (std::size_t g = 0; g < groups.size(); ++g) {
                if (groups[g].keyframe % stride != submap % stride) continue;
                if (votes[g] == kNotAsked) votes[g] = voteOf(groups[g]);
                *free += votes[g] == kFree;
                *hit += votes[g] == kHit;
              }
            };
            int free = 0, hit = 0;
            // Nearly every point is static and never seen through: half of the views shows that
            // (a ghost is seen through by most views once its mover has gone); points some view sees
            // through, and points that half sees on at most once (it cannot tell), are asked to all.
            vote(2, &free, &hit);
            if (free > 0 || hit <= 1) {
              free = hit = 0;
              vote(1, &free, &hit);
            }
            judged[i] = free + hit > 0;
            // A ghost is seen through by a fair share of the views that decide on it, not by most:
            // where people pace, later views also see them (or another) back on the same spot; a
            // static surface is seen through only by the rare view whose pose or mixed pixel is off.
            // Where the odometry saw something move in (space earlier views saw empty; kMinMoverReturns
            // returns, not the odd false detection) one such view is evidence enough; elsewhere it takes
            // two, so one off view alone never removes a surface.
            // In such a cell, a point no keyframe's view but at most its own sees there is a ghost too:
            // nothing confirms a surface in space known to have been free (a walker seen from far off in
            // a sweep between keyframes, then hidden or out of view).
            const bool mover_cell = moverReturns(p) >= kMinMoverReturns;
            ghost[i] = (free >= (mover_cell ? 1 : 2) && 2 * free >= hit) || (mover_cell && free == 0 && hit <= 1);
          }
        });
    std::vector<Point> removed;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      ghosts_.judged_points += judged[i];
      if (ghost[i]) {
        removed.push_back(points[i]);
        continue;
      }
      points[kept++] = points[i];
    }
    ghosts_.removed_points += points.size() - kept;
    points.resize(kept);
    if (cfg_.dynamic_map && !removed.empty()) dynamic_.add(removed, T_world_keyframe);
  }
}

std::vector<Point> MappingBackend::lidarMap(const std::string& lidar) const { return mergedMap(&lidar); }

std::vector<std::string> MappingBackend::lidarNames() const {
  std::vector<std::string> names;
  const auto note = [&](const std::string& lidar) {
    if (!lidar.empty() && std::find(names.begin(), names.end(), lidar) == names.end()) names.push_back(lidar);
  };
  for (const Submap& submap : submaps_)
    for (const auto& [lidar, pts] : submap) note(lidar);
  for (const auto& [lidar, acc] : open_) note(lidar);
  return names;
}

std::size_t MappingBackend::keyframes() const { return graph_.size(); }
std::size_t MappingBackend::loops() const { return graph_.loops(); }

LoopFigures MappingBackend::loopFigures() const {
  return {cfg_.loop_enabled, graph_.size(), loop_attempts_, graph_.loops(), rejected_, loops_};
}

}  // namespace mmlio::backend
