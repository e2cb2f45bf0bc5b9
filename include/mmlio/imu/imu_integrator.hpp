#pragma once
// Strapdown propagation of a navigation state with raw IMU samples (midpoint rule): the
// prediction for de-skew and the initial guess of the next state.
#include <Eigen/Core>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::imu {

/// Samples covering [t0, t1], with samples linearly interpolated exactly at t0 and t1 when the
/// buffer brackets them (so an integration spans exactly the interval). Sorted input.
std::vector<ImuSample> imuBetween(const std::vector<ImuSample>& sorted, Stamp t0, Stamp t1);

/// States at `query_times` (sorted, >= start.stamp_ns) propagated from `start` through `samples`
/// (sorted; the first at or before start). Beyond the last sample the last rates are held.
std::vector<NavState> propagate(const NavState& start, const std::vector<ImuSample>& samples,
                                const std::vector<Stamp>& query_times, const Eigen::Vector3d& g_world);

}  // namespace mmlio::imu
