#pragma once
// Keyframe pose graph (the back end): odometry edges between consecutive keyframes and loop
// edges, optimised with Ceres. The first keyframe is held fixed (it anchors the gauge).
//
// Poses are T_world_body. An edge a->b with measurement T_a_b has the residual
//   r = sqrt(I) * [ R_a^T (p_b - p_a) - p_ab ;  2 vec(q_ab^-1 * q_a^-1 q_b) ]   (tangent order dp, dtheta)
// i.e. the error of the estimated relative pose expressed in frame a (Ceres pose_graph_3d).
// Each keyframe also has a unary tilt factor r = (R^T e_z - R_odom^T e_z) / tilt_sigma_rad: its
// gravity direction stays the odometry's (IMU-observed) one, only position and yaw are corrected.
// Loop edges carry a wide Huber loss on the whitened residual so that one wrong loop cannot pull
// the whole graph without bound. Core code: no I/O.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::backend {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct KeyframeNode {
  Stamp stamp_ns = 0;
  Eigen::Isometry3d T_world_body_odom = Eigen::Isometry3d::Identity();  // pose from the odometry
  std::vector<Eigen::Vector3d> cloud_body;                              // downsampled de-skewed points, body frame (m)
};

/// Information (inverse covariance, tangent order dp, dtheta) of independent isotropic noise.
Matrix6d isotropicInformation(double sigma_translation_m, double sigma_rotation_rad);

class PoseGraph {
 public:
  struct Config {
    double odom_sigma_translation_m = 0.02;  // per odometry edge, each axis
    double odom_sigma_rotation_rad = 0.002;  // per odometry edge, each axis
    // Roll and pitch are observed by the IMU (gravity) at every keyframe, so they do not drift:
    // each keyframe keeps its odometry tilt within this sigma. Without it a 6-DoF graph happily
    // bends roll / pitch to absorb a translation residual. 3 mrad: the odometry tilt error measured
    // on the simulated sequences (hall within 3.7 mrad, office within 6 mrad).
    // <= 0 turns it off.
    double tilt_sigma_rad = 0.003;
    // Huber scale on the whitened loop residual (sigmas); <= 0: plain least squares. A loop arrives
    // verified (ICP fitness, overlap, uniqueness, plausible correction), and a genuine one is many
    // sigmas off the drifted estimate: at 1 sigma a 1.5 deg loop left a quarter of it uncorrected.
    double loop_huber = 10.0;
    int max_iterations = 50;  // Levenberg-Marquardt iterations per optimize()
  };

  PoseGraph();  // default Config (a nested Config with initialisers cannot be a default argument in GCC)
  explicit PoseGraph(Config cfg);

  /// Appends a keyframe (stamps must not decrease) and the odometry edge to the previous one,
  /// measured as T_prev_odom^-1 * T_odom. Its initial estimate chains that relative pose onto the
  /// previous keyframe's current estimate, so earlier corrections carry forward. Returns its index.
  int addKeyframe(KeyframeNode node);
  /// Loop edge: T_from_to maps `to`'s body frame into `from`'s; information in (dp, dtheta) order.
  /// Neither end may be folded.
  void addLoop(int from, int to, const Eigen::Isometry3d& T_from_to, const Matrix6d& information);
  /// Prior on keyframe k's pose: measured at T_world_body with this information ((dp, dtheta),
  /// dtheta on the right), robust like a loop. For a run that extends a saved map: where that map
  /// places the keyframe. The keyframe is not folded after.
  void addPrior(int k, const Eigen::Isometry3d& T_world_body, const Matrix6d& information);
  std::size_t priors() const { return priors_.size(); }
  /// Takes keyframe i out of the optimised problem: its two odometry edges become one between its
  /// neighbours in the problem (the steps' noise adding up), and from then on its pose follows
  /// theirs, its correction interpolated between theirs by the distance travelled. For keyframes
  /// that revisit mapped places: a survey that keeps revisiting would otherwise grow the problem
  /// each loop solves without end. Returns false, changing nothing, for keyframe 0 (the gauge), the
  /// newest keyframe, or one a loop ends at.
  bool fold(int i);
  /// Optimises all poses, keyframe 0 fixed. Returns false if the solver failed (estimate kept).
  bool optimize();

  std::size_t size() const { return nodes_.size(); }
  /// Keyframes in the optimised problem (size() less the folded ones).
  std::size_t optimised() const { return nodes_.size() - folded_count_; }
  const KeyframeNode& node(int i) const { return nodes_.at(static_cast<std::size_t>(i)); }
  /// Current estimate of T_world_body of keyframe i (its odometry pose until optimised).
  Eigen::Isometry3d pose(int i) const;
  std::size_t loops() const { return loops_.size(); }
  /// The loop edges as added (addLoop's arguments).
  struct LoopEdge {
    int from, to;
    Eigen::Isometry3d T_from_to;
    Matrix6d information;
  };
  std::vector<LoopEdge> loopEdges() const;
  /// Length of the shortest route between keyframes a and b through the graph, m: an odometry edge
  /// counts the distance the odometry travelled along it, a loop edge nothing (it ties its ends).
  /// What the estimate of b relative to a can have drifted over: after loops, far less than the
  /// distance travelled between them.
  double routeLength(int a, int b) const;
  /// Frees keyframe i's cloud (it then stops being a loop candidate; its pose stays in the graph).
  void dropCloud(int i);

  /// T_world_body of an odometry pose stamped t, corrected like the last keyframe at or before t:
  /// pose(k) * T_world_body_odom(k)^-1 * T_world_body_odom. Identity correction before keyframe 0.
  Eigen::Isometry3d correct(Stamp t, const Eigen::Isometry3d& T_world_body_odom) const;

  const Config& config() const { return cfg_; }

 private:
  struct Edge {
    int from, to;
    Eigen::Isometry3d T_from_to;
    Matrix6d sqrt_information;  // upper-triangular, r^T I r = |S r|^2
    Matrix6d information;
    Matrix6d covariance;  // odometry edges: of T_from_to, kept to compose folded edges
  };
  static Edge edge(int from, int to, const Eigen::Isometry3d& T_from_to, const Matrix6d& information);
  /// Distance the odometry travelled from keyframe i to i + 1, m.
  double odometryStep(int i) const;
  /// Sets the pose of every folded keyframe from its kept neighbours' (see fold()).
  void placeFolded();

  Config cfg_;
  std::vector<KeyframeNode> nodes_;
  std::vector<std::array<double, 7>> params_;  // {px,py,pz,qx,qy,qz,qw} per keyframe
  std::vector<Edge> odom_edges_;               // between kept keyframes, in order
  std::vector<Edge> loops_;
  std::vector<Edge> priors_;  // from == to == the keyframe, T_from_to its measured pose
  std::vector<bool> folded_;
  std::vector<bool> loop_end_;  // a loop edge starts or ends here
  std::size_t folded_count_ = 0;
};

}  // namespace mmlio::backend
