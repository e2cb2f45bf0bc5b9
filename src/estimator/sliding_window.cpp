#include "mmlio/estimator/sliding_window.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <unordered_map>

#include "mmlio/estimator/imu_factor.hpp"
#include "mmlio/estimator/marginalization.hpp"
#include "mmlio/estimator/pose_manifold.hpp"

namespace mmlio::estimator {

StateBlocks toBlocks(const NavState& s) {
  StateBlocks b;
  Eigen::Map<Eigen::Vector3d>(b.pose) = s.p_world;
  Eigen::Map<Eigen::Quaterniond>(b.pose + 3) = s.q_world_body.normalized();
  Eigen::Map<Eigen::Vector3d>(b.speed_bias) = s.v_world;
  Eigen::Map<Eigen::Vector3d>(b.speed_bias + 3) = s.bias.acc_m_s2;
  Eigen::Map<Eigen::Vector3d>(b.speed_bias + 6) = s.bias.gyro_rad_s;
  return b;
}

NavState fromBlocks(const StateBlocks& b, Stamp stamp) {
  NavState s;
  s.stamp_ns = stamp;
  s.p_world = Eigen::Map<const Eigen::Vector3d>(b.pose);
  s.q_world_body = Eigen::Map<const Eigen::Quaterniond>(b.pose + 3).normalized();
  s.v_world = Eigen::Map<const Eigen::Vector3d>(b.speed_bias);
  s.bias.acc_m_s2 = Eigen::Map<const Eigen::Vector3d>(b.speed_bias + 3);
  s.bias.gyro_rad_s = Eigen::Map<const Eigen::Vector3d>(b.speed_bias + 6);
  return s;
}

Eigen::Isometry3d poseOf(const double* pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Map<const Eigen::Quaterniond>(pose + 3).normalized().toRotationMatrix();
  T.translation() = Eigen::Map<const Eigen::Vector3d>(pose);
  return T;
}

ceres::Solver::Options odometrySolverOptions(int max_iterations) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_SCHUR;
  o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  o.max_num_iterations = max_iterations;
  o.num_threads = 1;
  o.minimizer_progress_to_stdout = false;
  return o;
}

void addMapResiduals(ceres::Problem& problem, double* pose, const std::vector<MapMatch>& matches, double sigma_m,
                     double huber_m) {
  if (matches.empty()) return;
  const double w = 1.0 / sigma_m;
  problem.AddResidualBlock(new MapMatchesFactor(matches, w, huber_m * w), nullptr, pose);
}

SlidingWindow::SlidingWindow(SlidingWindowConfig cfg, const Eigen::Vector3d& g_world)
    : cfg_(std::move(cfg)), g_world_(g_world) {}

SlidingWindow::~SlidingWindow() = default;

bool SlidingWindow::hasPrior() const { return prior_ && prior_->valid(); }

void SlidingWindow::push(WindowKeyframe kf) { keyframes_.push_back(std::move(kf)); }

void SlidingWindow::clear() {
  keyframes_.clear();
  prior_.reset();
  prior_blocks_.clear();
}

const std::vector<MapMatch>& SlidingWindow::matchesOf(WindowKeyframe& kf, const map::VoxelHashMap& edge_map,
                                                      const map::VoxelHashMap& plane_map) const {
  const Eigen::Isometry3d T = poseOf(kf.x.pose);
  if (!kf.matched || cfg_.reassociation.needed(kf.matched_at, T)) {
    MapMatchConfig matching = cfg_.matching;
    matching.max_residual_m = std::min(matching.max_residual_m, kf.max_match_residual_m);
    kf.matches = findMapMatches(kf.features, T, edge_map, plane_map, matching);
    kf.matched_at = T;
    kf.matched = true;
  }
  return kf.matches;
}

void SlidingWindow::optimize(const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map) {
  if (keyframes_.size() < 2) return;
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  PoseManifold manifold;
  for (auto& kf : keyframes_) {
    problem.AddParameterBlock(kf.x.pose, 7, &manifold);
    problem.AddParameterBlock(kf.x.speed_bias, 9);
  }
  if (hasPrior()) {
    problem.AddResidualBlock(new MarginalizationFactor(prior_), nullptr, prior_blocks_);
  } else {
    problem.SetParameterBlockConstant(keyframes_.front().x.pose);  // gauge
  }
  for (std::size_t i = 1; i < keyframes_.size(); ++i) {
    auto& a = keyframes_[i - 1];
    auto& b = keyframes_[i];
    problem.AddResidualBlock(new ImuFactor(b.pre, g_world_), nullptr, a.x.pose, a.x.speed_bias, b.x.pose,
                             b.x.speed_bias);
  }
  for (auto& kf : keyframes_)
    addMapResiduals(problem, kf.x.pose, matchesOf(kf, edge_map, plane_map), cfg_.lidar_sigma_m, cfg_.huber_loss_m);
  ceres::Solver::Summary summary;
  ceres::Solve(odometrySolverOptions(cfg_.max_iterations), &problem, &summary);
}

void SlidingWindow::marginalizeOldest(const map::VoxelHashMap& edge_map, const map::VoxelHashMap& plane_map) {
  if (keyframes_.size() <= static_cast<std::size_t>(std::max(cfg_.size, 2))) return;
  WindowKeyframe& old = keyframes_[0];
  WindowKeyframe& next = keyframes_[1];
  auto info = std::make_shared<MarginalizationInfo>();
  if (hasPrior()) {
    std::vector<int> drop;
    for (std::size_t i = 0; i < prior_blocks_.size(); ++i)
      if (prior_blocks_[i] == old.x.pose || prior_blocks_[i] == old.x.speed_bias) drop.push_back(static_cast<int>(i));
    // MarginalizationInfo owns the factors and losses it is given, as Ceres' Problem does.
    // NOLINTNEXTLINE(clang-analyzer-cplusplus.NewDeleteLeaks)
    info->addResidualBlock({new MarginalizationFactor(prior_), nullptr, prior_blocks_, drop});
  }
  // NOLINTNEXTLINE(clang-analyzer-cplusplus.NewDeleteLeaks): owned by info
  info->addResidualBlock({new ImuFactor(next.pre, g_world_),
                          nullptr,
                          {old.x.pose, old.x.speed_bias, next.x.pose, next.x.speed_bias},
                          {0, 1}});
  const double w = 1.0 / cfg_.lidar_sigma_m;
  ceres::LossFunction* loss = new ceres::HuberLoss(cfg_.huber_loss_m * w);  // shared, deleted once
  bool loss_used = false;
  for (const MapMatch& m : matchesOf(old, edge_map, plane_map)) {
    info->addResidualBlock({mapMatchCost(m, w), loss, {old.x.pose}, {0}});
    loss_used = true;
  }
  if (!loss_used) delete loss;
  // NOLINTNEXTLINE(clang-analyzer-cplusplus.NewDeleteLeaks): the loss is owned by info once used
  info->preMarginalize();
  info->marginalize();
  std::unordered_map<long, double*> same_address;
  for (std::size_t i = 1; i < keyframes_.size(); ++i) {
    same_address[reinterpret_cast<long>(keyframes_[i].x.pose)] = keyframes_[i].x.pose;
    same_address[reinterpret_cast<long>(keyframes_[i].x.speed_bias)] = keyframes_[i].x.speed_bias;
  }
  prior_blocks_ = info->keptBlockAddresses(same_address);
  prior_ = info;
  keyframes_.pop_front();
}

}  // namespace mmlio::estimator
