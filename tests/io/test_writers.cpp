// Trajectory (TUM / KITTI) and PCD writers and readers: exact round trips, the exact PCD header
// PCL expects, and the real PCD files in shared/data/real.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <functional>
#include <set>
#include <fstream>
#include <sstream>

#include "../common/error_of.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/pcd_io.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace fs = std::filesystem;
using namespace mmlio;
using namespace mmlio::io;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("mmlio_test_writers_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

Trajectory sampleTrajectory() {
  Trajectory t;
  for (int i = 0; i < 5; ++i) {
    StampedPose p;
    p.stamp_ns = 1673400472138016708LL + i * 100000001LL;  // needs all 19 digits to survive
    p.T_world_body.linear() =
        Eigen::AngleAxisd(0.3 * i + 0.1, Eigen::Vector3d(1, 2, 3 - i).normalized()).toRotationMatrix();
    p.T_world_body.translation() = Eigen::Vector3d(0.1 * i, -1.0 / 3.0 * i, 1e-7 + 1234.5678 * i);
    t.push_back(p);
  }
  return t;
}

}  // namespace

TEST(Stamp, NanosecondsPrintAsSecondsWithNineDecimalsAndParseBackExactly) {
  EXPECT_EQ(formatStampSeconds(1673400472138016708LL), "1673400472.138016708");
  EXPECT_EQ(formatStampSeconds(5), "0.000000005");
  EXPECT_EQ(formatStampSeconds(-1500000000LL), "-1.500000000");
  Stamp ns = 0;
  ASSERT_TRUE(parseStampSeconds("1673400472.138016708", ns));
  EXPECT_EQ(ns, 1673400472138016708LL);
  ASSERT_TRUE(parseStampSeconds("12.5", ns));
  EXPECT_EQ(ns, 12500000000LL);
  ASSERT_TRUE(parseStampSeconds("3", ns));
  EXPECT_EQ(ns, 3000000000LL);
  ASSERT_TRUE(parseStampSeconds("1.0000000015", ns));  // 10th decimal rounds
  EXPECT_EQ(ns, 1000000002LL);
  ASSERT_TRUE(parseStampSeconds("1.5e3", ns));
  EXPECT_EQ(ns, 1500000000000LL);
  EXPECT_FALSE(parseStampSeconds("1.2.3", ns));
  EXPECT_FALSE(parseStampSeconds("abc", ns));
  EXPECT_FALSE(parseStampSeconds("", ns));
  EXPECT_FALSE(parseStampSeconds("99999999999999999999", ns));
}

TEST(Tum, IdentityPoseIsOneLineOfStampTranslationQuaternion) {
  TempDir dir;
  StampedPose p;
  p.stamp_ns = 1500000000LL;
  p.T_world_body.translation() = Eigen::Vector3d(1, 2, 3);
  writeTum(dir.file("t.txt"), {p});
  EXPECT_EQ(slurp(dir.file("t.txt")), "1.500000000 1 2 3 0 0 0 1\n");
}

TEST(Tum, RoundTripKeepsStampsTranslationsAndQuaternionsExactly) {
  TempDir dir;
  const Trajectory in = sampleTrajectory();
  writeTum(dir.file("traj.tum"), in);
  const Trajectory out = readTum(dir.file("traj.tum"));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].stamp_ns, in[i].stamp_ns);
    EXPECT_EQ(out[i].T_world_body.translation(), in[i].T_world_body.translation());
    // Rotation matrix -> quaternion -> matrix is exact up to the last bits of a double.
    EXPECT_LT((out[i].T_world_body.linear() - in[i].T_world_body.linear()).cwiseAbs().maxCoeff(), 1e-15);
  }
}

