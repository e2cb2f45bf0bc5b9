#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "mmlio/io/pcd_io.hpp"
#include "mmlio/lidar/bad_frame.hpp"
#include "mmlio/lidar/features.hpp"
#include "synthetic_scans.hpp"

using namespace mmlio;
using namespace mmlio::lidar;
using mmlio::synth::BoxRoom;

namespace {

// Near one of the room's 12 edges: within tol of the bounds on two axes.
bool nearBoxEdge(const BoxRoom& room, const Point& p, double tol_m) {
  int close = 0;
  for (int a = 0; a < 3; ++a)
    close += std::abs(p.xyz[a] - room.lo[a]) < tol_m || std::abs(p.xyz[a] - room.hi[a]) < tol_m;
  return close >= 2;
}

struct Split {
  int at_edge = 0, elsewhere = 0;
};
Split splitByEdge(const BoxRoom& room, const std::vector<Point>& pts, double tol_m) {
  Split s;
  for (const auto& p : pts) (nearBoxEdge(room, p, tol_m) ? s.at_edge : s.elsewhere)++;
  return s;
}

}  // namespace

TEST(Features, RingScanOfABoxRoomGivesCornerEdgesAndWallPlanes) {
  const BoxRoom room;
  const LidarScan scan = synth::vlp16Room(room, 0.01);
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSpinning, 16, FeatureConfig{});
  EXPECT_EQ(f.input_points, scan.points.size());
  const Split e = splitByEdge(room, f.edges, 0.2);
  std::cout << "vlp16 synthetic: edges at room edges " << e.at_edge << " elsewhere " << e.elsewhere << " planes "
            << f.planes.size() << "\n";
  // Every ring crosses the four vertical corners: about 4 x 16 edges there, hardly any elsewhere.
  EXPECT_GE(e.at_edge, 56);
  EXPECT_LE(e.elsewhere, e.at_edge / 10);
  const Split p = splitByEdge(room, f.planes, 0.05);
  EXPECT_GT(p.elsewhere, 5000);
  EXPECT_LE(p.at_edge, p.elsewhere / 100);
}

TEST(Features, RangeImageRowsReplaceMissingRings) {
  const BoxRoom room;
  LidarScan scan = synth::vlp16Room(room, 0.01);
  FeatureConfig cfg;
  EXPECT_EQ(scanLines(scan, LidarKind::kSpinning, 1, cfg).size(), 16u);  // elevation clusters = lasers
  for (auto& p : scan.points) p.ring = 0;
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSpinning, 1, cfg);
  const Split e = splitByEdge(room, f.edges, 0.2);
  EXPECT_GE(e.at_edge, 56);
  EXPECT_LE(e.elsewhere, e.at_edge / 10);
  EXPECT_GT(f.planes.size(), 5000u);
}

