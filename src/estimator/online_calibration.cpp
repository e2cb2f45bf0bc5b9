#include "mmlio/estimator/online_calibration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "mmlio/core/so3.hpp"

namespace mmlio::estimator {
namespace {

constexpr int kPose = 6;                 // dp, dtheta (right perturbation, as the LiDAR factors)
constexpr std::size_t kMinMatches = 50;  // per LiDAR in a sweep that informs the calibration
// Tighter than the registration's gate (0.1 m) and robust scale: a lamp under a ceiling, a table's
// edge or a beam lies 3-6 cm from the surface it borders. Matched to it, points above the sensor
// sit high and points below sit low, for both LiDARs alike; as the LiDARs see different shares above
// and below, that biased the refined one's height and tilt. The points are matched where the
// estimate places them, so a tight gate does not hide a large error.
constexpr double kMaxResidualM = 0.03;
constexpr double kHuberM = 0.02;
constexpr double kMaxStepPriorSigmas = 3.0;    // a sweep moving the estimate further is an outlier
constexpr double kRelativeEigenFloor = 1e-9;   // pose directions weaker than this carry nothing
constexpr double kHeldSigma = 1e-6;            // the prior of a quantity kept as given
constexpr int kMinAnchorKeyframes = 5;         // an anchor map smaller than this matches too little of a sweep
constexpr double kIndependentMatches = 100.0;  // a sweep counts as at most this many matches
// A correction is applied once its standard deviation is below these.
constexpr double kDeterminedTimeS = 1e-3;
constexpr double kDeterminedRotationRad = 0.05 * M_PI / 180.0;
constexpr double kDeterminedTranslationM = 3e-3;
// ... or below kRoughly times these when the estimate is more than 3 sigma from what is applied: a
// given calibration that is clearly off is corrected before the motion has pinned the correction down.
constexpr double kRoughly = 3.0;
// Applied mid-run, a height (seen only on floors and ceilings) moves everything mapped after it: it
// is applied only when this much better determined than the other translations.
constexpr double kAppliedHeightStricter = 3.0;
constexpr Eigen::Index kHeight = 5;     // the translation's z in [rotation 3, translation 3, clock]
constexpr double kKeptAfterMove = 0.1;  // of the evidence gathered before the correction moved

/// Every k-th feature of each LiDAR so that none has more than max_per_lidar.
Features thinned(const Features& f, std::size_t lidars, std::size_t max_per_lidar) {
  const auto thin = [&](const std::vector<Eigen::Vector3d>& pts, const std::vector<std::uint8_t>& src,
                        std::vector<Eigen::Vector3d>* out_pts, std::vector<std::uint8_t>* out_src) {
    std::vector<std::size_t> count(lidars, 0), seen(lidars, 0);
    for (std::size_t i = 0; i < pts.size(); ++i) ++count[src.empty() ? 0 : src[i]];
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const std::uint8_t s = src.empty() ? 0 : src[i];
      const std::size_t stride = (count[s] + max_per_lidar - 1) / max_per_lidar;
      if (seen[s]++ % stride != 0) continue;
      out_pts->push_back(pts[i]);
      out_src->push_back(s);
    }
  };
  Features out;
  thin(f.edges, f.edge_source, &out.edges, &out.edge_source);
  thin(f.planes, f.plane_source, &out.planes, &out.plane_source);
  return out;
}

/// Refined LiDAR's extrinsic with correction c (rotation 3, translation 3, clock 1).
Eigen::Isometry3d corrected(const Eigen::Isometry3d& given, const Eigen::Ref<const Eigen::VectorXd>& c) {
  Eigen::Isometry3d T = given;
  T.linear() = so3::exp(Eigen::Vector3d(c.head<3>())).toRotationMatrix() * T.linear();
  T.translation() += c.segment<3>(3);
  return T;
}

/// The body-frame motion over clock correction dt_s at the body's velocity and turn rate.
Eigen::Isometry3d shiftedBy(double dt_s, const Eigen::Vector3d& v_body, const Eigen::Vector3d& w_body) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3::exp(w_body * dt_s).toRotationMatrix();
  T.translation() = v_body * dt_s;
  return T;
}

