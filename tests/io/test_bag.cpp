// Bags written with BagWriter and with the raw rosbag API, read back through BagSource and
// describeBag; the one-line errors for unusable input.
#include <gtest/gtest.h>

#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "../common/error_of.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/bag_info.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/io/bag_writer.hpp"

namespace mmlio::io {
namespace {

namespace fs = std::filesystem;

const Stamp kT0 = 1'700'000'000'000'000'000LL;
constexpr double kG = 9.80665;

fs::path tempDir() { return fs::temp_directory_path() / ("mmlio_test_bag_" + std::to_string(::getpid())); }

std::string tempPath(const std::string& name) {
  fs::create_directories(tempDir());
  return (tempDir() / name).string();
}

/// The bags this test process wrote go when it ends (ctest runs every test as its own process).
class RemoveTempDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(tempDir(), ec);
  }
};
[[maybe_unused]] ::testing::Environment* const remove_temp_dir = ::testing::AddGlobalTestEnvironment(new RemoveTempDir);

/// A scan of n points on a 10 m circle, ring = i % 16, time_s = i * 1 ms, intensity = i.
LidarScan ringScan(Stamp start_ns, int n) {
  LidarScan s;
  s.start_ns = start_ns;
  for (int i = 0; i < n; ++i) {
    Point p;
    const double a = 0.1 * i;
    p.xyz = Eigen::Vector3f(static_cast<float>(10 * std::cos(a)), static_cast<float>(10 * std::sin(a)), 0.5f);
    p.time_s = 0.001f * i;
    p.ring = static_cast<std::uint16_t>(i % 16);
    p.intensity = static_cast<float>(i);
    s.points.push_back(p);
  }
  return s;
}

ImuSample imuAt(Stamp t) {
  ImuSample m;
  m.stamp_ns = t;
  m.acc_m_s2 = Eigen::Vector3d(0.1, -0.2, kG);
  m.gyro_rad_s = Eigen::Vector3d(0.01, 0.02, 0.03);
  return m;
}

/// 1 s: IMU at 100 Hz in g, Velodyne at 10 Hz, Livox (driver 1) at 10 Hz offset by 50 ms,
/// Livox driver2 at 5 Hz.
std::string writeRigBag() {
  const std::string path = tempPath("rig.bag");
  BagWriter w(path);
  for (int k = 0; k < 100; ++k) {  // in recording order, as a real bag
    w.writeImu("/livox/imu", "imu", imuAt(kT0 + k * 10'000'000LL), true);
    const int j = k / 10;
    if (k % 10 == 0) {
      w.writeVelodyneCloud("/velodyne_points", "velodyne", ringScan(kT0 + j * 100'000'000LL + 1, 50));
      if (j % 2 == 0) w.writeLivoxCloud("/livox2/lidar", "livox", ringScan(kT0 + j * 100'000'000LL + 2, 20), true);
    }
    if (k % 10 == 5) w.writeLivoxCloud("/livox/lidar", "livox", ringScan(kT0 + j * 100'000'000LL + 50'000'000LL, 30));
  }
  w.close();
  w.close();  // idempotent
  return path;
}

BagSourceOptions rigOptions() {
  BagSourceOptions o;
  o.imu_topic = "/livox/imu";
  o.lidars.push_back({"/velodyne_points", {"velodyne", LidarKind::kSpinning, 0.5, 100.0, 16}});
  o.lidars.push_back({"livox/lidar", {"livox", LidarKind::kSolidState, 0.5, 100.0, 6}});  // no leading '/'
  o.lidars.push_back({"/livox2/lidar", {"livox2", LidarKind::kSolidState, 0.5, 100.0, 6}});
  return o;
}

