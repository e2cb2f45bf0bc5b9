#include "mmlio/sim/simulator.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "mmlio/core/error.hpp"
#include "mmlio/sim/furniture.hpp"
#include "mmlio/sim/random.hpp"

namespace mmlio::sim {

namespace {

constexpr std::uint64_t kVelodyneId = 1, kLivoxId = 2, kImuId = 3;
constexpr Stamp kFramePeriodNs = 100000000LL;

double deg(double d) { return d * M_PI / 180.0; }

}  // namespace

Simulator::Simulator(SimOptions options) : options_(std::move(options)) {
  if (options_.duration_s < 0) throw Error("simulation duration must be >= 0 s (0 = the scenario's default)");
  scenario_ = startingAt(makeScenario(options_.scenario), options_.route_start);
  if (options_.handheld) scenario_ = carriedByHand(scenario_);
  scene_ = Scene(scenario_.boxes);
  motion_ = scenario_.recorded.empty() ? walkMotion(scenario_.waypoints, scenario_.walk, options_.duration_s)
                                       : recordedMotion(scenario_.recorded, scenario_.walk, options_.duration_s);
  livox_.pattern = options_.livox_pattern;
  velodyne_beams_ = velodyneBeams(velodyne_);
  drawMount();
  if (options_.velodyne_phase_s >= 0) velodyne_phase_ns_ = fromSec(std::min(options_.velodyne_phase_s, 0.0999));

  imu_noise_ = options_.imu;
  imu_noise_.initial_bias.acc_m_s2 = Eigen::Vector3d(0.02, -0.015, 0.02);
  if (options_.acc_bias_m_s2 >= 0)
    for (int a = 0; a < 3; ++a)
      imu_noise_.initial_bias.acc_m_s2[a] =
          options_.acc_bias_m_s2 * (unitFromHash(hashKey(options_.seed, kImuId, 7, a)) < 0.5 ? -1.0 : 1.0);
  imu_noise_.initial_bias.gyro_rad_s = Eigen::Vector3d(0.003, -0.002, 0.0025);

  const double dt = 1.0 / imu_noise_.rate_hz;
  const Stamp dt_ns = fromSec(dt);
  const int n = static_cast<int>(std::floor(durationS() / dt + 1e-9)) + 1;
  const double acc_sigma = imu_noise_.acc_noise_density / std::sqrt(dt);
  const double gyro_sigma = imu_noise_.gyro_noise_density / std::sqrt(dt);
  const double acc_walk = imu_noise_.acc_random_walk * std::sqrt(dt);
  const double gyro_walk = imu_noise_.gyro_random_walk * std::sqrt(dt);
  ImuBias bias = imu_noise_.initial_bias;
  ground_truth_.reserve(n);
  imu_.reserve(n);
  true_bias_.reserve(n);
  auto noise = [&](int k, int channel) {
    return normalFromKey(
        hashKey(options_.seed, kImuId, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(channel)));
  };
  for (int k = 0; k < n; ++k) {
    const Stamp stamp = kSimStartNs + k * dt_ns;
    const MotionState m = motion_.at(k * dt);
    ground_truth_.push_back({stamp, m.pose()});
    true_bias_.push_back(bias);
    ImuSample s;
    s.stamp_ns = stamp;
    s.acc_m_s2 = m.specificForce() + bias.acc_m_s2;
    s.gyro_rad_s = m.omega_body + bias.gyro_rad_s;
    for (int a = 0; a < 3; ++a) {
      s.acc_m_s2[a] += acc_sigma * noise(k, a);
      s.gyro_rad_s[a] += gyro_sigma * noise(k, 3 + a);
      bias.acc_m_s2[a] += acc_walk * noise(k, 6 + a);
      bias.gyro_rad_s[a] += gyro_walk * noise(k, 9 + a);
    }
    imu_.push_back(s);
  }
  // Path length by fine sampling of the position.
  Eigen::Vector3d prev = motion_.at(0).p_world;
  std::vector<Eigen::Vector2d> route{prev.head<2>()};
  for (double t = 0.01; t <= durationS() + 1e-9; t += 0.01) {
    const Eigen::Vector3d p = motion_.at(t).p_world;
    path_length_m_ += (p - prev).norm();
    prev = p;
    route.emplace_back(p.head<2>());
  }
  if (options_.rearranged) {
    furniture_moved_ = rearrangeFurniture(&scenario_.boxes, route, options_.seed);
    scene_ = Scene(scenario_.boxes);
  }
  if (options_.people < 0) throw Error("the number of people must be >= 0");
  crowd_ = Crowd(scene_, route, options_.people, options_.seed);
}

NavState Simulator::trueState(Stamp stamp_ns) const {
  const double t = toSec(stamp_ns - kSimStartNs);
  const MotionState m = motion_.at(t);
  NavState s;
  s.stamp_ns = stamp_ns;
  s.p_world = m.p_world;
  s.q_world_body = m.q_world_body;
  s.v_world = m.v_world;
  if (!true_bias_.empty()) {
    const int k = std::clamp(static_cast<int>(std::floor(t * imu_noise_.rate_hz + 1e-9)), 0,
                             static_cast<int>(true_bias_.size()) - 1);
    s.bias = true_bias_[k];
  }
  return s;
}

ImuSample Simulator::idealImu(Stamp stamp_ns) const {
  const MotionState m = motion_.at(toSec(stamp_ns - kSimStartNs));
  ImuSample s;
  s.stamp_ns = stamp_ns;
  s.acc_m_s2 = m.specificForce();
  s.gyro_rad_s = m.omega_body;
  return s;
}

int Simulator::numVelodyneSweeps() const {
  const double first_s = toSec(velodyne_phase_ns_);
  return std::max(0, static_cast<int>(std::floor((durationS() - first_s) / 0.1 + 1e-9)));
}

int Simulator::numLivoxFrames() const { return std::max(0, static_cast<int>(std::floor(durationS() / 0.1 + 1e-9))); }

void Simulator::drawMount() {
  auto rotation = [](double yaw_deg, double pitch_deg, double roll_deg) {
    return (Eigen::AngleAxisd(deg(yaw_deg), Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(deg(pitch_deg), Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(deg(roll_deg), Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
  };
  T_imu_velodyne_.setIdentity();
  T_imu_velodyne_.linear() = rotation(3.0, -2.0, 1.5);
  T_imu_velodyne_.translation() = Eigen::Vector3d(0.03, -0.02, 0.18);
  T_imu_livox_.setIdentity();
  T_imu_livox_.translation() = Eigen::Vector3d(0.05512, 0.02226, -0.0297);
  if (!options_.random_mount) return;
  constexpr std::uint64_t kMountId = 4;
  auto uniform = [&](std::uint64_t i, double lo, double hi) {
    return lo + (hi - lo) * unitFromHash(hashKey(options_.seed, kMountId, i));
  };
  T_imu_livox_.linear() = rotation(uniform(0, -15, 15), uniform(1, -5, 5), uniform(2, -5, 5));
  T_imu_livox_.translation() = Eigen::Vector3d(uniform(3, -0.1, 0.1), uniform(4, -0.1, 0.1), uniform(5, -0.1, 0.1));
  T_imu_velodyne_.linear() = rotation(uniform(6, -180, 180), uniform(7, -5, 5), uniform(8, -5, 5));
  T_imu_velodyne_.translation() =
      Eigen::Vector3d(uniform(9, -0.1, 0.1), uniform(10, -0.1, 0.1), 0.18 + uniform(11, -0.1, 0.1));
  velodyne_phase_ns_ = static_cast<Stamp>(uniform(12, 0, 0.1) * 1e9);
}

LidarExtrinsic Simulator::velodyneExtrinsic() const {
  LidarExtrinsic e;
  e.name = "velodyne";
  e.kind = LidarKind::kSpinning;
  e.T_imu_sensor = T_imu_velodyne_;
  e.time_offset_s = options_.velodyne_time_offset_s;
  return e;
}

LidarExtrinsic Simulator::livoxExtrinsic() const {
  LidarExtrinsic e;
  e.name = "livox";
  e.kind = LidarKind::kSolidState;
  e.T_imu_sensor = T_imu_livox_;
  return e;
}

LidarScan Simulator::velodyneSweep(int k, std::vector<std::uint8_t>* on_person) const {
  if (k < 0 || k >= numVelodyneSweeps()) throw Error("velodyne sweep index " + std::to_string(k) + " out of range");
  LidarScan scan =
      cast(velodyne_beams_, velodyneTrueStartNs(k), velodyneExtrinsic().T_imu_sensor, velodyne_.range_noise_m,
           velodyne_.min_range_m, velodyne_.max_range_m, kVelodyneId, k, false, on_person);
  scan.sensor = "velodyne";
  scan.start_ns -= fromSec(options_.velodyne_time_offset_s);
  return scan;
}

LidarScan Simulator::livoxFrame(int k, std::vector<std::uint8_t>* on_person) const {
  if (k < 0 || k >= numLivoxFrames()) throw Error("livox frame index " + std::to_string(k) + " out of range");
  LidarScan scan =
      cast(livoxBeams(livox_, k), kSimStartNs + k * kFramePeriodNs, livoxExtrinsic().T_imu_sensor, livox_.range_noise_m,
           livox_.min_range_m, livox_.max_range_m, kLivoxId, k, options_.livox_no_returns_as_zero, on_person);
  scan.sensor = "livox";
  return scan;
}

LidarScan Simulator::cast(const std::vector<Beam>& beams, Stamp true_start_ns, const Eigen::Isometry3d& T_imu_sensor,
                          double range_noise_m, double min_range_m, double max_range_m, std::uint64_t sensor_id, int k,
                          bool keep_no_returns, std::vector<std::uint8_t>* on_person) const {
  std::vector<Point> points(beams.size());
  std::vector<char> valid(beams.size(), 0);
  std::vector<std::uint8_t> person(beams.size(), 0);
  const double t_start = toSec(true_start_ns - kSimStartNs);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, beams.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Beam& b = beams[i];
      const Eigen::Isometry3d T_world_sensor = motion_.at(t_start + b.time_s).pose() * T_imu_sensor;
      const Eigen::Vector3d d = T_world_sensor.linear() * b.dir.cast<double>();
      RayHit hit = scene_.cast(T_world_sensor.translation(), d, max_range_m);
      const Box* surface = hit.box < 0 ? nullptr : &scene_.boxes()[hit.box];
      Box person_box;
      if (!crowd_.empty()) {
        const double t = t_start + b.time_s;
        const RayHit p = crowd_.cast(T_world_sensor.translation(), d, std::min(hit.range_m, max_range_m), t);
        if (p.box >= 0 && p.range_m < hit.range_m) {
          hit = p;
          person_box = crowd_.boxAt(p.box, t);
          surface = &person_box;
          person[i] = 1;
        }
      }
      const double range = hit.box < 0
                               ? 0.0
                               : hit.range_m + range_noise_m * normalFromKey(hashKey(options_.seed, sensor_id,
                                                                                     static_cast<std::uint64_t>(k), i));
      if (hit.box < 0 || range < min_range_m || range > max_range_m) {
        person[i] = 0;
        if (keep_no_returns) {  // the driver's no-return point: (0,0,0) with its time
          points[i].xyz.setZero();
          points[i].time_s = b.time_s;
          points[i].ring = b.ring;
          valid[i] = 1;
        }
        continue;
      }
      // Intensity: the surface reflectivity, dimmed at grazing incidence.
      const double cos_incidence = std::abs(d[hit.axis]);
      Point& p = points[i];
      p.xyz = (b.dir.cast<double>() * range).cast<float>();
      p.intensity = std::round(surface->reflectivity * static_cast<float>(0.5 + 0.5 * cos_incidence));
      p.time_s = b.time_s;
      p.ring = b.ring;
      valid[i] = 1;
    }
  });
  LidarScan scan;
  scan.start_ns = true_start_ns;
  scan.points.reserve(beams.size());
  if (on_person) on_person->clear();
  for (size_t i = 0; i < beams.size(); ++i) {
    if (!valid[i]) continue;
    scan.points.push_back(points[i]);
    if (on_person) on_person->push_back(person[i]);
  }
  return scan;
}

}  // namespace mmlio::sim
