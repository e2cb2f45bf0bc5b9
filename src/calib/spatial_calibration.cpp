#include "mmlio/calib/spatial_calibration.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "mmlio/core/short_number.hpp"
#include "mmlio/core/so3.hpp"

namespace mmlio::calib {
namespace {

constexpr double kDeg = M_PI / 180.0;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

std::vector<Eigen::Vector3d> inRange(const std::vector<Eigen::Vector3d>& pts, double min_m, double max_m) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(pts.size());
  for (const auto& p : pts) {
    const double r = p.norm();
    if (p.allFinite() && r >= min_m && r <= max_m) out.push_back(p);
  }
  return out;
}

/// Spinning points (spinning frame) that T_solid_spinning puts inside the solid FOV (+ margin) as
/// seen from one of `views` (the solid-state LiDAR's poses in its start frame).
std::vector<Eigen::Vector3d> cropToSolidView(const std::vector<Eigen::Vector3d>& spinning,
                                             const Eigen::Isometry3d& T_solid_spinning,
                                             const std::vector<Eigen::Isometry3d>& views,
                                             const SpatialCalibrationConfig& cfg) {
  const double half_h = (0.5 * cfg.solid_fov_horizontal_deg + cfg.fov_margin_deg) * kDeg;
  const double half_v = (0.5 * cfg.solid_fov_vertical_deg + cfg.fov_margin_deg) * kDeg;
  std::vector<Eigen::Isometry3d> from_start;
  from_start.reserve(views.size());
  for (const Eigen::Isometry3d& v : views) from_start.push_back(v.inverse() * T_solid_spinning);
  const auto inView = [&](const Eigen::Vector3d& q) {
    return q.x() > 0 &&  // the solid-state LiDAR looks along +x
           std::abs(std::atan2(q.y(), q.x())) <= half_h && std::abs(std::atan2(q.z(), q.head<2>().norm())) <= half_v;
  };
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : spinning)
    if (std::any_of(from_start.begin(), from_start.end(), [&](const Eigen::Isometry3d& T) { return inView(T * p); }))
      out.push_back(p);
  return out;
}

/// The nearest return of the solid-state LiDAR per direction (azimuth, elevation bins of its frame),
/// for each frame it looked from: what it saw through. A spinning point well in front of that
/// return lies in space the solid-state LiDAR saw as empty, which a right extrinsic cannot produce
/// (but for the sensors' small parallax). Free space seen from anywhere is free: every frame's own
/// rays count, not only the start's.
class SeenThrough {
 public:
  SeenThrough(const std::vector<SolidView::Frame>& frames, const SpatialCalibrationConfig& cfg)
      : half_h_((0.5 * cfg.solid_fov_horizontal_deg + cfg.fov_margin_deg) * kDeg),
        half_v_((0.5 * cfg.solid_fov_vertical_deg + cfg.fov_margin_deg) * kDeg),
        bin_(cfg.seen_through_bin_deg * kDeg),
        cols_(static_cast<int>(std::ceil(2 * half_h_ / bin_))),
        rows_(static_cast<int>(std::ceil(2 * half_v_ / bin_))),
        margin_m_(cfg.seen_through_margin_m),
        margin_frac_(cfg.seen_through_margin_fraction) {
    for (const SolidView::Frame& f : frames) views_.push_back({f.T_start_sensor.inverse(), nearestReturns(f.returns)});
  }

  /// Fraction of `spinning` (spinning frame) that T_solid_spinning puts in front of the solid-state
  /// LiDAR's nearest return in its direction from one of the frames, among the points whose
  /// direction a frame saw a return in.
  double fraction(const std::vector<Eigen::Vector3d>& spinning, const Eigen::Isometry3d& T_solid_spinning) const {
    std::vector<Eigen::Isometry3d> T_sensor_spinning;
    for (const View& v : views_) T_sensor_spinning.push_back(v.T_sensor_start * T_solid_spinning);
    int seen = 0, through = 0;
    for (const auto& p : spinning) {
      bool seen_here = false, through_here = false;
      for (std::size_t k = 0; k < views_.size() && !through_here; ++k) {
        const Eigen::Vector3d q = T_sensor_spinning[k] * p;
        const int i = index(q);
        if (i < 0 || !std::isfinite(views_[k].nearest[i])) continue;
        seen_here = true;
        const double r = q.norm();
        through_here = views_[k].nearest[i] > r + margin_m_ + margin_frac_ * r;
      }
      seen += seen_here;
      through += through_here;
    }
    return seen > 0 ? static_cast<double>(through) / seen : 0.0;
  }

