// Fuzzing the bag readers and the message decoders (bounded, seeded, so CI runs it every time):
// a small valid bag with all three message kinds (ROS 1, and its ROS 2 twins as .mcap and .db3),
// damaged many ways (bytes flipped, stretches
// overwritten, cut short), must either be refused with an mmlio::Error or stream events whose
// points are finite, in a bounded number of steps. Anything else (another exception type, a
// crash, a hang) fails.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <cstring>
#include <random>
#include <unistd.h>

#include "mmlio/core/error.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/io/bag_writer.hpp"
#include "ros2_twin.hpp"

namespace mmlio::io {
namespace {

namespace fs = std::filesystem;

const Stamp kT0 = 1'700'000'000'000'000'000LL;

LidarScan scanAt(Stamp start_ns, int n) {
  LidarScan s;
  s.start_ns = start_ns;
  for (int i = 0; i < n; ++i) {
    Point p;
    p.xyz = Eigen::Vector3f(static_cast<float>(5 + 0.01 * i), static_cast<float>(0.02 * i), 0.3f);
    p.time_s = 0.0005f * static_cast<float>(i);
    p.ring = static_cast<std::uint16_t>(i % 16);
    p.intensity = 10.f;
    s.points.push_back(p);
  }
  return s;
}

std::vector<char> validBag(const std::string& path) {
  {
    BagWriter w(path);
    for (int k = 0; k < 60; ++k) {
      ImuSample m;
      m.stamp_ns = kT0 + k * 10'000'000LL;
      m.acc_m_s2 = Eigen::Vector3d(0.1, 0.0, 9.81);
      w.writeImu("/livox/imu", "imu", m, true);
      if (k % 10 == 0) w.writeVelodyneCloud("/velodyne_points", "velodyne", scanAt(m.stamp_ns + 1, 64));
      if (k % 10 == 5) w.writeLivoxCloud("/livox/lidar", "livox", scanAt(m.stamp_ns + 2, 48));
    }
  }
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

BagSourceOptions rig() {
  BagSourceOptions o;
  o.imu_topic = "/livox/imu";
  o.lidars.push_back({"/velodyne_points", {"velodyne", LidarKind::kSpinning, 0.5, 100.0, 16}});
  o.lidars.push_back({"/livox/lidar", {"livox", LidarKind::kSolidState, 0.5, 100.0, 6}});
  return o;
}

std::vector<char> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// kCases damaged copies of `good`, written as `dir`/caseN`extension`: each refused with an
/// mmlio::Error or streamed (finite points, bounded events).
void fuzz(const std::vector<char>& good, const fs::path& dir, const std::string& extension, int kCases, unsigned seed) {
  ASSERT_GT(good.size(), 1000u);
  std::mt19937 rng(seed);
  std::size_t refused = 0, streamed = 0, events_total = 0;
  for (int c = 0; c < kCases; ++c) {
    std::vector<char> bytes = good;
    const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
    switch (c % 4) {
      case 0:  // a few bytes flipped anywhere
        for (int k = 0; k < 1 + static_cast<int>(pick(8)); ++k)
          bytes[pick(bytes.size())] ^= static_cast<char>(1 + pick(255));
        break;
      case 1: {  // a stretch overwritten with garbage
        const std::size_t at = pick(bytes.size()), len = 16 + pick(2048);
        for (std::size_t k = at; k < std::min(bytes.size(), at + len); ++k) bytes[k] = static_cast<char>(pick(256));
        break;
      }
      case 2:  // cut short
        bytes.resize(13 + pick(bytes.size() - 13));
        break;
      default: {  // a 4-byte length field made huge (record lengths, array sizes)
        const std::size_t at = pick(bytes.size() - 4);
        const std::uint32_t big = 0x7fffff00u + static_cast<std::uint32_t>(pick(255));
        std::memcpy(&bytes[at], &big, 4);
      }
    }
    const std::string path = (dir / ("case" + std::to_string(c) + extension)).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    try {
      BagSource src(path, rig());
      SensorEvent e;
      std::size_t events = 0;
      while (src.next(&e)) {
        ASSERT_LT(++events, 1000u) << "case " << c << ": more events than the bag holds";
        if (e.kind == SensorEvent::Kind::kLidar) {
          for (const Point& p : e.scan.points) ASSERT_TRUE(p.xyz.allFinite()) << "case " << c;
        }
      }
      ++streamed;
      events_total += events;
    } catch (const Error&) {
      ++refused;  // a clear one-line refusal
    }
    fs::remove(path);
  }
  std::printf("%d damaged %s: %zu refused with a message, %zu streamed (%zu events)\n", kCases, extension.c_str(),
              refused, streamed, events_total);
  EXPECT_EQ(refused + streamed, static_cast<std::size_t>(kCases));
  EXPECT_GT(streamed, 0u);
}

fs::path fuzzDir() {
  const fs::path dir = fs::temp_directory_path() / ("mmlio_fuzz_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(BagFuzz, DamagedBagsAreRefusedOrStreamFiniteEventsNeverAnythingElse) {
  const fs::path dir = fuzzDir();
  fuzz(validBag((dir / "good.bag").string()), dir, ".bag", 400, 20261201);
  fs::remove_all(dir);
}

TEST(BagFuzz, DamagedRos2BagsAreRefusedOrStreamFiniteEventsNeverAnythingElse) {
  const fs::path dir = fuzzDir();
  const std::string ros1 = (dir / "good.bag").string();
  validBag(ros1);
  const auto records = testing::ros2Records(ros1, "livox_ros_driver2/msg/CustomMsg");
  testing::writeMcap(records, (dir / "good.mcap").string(), {true, "", 4096, true});
  fuzz(readAll((dir / "good.mcap").string()), dir, ".mcap", 300, 20261202);
  testing::writeMcap(records, (dir / "good_lz4.mcap").string(), {true, "lz4", 4096, true});
  fuzz(readAll((dir / "good_lz4.mcap").string()), dir, ".mcap", 100, 20261203);
  testing::writeRosbag2(records, (dir / "good_db3").string(), {"", 1, false});
  fuzz(readAll((dir / "good_db3" / "good_db3_0.db3").string()), dir, ".db3", 200, 20261204);
  fs::remove_all(dir);
}

}  // namespace mmlio::io
