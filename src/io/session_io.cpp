#include "mmlio/io/session_io.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "mmlio/core/error.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::io {
namespace fs = std::filesystem;
namespace {

constexpr const char* kFormatName = "mmlio-session";

void writeMatrix(std::ostream& os, const Eigen::Isometry3d& T) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) os << ' ' << formatDouble(T.matrix()(r, c));
}

/// The numbers of one text row, checked: `file:line` in every error.
class Row {
 public:
  Row(const std::string& line, std::string where) : is_(line), where_(std::move(where)) {}
  double number() {
    std::string token;
    if (!(is_ >> token)) throw Error(where_ + ": too few numbers");
    double v = 0;
    const auto r = std::from_chars(token.data(), token.data() + token.size(), v);
    if (r.ec != std::errc() || r.ptr != token.data() + token.size() || !std::isfinite(v))
      throw Error(where_ + ": not a finite number: '" + token + "'");
    return v;
  }
  int natural() {
    const double v = number();
    if (v < 0 || v != static_cast<double>(static_cast<int>(v))) throw Error(where_ + ": not a whole number");
    return static_cast<int>(v);
  }
  Stamp stamp() {
    std::string token;
    Stamp t = 0;
    if (!(is_ >> token) || !parseStampSeconds(token, t)) throw Error(where_ + ": not a stamp");
    return t;
  }
  Eigen::Isometry3d pose() {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) T.matrix()(r, c) = number();
    const Eigen::Matrix3d R = T.linear();
    if (!(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || R.determinant() < 0)
      throw Error(where_ + ": not a rotation");
    return T;
  }
  void end() {
    std::string token;
    if (is_ >> token) throw Error(where_ + ": too many numbers");
  }

 private:
  std::istringstream is_;
  std::string where_;
};

/// f(row, "file:line") for every line that is not blank or a comment.
template <class F> void forEachRow(const fs::path& path, F&& f) {
  std::ifstream in(path);
  if (!in) throw Error("session file missing: " + path.string());
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    Row row(line, path.string() + ":" + std::to_string(n));
    f(row);
  }
}

void writeInto(const fs::path& dir, const Session& s, const SessionInfo& info) {
  std::size_t cloud_points = 0;
  for (const SessionKeyframe& k : s.keyframes) cloud_points += k.cloud_body.size();
  writeFileAtomically((dir / "session.yaml").string(), [&](std::ostream& os) {
    os << "# An mmlio session: what a later run needs to localize in this map and extend it (docs/session.md)\n"
       << "format: " << kFormatName << "\nformat_version: " << info.format_version << "\nmmlio_version: \""
       << info.mmlio_version << "\"\ncommit: \"" << info.commit << "\"\nmode: \"" << info.mode
       << "\"\nkeyframes: " << s.keyframes.size() << "\nloops: " << s.loops.size()
       << "\nkeyframe_cloud_points: " << cloud_points << "\nmap_points: " << s.map.size()
       << "\nmap_voxel_m: " << formatDouble(s.map_voxel_m) << "\ncloud_voxel_m: " << formatDouble(s.cloud_voxel_m)
       << '\n';
  });
  writeFileAtomically((dir / "rig.yaml").string(), [&](std::ostream& os) { os << info.rig_yaml; });
  writeFileAtomically((dir / "keyframes.txt").string(), [&](std::ostream& os) {
    os << "# index stamp_s T_map_body(3x4 row-major) T_odom_body(3x4 row-major) cloud_points\n";
    for (std::size_t i = 0; i < s.keyframes.size(); ++i) {
      const SessionKeyframe& k = s.keyframes[i];
      os << i << ' ' << formatStampSeconds(k.stamp_ns);
      writeMatrix(os, k.T_map_body);
      writeMatrix(os, k.T_odom_body);
      os << ' ' << k.cloud_body.size() << '\n';
    }
  });
  Trajectory keyframe_poses;
  for (const SessionKeyframe& k : s.keyframes) keyframe_poses.push_back({k.stamp_ns, k.T_map_body});
  writeTum((dir / "keyframes.tum").string(), keyframe_poses);
  writeFileAtomically((dir / "loops.txt").string(), [&](std::ostream& os) {
    os << "# from to T_from_to(3x4 row-major) information(6x6 row-major, order dp dtheta)\n";
    for (const SessionLoop& l : s.loops) {
      os << l.from << ' ' << l.to;
      writeMatrix(os, l.T_from_to);
      for (int i = 0; i < 36; ++i) os << ' ' << formatDouble(l.information(i / 6, i % 6));
      os << '\n';
    }
  });
  // Row by row from the keyframes: a hall's clouds are millions of points.
  std::size_t keyframe = 0, point = 0;
  writePcdFieldsBinary((dir / "keyframe_clouds.pcd").string(),
                       {{"x", 4, 'F', 1}, {"y", 4, 'F', 1}, {"z", 4, 'F', 1}, {"keyframe", 4, 'U', 1}}, cloud_points,
                       [&](double* values) {
                         while (point >= s.keyframes[keyframe].cloud_body.size()) {
                           ++keyframe;
                           point = 0;
                         }
                         const Eigen::Vector3d& p = s.keyframes[keyframe].cloud_body[point++];
                         for (int a = 0; a < 3; ++a) values[a] = static_cast<float>(p[a]);
                         values[3] = static_cast<double>(keyframe);
                       });
  writePcdBinary((dir / "map.pcd").string(), s.map);
}

}  // namespace

