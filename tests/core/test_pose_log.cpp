#include <gtest/gtest.h>

#include <cmath>

#include "mmlio/core/pose_log.hpp"

namespace mmlio {

TEST(PoseLog, ReadsBackEveryPoseBitForBitInOrder) {
  Trajectory in;
  for (int i = 0; i < 5000; ++i) {  // several blocks
    StampedPose p;
    p.stamp_ns = 1'000'000'000LL + 100'000'000LL * i;
    p.T_world_body.linear() =
        Eigen::AngleAxisd(0.001 * i, Eigen::Vector3d(std::sin(i), 1.0, std::cos(0.3 * i)).normalized())
            .toRotationMatrix();
    p.T_world_body.translation() = Eigen::Vector3d(0.1 * i, std::sqrt(i), -1.0 / (i + 1));
    in.push_back(p);
  }
  PoseLog log;
  EXPECT_TRUE(log.empty());
  for (const StampedPose& p : in) log.push_back(p);
  ASSERT_EQ(log.size(), in.size());
  const Trajectory out = log.trajectory();
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].stamp_ns, in[i].stamp_ns);
    EXPECT_TRUE(out[i].T_world_body.matrix() == in[i].T_world_body.matrix()) << i;  // exact, not approximate
  }
  EXPECT_TRUE(log[1234].T_world_body.matrix() == in[1234].T_world_body.matrix());
  EXPECT_EQ(log.front().stamp_ns, in.front().stamp_ns);
  EXPECT_TRUE(log.back().T_world_body.matrix() == in.back().T_world_body.matrix());
}

}  // namespace mmlio