 private:
  struct View {
    Eigen::Isometry3d T_sensor_start;
    std::vector<float> nearest;
  };

  std::vector<float> nearestReturns(const std::vector<Eigen::Vector3d>& returns) const {
    const std::size_t bins = static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_);
    std::vector<float> own(bins, std::numeric_limits<float>::infinity()), nearest(own);
    for (const auto& q : returns) {
      const int i = index(q);
      if (i >= 0) own[i] = std::min(own[i], static_cast<float>(q.norm()));
    }
    // The nearest over each bin and its neighbours: at an occluding edge the pattern may have
    // sampled only the background in the edge's own bin.
    for (int r = 0; r < rows_; ++r)
      for (int c = 0; c < cols_; ++c)
        for (int dr = std::max(0, r - 1); dr <= std::min(rows_ - 1, r + 1); ++dr)
          for (int dc = std::max(0, c - 1); dc <= std::min(cols_ - 1, c + 1); ++dc)
            nearest[r * cols_ + c] = std::min(nearest[r * cols_ + c], own[dr * cols_ + dc]);
    return nearest;
  }

  int index(const Eigen::Vector3d& q) const {
    if (q.x() <= 0) return -1;
    const double az = std::atan2(q.y(), q.x()), el = std::atan2(q.z(), q.head<2>().norm());
    const int c = static_cast<int>((az + half_h_) / bin_), r = static_cast<int>((el + half_v_) / bin_);
    if (az < -half_h_ || el < -half_v_ || c >= cols_ || r >= rows_) return -1;
    return r * cols_ + c;
  }

  double half_h_, half_v_, bin_;
  int cols_, rows_;
  double margin_m_, margin_frac_;
  std::vector<View> views_;
};

bool sameMount(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const SpatialCalibrationConfig& cfg) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return d.translation().norm() <= cfg.distinct_translation_m &&
         Eigen::AngleAxisd(d.rotation()).angle() <= cfg.distinct_rotation_deg * kDeg;
}

double yawDeg(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d x = T.linear().col(0);
  return std::atan2(x.y(), x.x()) / kDeg;
}

GicpConfig fineOnly(GicpConfig g) {
  g.levels = 1;
  g.max_corr_dist_coarse_m = g.max_corr_dist_fine_m;
  return g;
}

/// How far `to` lies from `from`: (translation difference, rotation to . from^-1 as a vector).
Vector6d moveBetween(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) {
  Vector6d d;
  d << to.translation() - from.translation(), so3::log(Eigen::Quaterniond(to.linear() * from.linear().transpose()));
  return d;
}

/// The frames' returns in the start frame, thinned to voxel_m: those of the frames `keep` keeps.
template <typename Keep> std::vector<Eigen::Vector3d> inStartFrame(const std::vector<SolidView::Frame>& frames,
                                                                   double voxel_m, const Keep& keep) {
  std::vector<Eigen::Vector3d> out;
  for (std::size_t f = 0; f < frames.size(); ++f)
    if (keep(f))
      for (const Eigen::Vector3d& p : frames[f].returns) out.push_back(frames[f].T_start_sensor * p);
  return map::voxelCentroids(out, voxel_m);
}

/// The delete-a-group jackknife's covariance of the mount T over `groups` registrations, the k-th
/// (fit_without(k)) without group k.
template <typename FitWithout>
Matrix6d jackknife(const Eigen::Isometry3d& T, int groups, const FitWithout& fit_without, int min_inliers) {
  std::vector<Vector6d> moves;
  for (int k = 0; k < groups; ++k) {
    const GicpResult g = fit_without(k);
    if (g.inliers >= min_inliers) moves.push_back(moveBetween(T, g.T_target_source));
  }
  if (moves.size() < 2) return Matrix6d::Zero();
  Vector6d mean = Vector6d::Zero();
  for (const Vector6d& d : moves) mean += d;
  mean /= static_cast<double>(moves.size());
  Matrix6d cov = Matrix6d::Zero();
  for (const Vector6d& d : moves) cov += (d - mean) * (d - mean).transpose();
  const double n = static_cast<double>(moves.size());
  return cov * (n - 1) / n;
}