void writeSession(const std::string& dir, const Session& session, const SessionInfo& info) {
  const fs::path target(dir);
  const fs::path aside = target.string() + ".writing-" + std::to_string(::getpid());
  const fs::path old = target.string() + ".old-" + std::to_string(::getpid());
  std::error_code ec;
  fs::remove_all(aside, ec);
  fs::create_directories(aside, ec);
  if (ec) throw Error("cannot create the session folder '" + aside.string() + "': " + ec.message());
  writeInto(aside, session, info);
  // The new folder takes the old one's place; the old one is removed only then.
  if (fs::exists(target)) fs::rename(target, old, ec);
  if (ec) throw Error("cannot replace the session '" + dir + "': " + ec.message());
  fs::rename(aside, target, ec);
  if (ec) throw Error("cannot move the session into '" + dir + "': " + ec.message());
  fs::remove_all(old, ec);
}

bool holdsSession(const std::string& out_dir, const std::string& session_dir) {
  fs::path folder = fs::absolute(fs::path(session_dir)).lexically_normal();
  if (!folder.has_filename()) folder = folder.parent_path();  // "out/session/"
  std::error_code ec;
  return fs::exists(out_dir, ec) && fs::equivalent(fs::path(out_dir), folder.parent_path(), ec);
}

Session readSession(const std::string& dir, SessionInfo* info_out) {
  const fs::path root(dir);
  if (!fs::is_directory(root)) throw Error("not a session folder: " + dir);
  const fs::path manifest = root / "session.yaml";
  if (!fs::exists(manifest)) throw Error("not a session folder (no session.yaml): " + dir);
  SessionInfo info;
  Session s;
  std::size_t keyframes = 0, loops = 0, cloud_points = 0, map_points = 0;
  try {
    const YAML::Node y = YAML::LoadFile(manifest.string());
    if (!y["format"] || y["format"].as<std::string>() != kFormatName)
      throw Error(manifest.string() + ": not an mmlio session (format is not '" + kFormatName + "')");
    info.format_version = y["format_version"].as<int>();
    if (info.format_version != kSessionFormatVersion)
      throw Error(manifest.string() + ": session format " + std::to_string(info.format_version) +
                  ", this mmlio reads format " + std::to_string(kSessionFormatVersion) +
                  " (map the building again, or use the mmlio that wrote it)");
    info.mmlio_version = y["mmlio_version"].as<std::string>();
    info.commit = y["commit"].as<std::string>();
    info.mode = y["mode"].as<std::string>();
    keyframes = y["keyframes"].as<std::size_t>();
    loops = y["loops"].as<std::size_t>();
    cloud_points = y["keyframe_cloud_points"].as<std::size_t>();
    map_points = y["map_points"].as<std::size_t>();
    s.map_voxel_m = y["map_voxel_m"].as<double>();
    s.cloud_voxel_m = y["cloud_voxel_m"].as<double>();
  } catch (const YAML::Exception& e) {
    throw Error(manifest.string() + ": " + e.what());
  }
  {
    std::ifstream in(root / "rig.yaml");
    if (!in) throw Error("session file missing: " + (root / "rig.yaml").string());
    std::ostringstream text;
    text << in.rdbuf();
    info.rig_yaml = text.str();
  }
  std::vector<std::size_t> expected_points;
  forEachRow(root / "keyframes.txt", [&](Row& row) {
    if (row.natural() != static_cast<int>(s.keyframes.size())) throw Error("keyframes.txt: indices out of order");
    SessionKeyframe k;
    k.stamp_ns = row.stamp();
    k.T_map_body = row.pose();
    k.T_odom_body = row.pose();
    expected_points.push_back(static_cast<std::size_t>(row.natural()));
    row.end();
    s.keyframes.push_back(std::move(k));
  });
  if (s.keyframes.size() != keyframes)
    throw Error((root / "keyframes.txt").string() + ": " + std::to_string(s.keyframes.size()) +
                " keyframes, session.yaml says " + std::to_string(keyframes));
  forEachRow(root / "loops.txt", [&](Row& row) {
    SessionLoop l;
    l.from = row.natural();
    l.to = row.natural();
    l.T_from_to = row.pose();
    for (int i = 0; i < 36; ++i) l.information(i / 6, i % 6) = row.number();
    row.end();
    if (static_cast<std::size_t>(std::max(l.from, l.to)) >= s.keyframes.size())
      throw Error((root / "loops.txt").string() + ": a loop ends at keyframe " +
                  std::to_string(std::max(l.from, l.to)) + " of " + std::to_string(s.keyframes.size()));
    s.loops.push_back(l);
  });
  if (s.loops.size() != loops)
    throw Error((root / "loops.txt").string() + ": " + std::to_string(s.loops.size()) + " loops, session.yaml says " +
                std::to_string(loops));
  const PcdCloud clouds = readPcdFields((root / "keyframe_clouds.pcd").string());
  if (clouds.size() != cloud_points)
    throw Error((root / "keyframe_clouds.pcd").string() + ": " + std::to_string(clouds.size()) +
                " points, session.yaml says " + std::to_string(cloud_points));
  const auto& x = clouds.column("x");
  const auto& y = clouds.column("y");
  const auto& z = clouds.column("z");
  const auto& owner = clouds.column("keyframe");
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    const auto k = static_cast<std::size_t>(owner[i]);
    if (k >= s.keyframes.size() || (i > 0 && owner[i] < owner[i - 1]))
      throw Error((root / "keyframe_clouds.pcd").string() + ": point " + std::to_string(i) +
                  " belongs to no keyframe in order");
    s.keyframes[k].cloud_body.emplace_back(x[i], y[i], z[i]);
  }
  for (std::size_t k = 0; k < s.keyframes.size(); ++k)
    if (s.keyframes[k].cloud_body.size() != expected_points[k])
      throw Error((root / "keyframe_clouds.pcd").string() + ": keyframe " + std::to_string(k) + " has " +
                  std::to_string(s.keyframes[k].cloud_body.size()) + " points, keyframes.txt says " +
                  std::to_string(expected_points[k]));
  s.map = readPcd((root / "map.pcd").string());
  if (s.map.size() != map_points)
    throw Error((root / "map.pcd").string() + ": " + std::to_string(s.map.size()) + " points, session.yaml says " +
                std::to_string(map_points));
  if (info_out) *info_out = std::move(info);
  return s;
}

}  // namespace mmlio::io