TEST(Tum, QuaternionIsWrittenWithNonNegativeW) {
  TempDir dir;
  StampedPose p;
  p.T_world_body.linear() = Eigen::AngleAxisd(3.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  writeTum(dir.file("t.txt"), {p});
  const auto out = readTum(dir.file("t.txt"));
  std::istringstream is(slurp(dir.file("t.txt")));
  double v[8];
  for (double& x : v) is >> x;
  EXPECT_GE(v[7], 0.0);
  EXPECT_NEAR(v[6], std::sin(1.5), 1e-15);
}

TEST(Tum, ReaderSkipsCommentsAndBlankLines) {
  TempDir dir;
  writeText(dir.file("t.txt"), "# timestamp tx ty tz qx qy qz qw\n\n10.25 1 2 3 0 0 0 2\n   # indented comment\n");
  const auto t = readTum(dir.file("t.txt"));
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].stamp_ns, 10250000000LL);
  EXPECT_TRUE(t[0].T_world_body.linear().isIdentity(1e-15));  // (0,0,0,2) normalised
}

TEST(Tum, MalformedRowErrorNamesFileAndLine) {
  TempDir dir;
  const std::string path = dir.file("bad.txt");
  writeText(path, "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  EXPECT_NE(mmlio::testing::errorOf([&] { readTum(path); }).find(path + ":3"), std::string::npos)
      << mmlio::testing::errorOf([&] { readTum(path); });
  writeText(path, "1.0 0 0 x 0 0 0 1\n");
  EXPECT_NE(mmlio::testing::errorOf([&] { readTum(path); }).find(path + ":1: bad number 'x'"), std::string::npos);
  writeText(path, "1.0 0 0 0 0 0 0 0\n");
  EXPECT_NE(mmlio::testing::errorOf([&] { readTum(path); }).find("zero quaternion"), std::string::npos);
}

TEST(Tum, MissingFileErrorNamesThePath) {
  EXPECT_NE(mmlio::testing::errorOf([] { readTum("/nonexistent/dir/traj.txt"); }).find("/nonexistent/dir/traj.txt"),
            std::string::npos);
}

TEST(Kitti, RoundTripKeepsAllTwelveNumbersAndStampsExactly) {
  TempDir dir;
  const Trajectory in = sampleTrajectory();
  writeKitti(dir.file("poses.txt"), in);
  writeKittiTimes(dir.file("times.txt"), in);
  const Trajectory out = readKitti(dir.file("poses.txt"), dir.file("times.txt"));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].stamp_ns, in[i].stamp_ns);
    EXPECT_EQ(out[i].T_world_body.matrix(), in[i].T_world_body.matrix());
  }
  // Without times the stamps are the pose index.
  const Trajectory indexed = readKitti(dir.file("poses.txt"));
  EXPECT_EQ(indexed[3].stamp_ns, 3);
}

TEST(Kitti, IdentityPoseIsTwelveRowMajorNumbers) {
  TempDir dir;
  StampedPose p;
  p.T_world_body.translation() = Eigen::Vector3d(4, 5, 6);
  writeKitti(dir.file("p.txt"), {p});
  EXPECT_EQ(slurp(dir.file("p.txt")), "1 0 0 4 0 1 0 5 0 0 1 6\n");
}

TEST(Kitti, TimesWithWrongLineCountIsAnError) {
  TempDir dir;
  writeKitti(dir.file("p.txt"), sampleTrajectory());
  writeText(dir.file("t.txt"), "0.1\n0.2\n");
  EXPECT_NE(
      mmlio::testing::errorOf([&] { readKitti(dir.file("p.txt"), dir.file("t.txt")); }).find("2 stamps for 5 poses"),
      std::string::npos);
}

TEST(AtomicWrite, FailedWriteLeavesNeitherTheTargetNorATempFile) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  EXPECT_THROW(writeFileAtomically(path,
                                   [](std::ostream& out) {
                                     out << "half";
                                     throw Error("boom");
                                   }),
               Error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::is_empty(dir.path));
  // An existing output survives a failed rewrite untouched.
  writeText(path, "old");
  EXPECT_THROW(writeFileAtomically(path, [](std::ostream&) { throw Error("boom"); }), Error);
  EXPECT_EQ(slurp(path), "old");
}