TEST(BagSource, BagWriterBagStreamsBackInTimeOrderWithTheWrittenContent) {
  const std::string path = writeRigBag();
  BagSource src(path, rigOptions());
  EXPECT_DOUBLE_EQ(src.accScale(), kG);  // auto: mean |acc| ~1 -> g
  EXPECT_EQ(src.beginNs(), kT0);
  EXPECT_EQ(src.endNs(), kT0 + 990'000'000LL);
  EXPECT_DOUBLE_EQ(src.progress(), 0.0);

  SensorEvent e;
  Stamp last = 0;
  std::map<std::string, int> scans;
  int imu = 0;
  while (src.next(&e)) {
    const Stamp t = e.kind == SensorEvent::Kind::kImu ? e.imu.stamp_ns : e.scan.start_ns;
    EXPECT_GE(t, last);
    last = t;
    if (e.kind == SensorEvent::Kind::kImu) {
      ++imu;
      EXPECT_NEAR(e.imu.acc_m_s2.z(), kG, 1e-9);
      EXPECT_NEAR(e.imu.acc_m_s2.y(), -0.2, 1e-9);
      EXPECT_DOUBLE_EQ(e.imu.gyro_rad_s.z(), 0.03);
      continue;
    }
    ++scans[e.scan.sensor];
    const LidarScan expect = ringScan(e.scan.start_ns, static_cast<int>(e.scan.points.size()));
    ASSERT_FALSE(e.scan.points.empty());
    for (std::size_t i = 0; i < e.scan.points.size(); ++i) {
      EXPECT_NEAR((e.scan.points[i].xyz - expect.points[i].xyz).norm(), 0.f, 1e-6f);
      EXPECT_NEAR(e.scan.points[i].time_s, expect.points[i].time_s, 2e-9);
      EXPECT_EQ(e.scan.points[i].ring, expect.points[i].ring);
      EXPECT_FLOAT_EQ(e.scan.points[i].intensity, expect.points[i].intensity);
    }
  }
  EXPECT_EQ(imu, 100);
  EXPECT_EQ(src.imuCount(), 100u);
  EXPECT_EQ(scans["velodyne"], 10);
  EXPECT_EQ(scans["livox"], 10);
  EXPECT_EQ(scans["livox2"], 5);
  EXPECT_EQ(src.stats().at("velodyne").kept, 500u);
  EXPECT_EQ(src.stats().at("livox").kept, 300u);
  EXPECT_EQ(src.stats().at("livox2").kept, 100u);
  EXPECT_DOUBLE_EQ(src.progress(), 1.0);
  EXPECT_FALSE(src.next(&e));
  EXPECT_EQ(src.skippedMessages(), 0u);
}

TEST(BagSource, ExplicitAccUnitOverridesTheGuess) {
  const std::string path = writeRigBag();
  BagSourceOptions o = rigOptions();
  o.acc_unit = "m/s2";
  BagSource src(path, o);
  EXPECT_DOUBLE_EQ(src.accScale(), 1.0);
  o.acc_unit = "furlongs";
  EXPECT_THROW(BagSource(path, o), Error);
}

/// A bag written with rosbag directly: an Ouster-like cloud (t in ns, organised 2 x 2, one NaN),
/// IMU in m/s^2, topics without a leading '/', and one foreign message on the IMU topic.
std::string writeRawBag(int short_cloud = -1) {
  const std::string path = tempPath("raw.bag");
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int k = 0; k < 60; ++k) {
    sensor_msgs::Imu m;
    m.header.stamp.fromNSec(static_cast<std::uint64_t>(kT0 + k * 5'000'000LL));
    m.linear_acceleration.z = 9.81;
    bag.write("imu", m.header.stamp, m);
  }
  std_msgs::Header foreign;
  ros::Time tf;
  tf.fromNSec(static_cast<std::uint64_t>(kT0 + 1));
  bag.write("imu", tf, foreign);
  for (int k = 0; k < 3; ++k) {
    sensor_msgs::PointCloud2 c;
    c.header.stamp.fromNSec(static_cast<std::uint64_t>(kT0 + k * 100'000'000LL));
    const char* names[4] = {"x", "y", "z", "t"};
    const std::uint8_t types[4] = {sensor_msgs::PointField::FLOAT32, sensor_msgs::PointField::FLOAT32,
                                   sensor_msgs::PointField::FLOAT32, sensor_msgs::PointField::UINT32};
    for (int f = 0; f < 4; ++f) {
      sensor_msgs::PointField pf;
      pf.name = names[f];
      pf.offset = 4 * f;
      pf.datatype = types[f];
      pf.count = 1;
      c.fields.push_back(pf);
    }
    c.height = 2;
    c.width = 2;
    c.point_step = 16;
    c.row_step = 32;
    c.data.assign(64, 0);
    for (int i = 0; i < 4; ++i) {
      const float x = i == 3 ? std::numeric_limits<float>::quiet_NaN() : 2.0f + i;
      const float y = 1.f, z = 0.f;
      const std::uint32_t t = static_cast<std::uint32_t>((3 - i) * 1000);
      std::memcpy(&c.data[16 * i + 0], &x, 4);
      std::memcpy(&c.data[16 * i + 4], &y, 4);
      std::memcpy(&c.data[16 * i + 8], &z, 4);
      std::memcpy(&c.data[16 * i + 12], &t, 4);
    }
    if (k == short_cloud) c.data.resize(40);  // damaged: shorter than width x height x point_step
    bag.write("os_cloud_node/points", c.header.stamp, c);
  }
  bag.close();
  return path;
}