TEST(Features, RingsAreReadInAzimuthOrderWhereverTheSweepStartsAndHoweverThePointsCome) {
  const BoxRoom room;
  const LidarScan scan = synth::vlp16Room(room, 0.01);
  const auto sameFeatures = [](const FeatureCloud& a, const FeatureCloud& b) {
    const auto same = [](const std::vector<Point>& x, const std::vector<Point>& y) {
      if (x.size() != y.size()) return false;
      for (std::size_t i = 0; i < x.size(); ++i)
        if (x[i].xyz != y[i].xyz) return false;
      return true;
    };
    return same(a.edges, b.edges) && same(a.planes, b.planes);
  };
  const FeatureCloud reference = extractFeatures(scan, LidarKind::kSpinning, 16, FeatureConfig{});
  ASSERT_GT(reference.edges.size(), 50u);
  LidarScan clockwise = scan;  // Velodyne's spin: azimuth falls along a ring
  std::reverse(clockwise.points.begin(), clockwise.points.end());
  for (const LidarScan* turn : std::array<const LidarScan*, 2>{&scan, &clockwise})
    for (const double start_fraction : {0.0, 0.1, 0.5, 0.93}) {  // a turn cut at another azimuth: one seam per ring
      LidarScan cut = *turn;
      const auto at = cut.points.begin() + static_cast<std::ptrdiff_t>(start_fraction * cut.points.size());
      std::rotate(cut.points.begin(), at, cut.points.end());
      EXPECT_TRUE(sameFeatures(extractFeatures(cut, LidarKind::kSpinning, 16, FeatureConfig{}), reference))
          << start_fraction << (turn == &clockwise ? " clockwise" : "");
    }
  // Dual returns: a farther return at the same azimuth right after some points, so a clockwise
  // ring holds equal keys; each pair must stay in its order (near, then far), as a stable sort keeps it.
  LidarScan dual = clockwise;
  dual.points.clear();
  std::vector<std::size_t> twins;  // index of each far return; its near one precedes it
  for (std::size_t i = 0; i < clockwise.points.size(); ++i) {
    dual.points.push_back(clockwise.points[i]);
    if (i % 7 != 0) continue;
    Point far = clockwise.points[i];
    far.xyz *= 2.f;  // exact: the same direction bit for bit
    twins.push_back(dual.points.size());
    dual.points.push_back(far);
  }
  std::vector<long> position(dual.points.size(), -1);
  for (const auto& line : scanLines(dual, LidarKind::kSpinning, 16, FeatureConfig{}))
    for (std::size_t k = 0; k < line.size(); ++k) position[line[k]] = static_cast<long>(k);
  for (const std::size_t far : twins) {
    ASSERT_GE(position[far - 1], 0);
    EXPECT_EQ(position[far], position[far - 1] + 1);
  }
  LidarScan shuffled = scan;  // e.g. dual-return packets: no seam structure at all
  std::mt19937 rng(4);
  std::shuffle(shuffled.points.begin(), shuffled.points.end(), rng);
  EXPECT_TRUE(sameFeatures(extractFeatures(shuffled, LidarKind::kSpinning, 16, FeatureConfig{}), reference));
  for (const auto& line : scanLines(shuffled, LidarKind::kSpinning, 16, FeatureConfig{}))
    for (std::size_t k = 1; k < line.size(); ++k) {
      const Point &a = shuffled.points[line[k - 1]], &b = shuffled.points[line[k]];
      EXPECT_LE(std::atan2(a.xyz.y(), a.xyz.x()), std::atan2(b.xyz.y(), b.xyz.x()));
    }
}

TEST(Features, RingsOfASweepLongerThanATurnAreReadInAzimuthOrder) {
  // A sweep window a little longer than one turn: each ring's last points pass its first azimuths
  // again, in either spin direction: 0.07 deg apart from them (a third of the VLP-16's step), or at
  // the very same azimuth (farther), which must come after the first-come point, as a stable sort has it.
  const LidarScan scan = synth::vlp16Room(BoxRoom{}, 0.01);
  LidarScan clockwise = scan;
  std::reverse(clockwise.points.begin(), clockwise.points.end());
  const Eigen::Matrix3f nudge =
      Eigen::AngleAxisf(0.07f * static_cast<float>(M_PI) / 180.f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const auto azimuth = [](const Point& p) {
    return std::atan2(static_cast<double>(p.xyz.y()), static_cast<double>(p.xyz.x()));
  };
  for (const LidarScan* turn : std::array<const LidarScan*, 2>{&scan, &clockwise})
    for (const double start_fraction : {0.0, 0.5})
      for (const bool same_azimuth : {false, true}) {
        LidarScan longer = *turn;
        std::rotate(longer.points.begin(),
                    longer.points.begin() + static_cast<std::ptrdiff_t>(start_fraction * longer.points.size()),
                    longer.points.end());
        const std::size_t again = longer.points.size() / 16;
        for (std::size_t i = 0; i < again; ++i) {
          Point p = longer.points[i];
          p.xyz = same_azimuth ? Eigen::Vector3f(2.f * p.xyz) : Eigen::Vector3f(nudge * p.xyz);  // x2: exact
          longer.points.push_back(p);
        }
        const auto lines = scanLines(longer, LidarKind::kSpinning, 16, FeatureConfig{});
        ASSERT_EQ(lines.size(), 16u);
        for (std::size_t r = 0; r < lines.size(); ++r) {
          std::vector<std::size_t> expected;  // the ring's points as they came, stably sorted by azimuth
          for (std::size_t i = 0; i < longer.points.size(); ++i)
            if (longer.points[i].ring == r) expected.push_back(i);
          std::stable_sort(expected.begin(), expected.end(), [&](std::size_t a, std::size_t b) {
            return azimuth(longer.points[a]) < azimuth(longer.points[b]);
          });
          EXPECT_EQ(lines[r], expected) << "ring " << r << (turn == &clockwise ? " clockwise" : "") << " from "
                                        << start_fraction << (same_azimuth ? " same azimuth" : "");
        }
      }
}

TEST(Features, LivoxLikeLineScanGivesCornerEdgesAndWallPlanes) {
  const BoxRoom room;
  // Looking at the corner (6, 5): the view holds two walls, the floor and their edges.
  const LidarScan scan = synth::livoxRoom(room, std::atan2(5.0, 6.0), 0.02);
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSolidState, 6, FeatureConfig{});
  const Split e = splitByEdge(room, f.edges, 0.3);
  std::cout << "livox synthetic: edges at room edges " << e.at_edge << " elsewhere " << e.elsewhere << " planes "
            << f.planes.size() << "\n";
  EXPECT_GE(e.at_edge, 6 * 4);            // 6 lines x 4 passes cross the vertical corner
  EXPECT_LE(e.elsewhere, e.at_edge / 5);  // 2 cm range noise, as a Horizon
  EXPECT_GT(f.planes.size(), 2000u);
  const Split p = splitByEdge(room, f.planes, 0.05);
  EXPECT_LE(p.at_edge, p.elsewhere / 50);
}

