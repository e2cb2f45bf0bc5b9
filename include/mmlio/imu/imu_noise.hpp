#pragma once
// Continuous-time IMU noise densities (datasheet / Allan-variance units, SI).
namespace mmlio::imu {

struct ImuNoise {
  double acc_noise_density = 0.05;      // m/s^2/sqrt(Hz)
  double gyro_noise_density = 0.005;    // rad/s/sqrt(Hz)
  double acc_bias_random_walk = 0.001;  // m/s^3/sqrt(Hz)
  double gyro_bias_random_walk = 1e-4;  // rad/s^2/sqrt(Hz)
};

}  // namespace mmlio::imu
