#pragma once
// What a mapping run leaves for a later run to localize in and extend (`OUT/session/`,
// docs/session.md): its keyframes at their loop-corrected poses with the clouds that place
// recognition and loop verification use, the loops that tied them, and the map. Core data only:
// the files are io/session_io's, the keyframes and loops come from backend::MappingBackend.
#include <Eigen/Geometry>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio {

struct SessionKeyframe {
  Stamp stamp_ns = 0;                                             // the input's clock (bag time)
  Eigen::Isometry3d T_map_body = Eigen::Isometry3d::Identity();   // loop-corrected
  Eigen::Isometry3d T_odom_body = Eigen::Isometry3d::Identity();  // as the odometry gave it
  // Voxel centroids in the body frame (cloud_voxel_m); empty where a revisit freed it.
  std::vector<Eigen::Vector3d> cloud_body;
};

struct SessionLoop {
  int from = 0, to = 0;                                                               // keyframe indices
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();                        // `to`'s body frame into `from`'s
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();  // (dp, dtheta) order
};

struct Session {
  std::vector<SessionKeyframe> keyframes;
  std::vector<SessionLoop> loops;
  std::vector<Point> map;    // map frame (the first keyframe's world), map_voxel_m voxels
  double map_voxel_m = 0;    // the map's voxel size
  double cloud_voxel_m = 0;  // the keyframe clouds' voxel size
};

}  // namespace mmlio
