#include "mmlio/lidar/features.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace mmlio::lidar {
namespace {

constexpr double kMaxArmCos = 0.5;  // arms of a line edge are more than 60 deg apart

enum class Label : unsigned char { kNone, kEdge, kBreak, kPlane };

struct Candidate {
  Label label = Label::kNone;
  int stride = 1;
  double curvature = 0.0;
};

// Eigen decomposition of the scatter of pts[0..n): ascending eigenvalues, matching eigenvectors.
void scatter(const Eigen::Vector3d* pts, int n, Eigen::Vector3d* evals, Eigen::Matrix3d* evecs) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) mean += pts[k];
  mean /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d d = pts[k] - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(cov / n);
  *evals = es.eigenvalues();
  if (evecs) *evecs = es.eigenvectors();
}

// (lambda_2 + lambda_3) / lambda_1 of the scatter of the 2K+1 strided neighbours of i, with the
// principal axis taken as the chord between the two ends (exact enough for the near-straight runs
// this is asked about, and much cheaper than an eigen decomposition).
double straightness(const std::vector<Eigen::Vector3d>& P, int i, int K, int stride) {
  const Eigen::Vector3d chord = P[i + K * stride] - P[i - K * stride];
  const double len = chord.norm();
  if (len <= 0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d d = chord / len;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int k = -K; k <= K; ++k) mean += P[i + k * stride];
  mean /= (2 * K + 1);
  double along = 0, across = 0;
  for (int k = -K; k <= K; ++k) {
    const Eigen::Vector3d v = P[i + k * stride] - mean;
    const double a = v.dot(d);
    along += a * a;
    across += v.squaredNorm() - a * a;
  }
  return along > 0 ? across / along : std::numeric_limits<double>::infinity();
}

// What every point's test reads of one ordered scan line, computed in one pass.
struct LineGeometry {
  std::vector<double> sq_norm;          // |P_j|^2
  std::vector<double> inv_range;        // 1 / |P_j| (P has no zero-range points)
  std::vector<Eigen::Vector3d> prefix;  // prefix[j] = sum of P[0..j)
  std::vector<char> gap;                // gap[j]: break between j and j+1
  std::vector<int> gaps_before;         // breaks between consecutive points among 0..j
  double step_rad = 0.0;                // median angular step between consecutive points (0: none)

  bool continuous(int a, int b) const { return gaps_before[b] == gaps_before[a]; }  // a <= b
};

// Fills *out (storage reused from line to line: every element read later is written here).
void lineGeometry(const std::vector<Eigen::Vector3d>& P, double continuity_jump_m, LineGeometry* out) {
  const int n = static_cast<int>(P.size());
  LineGeometry& g = *out;
  g.step_rad = 0.0;
  const auto atLeast = [](auto& v, std::size_t size) {
    if (v.size() < size) v.resize(size);
  };
  atLeast(g.sq_norm, P.size());
  atLeast(g.inv_range, P.size());
  atLeast(g.prefix, P.size() + 1);
  g.gap.assign(P.size(), 0);
  atLeast(g.gaps_before, P.size());
  g.gaps_before[0] = 0;
  g.prefix[0].setZero();
  // The angular step comes from the bearings (unit rays), which range noise does not inflate;
  // squared steps have the same median, without a square root per point.
  thread_local std::vector<double> squared_steps;
  squared_steps.clear();
  Eigen::Vector3d bearing_before = Eigen::Vector3d::Zero(), turn_before = Eigen::Vector3d::Zero();
  for (int j = 0; j < n; ++j) {
    g.sq_norm[j] = P[j].squaredNorm();
    g.inv_range[j] = 1.0 / std::sqrt(g.sq_norm[j]);
    g.prefix[j + 1] = g.prefix[j] + P[j];
    const Eigen::Vector3d bearing = P[j] * g.inv_range[j];
    if (j == 0) {
      bearing_before = bearing;
      continue;
    }
    const Eigen::Vector3d turn = bearing - bearing_before;
    char& gap = g.gap[j - 1];
    gap = (P[j] - P[j - 1]).squaredNorm() > continuity_jump_m * continuity_jump_m;
    if (!gap) squared_steps.push_back(turn.squaredNorm());
    // A line that turns back on itself (the Livox pattern at the edge of its view) breaks there too.
    if (j >= 2 && !gap && turn.dot(turn_before) < 0) gap = 1;
    g.gaps_before[j] = g.gaps_before[j - 1] + gap;
    bearing_before = bearing;
    turn_before = turn;
  }
  if (squared_steps.empty()) return;
  const auto middle = squared_steps.begin() + static_cast<std::ptrdiff_t>(squared_steps.size() / 2);
  std::nth_element(squared_steps.begin(), middle, squared_steps.end());
  g.step_rad = std::max(std::sqrt(*middle), 1e-6);
}