/// Inverse on the directions the matrix informs, zero on the others.
Eigen::MatrixXd pseudoInverse(const Eigen::MatrixXd& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
  const Eigen::VectorXd& ev = es.eigenvalues();
  const double floor = kRelativeEigenFloor * std::max(ev.maxCoeff(), 0.0);
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(ev.size());
  for (Eigen::Index i = 0; i < ev.size(); ++i)
    if (ev[i] > floor && ev[i] > 0.0) inv[i] = 1.0 / ev[i];
  return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

/// The standard deviation below which correction component i (rotation 3, translation 3, clock) is determined.
double determinedBelow(Eigen::Index i) {
  return i < 3 ? kDeterminedRotationRad : i < 6 ? kDeterminedTranslationM : kDeterminedTimeS;
}

}  // namespace

OnlineCalibration::OnlineCalibration(OnlineCalibrationConfig cfg, std::vector<LidarExtrinsic> lidars,
                                     std::vector<char> refine, int anchor, double map_voxel_m, double lidar_sigma_m,
                                     double map_radius_m)
    : cfg_(cfg),
      given_(std::move(lidars)),
      refine_(std::move(refine)),
      anchor_(anchor),
      lidar_sigma_m_(lidar_sigma_m),
      map_radius_m_(map_radius_m),
      edge_map_(2.5 * map_voxel_m, 60),
      plane_map_(2.5 * map_voxel_m, 60, true) {
  refine_.resize(given_.size(), 0);
  if (anchor_ >= 0) refine_[static_cast<std::size_t>(anchor_)] = 0;
  for (std::size_t i = 0; i < given_.size(); ++i)
    if (refine_[i]) refined_.push_back({i, 0});
  active_ = cfg_.enabled && anchor_ >= 0 && !refined_.empty();
  const double rot = cfg_.prior_sigma_rotation_deg * M_PI / 180.0;
  const auto held = [](double s) { return s > 0 ? s : kHeldSigma; };
  const double across = held(cfg_.prior_sigma_translation_m), up = held(cfg_.prior_sigma_translation_z_m);
  Vec sigma;
  sigma << rot, rot, rot, across, across, up, cfg_.prior_sigma_time_s;
  prior_info_ = sigma.cwiseInverse().cwiseAbs2().asDiagonal();
  const auto n = static_cast<Eigen::Index>(kParams * refined_.size());
  x_ = estimate_ = info_x_ = Eigen::VectorXd::Zero(n);
  info_ = priorInfo();
}

Eigen::Isometry3d OnlineCalibration::extrinsic(std::size_t lidar) const {
  for (std::size_t j = 0; j < refined_.size(); ++j)
    if (refined_[j].lidar == lidar && active_)
      return corrected(given_[lidar].T_imu_sensor, x_.segment<kParams>(kParams * j));
  return given_[lidar].T_imu_sensor;
}

Eigen::Isometry3d OnlineCalibration::clockShift(std::size_t lidar, const Eigen::Vector3d& v_body,
                                                const Eigen::Vector3d& w_body) const {
  for (std::size_t j = 0; j < refined_.size(); ++j)
    if (refined_[j].lidar == lidar && active_)
      return shiftedBy(x_[static_cast<Eigen::Index>(kParams * j + 6)], v_body, w_body);
  return Eigen::Isometry3d::Identity();
}

