#include "imu_unit.hpp"

#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>

#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"

namespace mmlio::io {

double meanImuAccNorm(const std::function<bool(sensor_msgs::Imu*)>& next, int samples) {
  double sum = 0.0;
  int n = 0;
  sensor_msgs::Imu imu;
  // Unreadable messages are skipped, a bounded number of them: a damaged stream ends the sample.
  for (int tries = 0; n < samples && tries < 10 * samples; ++tries) {
    try {
      if (!next(&imu)) break;
    } catch (const std::exception&) {
      continue;
    }
    const auto& a = imu.linear_acceleration;
    const double norm = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
    if (!std::isfinite(norm)) continue;
    sum += norm;
    ++n;
  }
  return n > 0 ? sum / n : -1.0;
}

double meanImuAccNorm(rosbag::Bag& bag, const std::string& topic, int samples) {
  std::vector<std::string> topics{topic};
  if (!topic.empty() && topic.front() == '/')
    topics.push_back(topic.substr(1));
  else
    topics.push_back("/" + topic);
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  auto it = view.begin();
  return meanImuAccNorm(
      [&](sensor_msgs::Imu* out) {
        while (it != view.end()) {
          const auto imu = (it++)->instantiate<sensor_msgs::Imu>();
          if (imu) {
            *out = *imu;
            return true;
          }
        }
        return false;
      },
      samples);
}

std::string guessImuUnit(rosbag::Bag& bag, const std::string& topic) {
  return imuUnitFromMeanAcc(meanImuAccNorm(bag, topic));
}

std::string imuUnitFromMeanAcc(double mean) {
  if (mean < 0) return "";
  return mean < 3.0 ? "g" : "m/s2";
}

double imuAccScale(rosbag::Bag& bag, const std::string& topic, const std::string& acc_unit, const std::string& path) {
  return imuAccScaleFromMean([&] { return meanImuAccNorm(bag, topic); }, topic, acc_unit, path);
}

double imuAccScaleFromMean(const std::function<double()>& mean_fn, const std::string& topic,
                           const std::string& acc_unit, const std::string& path) {
  if (acc_unit == "g") return kStandardGravity;
  if (acc_unit == "m/s2") return 1.0;
  if (acc_unit != "auto") throw Error("imu.acc_unit '" + acc_unit + "' is not auto, g or m/s2");
  const double mean = mean_fn();
  if (mean < 0) {
    log::warn("cannot guess the IMU acceleration unit of ", topic, " in ", path,
              ": no readable message; assuming m/s^2");
    return 1.0;
  }
  const bool g = imuUnitFromMeanAcc(mean) == "g";
  log::info("IMU ", topic, ": mean |acc| ", mean, " over the first messages -> ", g ? "g" : "m/s^2");
  return g ? kStandardGravity : 1.0;
}

}  // namespace mmlio::io