TEST(AtomicWrite, UnwritableDirectoryErrorNamesThePath) {
  const std::string msg = mmlio::testing::errorOf([] { writeTum("/nonexistent/dir/out.tum", sampleTrajectory()); });
  EXPECT_NE(msg.find("/nonexistent/dir/out.tum"), std::string::npos) << msg;
}

TEST(Pcd, BinaryHeaderIsExactlyWhatPclWrites) {
  EXPECT_EQ(pcdBinaryHeader(3),
            "# .PCD v0.7 - Point Cloud Data file format\n"
            "VERSION 0.7\n"
            "FIELDS x y z intensity\n"
            "SIZE 4 4 4 4\n"
            "TYPE F F F F\n"
            "COUNT 1 1 1 1\n"
            "WIDTH 3\n"
            "HEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\n"
            "POINTS 3\n"
            "DATA binary\n");
}

TEST(Pcd, BinaryRoundTripKeepsEveryFloatExactly) {
  TempDir dir;
  std::vector<Point> in;
  for (int i = 0; i < 1000; ++i) {
    Point p;
    p.xyz = Eigen::Vector3f(0.1f * i, -1.0f / (i + 1), 1e-3f * i * i);
    p.intensity = static_cast<float>(i % 256);
    in.push_back(p);
  }
  writePcdBinary(dir.file("map.pcd"), in);
  const std::string bytes = slurp(dir.file("map.pcd"));
  EXPECT_EQ(bytes.size(), pcdBinaryHeader(in.size()).size() + in.size() * 16);
  EXPECT_EQ(bytes.substr(0, pcdBinaryHeader(in.size()).size()), pcdBinaryHeader(in.size()));
  // Little-endian float32 of the first point's y right after the header.
  float y0 = 0;
  std::memcpy(&y0, bytes.data() + pcdBinaryHeader(in.size()).size() + 4, 4);
  EXPECT_EQ(y0, -1.0f);

  const auto out = readPcd(dir.file("map.pcd"));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].xyz, in[i].xyz);
    EXPECT_EQ(out[i].intensity, in[i].intensity);
  }
}

TEST(Pcd, GenericFieldsRoundTripWithTheirTypes) {
  TempDir dir;
  PcdCloud in;
  in.header.fields = {{"x", 4, 'F', 1}, {"ring", 2, 'U', 1}, {"t", 8, 'F', 1}, {"d", 1, 'I', 1}};
  in.fields = {"x", "ring", "t", "d"};
  in.columns = {{0.5, -1.25, 3.0}, {0, 15, 65535}, {1673400472.138016708, 1e-9, -2.0}, {-128, 0, 127}};
  writePcdFieldsBinary(dir.file("g.pcd"), in);
  const PcdCloud out = readPcdFields(dir.file("g.pcd"));
  EXPECT_EQ(out.header.pointStepBytes(), 4u + 2u + 8u + 1u);
  EXPECT_EQ(out.fields, in.fields);
  EXPECT_EQ(out.columns, in.columns);  // all values representable exactly in their types
  in.header.fields[1].count = 2;
  EXPECT_THROW(writePcdFieldsBinary(dir.file("bad.pcd"), in), Error);
}

TEST(Pcd, EmptyCloudWritesAndReadsBack) {
  TempDir dir;
  writePcdBinary(dir.file("empty.pcd"), {});
  EXPECT_TRUE(readPcd(dir.file("empty.pcd")).empty());
}