TEST(Features, EdgesOnlyPicksTheSameEdgesAndNoPlanes) {
  // A LiDAR whose every return is matched as a surface point needs only its edges.
  const BoxRoom room;
  const LidarScan scan = synth::livoxRoom(room, std::atan2(5.0, 6.0), 0.02);
  const FeatureCloud both = extractFeatures(scan, LidarKind::kSolidState, 6, FeatureConfig{});
  FeatureConfig edges_only;
  edges_only.planes = false;
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSolidState, 6, edges_only);
  EXPECT_TRUE(f.planes.empty());
  ASSERT_GT(both.edges.size(), 20u);
  ASSERT_EQ(f.edges.size(), both.edges.size());
  for (std::size_t i = 0; i < f.edges.size(); ++i) EXPECT_EQ(f.edges[i].xyz, both.edges[i].xyz);
}

TEST(Features, DepthJumpMakesTheNearSideABreakPointEdge) {
  // One line: a wall at 5 m, then (nearer) a wall at 3 m; 0.2 deg steps.
  LidarScan scan;
  for (int i = 0; i < 400; ++i) {
    const double az = (-40.0 + 0.2 * i) * M_PI / 180;
    const double x = i < 200 ? 5.0 : 3.0;
    Point p;
    p.xyz = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(x * std::tan(az)), 0.f);
    p.time_s = static_cast<float>(i * 1e-4);
    p.ring = 1;
    scan.points.push_back(p);
  }
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSpinning, 2, FeatureConfig{});
  ASSERT_EQ(f.edges.size(), 1u);
  EXPECT_FLOAT_EQ(f.edges[0].xyz.x(), 3.f);  // near side (index 200)
  EXPECT_NEAR(f.edges[0].time_s, 200e-4, 1e-7);
  for (const auto& p : f.planes) EXPECT_GT(std::abs(p.time_s - 0.02f), 5.5e-4f) << "no plane at the jump";
}

TEST(BadFrame, WallOnlyFrameIsBadAndAFrameWithCornersIsNot) {
  // Facing the long wall of an 8 m wide hall head-on: a single plane fills the view.
  synth::BoxRoom hall;
  hall.lo = Eigen::Vector3d(-4, -30, -1.5);
  hall.hi = Eigen::Vector3d(4, 30, 2.5);
  const FeatureConfig fc;
  BadFrameConfig bc;
  const FeatureCloud wall = extractFeatures(synth::livoxRoom(hall, 0.0, 0.02), LidarKind::kSolidState, 6, fc);
  const BadFrameResult wall_result = checkSolidStateFrame(wall, bc);
  EXPECT_TRUE(wall_result.bad);
  EXPECT_LT(wall_result.counted_edges, 10);
  // Facing a room corner: one vertical corner and the floor edges. The synthetic frame is small
  // (24k points, 4 line passes) so tau_e is scaled down with it.
  const BoxRoom room;
  const FeatureCloud corner =
      extractFeatures(synth::livoxRoom(room, std::atan2(5.0, 6.0), 0.02), LidarKind::kSolidState, 6, fc);
  bc.min_edge_points = 20;
  EXPECT_FALSE(checkSolidStateFrame(corner, bc).bad);
  EXPECT_TRUE(checkSolidStateFrame(wall, bc).bad);
  BadFrameConfig off = bc;
  off.enabled = false;
  EXPECT_FALSE(checkSolidStateFrame(wall, off).bad);
  // Range gate: edges within 2 m are not counted.
  FeatureCloud near;
  near.edges.resize(500);
  for (auto& p : near.edges) p.xyz = Eigen::Vector3f(1.5f, 0, 0);
  EXPECT_EQ(checkSolidStateFrame(near, BadFrameConfig{}).counted_edges, 0);
  EXPECT_TRUE(checkSolidStateFrame(near, BadFrameConfig{}).bad);
}