TEST(BagSource, RawRosbagOusterBagDecodesWithMetricImuAndSkipsAForeignMessage) {
  const std::string path = writeRawBag();
  BagSourceOptions o;
  o.imu_topic = "/imu";
  o.lidars.push_back({"/os_cloud_node/points", {"ouster", LidarKind::kSpinning, 0.5, 100.0, 16}});
  BagSource src(path, o);
  EXPECT_DOUBLE_EQ(src.accScale(), 1.0);
  SensorEvent e;
  int scans = 0;
  while (src.next(&e)) {
    if (e.kind != SensorEvent::Kind::kLidar) continue;
    ++scans;
    ASSERT_EQ(e.scan.points.size(), 3u);  // the NaN point dropped
    EXPECT_EQ(e.scan.start_ns, kT0 + (scans - 1) * 100'000'000LL + 1000);
    EXPECT_FLOAT_EQ(e.scan.points[0].xyz.x(), 4.f);  // t = 1000 ns is the earliest
    EXPECT_FLOAT_EQ(e.scan.points[2].xyz.x(), 2.f);
    EXPECT_EQ(e.scan.sensor, "ouster");
  }
  EXPECT_EQ(scans, 3);
  EXPECT_EQ(src.imuCount(), 60u);
  EXPECT_EQ(src.skippedMessages(), 1u);
  EXPECT_EQ(src.stats().at("ouster").dropped_nan, 3u);
}

TEST(BagSource, ADamagedCloudAfterGoodOnesIsSkippedAndCountedAndReadingGoesOn) {
  BagSourceOptions o;
  o.imu_topic = "/imu";
  o.lidars.push_back({"/os_cloud_node/points", {"ouster", LidarKind::kSpinning, 0.5, 100.0, 16}});
  BagSource src(writeRawBag(1), o);
  SensorEvent e;
  std::vector<Stamp> starts;
  while (src.next(&e))
    if (e.kind == SensorEvent::Kind::kLidar) starts.push_back(e.scan.start_ns);
  ASSERT_EQ(starts.size(), 2u);  // clouds 0 and 2
  EXPECT_EQ(starts[1], kT0 + 200'000'000LL + 1000);
  EXPECT_EQ(src.skippedMessages(), 2u);  // the foreign message and the damaged cloud
  EXPECT_FALSE(src.truncated());
}