/// GICP runs from given mounts on the spinning points each puts in view, judged as the
/// calibration judges them, and the yaw search built of them.
class MountSearch {
 public:
  struct Attempt {
    GicpResult gicp;
    int source_points = 0;
    double seen_through = 0;
  };

  MountSearch(const std::vector<Eigen::Vector3d>& spinning, std::vector<Eigen::Vector3d> solid,
              const std::vector<SolidView::Frame>& frames, const SpatialCalibrationConfig& cfg)
      : spinning_(spinning), solid_(std::move(solid), cfg.gicp), cfg_(cfg), seen_through_(frames, cfg) {
    for (const SolidView::Frame& f : frames) views_.push_back(f.T_start_sensor);
  }

  /// One GICP run from an initial T_solid_spinning, on the spinning points that fall in the view.
  Attempt attempt(const Eigen::Isometry3d& init) const {
    Attempt a;
    const auto source = cropToSolidView(spinning_, init, views_, cfg_);
    a.source_points = static_cast<int>(source.size());
    if (a.source_points < cfg_.min_points) return a;
    a.gicp = gicp(source, solid_, init, cfg_.gicp);
    a.seen_through = seen_through_.fraction(spinning_, a.gicp.T_target_source);
    return a;
  }

  bool agrees(const Attempt& a) const { return a.gicp.converged && fits(a); }
  /// The clouds agree, whether or not GICP's last step was still moving by a hair.
  bool fits(const Attempt& a) const {
    return a.gicp.inliers >= cfg_.gicp.min_correspondences &&
           cloudsAgree(a.gicp.fitness_m, a.gicp.overlap, a.seen_through, cfg_);
  }

  /// The stated uncertainty of the mount T (see SpatialCalibrationResult::covariance), on the
  /// spinning points it puts in view.
  Matrix6d covariance(const Eigen::Isometry3d& T, const std::vector<SolidView::Frame>& frames) const {
    const std::vector<Eigen::Vector3d> source = cropToSolidView(spinning_, T, views_, cfg_);
    Matrix6d cov = stripJackknife(T, source) + halvesDisagreement(T, source, frames);
    cov.diagonal().head<3>().array() += std::pow(cfg_.sigma_floor_translation_m, 2);
    cov.diagonal().tail<3>().array() += std::pow(cfg_.sigma_floor_rotation_deg * kDeg, 2);
    return cov;
  }

  /// How much the mount found depends on which part of the scene it stands on: GICP again from it
  /// with each of cfg.sigma_groups azimuth strips of the spinning points in view left out.
  Matrix6d stripJackknife(const Eigen::Isometry3d& T, const std::vector<Eigen::Vector3d>& source) const {
    std::vector<std::pair<double, std::size_t>> by_azimuth;
    by_azimuth.reserve(source.size());
    for (std::size_t i = 0; i < source.size(); ++i) {
      const Eigen::Vector3d q = T * source[i];
      by_azimuth.emplace_back(std::atan2(q.y(), q.x()), i);
    }
    std::sort(by_azimuth.begin(), by_azimuth.end());
    const std::size_t n = by_azimuth.size();
    const int groups = cfg_.sigma_groups;
    const auto without = [&](int k) {
      const std::size_t begin = n * k / groups, end = n * (k + 1) / groups;
      std::vector<Eigen::Vector3d> kept;
      kept.reserve(n);
      for (std::size_t j = 0; j < n; ++j)
        if (j < begin || j >= end) kept.push_back(source[by_azimuth[j].second]);
      return gicp(kept, solid_, T, fineOnly(cfg_.gicp));
    };
    return jackknife(T, groups, without, cfg_.gicp.min_correspondences);
  }

