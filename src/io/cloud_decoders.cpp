#include "mmlio/io/cloud_decoders.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "mmlio/core/error.hpp"

namespace mmlio::io {
namespace {

using PF = sensor_msgs::PointField;

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kAbsoluteTimeS = 1e6;  // a per-point time above this is an absolute stamp

std::size_t datatypeSize(std::uint8_t type) {
  switch (type) {
    case PF::INT8:
    case PF::UINT8:
      return 1;
    case PF::INT16:
    case PF::UINT16:
      return 2;
    case PF::INT32:
    case PF::UINT32:
    case PF::FLOAT32:
      return 4;
    case PF::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

const char* datatypeName(std::uint8_t type) {
  switch (type) {
    case PF::INT8:
      return "int8";
    case PF::UINT8:
      return "uint8";
    case PF::INT16:
      return "int16";
    case PF::UINT16:
      return "uint16";
    case PF::INT32:
      return "int32";
    case PF::UINT32:
      return "uint32";
    case PF::FLOAT32:
      return "float32";
    case PF::FLOAT64:
      return "float64";
    default:
      return "unknown";
  }
}

/// Reads one scalar field of any PointField datatype as double.
struct FieldReader {
  bool present = false;
  std::uint32_t offset = 0;
  std::uint8_t type = 0;
  bool swap = false;

  template <typename T> T raw(const std::uint8_t* p) const {
    std::uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, p + offset, sizeof(T));
    if (swap) std::reverse(bytes, bytes + sizeof(T));
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
  double operator()(const std::uint8_t* p) const {
    if (type == PF::FLOAT32 && !swap) return raw<float>(p);  // nearly every driver's x, y, z, intensity, time
    switch (type) {
      case PF::INT8:
        return raw<std::int8_t>(p);
      case PF::UINT8:
        return raw<std::uint8_t>(p);
      case PF::INT16:
        return raw<std::int16_t>(p);
      case PF::UINT16:
        return raw<std::uint16_t>(p);
      case PF::INT32:
        return raw<std::int32_t>(p);
      case PF::UINT32:
        return raw<std::uint32_t>(p);
      case PF::FLOAT32:
        return raw<float>(p);
      case PF::FLOAT64:
        return raw<double>(p);
      default:
        return 0.0;
    }
  }
};

FieldReader findField(const sensor_msgs::PointCloud2& msg, const std::string& name) {
  FieldReader r;
  for (const PF& f : msg.fields) {
    if (f.name != name) continue;
    const std::size_t size = datatypeSize(f.datatype);
    if (size == 0 || f.offset + size > msg.point_step) {
      throw Error("point cloud field '" + name + "' has an invalid datatype or offset (offset " +
                  std::to_string(f.offset) + ", point_step " + std::to_string(msg.point_step) + ")");
    }
    r.present = true;
    r.offset = f.offset;
    r.type = f.datatype;
    r.swap = msg.is_bigendian != 0;
    return r;
  }
  return r;
}

/// A candidate point with its absolute time, before sorting.
struct TimedPoint {
  Stamp t_ns;
  Point p;
};

/// Classifies a point: true if kept, else counts the reason.
bool keepPoint(const Eigen::Vector3f& xyz, double time_value, const CloudDecodeOptions& o, DecodeStats& s) {
  if (!xyz.allFinite() || !std::isfinite(time_value)) {
    ++s.dropped_nan;
    return false;
  }
  if (xyz.x() == 0.f && xyz.y() == 0.f && xyz.z() == 0.f) {
    ++s.dropped_zero;
    return false;
  }
  const double r = xyz.cast<double>().norm();
  if (r < o.min_range_m || r > o.max_range_m) {
    ++s.dropped_range;
    return false;
  }
  ++s.kept;
  return true;
}

LidarScan finish(std::vector<TimedPoint>& pts, const CloudDecodeOptions& o, Stamp fallback_ns) {
  // Drivers mostly publish in firing order: checking is one pass, sorting allocates and merges.
  const auto earlier = [](const TimedPoint& a, const TimedPoint& b) { return a.t_ns < b.t_ns; };
  if (!std::is_sorted(pts.begin(), pts.end(), earlier)) std::stable_sort(pts.begin(), pts.end(), earlier);
  LidarScan scan;
  scan.sensor = o.sensor;
  scan.start_ns = pts.empty() ? fallback_ns : pts.front().t_ns;
  scan.points.reserve(pts.size());
  for (TimedPoint& tp : pts) {
    tp.p.time_s = static_cast<float>(toSec(tp.t_ns - scan.start_ns));
    scan.points.push_back(tp.p);
  }
  return scan;
}

Stamp stampNs(const ros::Time& t) { return static_cast<Stamp>(t.toNSec()); }

/// LOAM-style relative time from the azimuth: the sensor turns clockwise seen from above
/// (azimuth -atan2(y, x) grows) through one turn of period_s, starting at the first point.
class AzimuthClock {
 public:
  explicit AzimuthClock(double period_s) : period_s_(period_s) {}
  double timeS(const Eigen::Vector3f& xyz) {
    const double ori = -std::atan2(static_cast<double>(xyz.y()), static_cast<double>(xyz.x()));
    if (!started_) {
      started_ = true;
      start_ = ori;
    }
    double d = std::fmod(ori - start_, kTwoPi);
    if (d < 0) d += kTwoPi;
    if (half_passed_) {
      // Past half a turn, angles just after the start belong to the overlap at the end of the turn.
      if (d < 0.5 * M_PI) d += kTwoPi;
    } else {
      // Before half a turn, angles just short of the start are jitter around the first point.
      if (d > 1.75 * M_PI) d -= kTwoPi;
      if (d > M_PI) half_passed_ = true;
    }
    return d / kTwoPi * period_s_;
  }

 private:
  double period_s_;
  bool started_ = false, half_passed_ = false;
  double start_ = 0;
};

std::uint16_t ringFromElevation(const Eigen::Vector3f& xyz, int num_rings) {
  if (num_rings <= 1) return 0;
  const double horiz = std::hypot(static_cast<double>(xyz.x()), static_cast<double>(xyz.y()));
  const double elev_deg = std::atan2(static_cast<double>(xyz.z()), horiz) * 180.0 / M_PI;
  const double spacing = 30.0 / (num_rings - 1);
  const long ring = std::lround((elev_deg + 15.0) / spacing);
  return static_cast<std::uint16_t>(std::clamp<long>(ring, 0, num_rings - 1));
}

}  // namespace

void DecodeStats::add(const DecodeStats& o) {
  kept += o.kept;
  dropped_nan += o.dropped_nan;
  dropped_zero += o.dropped_zero;
  dropped_range += o.dropped_range;
}

LidarScan decodePointCloud2(const sensor_msgs::PointCloud2& msg, const CloudDecodeOptions& o, DecodeStats* stats) {
  const FieldReader fx = findField(msg, "x"), fy = findField(msg, "y"), fz = findField(msg, "z");
  if (!fx.present || !fy.present || !fz.present) {
    std::string names;
    for (const PF& f : msg.fields) names += (names.empty() ? "" : " ") + f.name;
    throw Error("point cloud has no x/y/z fields (fields: " + (names.empty() ? std::string("none") : names) + ")");
  }
  FieldReader fi = findField(msg, "intensity");
  if (!fi.present) fi = findField(msg, "reflectivity");
  const FieldReader fring = findField(msg, "ring");
  // The fields tell the kind of LiDAR; a declared kind that disagrees (a wrong type, swapped
  // topics) would run without a word, on rings and sweeps the points do not have.
  if (o.kind == LidarKind::kSolidState && fring.present)
    throw Error("its points have a ring field, a spinning LiDAR's, but LiDAR '" + o.sensor +
                "' is declared solid-state (type: livox): give it its spinning type (velodyne, ouster, hesai, "
                "generic_spinning) or check that the topics are not swapped");
  if (o.kind == LidarKind::kSpinning && !fring.present && findField(msg, "tag").present &&
      findField(msg, "line").present)
    throw Error("its points have a Livox driver's tag and line fields, but LiDAR '" + o.sensor +
                "' is declared as a spinning one: give it type: livox");

  enum class TimeKind { kRelativeS, kRelativeNs, kAbsoluteS, kAzimuth } time_kind = TimeKind::kAzimuth;
  FieldReader ft = findField(msg, "time");
  if (ft.present) {
    time_kind = TimeKind::kRelativeS;
  } else if ((ft = findField(msg, "t")).present) {
    time_kind = TimeKind::kRelativeNs;
  } else if ((ft = findField(msg, "timestamp")).present) {
    time_kind = TimeKind::kAbsoluteS;
  }

  const std::size_t n = static_cast<std::size_t>(msg.width) * msg.height;
  if (msg.height > 0 && msg.width > 0 &&
      (msg.row_step < static_cast<std::size_t>(msg.width) * msg.point_step ||
       msg.data.size() < static_cast<std::size_t>(msg.row_step) * msg.height)) {
    throw Error("point cloud data is shorter than width x height x point_step (" + std::to_string(msg.data.size()) +
                " bytes for " + std::to_string(n) + " points)");
  }

  const Stamp header_ns = stampNs(msg.header.stamp);
  DecodeStats local;
  std::vector<TimedPoint> pts;
  pts.reserve(n);
  AzimuthClock clock(o.scan_period_s);
  for (std::uint32_t row = 0; row < msg.height; ++row) {
    const std::uint8_t* base = msg.data.data() + static_cast<std::size_t>(row) * msg.row_step;
    for (std::uint32_t col = 0; col < msg.width; ++col) {
      const std::uint8_t* p = base + static_cast<std::size_t>(col) * msg.point_step;
      const Eigen::Vector3f xyz(static_cast<float>(fx(p)), static_cast<float>(fy(p)), static_cast<float>(fz(p)));
      double tv = 0.0;
      if (time_kind != TimeKind::kAzimuth) tv = ft(p);
      if (!keepPoint(xyz, tv, o, local)) continue;
      const Stamp t_ns = [&]() -> Stamp {
        switch (time_kind) {
          case TimeKind::kRelativeS:
          case TimeKind::kAbsoluteS:
            return std::abs(tv) > kAbsoluteTimeS ? fromSec(tv) : header_ns + fromSec(tv);
          case TimeKind::kRelativeNs:
            return header_ns + static_cast<Stamp>(std::llround(tv));
          case TimeKind::kAzimuth:
            break;
        }
        return header_ns + fromSec(clock.timeS(xyz));
      }();
      TimedPoint tp{t_ns, Point{}};
      tp.p.xyz = xyz;
      tp.p.intensity = fi.present ? static_cast<float>(fi(p)) : 0.f;
      tp.p.ring = fring.present ? static_cast<std::uint16_t>(std::clamp(fring(p), 0.0, 65535.0))
                                : ringFromElevation(xyz, o.num_rings);
      pts.push_back(tp);
    }
  }
  if (stats) stats->add(local);
  return finish(pts, o, header_ns);
}

LidarScan decodeLivox(const LivoxCustomMsg& msg, const CloudDecodeOptions& o, DecodeStats* stats) {
  const Stamp base_ns = msg.timebase != 0 ? static_cast<Stamp>(msg.timebase) : stampNs(msg.header.stamp);
  DecodeStats local;
  std::vector<TimedPoint> pts;
  pts.reserve(msg.points.size());
  for (const LivoxCustomPoint& q : msg.points) {
    const Eigen::Vector3f xyz(q.x, q.y, q.z);
    if (!keepPoint(xyz, 0.0, o, local)) continue;
    TimedPoint tp{base_ns + static_cast<Stamp>(q.offset_time), Point{}};
    tp.p.xyz = xyz;
    tp.p.intensity = static_cast<float>(q.reflectivity);
    tp.p.ring = q.line;
    pts.push_back(tp);
  }
  if (stats) stats->add(local);
  return finish(pts, o, base_ns);
}

ImuSample decodeImu(const sensor_msgs::Imu& msg, double acc_scale) {
  ImuSample s;
  s.stamp_ns = stampNs(msg.header.stamp);
  s.gyro_rad_s = {msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z};
  s.acc_m_s2 =
      Eigen::Vector3d(msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z) * acc_scale;
  return s;
}

std::vector<std::string> pointFieldDescriptions(const sensor_msgs::PointCloud2& msg) {
  std::vector<std::string> out;
  for (const PF& f : msg.fields) {
    std::string d = f.name + "(" + datatypeName(f.datatype);
    if (f.count > 1) d += "x" + std::to_string(f.count);
    out.push_back(d + ")");
  }
  return out;
}

}  // namespace mmlio::io
