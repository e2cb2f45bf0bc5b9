// The session folder: what is written reads back as written, a loaded session saved again is the
// same bytes, and a damaged or foreign folder is refused in one line naming the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "../common/error_of.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/session_io.hpp"

namespace fs = std::filesystem;
using namespace mmlio;
using namespace mmlio::io;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("mmlio_test_session_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string sub(const std::string& name) const { return (path / name).string(); }
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

Eigen::Isometry3d randomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 3.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return T;
}

/// Twelve keyframes (the fourth without a cloud, as a revisit leaves it), two loops, a map.
Session exampleSession() {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 4.0);
  Session s;
  s.map_voxel_m = 0.05;
  s.cloud_voxel_m = 0.1;
  for (int k = 0; k < 12; ++k) {
    SessionKeyframe kf;
    kf.stamp_ns = 1'673'400'472'138'016'708LL + k * 333'333'333LL;
    kf.T_map_body = randomPose(rng);
    kf.T_odom_body = randomPose(rng);
    if (k != 3)
      for (int i = 0; i < 50 + 10 * k; ++i) kf.cloud_body.emplace_back(n(rng), n(rng), n(rng));
    s.keyframes.push_back(kf);
  }
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Random();
  s.loops.push_back({11, 0, randomPose(rng), a * a.transpose()});
  s.loops.push_back({9, 2, randomPose(rng), Eigen::Matrix<double, 6, 6>::Identity() * 1e4});
  for (int i = 0; i < 300; ++i) {
    Point p;
    p.xyz = Eigen::Vector3f(static_cast<float>(n(rng)), static_cast<float>(n(rng)), static_cast<float>(n(rng)));
    p.intensity = static_cast<float>(i % 97);
    s.map.push_back(p);
  }
  return s;
}

const SessionInfo kInfo{kSessionFormatVersion, "0.9.0", "abc1234", "hvi", "mode: hvi\nlidars: []\n"};

TEST(Session, ReadsBackWhatWasWritten) {
  TempDir tmp;
  const Session s = exampleSession();
  writeSession(tmp.sub("session"), s, kInfo);
  SessionInfo info;
  const Session r = readSession(tmp.sub("session"), &info);
  EXPECT_EQ(info.mmlio_version, "0.9.0");
  EXPECT_EQ(info.commit, "abc1234");
  EXPECT_EQ(info.mode, "hvi");
  EXPECT_EQ(info.rig_yaml, kInfo.rig_yaml);
  EXPECT_EQ(r.map_voxel_m, 0.05);
  EXPECT_EQ(r.cloud_voxel_m, 0.1);
  ASSERT_EQ(r.keyframes.size(), s.keyframes.size());
  for (std::size_t k = 0; k < s.keyframes.size(); ++k) {
    EXPECT_EQ(r.keyframes[k].stamp_ns, s.keyframes[k].stamp_ns);
    // Poses exactly; clouds to float precision (they are stored as PCD float32).
    EXPECT_EQ(r.keyframes[k].T_map_body.matrix(), s.keyframes[k].T_map_body.matrix());
    EXPECT_EQ(r.keyframes[k].T_odom_body.matrix(), s.keyframes[k].T_odom_body.matrix());
    ASSERT_EQ(r.keyframes[k].cloud_body.size(), s.keyframes[k].cloud_body.size()) << "keyframe " << k;
    for (std::size_t i = 0; i < s.keyframes[k].cloud_body.size(); ++i)
      EXPECT_EQ(r.keyframes[k].cloud_body[i], s.keyframes[k].cloud_body[i].cast<float>().cast<double>());
  }
  ASSERT_EQ(r.loops.size(), 2u);
  EXPECT_EQ(r.loops[0].from, 11);
  EXPECT_EQ(r.loops[0].to, 0);
  EXPECT_EQ(r.loops[0].T_from_to.matrix(), s.loops[0].T_from_to.matrix());
  EXPECT_EQ(r.loops[0].information, s.loops[0].information);
  ASSERT_EQ(r.map.size(), s.map.size());
  EXPECT_EQ(r.map[17].xyz, s.map[17].xyz);
  EXPECT_EQ(r.map[17].intensity, s.map[17].intensity);
}