// ---- real data ----

TEST(FeaturesRealData, Vlp16RotationGivesFewerEdgesThanPlanesWithAndWithoutRings) {
  const std::string path = std::string(MMLIO_SHARED_DATA_DIR) + "/vlp16-nebula/1673400472138016708.pcd";
  const io::PcdCloud cloud = io::readPcdFields(path);
  LidarScan scan;
  const auto& x = cloud.column("x");
  const auto& y = cloud.column("y");
  const auto& z = cloud.column("z");
  const auto& ch = cloud.column("channel");
  const auto& t = cloud.column("time_stamp");
  const auto& in = cloud.column("intensity");
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    Point p;
    p.xyz = Eigen::Vector3f(float(x[i]), float(y[i]), float(z[i]));
    p.ring = static_cast<std::uint16_t>(ch[i]);
    p.time_s = static_cast<float>(t[i] * 1e-9);
    p.intensity = static_cast<float>(in[i]);
    scan.points.push_back(p);
  }
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSpinning, 16, FeatureConfig{});
  std::cout << "VLP-16 real: " << scan.points.size() << " points, " << f.edges.size() << " edges, " << f.planes.size()
            << " planes\n";
  EXPECT_GT(f.edges.size(), 50u);
  EXPECT_GT(f.planes.size(), 1000u);
  EXPECT_LT(f.edges.size(), f.planes.size());
  for (auto& p : scan.points) p.ring = 0;
  const FeatureCloud g = extractFeatures(scan, LidarKind::kSpinning, 1, FeatureConfig{});
  std::cout << "VLP-16 real, range image: " << g.edges.size() << " edges, " << g.planes.size() << " planes\n";
  EXPECT_EQ(scanLines(scan, LidarKind::kSpinning, 1, FeatureConfig{}).size(), 15u);  // ring 0 (-15 deg) is empty
  EXPECT_GT(g.edges.size(), 50u);
  EXPECT_GT(g.planes.size(), 500u);
  EXPECT_LT(g.edges.size(), g.planes.size());
}

TEST(FeaturesRealData, LivoxFrameGivesFewerEdgesThanPlanes) {
  const std::string path = std::string(MMLIO_SHARED_DATA_DIR) + "/livox-frame-livox-detection/test_data.csv";
  std::ifstream file(path);
  ASSERT_TRUE(file.good()) << path;
  LidarScan scan;
  const Eigen::Vector3f origin(-0.09f, 0.43f, 0.15f);
  std::string row;
  std::size_t index = 0, rows = 0;
  while (std::getline(file, row)) {
    std::stringstream ss(row);
    float v[4];
    char comma;
    if (!(ss >> v[0] >> comma >> v[1] >> comma >> v[2] >> comma >> v[3])) continue;
    const std::size_t k = rows++;
    if (v[3] == 0.f && (Eigen::Vector3f(v[0], v[1], v[2]) - origin).norm() < 0.05f) continue;  // no return
    Point p;
    p.xyz = Eigen::Vector3f(v[0], v[1], v[2]) - origin;
    p.intensity = v[3];
    p.ring = static_cast<std::uint16_t>(k % 6);
    p.time_s = static_cast<float>(0.1 * k / 21000.0);
    scan.points.push_back(p);
    ++index;
  }
  ASSERT_GT(scan.points.size(), 10000u);
  const FeatureCloud f = extractFeatures(scan, LidarKind::kSolidState, 6, FeatureConfig{});
  std::cout << "Livox real: " << scan.points.size() << " points, " << f.edges.size() << " edges, " << f.planes.size()
            << " planes\n";
  EXPECT_GT(f.edges.size(), 20u);
  EXPECT_GT(f.planes.size(), 500u);
  EXPECT_LT(f.edges.size(), f.planes.size());
  // A road scene with structure beyond 2 m is a good frame for the paper's tau_e = 100.
  EXPECT_FALSE(checkSolidStateFrame(f, BadFrameConfig{}).bad);
}