TEST(BagSourceErrors, MissingFileNotABagAndTruncatedBagAreOneLineErrors) {
  const std::string missing = tempPath("nope.bag");
  std::string msg = mmlio::testing::errorOf([&] { BagSource(missing, rigOptions()); });
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
  EXPECT_NE(msg.find(missing), std::string::npos) << msg;

  const std::string text = tempPath("text.bag");
  std::ofstream(text) << "hello, not a bag\n";
  msg = mmlio::testing::errorOf([&] { BagSource(text, rigOptions()); });
  EXPECT_NE(msg.find("is not a bag"), std::string::npos) << msg;

  const std::string full = writeRigBag();
  const std::string cut = tempPath("cut.bag");
  fs::copy_file(full, cut, fs::copy_options::overwrite_existing);
  fs::resize_file(cut, 4200);  // inside the first chunk: no complete message
  msg = mmlio::testing::errorOf([&] { BagSource(cut, rigOptions()); });
  EXPECT_NE(msg.find("rosbag reindex"), std::string::npos) << msg;
  EXPECT_NE(msg.find(cut), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST(BagSource, TruncatedBagIsReadUpToItsLastCompleteMessage) {
  const std::string full = writeRigBag();
  const std::string cut = tempPath("half.bag");
  fs::copy_file(full, cut, fs::copy_options::overwrite_existing);
  fs::resize_file(cut, fs::file_size(full) / 2);
  BagSource src(cut, rigOptions());
  EXPECT_TRUE(src.truncated());
  EXPECT_DOUBLE_EQ(src.accScale(), kG);
  EXPECT_EQ(src.beginNs(), kT0);
  EXPECT_LT(src.endNs(), kT0 + 990'000'000LL);
  SensorEvent e;
  std::size_t events = 0, scans = 0;
  Stamp last = 0;
  while (src.next(&e)) {
    ++events;
    const Stamp t = e.kind == SensorEvent::Kind::kImu ? e.imu.stamp_ns : e.scan.start_ns;
    EXPECT_GE(t, last);
    last = t;
    if (e.kind == SensorEvent::Kind::kLidar) {
      ++scans;
      const LidarScan expect = ringScan(e.scan.start_ns, static_cast<int>(e.scan.points.size()));
      EXPECT_NEAR((e.scan.points.back().xyz - expect.points.back().xyz).norm(), 0.f, 1e-6f);
    } else {
      EXPECT_NEAR(e.imu.acc_m_s2.z(), kG, 1e-9);
    }
  }
  EXPECT_GT(scans, 3u);
  EXPECT_GT(events, 20u);
  EXPECT_LT(events, 125u);  // the full bag has 100 IMU + 25 scans
  EXPECT_DOUBLE_EQ(src.progress(), 1.0);
}

/// 400 IMU messages (4 s at 100 Hz) in small chunks (about 13 messages each), compressed as asked.
std::string writeChunkedImuBag(const std::string& name, rosbag::compression::CompressionType compression) {
  const std::string path = tempPath(name);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setChunkThreshold(4096);
  bag.setCompression(compression);
  for (int k = 0; k < 400; ++k) {
    sensor_msgs::Imu m;
    m.header.stamp.fromNSec(static_cast<std::uint64_t>(kT0 + k * 10'000'000LL));
    m.linear_acceleration.z = 1.0;  // g
    m.angular_velocity.x = 0.001 * k;
    bag.write("/imu", m.header.stamp, m);
  }
  bag.close();
  return path;
}

BagSourceOptions imuOnly() {
  BagSourceOptions o;
  o.imu_topic = "/imu";
  return o;
}

TEST(BagSource, ADamagedStretchIsSkippedAndReadingGoesOnAtTheNextIntactChunk) {
  const std::string path = writeChunkedImuBag("damaged.bag", rosbag::compression::Uncompressed);
  {  // 3 KiB of garbage in the middle of the file: at least one chunk header is gone
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(path) / 2));
    for (int i = 0; i < 3072; ++i) f.put(static_cast<char>((i * 131 + 7) & 0xff));
  }
  BagSource src(path, imuOnly());
  SensorEvent e;
  std::size_t read = 0;
  Stamp last = 0;
  while (src.next(&e)) {
    ++read;
    EXPECT_GT(e.imu.stamp_ns, last);
    last = e.imu.stamp_ns;
  }
  EXPECT_EQ(last, kT0 + 399 * 10'000'000LL);  // the second half was read
  EXPECT_GE(read, 340u);                      // only the damaged stretch is lost
  EXPECT_LT(read, 400u);
  EXPECT_GE(src.damagedChunks() + src.skippedMessages(), 1u);
}

TEST(BagSource, Bz2ChunksOfACutBagAreRead) {
  const std::string full = writeChunkedImuBag("bz2.bag", rosbag::compression::BZ2);
  const std::string cut = tempPath("bz2_half.bag");
  fs::copy_file(full, cut, fs::copy_options::overwrite_existing);
  fs::resize_file(cut, fs::file_size(full) / 2);
  BagSource src(cut, imuOnly());
  EXPECT_TRUE(src.truncated());
  SensorEvent e;
  std::size_t read = 0;
  while (src.next(&e)) {
    EXPECT_NEAR(e.imu.gyro_rad_s.x(), 0.001 * static_cast<double>(read), 1e-12);  // in order, none lost
    ++read;
  }
  EXPECT_GT(read, 100u);
  EXPECT_LT(read, 400u);
}

TEST(BagSourceErrors, MissingTopicIsNamedWithTheBagsTopics) {
  const std::string path = writeRigBag();
  BagSourceOptions o = rigOptions();
  o.lidars[0].topic = "/points_raw";
  const std::string msg = mmlio::testing::errorOf([&] { BagSource(path, o); });
  EXPECT_NE(msg.find("/points_raw"), std::string::npos) << msg;
  EXPECT_NE(msg.find("velodyne"), std::string::npos) << msg;
  EXPECT_NE(msg.find("/velodyne_points (sensor_msgs/PointCloud2)"), std::string::npos) << msg;
}

TEST(BagSourceErrors, TopicOfTheWrongTypeNamesFoundAndExpected) {
  const std::string path = writeRigBag();
  BagSourceOptions o = rigOptions();
  o.imu_topic = "/velodyne_points";
  o.lidars.erase(o.lidars.begin());
  std::string msg = mmlio::testing::errorOf([&] { BagSource(path, o); });
  EXPECT_NE(msg.find("/velodyne_points"), std::string::npos) << msg;
  EXPECT_NE(msg.find("is sensor_msgs/PointCloud2, expected sensor_msgs/Imu"), std::string::npos) << msg;

  o = rigOptions();
  o.lidars[0].topic = "/livox/imu";
  o.imu_topic.clear();
  msg = mmlio::testing::errorOf([&] { BagSource(path, o); });
  EXPECT_NE(msg.find("is sensor_msgs/Imu, expected sensor_msgs/PointCloud2 or livox_ros_driver/CustomMsg"),
            std::string::npos)
      << msg;
}