Features OnlineCalibration::placedAtEstimate(Features f, const Eigen::Vector3d& v_body,
                                             const Eigen::Vector3d& w_body) const {
  for (std::size_t j = 0; j < refined_.size(); ++j) {
    const auto k = static_cast<Eigen::Index>(kParams * j);
    const std::size_t lidar = refined_[j].lidar;
    const Eigen::Isometry3d applied = clockShift(lidar, v_body, w_body) * extrinsic(lidar);
    const Eigen::Isometry3d estimated = shiftedBy(estimate_[k + 6], v_body, w_body) *
                                        corrected(given_[lidar].T_imu_sensor, estimate_.segment<kParams>(k));
    const Eigen::Isometry3d move = estimated * applied.inverse();
    const auto source = static_cast<std::uint8_t>(lidar);
    for (std::size_t i = 0; i < f.planes.size(); ++i)
      if (f.plane_source[i] == source) f.planes[i] = move * f.planes[i];
    for (std::size_t i = 0; i < f.edges.size(); ++i)
      if (f.edge_source[i] == source) f.edges[i] = move * f.edges[i];
  }
  return f;
}

void OnlineCalibration::addAnchorKeyframe(const Features& f, const Eigen::Isometry3d& T_world_body) {
  if (!active_) return;
  const auto fromAnchor = [&](const std::vector<Eigen::Vector3d>& pts, const std::vector<std::uint8_t>& src) {
    std::vector<Eigen::Vector3d> world;
    world.reserve(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i)
      if ((src.empty() ? 0 : src[i]) == anchor_) world.push_back(T_world_body * pts[i]);
    return world;
  };
  edge_map_.add(fromAnchor(f.edges, f.edge_source));
  plane_map_.add(fromAnchor(f.planes, f.plane_source));
  edge_map_.removeFarFrom(T_world_body.translation(), map_radius_m_);
  plane_map_.removeFarFrom(T_world_body.translation(), map_radius_m_);
  plane_map_.refitPlanes();
  ++anchor_keyframes_;
}

