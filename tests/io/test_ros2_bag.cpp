// ROS 2 bags in: the ROS 2 twins of a simulated ROS 1 bag (.mcap with every chunk compression, with and without chunks
// and summary; rosbag2 sqlite3 folders uncompressed, zstd per file and per message, split, without metadata.yaml)
// stream exactly the ROS 1 bag's events and give `mmlio run` the same trajectory; a truncated .mcap is read up to its
// last complete chunk; bad ROS 2 input gets one line or a counted skip.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "../pipeline/sim_feed.hpp"
#include "mmlio/config/source_options.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/bag_info.hpp"
#include "mmlio/io/bag_source.hpp"
#include "mmlio/pipeline/runner.hpp"
#include "ros2_twin.hpp"

namespace mmlio::io {
namespace {

namespace fs = std::filesystem;

// One folder per test process (CTest runs tests in parallel processes), removed at exit.
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("mmlio_ros2_test_" + std::to_string(::getpid()));
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
const TempDir kTemp;
const fs::path& kDir = kTemp.path;

sim::Simulator office(double duration_s) {
  sim::SimOptions so;
  so.scenario = "office";
  so.duration_s = duration_s;
  return sim::Simulator(so);
}

/// A 2 s simulated office as a ROS 1 bag and its ROS 2 records, made once for the suite.
struct Fixture {
  sim::Simulator sim = office(2.0);
  std::string ros1 = (kDir / "office2.bag").string();
  std::vector<testing::Ros2Record> records;
  Fixture() {
    fs::create_directories(kDir);
    testing::writeSimBag(sim, ros1);
    records = testing::ros2Records(ros1, "livox_ros_driver2/msg/CustomMsg");
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

std::vector<SensorEvent> events(const std::string& path) {
  BagSource src(path, config::bagSourceOptions(testing::simRigConfig(fixture().sim), "hvi"));
  std::vector<SensorEvent> out;
  SensorEvent e;
  while (src.next(&e)) out.push_back(e);
  return out;
}

void expectSameEvents(const std::vector<SensorEvent>& want, const std::vector<SensorEvent>& got,
                      const std::string& what) {
  ASSERT_EQ(want.size(), got.size()) << what;
  for (std::size_t i = 0; i < want.size(); ++i) {
    const SensorEvent& a = want[i];
    const SensorEvent& b = got[i];
    ASSERT_EQ(a.kind, b.kind) << what << " event " << i;
    if (a.kind == SensorEvent::Kind::kImu) {
      ASSERT_EQ(a.imu.stamp_ns, b.imu.stamp_ns) << what << " event " << i;
      ASSERT_EQ(a.imu.acc_m_s2, b.imu.acc_m_s2) << what << " event " << i;
      ASSERT_EQ(a.imu.gyro_rad_s, b.imu.gyro_rad_s) << what << " event " << i;
      continue;
    }
    ASSERT_EQ(a.scan.sensor, b.scan.sensor) << what << " event " << i;
    ASSERT_EQ(a.scan.start_ns, b.scan.start_ns) << what << " event " << i;
    ASSERT_EQ(a.scan.points.size(), b.scan.points.size()) << what << " event " << i;
    for (std::size_t k = 0; k < a.scan.points.size(); ++k) {
      const Point& p = a.scan.points[k];
      const Point& q = b.scan.points[k];
      ASSERT_TRUE(p.xyz == q.xyz && p.time_s == q.time_s && p.ring == q.ring && p.intensity == q.intensity)
          << what << " event " << i << " point " << k;
    }
  }
}

}  // namespace

TEST(Ros2Bag, McapTwinsStreamExactlyTheRos1BagsEvents) {
  const auto want = events(fixture().ros1);
  ASSERT_GT(want.size(), 400u);
  struct Case {
    const char* name;
    testing::McapOptions o;
  };
  const Case cases[] = {{"chunks-none", {true, "", 1 << 20, true}},
                        {"chunks-zstd-no-summary", {true, "zstd", 1 << 20, false}},
                        {"chunks-zstd", {true, "zstd", 1 << 20, true}},
                        {"chunks-lz4-small", {true, "lz4", 64 << 10, true}},
                        {"no-chunks-no-summary", {false, "", 0, false}}};
  for (const Case& c : cases) {
    const std::string path = (kDir / (std::string(c.name) + ".mcap")).string();
    testing::writeMcap(fixture().records, path, c.o);
    expectSameEvents(want, events(path), c.name);
    // With a summary and message indexes the file is opened from them, without a scan.
    const bool indexed = c.o.chunked && c.o.summary;
    EXPECT_NE(describeBag(path).format.find(indexed ? "indexed" : "scanned"), std::string::npos) << c.name;
  }
  // A rosbag2 folder split into three .mcap files.
  testing::writeSplitMcap(fixture().records, (kDir / "split_mcap").string(), 3);
  expectSameEvents(want, events((kDir / "split_mcap").string()), "split mcap folder");
}

TEST(Ros2Bag, Rosbag2SqliteTwinsStreamExactlyTheRos1BagsEvents) {
  const auto want = events(fixture().ros1);
  struct Case {
    const char* name;
    testing::Db3Options o;
  };
  const Case cases[] = {{"db3-plain", {"", 1, true}},
                        {"db3-zstd-file", {"file", 1, true}},
                        {"db3-zstd-message", {"message", 1, true}},
                        {"db3-split", {"", 3, true}},
                        {"db3-no-metadata", {"", 2, false}}};
  for (const Case& c : cases) {
    const fs::path dir = kDir / c.name;
    testing::writeRosbag2(fixture().records, dir.string(), c.o);
    expectSameEvents(want, events(dir.string()), c.name);
  }
  // The .db3 file itself, without its folder's metadata.yaml.
  const fs::path dir = kDir / "db3-plain";
  expectSameEvents(want, events((dir / "db3-plain_0.db3").string()), "a .db3 file");
}

TEST(Ros2Bag, LivoxRos2DriverTypeNamesAreRead) {
  const auto records = testing::ros2Records(fixture().ros1, "livox_interfaces/msg/CustomMsg");
  const std::string path = (kDir / "livox_interfaces.mcap").string();
  testing::writeMcap(records, path, {true, "zstd", 1 << 20, true});
  expectSameEvents(events(fixture().ros1), events(path), "livox_ros2_driver");
}

TEST(Ros2Bag, InfoListsTopicsWithTheirRos2TypesCountsAndFields) {
  const std::string path = (kDir / "info.mcap").string();
  testing::writeMcap(fixture().records, path, {true, "zstd", 1 << 20, true});
  const BagInfo ros1 = describeBag(fixture().ros1);
  const BagInfo ros2 = describeBag(path);
  EXPECT_NE(ros2.format.find("mcap"), std::string::npos) << ros2.format;
  ASSERT_EQ(ros1.topics.size(), ros2.topics.size());
  for (std::size_t i = 0; i < ros1.topics.size(); ++i) {
    EXPECT_EQ(ros1.topics[i].topic, ros2.topics[i].topic);
    EXPECT_EQ(ros1.topics[i].messages, ros2.topics[i].messages);
    EXPECT_EQ(ros1.topics[i].fields, ros2.topics[i].fields);
    EXPECT_DOUBLE_EQ(ros1.topics[i].mean_points, ros2.topics[i].mean_points);
    EXPECT_NE(ros2.topics[i].type.find("/msg/"), std::string::npos) << ros2.topics[i].type;
  }
  EXPECT_EQ(ros1.begin_ns, ros2.begin_ns);
  EXPECT_EQ(ros1.end_ns, ros2.end_ns);
  EXPECT_EQ(ros2.imu_unit_guess, "g");
  EXPECT_NE(formatBagInfo(ros2).find("sensor_msgs/msg/PointCloud2"), std::string::npos);
}

TEST(Ros2Bag, ATruncatedMcapIsReadUpToItsLastCompleteChunk) {
  const std::string path = (kDir / "cut.mcap").string();
  testing::writeMcap(fixture().records, path, {true, "zstd", 256 << 10, false});
  const auto full = events(path);
  fs::resize_file(path, fs::file_size(path) * 6 / 10);  // cut inside a chunk
  BagSource src(path, config::bagSourceOptions(testing::simRigConfig(fixture().sim), "hvi"));
  std::vector<SensorEvent> got;
  SensorEvent e;
  while (src.next(&e)) got.push_back(e);
  EXPECT_TRUE(src.truncated());
  EXPECT_GT(got.size(), full.size() / 3);
  EXPECT_LT(got.size(), full.size());
  got.resize(std::min(got.size(), full.size()));
  expectSameEvents(std::vector<SensorEvent>(full.begin(), full.begin() + static_cast<long>(got.size())), got, "prefix");
}

TEST(Ros2Bag, BadRos2InputGetsOneClearLineOrACountedSkip) {
  const auto options = config::bagSourceOptions(testing::simRigConfig(fixture().sim), "hvi");
  auto error = [&](const std::string& path) {
    try {
      BagSource src(path, options);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A folder without metadata.yaml or data files.
  const fs::path empty = kDir / "empty_folder";
  fs::create_directories(empty);
  std::ofstream(empty / "notes.txt") << "x";
  EXPECT_NE(error(empty.string()).find("not a rosbag2 bag"), std::string::npos) << error(empty.string());
  // metadata.yaml naming a file that is not there.
  const fs::path missing = kDir / "missing_file";
  testing::writeRosbag2(fixture().records, missing.string(), {"", 1, true});
  fs::remove(missing / "missing_file_0.db3");
  EXPECT_NE(error(missing.string()).find("missing"), std::string::npos) << error(missing.string());
  // A configured topic of another type.
  auto records = fixture().records;
  for (auto& r : records)
    if (r.topic == "/livox/imu") r.type = "sensor_msgs/msg/MagneticField";
  const std::string wrong = (kDir / "wrong_type.mcap").string();
  testing::writeMcap(records, wrong, {});
  EXPECT_NE(error(wrong).find("expected sensor_msgs/Imu"), std::string::npos) << error(wrong);
  // Not a bag at all.
  const std::string text = (kDir / "not_a_bag.mcap").string();
  std::ofstream(text) << "hello";
  EXPECT_NE(error(text).find("is not a bag"), std::string::npos) << error(text);

  // CDR payloads too short for their fields (an IMU sample, a cloud after the first) are skipped and counted.
  records = fixture().records;
  int imu = 0, clouds = 0;
  for (auto& r : records) {
    if (r.topic == "/livox/imu" && ++imu == 10) r.cdr.resize(40);
    if (r.topic == "/velodyne_points" && ++clouds == 3) r.cdr.resize(r.cdr.size() / 2);
  }
  const std::string shortened = (kDir / "short.mcap").string();
  testing::writeMcap(records, shortened, {});
  BagSource src(shortened, options);
  std::size_t n = 0;
  SensorEvent e;
  while (src.next(&e)) ++n;
  EXPECT_EQ(src.skippedMessages(), 2u);
  EXPECT_EQ(n + 2, events(fixture().ros1).size());
}

}  // namespace mmlio::io

namespace mmlio::pipeline {

TEST(Ros2Bag, RunOnTheRos2TwinsGivesTheRos1BagsTrajectory) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("mmlio_ros2_run_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  sim::SimOptions so;
  so.scenario = "office";
  so.duration_s = 6.0;
  const sim::Simulator sim(so);
  const std::string ros1 = (dir / "office.bag").string();
  testing::writeSimBag(sim, ros1);
  const auto records = testing::ros2Records(ros1, "livox_ros_driver2/msg/CustomMsg");
  testing::writeMcap(records, (dir / "office.mcap").string(), {true, "zstd", 1 << 20, true});
  testing::writeRosbag2(records, (dir / "office_db3").string(), {"message", 2, true});

  RunOptions options;
  options.config = testing::simRigConfig(sim);
  options.progress = false;
  options.bag_path = ros1;
  const RunResult want = runBag(options);
  ASSERT_GT(want.trajectory.size(), 40u);
  for (const std::string& bag : {(dir / "office.mcap").string(), (dir / "office_db3").string()}) {
    options.bag_path = bag;
    const RunResult got = runBag(options);
    ASSERT_EQ(got.trajectory.size(), want.trajectory.size()) << bag;
    for (std::size_t i = 0; i < want.trajectory.size(); ++i) {
      EXPECT_EQ(got.trajectory[i].stamp_ns, want.trajectory[i].stamp_ns) << bag;
      EXPECT_TRUE(got.trajectory[i].T_world_body.matrix() == want.trajectory[i].T_world_body.matrix())
          << bag << " pose " << i;
    }
    EXPECT_TRUE(got.untrusted.empty()) << got.untrusted;
    EXPECT_EQ(got.report.input.source, bag);
  }
  fs::remove_all(dir);
}

}  // namespace mmlio::pipeline