TEST(BagSourceErrors, ALivoxMessageDeclaredAsASpinningLidarIsAnError) {
  // The two LiDAR topics swapped (or a Livox topic given type: velodyne): the Livox driver's own
  // message says what it comes from.
  const std::string path = writeRigBag();
  BagSourceOptions o = rigOptions();
  std::swap(o.lidars[0].topic, o.lidars[1].topic);
  const std::string msg = mmlio::testing::errorOf([&] { BagSource(path, o); });
  EXPECT_NE(msg.find("livox/lidar (LiDAR 'velodyne')"), std::string::npos) << msg;
  EXPECT_NE(msg.find("declared as a spinning one: give it type: livox"), std::string::npos) << msg;
}

TEST(BagSourceErrors, ACloudWhoseFieldsSayTheOtherKindOfLidarStopsTheRunSayingWhy) {
  // A VLP-16's PointCloud2 (ring field) declared solid-state: its first cloud says so.
  const std::string path = writeRigBag();
  BagSourceOptions o = rigOptions();
  o.lidars[0].decode.kind = LidarKind::kSolidState;
  const std::string msg = mmlio::testing::errorOf([&] {
    BagSource src(path, o);
    SensorEvent e;
    while (src.next(&e)) {
    }
  });
  EXPECT_NE(msg.find("/velodyne_points"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ring field, a spinning LiDAR's, but LiDAR 'velodyne' is declared solid-state"), std::string::npos)
      << msg;
}

TEST(BagInfo, DescribesTopicsCountsRatesFieldsPointsAndImuUnit) {
  const BagInfo info = describeBag(writeRigBag());
  EXPECT_EQ(info.begin_ns, kT0);
  EXPECT_EQ(info.end_ns, kT0 + 990'000'000LL);
  EXPECT_EQ(info.imu_unit_guess, "g");
  ASSERT_EQ(info.topics.size(), 4u);  // sorted by name
  const TopicInfo& imu = info.topics[0];
  EXPECT_EQ(imu.topic, "/livox/imu");
  EXPECT_EQ(imu.type, "sensor_msgs/Imu");
  EXPECT_EQ(imu.messages, 100u);
  EXPECT_NEAR(imu.rate_hz, 100.0, 1e-6);
  EXPECT_TRUE(imu.fields.empty());
  const TopicInfo& livox = info.topics[1];
  EXPECT_EQ(livox.type, "livox_ros_driver/CustomMsg");
  EXPECT_DOUBLE_EQ(livox.mean_points, 30.0);
  EXPECT_EQ(livox.fields.back(), "line(uint8)");
  const TopicInfo& livox2 = info.topics[2];
  EXPECT_EQ(livox2.type, "livox_ros_driver2/CustomMsg");
  EXPECT_EQ(livox2.messages, 5u);
  EXPECT_NEAR(livox2.rate_hz, 5.0, 1e-6);
  const TopicInfo& velo = info.topics[3];
  EXPECT_EQ(velo.topic, "/velodyne_points");
  EXPECT_DOUBLE_EQ(velo.mean_points, 50.0);
  const std::vector<std::string> fields = {"x(float32)",         "y(float32)",   "z(float32)",
                                           "intensity(float32)", "ring(uint16)", "time(float32)"};
  EXPECT_EQ(velo.fields, fields);
  const std::string text = formatBagInfo(info);
  EXPECT_NE(text.find("duration  0.990 s"), std::string::npos) << text;
  EXPECT_NE(text.find("ring(uint16)"), std::string::npos) << text;
  EXPECT_NE(text.find("(guess): g"), std::string::npos) << text;
}

TEST(BagInfo, RawBagGuessesMetricImuAndCountsOrganisedCloudPoints) {
  const BagInfo info = describeBag(writeRawBag());
  EXPECT_EQ(info.imu_unit_guess, "m/s2");
  ASSERT_EQ(info.topics.size(), 2u);
  EXPECT_EQ(info.topics[1].topic, "os_cloud_node/points");
  EXPECT_DOUBLE_EQ(info.topics[1].mean_points, 4.0);  // width x height, NaNs included
  EXPECT_EQ(info.topics[0].messages, 61u);
  EXPECT_THROW(describeBag(tempPath("missing.bag")), Error);
}

}  // namespace
}  // namespace mmlio::io