bool OnlineCalibration::observe(const Features& f, const Eigen::Isometry3d& T_world_body, const Eigen::Vector3d& v_body,
                                const Eigen::Vector3d& w_body, Stamp stamp_ns) {
  if (!active_ || anchor_keyframes_ < kMinAnchorKeyframes) return false;
  MapMatchConfig matching;
  matching.max_residual_m = kMaxResidualM;
  matching.voxel_plane_gate_m = kMaxResidualM;
  // The refined LiDARs' points where the estimate puts them: the sweep is linearised at the estimate.
  const std::vector<MapMatch> matches =
      findMapMatches(placedAtEstimate(thinned(f, given_.size(), kMatchedPerLidar), v_body, w_body), T_world_body,
                     edge_map_, plane_map_, matching);

  std::vector<int> block(given_.size(), -1);  // column of each refined LiDAR's correction
  std::vector<Eigen::Vector3d> origin(given_.size(), Eigen::Vector3d::Zero());  // its sensor origin, IMU frame
  for (std::size_t j = 0; j < refined_.size(); ++j) {
    block[refined_[j].lidar] = kPose + static_cast<int>(kParams * j);
    origin[refined_[j].lidar] =
        corrected(given_[refined_[j].lidar].T_imu_sensor, estimate_.segment<kParams>(kParams * j)).translation();
  }
  std::vector<std::size_t> per_lidar(given_.size(), 0);
  const auto n = static_cast<Eigen::Index>(kPose + x_.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  const Eigen::Matrix3d R = T_world_body.linear();
  using Row = Eigen::Matrix<double, 1, kPose + kParams>;  // a residual's pose and own-correction columns
  const auto accumulate = [&](const Row& j, double r, double w, int own) {
    const Row wj = w * j;
    H.topLeftCorner<kPose, kPose>().noalias() += wj.head<kPose>().transpose() * j.head<kPose>();
    g.head<kPose>() += wj.head<kPose>().transpose() * r;
    if (own < 0) return;
    H.block<kParams, kParams>(own, own).noalias() += wj.tail<kParams>().transpose() * j.tail<kParams>();
    H.block<kParams, kPose>(own, 0).noalias() += wj.tail<kParams>().transpose() * j.head<kPose>();
    H.block<kPose, kParams>(0, own).noalias() += wj.head<kPose>().transpose() * j.tail<kParams>();
    g.segment<kParams>(own) += wj.tail<kParams>().transpose() * r;
  };
  for (const MapMatch& m : matches) {
    const int own = block[m.source];
    if (m.source != anchor_ && own < 0) continue;
    ++per_lidar[m.source];
    Eigen::Matrix3d A;  // rows: d residual / d world point (a plane uses the first)
    Eigen::Vector3d r;
    int rows = 3;
    const Eigen::Vector3d q = T_world_body * m.p_body;
    if (m.kind == MapMatch::Kind::kPlane) {
      A.row(0) = m.a.transpose();
      r[0] = m.a.dot(q) + m.b.x();
      rows = 1;
    } else {
      const Eigen::Vector3d u = m.b.normalized();
      A = Eigen::Matrix3d::Identity() - u * u.transpose();
      r = A * (q - m.a);
    }
    const double norm = r.head(rows).norm();
    const double w = (norm <= kHuberM ? 1.0 : kHuberM / norm) / (lidar_sigma_m_ * lidar_sigma_m_);
    const Eigen::Matrix3d AR = A * R;
    const Eigen::Matrix3d lever_hat = own >= 0 ? so3::hat(m.p_body - origin[m.source]) : Eigen::Matrix3d::Zero();
    const Eigen::Vector3d clock = w_body.cross(m.p_body) + v_body;
    for (int i = 0; i < rows; ++i) {
      Row j = Row::Zero();
      j.head<3>() = A.row(i);
      j.segment<3>(3) = -AR.row(i) * so3::hat(m.p_body);
      if (own >= 0) {
        j.segment<3>(kPose) = -AR.row(i) * lever_hat;
        j.segment<3>(kPose + 3) = AR.row(i);
        j[kPose + 6] = AR.row(i).dot(clock);
      }
      accumulate(j, r[i], w, own);
    }
  }
  if (per_lidar[static_cast<std::size_t>(anchor_)] < kMinMatches) return false;
  for (const Refined& rf : refined_)
    if (per_lidar[rf.lidar] < kMinMatches) return false;
  // Map and association errors are shared by neighbouring matches: a sweep counts as at most
  // kIndependentMatches independent ones.
  std::size_t total = 0;
  for (std::size_t c : per_lidar) total += c;
  const double scale = std::min(1.0, kIndependentMatches / static_cast<double>(total));
  H *= scale;
  g *= scale;

  // The pose eliminated: what the sweep says about the corrections whatever its pose.
  const Eigen::MatrixXd Hpp_inv = pseudoInverse(H.topLeftCorner(kPose, kPose));
  const Eigen::MatrixXd Hcp = H.bottomLeftCorner(n - kPose, kPose);
  const Eigen::MatrixXd H_calib = H.bottomRightCorner(n - kPose, n - kPose) - Hcp * Hpp_inv * Hcp.transpose();
  const Eigen::VectorXd b_calib = -(g.tail(n - kPose) - Hcp * Hpp_inv * g.head(kPose));

  // Information form: the sweep measured the corrections beyond the estimate its points were placed with.
  const double fade = last_ns_ == 0 ? 1.0 : std::exp(-toSec(stamp_ns - last_ns_) / cfg_.memory_s);
  const Eigen::MatrixXd prior = priorInfo();
  const Eigen::MatrixXd info = fade * info_ + (1.0 - fade) * prior + H_calib;
  const Eigen::VectorXd info_x = fade * info_x_ + H_calib * estimate_ + b_calib;
  const Eigen::VectorXd estimate = info.ldlt().solve(info_x);
  if (!estimate.allFinite()) return false;
  const Eigen::VectorXd prior_sigma = prior.diagonal().cwiseInverse().cwiseSqrt();
  if (((estimate - estimate_).cwiseAbs().array() > kMaxStepPriorSigmas * prior_sigma.array()).any()) return false;
  info_ = info;
  info_x_ = info_x;
  estimate_ = estimate;
  last_ns_ = stamp_ns;
  for (Refined& rf : refined_) ++rf.sweeps;
  applyDetermined();
  return true;
}

Eigen::MatrixXd OnlineCalibration::priorInfo() const {
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(x_.size(), x_.size());
  for (std::size_t j = 0; j < refined_.size(); ++j)
    prior.block<kParams, kParams>(kParams * j, kParams * j) = prior_info_;
  return prior;
}

// A correction is applied once the motion has determined it (or shown the given value clearly
// wrong): before, a clock error and a shift along the way the rig moves look alike, and a guess
// between them would go into the map.
void OnlineCalibration::applyDetermined() {
  if (!cfg_.apply) return;
  const Eigen::VectorXd sigma =
      info_.ldlt().solve(Eigen::MatrixXd::Identity(x_.size(), x_.size())).diagonal().cwiseSqrt();
  const Eigen::VectorXd before = x_;
  for (std::size_t j = 0; j < refined_.size(); ++j) {
    const auto k = static_cast<Eigen::Index>(kParams * j);
    for (Eigen::Index i = 0; i < kParams; ++i) {
      const double threshold = i == kHeight ? determinedBelow(i) / kAppliedHeightStricter : determinedBelow(i);
      const double s = sigma[k + i], change = std::abs(estimate_[k + i] - x_[k + i]);
      if (s <= threshold || (s <= kRoughly * threshold && change > 3.0 * s)) x_[k + i] = estimate_[k + i];
    }
  }
  // Sweeps whose points sat far from where the correction now puts them measured it through the
  // matching's robust loss and gate, which shrink large errors: once the points have moved by
  // more than the estimate's uncertainty, the evidence gathered before counts for less.
  if (((x_ - before).cwiseAbs().array() > 3.0 * sigma.array()).any()) {
    const Eigen::MatrixXd prior = priorInfo();
    info_ = prior + kKeptAfterMove * (info_ - prior);
    info_x_ = info_ * estimate_;
  }
}

std::vector<LidarCalibrationEstimate> OnlineCalibration::estimates() const {
  std::vector<LidarCalibrationEstimate> out;
  if (!active_) return out;
  const Eigen::VectorXd sigma =
      info_.ldlt().solve(Eigen::MatrixXd::Identity(x_.size(), x_.size())).diagonal().cwiseSqrt();
  for (std::size_t j = 0; j < refined_.size(); ++j) {
    const auto k = static_cast<Eigen::Index>(kParams * j);
    LidarCalibrationEstimate e;
    e.sensor = given_[refined_[j].lidar].name;
    e.rotation_rad = x_.segment<3>(k);
    e.translation_m = x_.segment<3>(k + 3);
    e.time_offset_s = x_[k + 6];
    e.estimate_rotation_rad = estimate_.segment<3>(k);
    e.estimate_translation_m = estimate_.segment<3>(k + 3);
    e.estimate_time_offset_s = estimate_[k + 6];
    Vec settled;
    for (Eigen::Index i = 0; i < kParams; ++i)
      settled[i] = sigma[k + i] <= kRoughly * determinedBelow(i) ? estimate_[k + i] : x_[k + i];
    e.settled_rotation_rad = settled.head<3>();
    e.settled_translation_m = settled.segment<3>(3);
    e.settled_time_offset_s = settled[6];
    e.rotation_sigma_rad = sigma.segment<3>(k);
    e.translation_sigma_m = sigma.segment<3>(k + 3);
    e.time_offset_sigma_s = sigma[k + 6];
    e.sweeps = refined_[j].sweeps;
    out.push_back(e);
  }
  return out;
}

}  // namespace mmlio::estimator
