#pragma once
// Private helper of src/io: which unit an IMU topic reports its acceleration in.
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>

#include <functional>
#include <string>

namespace mmlio::io {

inline constexpr double kStandardGravity = 9.80665;

/// Mean |linear_acceleration| over the first `samples` finite messages `next` yields (false: no
/// more; a throw: that message is unreadable, try the next); negative when none is readable.
double meanImuAccNorm(const std::function<bool(sensor_msgs::Imu*)>& next, int samples = 50);
/// The same over the first messages of `topic` (its own View, so the main stream is untouched).
double meanImuAccNorm(rosbag::Bag& bag, const std::string& topic, int samples = 50);

/// "g" when the mean |acc| is below 3 (nobody accelerates at 0.3 g for the first messages of a
/// bag, and gravity in m/s^2 is 9.8), "m/s2" otherwise, "" when the topic has no readable message.
std::string guessImuUnit(rosbag::Bag& bag, const std::string& topic);
/// The same guess from a mean |acc| (negative: no readable message).
std::string imuUnitFromMeanAcc(double mean);

/// Multiplier to m/s^2 for acc_unit "g" (9.80665), "m/s2" (1) or "auto" (guessed; 1 with a
/// warning when it cannot be). Throws mmlio::Error naming `path` for another unit.
double imuAccScale(rosbag::Bag& bag, const std::string& topic, const std::string& acc_unit, const std::string& path);
/// Same from an already computed mean |acc| (negative: none); `mean` is only called for "auto".
double imuAccScaleFromMean(const std::function<double()>& mean, const std::string& topic, const std::string& acc_unit,
                           const std::string& path);

}  // namespace mmlio::io
