// Decoders on messages built here with known bytes: each PointCloud2 layout, drops, Livox, IMU.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <ros/serialization.h>

#include "mmlio/core/error.hpp"
#include "cloud_builder.hpp"
#include "mmlio/io/cloud_decoders.hpp"

namespace mmlio::io {
namespace {

const Stamp kStamp = 1'600'000'000'000'000'000LL;

const std::vector<FieldSpec> kVelodyne = {{"x", PF::FLOAT32},         {"y", PF::FLOAT32},   {"z", PF::FLOAT32},
                                          {"intensity", PF::FLOAT32}, {"ring", PF::UINT16}, {"time", PF::FLOAT32}};

TEST(CloudDecoders, VelodyneNegativeRelativeTimesAreSortedAndRebasedOnTheEarliestPoint) {
  auto c = makeCloud(kVelodyne, kStamp, 4);
  const float times[4] = {-0.05f, 0.0f, -0.1f, 0.02f};
  for (std::size_t i = 0; i < 4; ++i) {
    putXyz(c, i, 5.f + i, 0.f, 0.f);
    put(c, i, "intensity", 10.f * i);
    put(c, i, "ring", static_cast<std::uint16_t>(i + 3));
    put(c, i, "time", times[i]);
  }
  CloudDecodeOptions o;
  o.sensor = "velodyne";
  DecodeStats st;
  const LidarScan s = decodePointCloud2(c, o, &st);
  EXPECT_EQ(s.sensor, "velodyne");
  EXPECT_EQ(st.kept, 4u);
  ASSERT_EQ(s.points.size(), 4u);
  EXPECT_NEAR(static_cast<double>(s.start_ns - kStamp), -0.1e9, 1e3);
  // Time order: index 2 (-0.1), 0 (-0.05), 1 (0), 3 (0.02).
  const int order[4] = {2, 0, 1, 3};
  const double rel[4] = {0.0, 0.05, 0.1, 0.12};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(s.points[k].time_s, rel[k], 1e-6);
    EXPECT_FLOAT_EQ(s.points[k].xyz.x(), 5.f + order[k]);
    EXPECT_EQ(s.points[k].ring, order[k] + 3);
    EXPECT_FLOAT_EQ(s.points[k].intensity, 10.f * order[k]);
  }
}

TEST(CloudDecoders, OusterTIsNanosecondsAfterTheHeaderStamp) {
  auto c = makeCloud({{"x", PF::FLOAT32},
                      {"y", PF::FLOAT32},
                      {"z", PF::FLOAT32},
                      {"t", PF::UINT32},
                      {"reflectivity", PF::UINT16},
                      {"ring", PF::UINT8}},
                     kStamp, 3);
  const std::uint32_t t[3] = {3000, 1000, 2000};
  for (std::size_t i = 0; i < 3; ++i) {
    putXyz(c, i, 0.f, 2.f + i, 0.f);
    put(c, i, "t", t[i]);
    put(c, i, "reflectivity", static_cast<std::uint16_t>(100 + i));
    put(c, i, "ring", static_cast<std::uint8_t>(60 + i));
  }
  const LidarScan s = decodePointCloud2(c, CloudDecodeOptions{}, nullptr);
  ASSERT_EQ(s.points.size(), 3u);
  EXPECT_EQ(s.start_ns, kStamp + 1000);
  EXPECT_NEAR(s.points[2].time_s, 2e-6, 1e-9);
  EXPECT_FLOAT_EQ(s.points[0].xyz.y(), 3.f);  // index 1
  EXPECT_EQ(s.points[0].ring, 61);
  EXPECT_FLOAT_EQ(s.points[0].intensity, 101.f);  // reflectivity stands in for intensity
}

TEST(CloudDecoders, HesaiTimestampIsAbsoluteSeconds) {
  auto c = makeCloud({{"x", PF::FLOAT32},
                      {"y", PF::FLOAT32},
                      {"z", PF::FLOAT32},
                      {"intensity", PF::FLOAT32},
                      {"timestamp", PF::FLOAT64},
                      {"ring", PF::UINT16}},
                     kStamp, 2);
  putXyz(c, 0, 3.f, 0.f, 0.f);
  putXyz(c, 1, 4.f, 0.f, 0.f);
  put(c, 0, "timestamp", 1'600'000'000.05);
  put(c, 1, "timestamp", 1'600'000'000.01);
  const LidarScan s = decodePointCloud2(c, CloudDecodeOptions{}, nullptr);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_NEAR(static_cast<double>(s.start_ns - kStamp), 0.01e9, 1e3);  // float64 at 1.6e9 s: ~0.2 us
  EXPECT_FLOAT_EQ(s.points[0].xyz.x(), 4.f);
  EXPECT_NEAR(s.points[1].time_s, 0.04, 1e-6);
}

TEST(CloudDecoders, WithoutTimeOrRingTheAzimuthGivesTimeAndTheElevationGivesRing) {
  auto c = makeCloud({{"x", PF::FLOAT32}, {"y", PF::FLOAT32}, {"z", PF::FLOAT32}}, kStamp, 5);
  // Clockwise from +x: +x, -y, -x, +y, then just short of a full turn (atan2 = +0.01 rad).
  const double d2r = M_PI / 180.0;
  putXyz(c, 0, 10.f, 0.f, static_cast<float>(10.0 * std::tan(15.0 * d2r)));    // +15 deg -> ring 15
  putXyz(c, 1, 0.f, -10.f, static_cast<float>(10.0 * std::tan(-15.0 * d2r)));  // -15 deg -> ring 0
  putXyz(c, 2, -10.f, 0.f, static_cast<float>(10.0 * std::tan(1.0 * d2r)));    // +1 deg -> ring 8
  putXyz(c, 3, 0.f, 10.f, static_cast<float>(10.0 * std::tan(-1.0 * d2r)));    // -1 deg -> ring 7
  putXyz(c, 4, static_cast<float>(10.0 * std::cos(0.01)), static_cast<float>(10.0 * std::sin(0.01)), 0.f);
  CloudDecodeOptions o;
  o.scan_period_s = 0.1;
  o.num_rings = 16;
  const LidarScan s = decodePointCloud2(c, o, nullptr);
  ASSERT_EQ(s.points.size(), 5u);
  EXPECT_EQ(s.start_ns, kStamp);
  const double expect_t[5] = {0.0, 0.025, 0.05, 0.075, 0.1 * (1.0 - 0.01 / (2 * M_PI))};
  const int expect_ring[4] = {15, 0, 8, 7};
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(s.points[k].time_s, expect_t[k], 1e-6) << k;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.points[k].ring, expect_ring[k]) << k;
}

TEST(CloudDecoders, NanZeroAndOutOfRangePointsAreDroppedAndCounted) {
  auto c = makeCloud(kVelodyne, kStamp, 6);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  putXyz(c, 0, nan, 1.f, 1.f);
  putXyz(c, 1, 1.f, std::numeric_limits<float>::infinity(), 1.f);
  putXyz(c, 2, 0.f, 0.f, 0.f);
  putXyz(c, 3, 0.2f, 0.f, 0.f);   // closer than 0.5 m
  putXyz(c, 4, 150.f, 0.f, 0.f);  // farther than 100 m
  putXyz(c, 5, 10.f, 0.f, 0.f);   // kept
  put(c, 5, "time", 0.03f);
  DecodeStats st;
  const LidarScan s = decodePointCloud2(c, CloudDecodeOptions{}, &st);
  ASSERT_EQ(s.points.size(), 1u);
  EXPECT_EQ(st.kept, 1u);
  EXPECT_EQ(st.dropped_nan, 2u);
  EXPECT_EQ(st.dropped_zero, 1u);
  EXPECT_EQ(st.dropped_range, 2u);
  EXPECT_NEAR(static_cast<double>(s.start_ns - kStamp), 30e6, 10.0);  // the only kept point (float32 time)
  EXPECT_FLOAT_EQ(s.points[0].time_s, 0.f);
  decodePointCloud2(c, CloudDecodeOptions{}, &st);  // stats accumulate
  EXPECT_EQ(st.kept, 2u);
  EXPECT_EQ(st.dropped_range, 4u);
}

TEST(CloudDecoders, AllPointsDroppedGivesAnEmptyScanAtTheHeaderStamp) {
  auto c = makeCloud(kVelodyne, kStamp, 2);
  const LidarScan s = decodePointCloud2(c, CloudDecodeOptions{}, nullptr);
  EXPECT_TRUE(s.points.empty());
  EXPECT_EQ(s.start_ns, kStamp);
}

TEST(CloudDecoders, CloudWithoutXyzOrWithShortDataIsAnError) {
  auto c = makeCloud({{"a", PF::FLOAT32}}, kStamp, 1);
  EXPECT_THROW(decodePointCloud2(c, CloudDecodeOptions{}, nullptr), Error);
  auto d = makeCloud(kVelodyne, kStamp, 3);
  d.data.resize(d.data.size() - 1);
  EXPECT_THROW(decodePointCloud2(d, CloudDecodeOptions{}, nullptr), Error);
}

LivoxCustomMsg makeLivox(bool driver2) {
  LivoxCustomMsg m;
  m.driver2 = driver2;
  m.header.stamp.fromNSec(static_cast<std::uint64_t>(kStamp));
  m.timebase = static_cast<std::uint64_t>(kStamp + 500);
  const std::uint32_t off[3] = {2000, 0, 1000};
  for (int i = 0; i < 3; ++i) {
    LivoxCustomPoint p;
    p.offset_time = off[i];
    p.x = 10.f + i;
    p.reflectivity = static_cast<std::uint8_t>(20 + i);
    p.tag = 0x10;
    p.line = static_cast<std::uint8_t>(i);
    m.points.push_back(p);
  }
  LivoxCustomPoint zero;  // no return
  m.points.push_back(zero);
  m.point_num = static_cast<std::uint32_t>(m.points.size());
  return m;
}

TEST(LivoxDecoder, LineIsRingReflectivityIsIntensityAndTimeIsTimebasePlusOffset) {
  for (bool driver2 : {false, true}) {
    DecodeStats st;
    CloudDecodeOptions o;
    o.sensor = "livox";
    const LidarScan s = decodeLivox(makeLivox(driver2), o, &st);
    ASSERT_EQ(s.points.size(), 3u);
    EXPECT_EQ(st.dropped_zero, 1u);
    EXPECT_EQ(s.start_ns, kStamp + 500);
    EXPECT_EQ(s.points[0].ring, 1);
    EXPECT_FLOAT_EQ(s.points[0].intensity, 21.f);
    EXPECT_FLOAT_EQ(s.points[2].xyz.x(), 10.f);
    EXPECT_NEAR(s.points[2].time_s, 2e-6, 1e-10);
  }
}

TEST(LivoxDecoder, ZeroTimebaseFallsBackToTheHeaderStamp) {
  LivoxCustomMsg m = makeLivox(false);
  m.timebase = 0;
  const LidarScan s = decodeLivox(m, CloudDecodeOptions{}, nullptr);
  EXPECT_EQ(s.start_ns, kStamp);
}

TEST(LivoxMessage, SerialisesToTheDriverWireFormatAndReportsItsTypeAndMd5) {
  LivoxCustomMsg m;
  m.header.frame_id = "ab";
  m.timebase = 0x0102030405060708ULL;
  m.point_num = 1;
  LivoxCustomPoint p;
  p.offset_time = 0xAABBCCDD;
  p.x = 1.5f;
  p.line = 5;
  m.points.push_back(p);
  // header 4+8+(4+2) + timebase 8 + point_num 4 + lidar_id 1 + rsvd 3 + length 4 + point 19
  const std::uint32_t len = ros::serialization::serializationLength(m);
  ASSERT_EQ(len, 18u + 8u + 4u + 1u + 3u + 4u + 19u);
  std::vector<std::uint8_t> buf(len);
  ros::serialization::OStream os(buf.data(), len);
  ros::serialization::serialize(os, m);
  EXPECT_EQ(buf[18], 0x08);  // little-endian timebase
  EXPECT_EQ(buf[34], 1);     // points length
  EXPECT_EQ(buf[38], 0xDD);  // offset_time
  float x;
  std::memcpy(&x, &buf[42], 4);
  EXPECT_FLOAT_EQ(x, 1.5f);
  EXPECT_EQ(buf[len - 1], 5);  // line is the last byte

  LivoxCustomMsg back;
  ros::serialization::IStream is(buf.data(), len);
  ros::serialization::deserialize(is, back);
  EXPECT_EQ(back.timebase, m.timebase);
  EXPECT_EQ(back.header.frame_id, "ab");
  ASSERT_EQ(back.points.size(), 1u);
  EXPECT_EQ(back.points[0].offset_time, 0xAABBCCDDu);

  EXPECT_STREQ(ros::message_traits::md5sum(m), "e4d6829bdfe657cb6c21a746c86b21a6");
  EXPECT_STREQ(ros::message_traits::datatype(m), "livox_ros_driver/CustomMsg");
  m.driver2 = true;
  EXPECT_STREQ(ros::message_traits::datatype(m), "livox_ros_driver2/CustomMsg");
  const std::string def = ros::message_traits::definition(m);
  EXPECT_NE(def.find(std::string(80, '=') + "\nMSG: livox_ros_driver2/CustomPoint\n"), std::string::npos);
  EXPECT_NE(def.find("uint8[3]  rsvd"), std::string::npos);
}

TEST(ImuDecoder, AccelerationIsScaledAndGyroCopied) {
  sensor_msgs::Imu m;
  m.header.stamp.fromNSec(123456789012345ULL);
  m.linear_acceleration.z = 1.0;
  m.angular_velocity.x = 0.25;
  const ImuSample s = decodeImu(m, 9.80665);
  EXPECT_EQ(s.stamp_ns, 123456789012345LL);
  EXPECT_DOUBLE_EQ(s.acc_m_s2.z(), 9.80665);
  EXPECT_DOUBLE_EQ(s.gyro_rad_s.x(), 0.25);
}

}  // namespace
}  // namespace mmlio::io