  /// Where the solid-state view is frames placed by odometry, their placement's drift: the mount
  /// found on the start and the earlier half of the moving frames against the one found on the
  /// start and the later half (the drift grows along the way; what it moves the mount by, both
  /// halves share in part, so the whole difference is stated, not half of it).
  Matrix6d halvesDisagreement(const Eigen::Isometry3d& T, const std::vector<Eigen::Vector3d>& source,
                              const std::vector<SolidView::Frame>& frames) const {
    const std::size_t moving = frames.size() - 1;
    if (frames.size() < 3) return Matrix6d::Zero();
    std::optional<Eigen::Isometry3d> half[2];
    for (std::size_t h = 0; h < 2; ++h) {
      const GicpTarget target(
          inStartFrame(frames, cfg_.target_voxel_m, [&](std::size_t f) { return f == 0 || 2 * (f - 1) / moving == h; }),
          cfg_.gicp);
      const GicpResult g = gicp(source, target, T, fineOnly(cfg_.gicp));
      if (g.inliers >= cfg_.gicp.min_correspondences) half[h] = g.T_target_source;
    }
    if (!half[0] || !half[1]) return Matrix6d::Zero();
    return Matrix6d(moveBetween(*half[0], *half[1]).cwiseAbs2().asDiagonal());
  }

  /// Matched points not seen through: what ranks the finalists.
  static double explained(const Attempt& a) { return a.gicp.inliers * (1.0 - a.seen_through); }

  /// GICP from every yaw_step_deg about the solid-state LiDAR's vertical axis (the guess's
  /// translation and tilt kept), then the best distinct results measured again: agreeing ones
  /// first, by points explained.
  std::vector<Attempt> finalists(const std::optional<Eigen::Isometry3d>& guess) const {
    const Eigen::Vector3d t0 = guess ? Eigen::Vector3d(guess->translation()) : Eigen::Vector3d::Zero();
    const Eigen::Matrix3d R0 = guess ? Eigen::Matrix3d(guess->linear()) : Eigen::Matrix3d::Identity();
    const int steps = std::max(1, static_cast<int>(std::round(360.0 / cfg_.yaw_step_deg)));
    std::vector<Attempt> tried;
    for (int i = 0; i < steps; ++i) {
      Eigen::Isometry3d init = Eigen::Isometry3d::Identity();
      init.linear() = Eigen::AngleAxisd(i * 2 * M_PI / steps, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R0;
      init.translation() = t0;
      Attempt a = attempt(init);
      if (a.gicp.converged) tried.push_back(std::move(a));
    }
    // A start's matched fraction counts only the points that start put in view: a wrong one with few
    // points in view can match nearly all of them. The best few are measured again on the view
    // their own result gives, and compared by how many points they explain.
    std::stable_sort(tried.begin(), tried.end(), [](const Attempt& a, const Attempt& b) {
      return a.gicp.overlap / std::max(a.gicp.fitness_m, 1e-4) > b.gicp.overlap / std::max(b.gicp.fitness_m, 1e-4);
    });
    std::vector<Attempt> out;
    for (const Attempt& a : tried) {
      if (static_cast<int>(out.size()) >= cfg_.yaw_finalists) break;
      Attempt m = attempt(a.gicp.T_target_source);
      // Started where GICP settled once, it is a measurement: it stands on enough correspondences
      // (flickering at the fine gate, or sliding along a wall, it may not pass the strict test).
      m.gicp.converged = m.gicp.inliers >= cfg_.gicp.min_correspondences;
      if (!m.gicp.converged) continue;
      const bool known = std::any_of(out.begin(), out.end(), [&](const Attempt& f) {
        return sameMount(f.gicp.T_target_source, m.gicp.T_target_source, cfg_);
      });
      if (!known) out.push_back(std::move(m));
    }
    std::stable_sort(out.begin(), out.end(), [&](const Attempt& a, const Attempt& b) {
      if (agrees(a) != agrees(b)) return agrees(a);
      return explained(a) > explained(b);
    });
    return out;
  }

 private:
  const std::vector<Eigen::Vector3d>& spinning_;
  const GicpTarget solid_;
  std::vector<Eigen::Isometry3d> views_;
  const SpatialCalibrationConfig& cfg_;
  SeenThrough seen_through_;
};

}  // namespace

