#pragma once
// fast_lio/Pose6D without message generation: FAST-LIO2 uses it only as a plain struct.
#include <boost/array.hpp>
namespace fast_lio {
struct Pose6D {
  double offset_time = 0;
  boost::array<double, 3> acc, gyr, vel, pos;
  boost::array<double, 9> rot;
};
}  // namespace fast_lio
