#pragma once
// `mmlio init`: a starter rig config from what a bag holds. Only what differs from the defaults,
// each guessed value with a comment saying how it was guessed and what to check.
#include <string>

#include "mmlio/io/bag_info.hpp"

namespace mmlio::io {

/// The rig config text for a bag described by `info`: the IMU topic, one LiDAR per point-cloud
/// topic (spinning: PointCloud2, its type from the point fields; solid state: a Livox CustomMsg),
/// the mode their kinds allow, extrinsics from /tf_static where it connects the IMU's frame to a
/// LiDAR's (ROS 1 bags), otherwise to check or calibrate. Throws mmlio::Error when the bag
/// has no IMU or no LiDAR topic (mmlio needs both).
std::string starterRigConfig(const BagInfo& info);

}  // namespace mmlio::io