TEST(Session, LoadedAndSavedAgainIsTheSameBytes) {
  TempDir tmp;
  writeSession(tmp.sub("a"), exampleSession(), kInfo);
  SessionInfo info;
  const Session loaded = readSession(tmp.sub("a"), &info);
  writeSession(tmp.sub("b"), loaded, info);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(tmp.sub("a"))) {
    ++files;
    const fs::path other = fs::path(tmp.sub("b")) / entry.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_EQ(slurp(entry.path()), slurp(other)) << entry.path().filename();
  }
  EXPECT_EQ(files, 7);  // session.yaml rig.yaml keyframes.txt keyframes.tum loops.txt keyframe_clouds.pcd map.pcd
}

TEST(Session, ReplacesAnOlderSessionWhole) {
  TempDir tmp;
  Session big = exampleSession();
  writeSession(tmp.sub("s"), big, kInfo);
  Session small = big;
  small.keyframes.resize(2);
  small.loops.clear();
  writeSession(tmp.sub("s"), small, kInfo);
  EXPECT_EQ(readSession(tmp.sub("s")).keyframes.size(), 2u);
  for (const auto& entry : fs::directory_iterator(tmp.path))  // nothing left beside it
    EXPECT_EQ(entry.path().filename(), "s");
}

TEST(Session, RefusesAnotherFormatVersionInOneLine) {
  TempDir tmp;
  writeSession(tmp.sub("s"), exampleSession(), {2, "9.0", "x", "hvi", ""});
  EXPECT_ERROR_CONTAINS(readSession(tmp.sub("s")), "session format 2, this mmlio reads format 1");
}

TEST(Session, RefusesAFolderThatIsNoSession) {
  TempDir tmp;
  EXPECT_ERROR_CONTAINS(readSession(tmp.sub("missing")), "not a session folder");
  fs::create_directories(tmp.sub("empty"));
  EXPECT_ERROR_CONTAINS(readSession(tmp.sub("empty")), "no session.yaml");
}

TEST(Session, RefusesDamagedFilesNamingThem) {
  TempDir tmp;
  const Session s = exampleSession();
  const auto fresh = [&] {
    writeSession(tmp.sub("s"), s, kInfo);
    return fs::path(tmp.sub("s"));
  };
  // The clouds cut short.
  fs::path dir = fresh();
  fs::resize_file(dir / "keyframe_clouds.pcd", fs::file_size(dir / "keyframe_clouds.pcd") - 100);
  EXPECT_ERROR_CONTAINS(readSession(dir.string()), "keyframe_clouds.pcd");
  // A keyframe row with a damaged number.
  dir = fresh();
  std::string text = slurp(dir / "keyframes.txt");
  text.replace(text.find('\n', text.find('\n') + 1) - 3, 1, "x");
  std::ofstream(dir / "keyframes.txt", std::ios::binary) << text;
  EXPECT_ERROR_CONTAINS(readSession(dir.string()), "keyframes.txt:2");
  // A loop to a keyframe that is not there.
  dir = fresh();
  text = slurp(dir / "loops.txt");
  text.replace(text.find("\n11 0") + 1, 2, "40");
  std::ofstream(dir / "loops.txt", std::ios::binary) << text;
  EXPECT_ERROR_CONTAINS(readSession(dir.string()), "loops.txt: a loop ends at keyframe 40 of 12");
  // The map missing.
  dir = fresh();
  fs::remove(dir / "map.pcd");
  EXPECT_ERROR_CONTAINS(readSession(dir.string()), "map.pcd");
}

}  // namespace