// Features of one ordered scan line. Neighbours are taken every `stride` points, the stride
// chosen per point so that neighbours are at least min_neighbour_spacing_m apart: on dense lines
// (a close wall, Livox) range noise would otherwise dominate the curvature. The centre is the mean
// of the points between its two nearest neighbours, which damps its own noise without moving a
// corner.
void processLine(const std::vector<Eigen::Vector3d>& P, int K, const FeatureConfig& cfg,
                 std::vector<std::size_t>* edges, std::vector<std::size_t>* planes) {
  const int n = static_cast<int>(P.size());
  if (n < 2 * K + 1) return;
  thread_local LineGeometry scratch;
  lineGeometry(P, cfg.continuity_jump_m, &scratch);
  const LineGeometry& g = scratch;
  if (g.step_rad <= 0.0) return;
  const int max_stride = std::max(1, cfg.max_stride);
  // A neighbour `stride` points away lies about stride * step_rad * range away.
  const double points_per_spacing_at_1m = cfg.min_neighbour_spacing_m / g.step_rad;
  std::vector<double> inv_centre_count(static_cast<std::size_t>(max_stride) + 1);
  for (int s = 1; s <= max_stride; ++s) inv_centre_count[s] = 1.0 / (2 * s - 1);

  std::vector<Candidate> cand(P.size());
  const double min_bend_cos = std::cos(cfg.edge_min_bend_deg * M_PI / 180.0);
  std::vector<Eigen::Vector3d> buf(static_cast<std::size_t>(2 * K + 1));
  for (int i = 0; i < n; ++i) {
    const double wanted = points_per_spacing_at_1m * g.inv_range[i];
    int stride = max_stride;
    if (wanted < max_stride) {
      stride = std::max(1, static_cast<int>(wanted));
      if (stride < wanted) ++stride;  // ceil
    }
    cand[i].stride = stride;
    const int span = K * stride;
    const int lo = i - span, hi = i + span;
    if (lo >= 0 && hi < n && g.continuous(lo, hi)) {
      const Eigen::Vector3d centre = (g.prefix[i + stride] - g.prefix[i - stride + 1]) * inv_centre_count[stride];
      // c = |sum_j (p_j - centre)|^2 / sum_j |p_j - centre|^2, from the sums of p_j and |p_j|^2.
      Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
      double sum_sq = 0.0;
      for (int k = 1; k <= K; ++k) {
        const int l = i - k * stride, r = i + k * stride;
        sum_p += P[l] + P[r];
        sum_sq += g.sq_norm[l] + g.sq_norm[r];
      }
      const double m = 2.0 * K;
      const Eigen::Vector3d offsets = sum_p - m * centre;
      const double spread = sum_sq - 2.0 * centre.dot(sum_p) + m * centre.squaredNorm();
      if (!(spread > 1e-12 * sum_sq)) continue;  // all neighbours on the centre (cancellation floor)
      // Only candidates need their curvature (for ranking): the rest are told by a product.
      const double bent = offsets.squaredNorm();
      if (bent > cfg.edge_threshold * spread)
        cand[i].label = Label::kEdge;  // the line-edge shape is checked only for the points picked below
      else if (cfg.planes && bent < cfg.plane_threshold * spread)
        cand[i].label = Label::kPlane;  // flatness is checked only for the points picked below
      if (cand[i].label != Label::kNone) cand[i].curvature = bent / spread;
      continue;
    }
    // Break points: the near side of a depth jump, with a continuous neighbourhood on its own side.
    const double range = std::sqrt(g.sq_norm[i]);
    const auto fartherThanI = [&](int j) { return std::sqrt(g.sq_norm[j]) - range > cfg.continuity_jump_m; };
    const bool jump_right = i + 1 < n && g.gap[i] && fartherThanI(i + 1);
    const bool jump_left = i >= 1 && g.gap[i - 1] && fartherThanI(i - 1);
    if ((jump_right && lo >= 0 && g.continuous(lo, i)) || (jump_left && hi < n && g.continuous(i, hi))) {
      cand[i].label = Label::kBreak;
      cand[i].curvature = std::numeric_limits<double>::infinity();
    }
  }

  // Line edge only if the two halves are lines meeting at an angle (not one noisy point). Two
  // eigen decompositions per point: evaluated only for the candidates the picking reaches.
  const auto isLineEdge = [&](int i, int stride) {
    const Eigen::Vector3d centre = (g.prefix[i + stride] - g.prefix[i - stride + 1]) * inv_centre_count[stride];
    Eigen::Vector3d ev;
    Eigen::Matrix3d evec;
    for (int k = 0; k <= K; ++k) buf[k] = P[i - k * stride];
    scatter(buf.data(), K + 1, &ev, &evec);
    const Eigen::Vector3d dl = evec.col(2);
    for (int k = 0; k <= K; ++k) buf[k] = P[i + k * stride];
    scatter(buf.data(), K + 1, &ev, &evec);
    const Eigen::Vector3d dr = evec.col(2);
    // The arms must not fold back onto each other (a Livox line turning round, a thin spike).
    const Eigen::Vector3d arm_l = P[i - K * stride] - centre, arm_r = P[i + K * stride] - centre;
    const bool folded = arm_l.dot(arm_r) > kMaxArmCos * arm_l.norm() * arm_r.norm();
    return !folded && std::abs(dl.dot(dr)) < min_bend_cos;
  };

  // LOAM-style spreading: per sector, sharpest edges first with neighbour suppression, flattest planes.
  const int sectors = std::max(1, cfg.sectors_per_line);
  std::vector<char> suppressed(P.size(), 0), picked_plane(P.size(), 0);
  std::vector<int> order;
  std::vector<std::pair<double, int>> flat;
  for (int s = 0; s < sectors; ++s) {
    const int begin = n * s / sectors, end = n * (s + 1) / sectors;
    order.clear();
    for (int i = begin; i < end; ++i)
      if (cand[i].label == Label::kEdge || cand[i].label == Label::kBreak) order.push_back(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return cand[a].curvature > cand[b].curvature; });
    int picked = 0;
    for (int i : order) {
      if (picked >= cfg.max_edges_per_sector) break;
      if (suppressed[i]) continue;
      if (cand[i].label == Label::kEdge && !isLineEdge(i, cand[i].stride)) continue;
      edges->push_back(static_cast<std::size_t>(i));
      ++picked;
      const int span = K * cand[i].stride;
      for (int k = std::max(0, i - span); k <= std::min(n - 1, i + span); ++k) suppressed[k] = 1;
    }
    if (!cfg.planes) continue;
    // Planes: the flattest max_planes_per_sector; the neighbourhood must be a straight run.
    // Ranked by (curvature, index) in one contiguous array (comparing through indices into cand
    // was a fifth of the extraction), then taken in line order.
    flat.clear();
    for (int i = begin; i < end; ++i)
      if (cand[i].label == Label::kPlane && !suppressed[i]) flat.emplace_back(cand[i].curvature, i);
    const std::size_t cap = static_cast<std::size_t>(std::max(0, cfg.max_planes_per_sector));
    if (flat.size() > cap) {
      std::nth_element(flat.begin(), flat.begin() + static_cast<std::ptrdiff_t>(cap), flat.end());
      flat.resize(cap);
    }
    for (const auto& [curvature, i] : flat) picked_plane[i] = 1;
    for (int i = begin; i < end; ++i) {
      if (!picked_plane[i]) continue;
      picked_plane[i] = 0;
      if (straightness(P, i, K, cand[i].stride) < cfg.plane_max_flatness)
        planes->push_back(static_cast<std::size_t>(i));
    }
  }
  std::sort(edges->begin(), edges->end());
}

}  // namespace