bool cloudsAgree(double fitness_m, double overlap, double seen_through, const SpatialCalibrationConfig& cfg) {
  return fitness_m <= cfg.max_fitness_m && overlap >= cfg.min_overlap && seen_through <= cfg.max_seen_through;
}

SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning,
                                                  const std::vector<Eigen::Vector3d>& solid,
                                                  const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg) {
  SolidView view;
  view.frames.push_back({Eigen::Isometry3d::Identity(), solid});
  return calibrateSpinningToSolid(spinning, view, guess, cfg);
}

SpatialCalibrationResult calibrateSpinningToSolid(const std::vector<Eigen::Vector3d>& spinning_in,
                                                  const SolidView& view, const std::optional<Eigen::Isometry3d>& guess,
                                                  const SpatialCalibrationConfig& cfg) {
  using Refusal = SpatialCalibrationResult::Refusal;
  SpatialCalibrationResult res;
  // Each frame's returns in range, thinned; together, in the start frame, the cloud registered onto.
  std::vector<SolidView::Frame> frames;
  for (const SolidView::Frame& f : view.frames)
    frames.push_back({f.T_start_sensor,
                      map::voxelCentroids(inRange(f.returns, cfg.min_range_m, cfg.max_range_m), cfg.target_voxel_m)});
  std::vector<Eigen::Vector3d> solid;
  // The still start alone is its own cloud (already thinned; thinning it again would reorder it).
  if (frames.size() == 1 && frames[0].T_start_sensor.isApprox(Eigen::Isometry3d::Identity())) {
    solid = frames[0].returns;
  } else {
    solid = inStartFrame(frames, cfg.target_voxel_m, [](std::size_t) { return true; });
  }
  const auto spinning = map::voxelCentroids(inRange(spinning_in, cfg.min_range_m, cfg.max_range_m), cfg.source_voxel_m);
  res.solid_points = static_cast<int>(solid.size());
  if (static_cast<int>(solid.size()) < cfg.min_points || static_cast<int>(spinning.size()) < cfg.min_points) {
    res.refusal = Refusal::kTooFewPoints;
    res.message = "too few points to calibrate (solid-state " + std::to_string(solid.size()) + ", spinning " +
                  std::to_string(spinning.size()) + " within " + shortNumber(cfg.min_range_m) + "-" +
                  shortNumber(cfg.max_range_m) + " m; need " + std::to_string(cfg.min_points) +
                  "): is either LiDAR blocked or missing at the start?";
    return res;
  }

  const std::size_t solid_points = solid.size();
  const MountSearch search(spinning, std::move(solid), frames, cfg);
  MountSearch::Attempt best;
  if (guess) best = search.attempt(*guess);
  if (guess && search.fits(best) && cfg.probe_quarter_turns) {
    // A guess that fits is not yet the mount: in a view alike turned by a quarter, a guess a
    // quarter turn off fits as well. Its turns that fit about as well make the view ambiguous.
    for (int k = 1; k < 4; ++k) {
      Eigen::Isometry3d turned = *guess;
      turned.linear() = Eigen::AngleAxisd(k * M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() * guess->linear();
      const MountSearch::Attempt a = search.attempt(turned);
      if (!search.fits(a) || sameMount(a.gicp.T_target_source, best.gicp.T_target_source, cfg) ||
          MountSearch::explained(a) < cfg.ambiguity_ratio * MountSearch::explained(best))
        continue;
      res.T_solid_spinning = best.gicp.T_target_source;
      res.spinning_points = best.source_points;
      res.refusal = Refusal::kAmbiguous;
      res.message = "two mounts fit the start about equally (the one given, spinning LiDAR yaw " +
                    shortNumber(yawDeg(best.gicp.T_target_source)) +
                    " deg in the solid-state frame, and it turned to " + shortNumber(yawDeg(a.gicp.T_target_source)) +
                    " deg): the start's view looks alike turned";
      return res;
    }
  }
  if (!search.agrees(best) && cfg.yaw_search) {
    res.yaw_searched = true;
    const std::vector<MountSearch::Attempt> finalists = search.finalists(guess);
    for (const MountSearch::Attempt& f : finalists) {
      res.candidates.push_back({f.gicp.T_target_source, yawDeg(f.gicp.T_target_source), f.gicp.fitness_m,
                                f.gicp.overlap, f.gicp.inliers, f.source_points, f.seen_through, search.agrees(f)});
    }
    if (!finalists.empty()) best = finalists.front();
    if (finalists.size() >= 2 && search.agrees(finalists[0]) && search.agrees(finalists[1]) &&
        MountSearch::explained(finalists[1]) >= cfg.ambiguity_ratio * MountSearch::explained(finalists[0])) {
      res.T_solid_spinning = finalists[0].gicp.T_target_source;
      res.spinning_points = finalists[0].source_points;
      res.refusal = Refusal::kAmbiguous;
      res.message = "two mounts fit the start about equally (spinning LiDAR yaw " +
                    shortNumber(yawDeg(finalists[0].gicp.T_target_source)) + " and " +
                    shortNumber(yawDeg(finalists[1].gicp.T_target_source)) +
                    " deg in the solid-state frame): give a rough T_imu_sensor for the spinning LiDAR "
                    "(within 30 deg), or start the bag where the view is not symmetric";
      return res;
    }
  }

  const GicpResult& g = best.gicp;
  res.T_solid_spinning = g.T_target_source;
  res.fitness_m = g.fitness_m;
  res.overlap = g.overlap;
  res.spinning_points = best.source_points;
  res.hessian = g.hessian;
  res.seen_through = best.seen_through;
  if (best.source_points < cfg.min_points) {
    res.refusal = Refusal::kNoOverlap;
    res.message = "the spinning LiDAR sees fewer than " + std::to_string(cfg.min_points) +
                  " points inside the solid-state field of view: the two LiDARs do not overlap enough";
    return res;
  }
  if (!g.converged) {
    res.refusal = Refusal::kNotConverged;
    res.message = "GICP did not converge (" + std::to_string(g.inliers) +
                  " correspondences): give a rough "
                  "T_imu_sensor for the spinning LiDAR in the config, or start the bag facing a structured scene";
    return res;
  }
  if (best.seen_through > cfg.max_seen_through) {
    res.refusal = Refusal::kSeenThrough;
    res.message = shortNumber(100 * best.seen_through, 2) +
                  " % of the spinning points in view lie where the solid-state "
                  "LiDAR sees through (at most " +
                  shortNumber(100 * cfg.max_seen_through, 2) +
                  " %): no mount explains both views; check that both LiDARs see the same scene at the start";
    return res;
  }
  if (g.fitness_m > cfg.max_fitness_m || g.overlap < cfg.min_overlap) {
    res.refusal = Refusal::kDisagree;
    res.message = "GICP fitness " + shortNumber(g.fitness_m) + " m, overlap " + shortNumber(g.overlap) +
                  " (need <= " + shortNumber(cfg.max_fitness_m) + " m, >= " + shortNumber(cfg.min_overlap) +
                  "): the clouds do not agree; check that the rig stood still and both LiDARs see the same scene";
    return res;
  }
  // A single wall (or two parallel ones) in the overlap leaves translations along it free: the
  // alignment then only looks good. Compare the weakest translation direction with the strongest.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(g.hessian.topLeftCorner<3, 3>());
  const double conditioning = es.eigenvalues()(0) / std::max(es.eigenvalues()(2), 1e-12);
  if (conditioning < cfg.min_translation_conditioning) {
    res.refusal = Refusal::kDegenerate;
    res.message = "the overlapping region constrains the extrinsic poorly (translation conditioning " +
                  shortNumber(conditioning) + " < " + shortNumber(cfg.min_translation_conditioning) +
                  "): start the bag facing a corner or furniture, not a single wall";
    return res;
  }
  res.ok = true;
  res.covariance = search.covariance(g.T_target_source, frames);
  res.message = "GICP fitness " + shortNumber(g.fitness_m) + " m, overlap " + shortNumber(g.overlap) +
                ", conditioning " + shortNumber(conditioning) + " on " + std::to_string(best.source_points) +
                " spinning / " + std::to_string(solid_points) + " solid-state points" +
                (res.yaw_searched ? " (yaw search)" : "");
  return res;
}

}  // namespace mmlio::calib