TEST(Pcd, AsciiWithExtraFieldsAndCountReads) {
  TempDir dir;
  writeText(dir.file("a.pcd"),
            "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb normal ring\nSIZE 4 4 4 4 4 2\nTYPE F F F U F U\n"
            "COUNT 1 1 1 1 3 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
            "1 2 3 255 0 0 1 7\n-4.5 nan 6 0 1 0 0 3\n");
  const PcdCloud cloud = readPcdFields(dir.file("a.pcd"));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.fields,
            (std::vector<std::string>{"x", "y", "z", "rgb", "normal[0]", "normal[1]", "normal[2]", "ring"}));
  EXPECT_EQ(cloud.column("normal[2]")[0], 1.0);
  EXPECT_EQ(cloud.column("ring")[1], 3.0);
  const auto points = readPcd(dir.file("a.pcd"));
  ASSERT_EQ(points.size(), 1u);  // the NaN point is dropped
  EXPECT_EQ(points[0].ring, 7);
  EXPECT_EQ(points[0].intensity, 0.f);  // no intensity field
  EXPECT_NE(mmlio::testing::errorOf([&] { cloud.column("intensity"); }).find("fields: x y z rgb"), std::string::npos);
}

TEST(Pcd, BinaryCompressedDecodesFieldMajorLzfData) {
  // Two points, fields x (F4) and ring (U2): field-major raw data is x0 x1 r0 r1 = 12 bytes.
  // LZF stream: two literal runs (back references are covered by the Lzf test below).
  const float x[2] = {1.5f, -2.25f};
  std::string lzf;
  lzf.push_back(9);  // literal, 10 bytes
  lzf.append(reinterpret_cast<const char*>(x), 8);
  lzf.push_back(5);
  lzf.push_back(0);
  lzf.push_back(1);  // literal, 2 bytes
  lzf.push_back(5);
  lzf.push_back(0);
  std::string file =
      "VERSION 0.7\nFIELDS x ring\nSIZE 4 2\nTYPE F U\nCOUNT 1 1\nWIDTH 2\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary_compressed\n";
  const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(lzf.size()), 12};
  file.append(reinterpret_cast<const char*>(sizes), 8);
  file += lzf;
  TempDir dir;
  writeText(dir.file("c.pcd"), file);
  const PcdCloud cloud = readPcdFields(dir.file("c.pcd"));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.column("x")[0], 1.5);
  EXPECT_EQ(cloud.column("x")[1], -2.25);
  EXPECT_EQ(cloud.column("ring")[0], 5.0);
  EXPECT_EQ(cloud.column("ring")[1], 5.0);
}

TEST(Lzf, BackReferencesRepeatEarlierBytesIncludingOverlappingRuns) {
  // "abc" as a literal, then a back reference ctrl = (len - 2) << 5 | (dist - 1) >> 8, followed by
  // the low byte of dist - 1. Copy 6 bytes from distance 3: ctrl = 4 << 5 = 128, low byte = 2.
  const std::uint8_t in[] = {2, 'a', 'b', 'c', 128, 2};
  std::uint8_t out[16] = {};
  ASSERT_EQ(lzfDecompress(in, sizeof(in), out, sizeof(out)), 9u);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(out), 9), "abcabcabc");
  // Long match: L = 7 plus an extra length byte; copy 7 + 10 + 2 = 19 bytes from distance 1.
  const std::uint8_t in2[] = {0, 'z', 7 << 5, 10, 0};
  std::uint8_t out2[32] = {};
  ASSERT_EQ(lzfDecompress(in2, sizeof(in2), out2, sizeof(out2)), 20u);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(out2), 20), std::string(20, 'z'));
  // A reference before the start of the output is corrupt input.
  const std::uint8_t bad[] = {0, 'a', 32, 5};
  EXPECT_EQ(lzfDecompress(bad, sizeof(bad), out, sizeof(out)), 0u);
  // Output that does not fit is rejected.
  EXPECT_EQ(lzfDecompress(in, sizeof(in), out, 5), 0u);
}

TEST(Pcd, TruncatedBinaryDataErrorNamesThePath) {
  TempDir dir;
  writePcdBinary(dir.file("t.pcd"), std::vector<Point>(10));
  std::string bytes = slurp(dir.file("t.pcd"));
  writeText(dir.file("t.pcd"), bytes.substr(0, bytes.size() - 5));
  const std::string msg = mmlio::testing::errorOf([&] { readPcd(dir.file("t.pcd")); });
  EXPECT_NE(msg.find(dir.file("t.pcd")), std::string::npos);
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
}

