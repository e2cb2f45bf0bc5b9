#include "mmlio/io/trajectory_writer.hpp"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "mmlio/core/error.hpp"

namespace mmlio::io {

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("cannot open '" + tmp + "' for writing (does the directory exist and is it writable?)");
    write(out);
    out.flush();
    if (!out) throw Error("write to '" + path + "' failed (disk full?)");
    out.close();
    if (!out) throw Error("closing '" + path + "' failed (disk full?)");
    if (std::rename(tmp.c_str(), path.c_str()) != 0) throw Error("cannot rename '" + tmp + "' to '" + path + "'");
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
}

std::string formatDouble(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (value == 0.0) value = 0.0;  // print -0 as 0
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof(buf), value);
  return std::string(buf, result.ptr);
}

std::string formatStampSeconds(Stamp stamp_ns) {
  const bool negative = stamp_ns < 0;
  // Work in unsigned to survive INT64_MIN.
  const std::uint64_t magnitude =
      negative ? 0ULL - static_cast<std::uint64_t>(stamp_ns) : static_cast<std::uint64_t>(stamp_ns);
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000ULL),
                static_cast<unsigned long long>(magnitude % 1000000000ULL));
  return buf;
}

bool parseStampSeconds(const std::string& text, Stamp& stamp_ns) {
  if (text.empty()) return false;
  if (text.find_first_of("eEnN") != std::string::npos) {  // exponent form, or nan/inf
    double s = 0.0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), s);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(s)) return false;
    stamp_ns = fromSec(s);
    return true;
  }
  std::size_t i = 0;
  bool negative = false;
  if (text[i] == '-' || text[i] == '+') negative = text[i++] == '-';
  std::int64_t whole = 0, frac = 0;
  int whole_digits = 0, frac_digits = 0;
  for (; i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); ++i, ++whole_digits) {
    whole = whole * 10 + (text[i] - '0');
    if (whole > 9000000000LL) return false;  // beyond int64 nanoseconds
  }
  bool round_up = false;
  if (i < text.size() && text[i] == '.') {
    ++i;
    for (; i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); ++i) {
      if (frac_digits < 9) {
        frac = frac * 10 + (text[i] - '0');
      } else if (frac_digits == 9) {
        round_up = text[i] >= '5';
      }
      ++frac_digits;
    }
  }
  if (i != text.size() || whole_digits + frac_digits == 0) return false;
  for (int d = frac_digits; d < 9; ++d) frac *= 10;
  std::int64_t ns = whole * 1000000000LL + frac + (round_up ? 1 : 0);
  stamp_ns = negative ? -ns : ns;
  return true;
}