FeatureCloud extractFeatures(const LidarScan& scan, LidarKind kind, int num_rings, const FeatureConfig& cfg) {
  FeatureCloud out;
  out.input_points = scan.points.size();
  const auto lines = scanLines(scan, kind, num_rings, cfg);
  const int K = std::max(1, cfg.neighbours);

  struct LineResult {
    std::vector<std::size_t> edges, planes;  // indices into scan.points
  };
  std::vector<LineResult> results(lines.size());
  tbb::parallel_for(std::size_t{0}, lines.size(), [&](std::size_t l) {
    const auto& ids = lines[l];
    // Positions along the line, consecutive duplicates (dual returns) dropped.
    std::vector<Eigen::Vector3d> P;
    std::vector<std::size_t> id_of;
    P.reserve(ids.size());
    id_of.reserve(ids.size());
    for (std::size_t id : ids) {
      const Eigen::Vector3d p = scan.points[id].xyz.cast<double>();
      if (!P.empty() && (p - P.back()).squaredNorm() < 1e-6) continue;
      P.push_back(p);
      id_of.push_back(id);
    }
    std::vector<std::size_t> e, pl;
    processLine(P, K, cfg, &e, &pl);
    for (std::size_t i : e) results[l].edges.push_back(id_of[i]);
    for (std::size_t i : pl) results[l].planes.push_back(id_of[i]);
  });
  for (const auto& r : results) {
    for (std::size_t id : r.edges) out.edges.push_back(scan.points[id]);
    for (std::size_t id : r.planes) out.planes.push_back(scan.points[id]);
  }
  return out;
}

}  // namespace mmlio::lidar