TEST(Pcd, NotAPcdFileIsAnError) {
  TempDir dir;
  writeText(dir.file("x.pcd"), "hello world\n");
  EXPECT_NE(mmlio::testing::errorOf([&] { readPcd(dir.file("x.pcd")); }).find(dir.file("x.pcd")), std::string::npos);
}

// ---- real files -------------------------------------------------------------------------------

namespace {
const std::string kReal = MMLIO_SHARED_DATA_DIR;

void expectPlausible(const PcdCloud& cloud, double max_range_m, std::size_t max_nonfinite) {
  std::size_t nonfinite = 0;
  const auto &x = cloud.column("x"), &y = cloud.column("y"), &z = cloud.column("z");
  double max_range = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i])) {
      ++nonfinite;
      continue;
    }
    max_range = std::max(max_range, std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]));
  }
  EXPECT_LE(nonfinite, max_nonfinite);
  EXPECT_GT(max_range, 1.0);
  EXPECT_LT(max_range, max_range_m);
}
}  // namespace

TEST(RealPcd, Vlp16NebulaBinaryHasAllPointsWithSixteenChannelsAndConsistentDistances) {
  const std::string path = kReal + "/vlp16-nebula/1673400472138016708.pcd";
  const PcdCloud cloud = readPcdFields(path);
  EXPECT_EQ(cloud.header.data, "binary");
  ASSERT_EQ(cloud.size(), 14831u);
  EXPECT_EQ(cloud.header.pointStepBytes(), 32u);
  expectPlausible(cloud, 130.0, 0);
  const auto &x = cloud.column("x"), &y = cloud.column("y"), &z = cloud.column("z");
  const auto& distance = cloud.column("distance");
  const auto& channel = cloud.column("channel");
  std::set<int> channels;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    // The decoder's own distance field agrees with |xyz|: proves the packed field offsets.
    ASSERT_NEAR(std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]), distance[i], 1e-3) << "point " << i;
    channels.insert(static_cast<int>(channel[i]));
  }
  // VLP-16 laser ids are 0..15; this indoor scan has returns on 15 of them (none on id 0).
  EXPECT_GE(channels.size(), 15u);
  EXPECT_GE(*channels.begin(), 0);
  EXPECT_EQ(*channels.rbegin(), 15);
  // time_stamp is ns within one 0.1 s rotation.
  const auto& t = cloud.column("time_stamp");
  EXPECT_LT(*std::max_element(t.begin(), t.end()), 0.11e9);
  EXPECT_EQ(readPcd(path).size(), 14831u);
}

TEST(RealPcd, PjlabTopBinaryCompressedHasHeaderPointCountAndPlausibleRings) {
  const std::string path = kReal + "/multilidar-pjlab/0001/top.pcd";
  const PcdHeader header = readPcdHeader(path);
  EXPECT_EQ(header.data, "binary_compressed");
  EXPECT_EQ(header.points, 92677u);
  const PcdCloud cloud = readPcdFields(path);
  ASSERT_EQ(cloud.size(), header.points);
  EXPECT_EQ(cloud.fields, (std::vector<std::string>{"x", "y", "z", "intensity", "ring", "timestamp"}));
  expectPlausible(cloud, 300.0, 0);
  const auto& ring = cloud.column("ring");
  EXPECT_LT(*std::max_element(ring.begin(), ring.end()), 256.0);
  const auto points = readPcd(path);
  EXPECT_EQ(points.size(), header.points);
}

TEST(RealPcd, EveryRealPcdFileReadsWithItsHeaderPointCount) {
  for (const auto& entry : fs::recursive_directory_iterator(kReal)) {
    if (entry.path().extension() != ".pcd") continue;
    SCOPED_TRACE(entry.path().string());
    const PcdCloud cloud = readPcdFields(entry.path().string());
    EXPECT_EQ(cloud.size(), cloud.header.points);
    expectPlausible(cloud, 300.0, cloud.size() / 2);
  }
}