namespace {

std::vector<std::string> splitWhitespace(const std::string& line) {
  std::vector<std::string> tokens;
  std::istringstream is(line);
  std::string token;
  while (is >> token) tokens.push_back(token);
  return tokens;
}

bool parseDouble(const std::string& text, double& value) {
  const char* begin = text.data();
  if (!text.empty() && text[0] == '+') ++begin;
  const auto r = std::from_chars(begin, text.data() + text.size(), value);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

bool isBlankOrComment(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

std::ifstream openForReading(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open '" + path + "' for reading (missing file?)");
  return in;
}

Eigen::Quaterniond canonicalQuaternion(const Eigen::Isometry3d& T) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

}  // namespace

void writeTum(const std::string& path, const Trajectory& trajectory) {
  writeFileAtomically(path, [&](std::ostream& out) {
    for (const auto& pose : trajectory) {
      const Eigen::Vector3d t = pose.T_world_body.translation();
      const Eigen::Quaterniond q = canonicalQuaternion(pose.T_world_body);
      out << formatStampSeconds(pose.stamp_ns) << ' ' << formatDouble(t.x()) << ' ' << formatDouble(t.y()) << ' '
          << formatDouble(t.z()) << ' ' << formatDouble(q.x()) << ' ' << formatDouble(q.y()) << ' '
          << formatDouble(q.z()) << ' ' << formatDouble(q.w()) << '\n';
    }
  });
}

Trajectory readTum(const std::string& path) {
  std::ifstream in = openForReading(path);
  Trajectory trajectory;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (isBlankOrComment(line)) continue;
    const std::string where = path + ":" + std::to_string(line_no);
    const auto tokens = splitWhitespace(line);
    if (tokens.size() != 8)
      throw Error(where + ": expected 8 numbers 'stamp tx ty tz qx qy qz qw', got " + std::to_string(tokens.size()) +
                  " fields");
    StampedPose pose;
    if (!parseStampSeconds(tokens[0], pose.stamp_ns)) throw Error(where + ": bad stamp '" + tokens[0] + "'");
    double v[7];
    for (int k = 0; k < 7; ++k) {
      if (!parseDouble(tokens[k + 1], v[k]) || !std::isfinite(v[k]))
        throw Error(where + ": bad number '" + tokens[k + 1] + "' in field " + std::to_string(k + 2));
    }
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (q.norm() < 1e-9) throw Error(where + ": zero quaternion");
    pose.T_world_body.linear() = q.normalized().toRotationMatrix();
    pose.T_world_body.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    trajectory.push_back(pose);
  }
  return trajectory;
}

void writeKitti(const std::string& path, const Trajectory& trajectory) {
  writeFileAtomically(path, [&](std::ostream& out) {
    for (const auto& pose : trajectory) {
      const Eigen::Matrix4d m = pose.T_world_body.matrix();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) out << formatDouble(m(r, c)) << (r == 2 && c == 3 ? '\n' : ' ');
    }
  });
}

void writeKittiTimes(const std::string& path, const Trajectory& trajectory) {
  writeFileAtomically(path, [&](std::ostream& out) {
    for (const auto& pose : trajectory) out << formatStampSeconds(pose.stamp_ns) << '\n';
  });
}

Trajectory readKitti(const std::string& path, const std::string& times_path) {
  Trajectory trajectory;
  {
    std::ifstream in = openForReading(path);
    std::string line;
    for (int line_no = 1; std::getline(in, line); ++line_no) {
      if (isBlankOrComment(line)) continue;
      const std::string where = path + ":" + std::to_string(line_no);
      const auto tokens = splitWhitespace(line);
      if (tokens.size() != 12)
        throw Error(where + ": expected 12 numbers (3x4 row-major), got " + std::to_string(tokens.size()));
      StampedPose pose;
      pose.stamp_ns = static_cast<Stamp>(trajectory.size());
      Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
      for (int k = 0; k < 12; ++k) {
        if (!parseDouble(tokens[k], m(k / 4, k % 4)) || !std::isfinite(m(k / 4, k % 4)))
          throw Error(where + ": bad number '" + tokens[k] + "'");
      }
      pose.T_world_body.matrix() = m;
      trajectory.push_back(pose);
    }
  }
  if (!times_path.empty()) {
    std::ifstream in = openForReading(times_path);
    std::string line;
    std::size_t index = 0;
    for (int line_no = 1; std::getline(in, line); ++line_no) {
      if (isBlankOrComment(line)) continue;
      const std::string where = times_path + ":" + std::to_string(line_no);
      const auto tokens = splitWhitespace(line);
      if (tokens.size() != 1) throw Error(where + ": expected one stamp per line");
      if (index >= trajectory.size())
        throw Error(where + ": more stamps than poses in '" + path + "' (" + std::to_string(trajectory.size()) + ")");
      if (!parseStampSeconds(tokens[0], trajectory[index].stamp_ns))
        throw Error(where + ": bad stamp '" + tokens[0] + "'");
      ++index;
    }
    if (index != trajectory.size())
      throw Error(times_path + ": " + std::to_string(index) + " stamps for " + std::to_string(trajectory.size()) +
                  " poses in '" + path + "'");
  }
  return trajectory;
}

}  // namespace mmlio::io
