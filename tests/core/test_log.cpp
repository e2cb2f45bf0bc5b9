#include <gtest/gtest.h>

#include "mmlio/core/log.hpp"

namespace mmlio::log {
namespace {

TEST(StampText, PrintsEpochStampsWithMillisecondsNotInScientificNotation) {
  EXPECT_EQ(stampText(1700000012967000000LL), "1700000012.967");
  EXPECT_EQ(stampText(1700000012000400000LL), "1700000012.000");  // rounds below half a millisecond down
  EXPECT_EQ(stampText(1700000012999600000LL), "1700000013.000");  // and carries into the seconds
  EXPECT_EQ(stampText(0), "0.000");
  EXPECT_EQ(stampText(-1500000000LL), "-1.500");
}

TEST(StampText, ReadsInsideALogLine) {
  std::string line;
  configure(Level::kInfo, [&](Level, const std::string& message) { line = message; });
  warn("no IMU data over the sweep ending at ", stampText(1700000004965865925LL), " s");
  configure(Level::kInfo);
  EXPECT_EQ(line, "no IMU data over the sweep ending at 1700000004.966 s");
}

}  // namespace
}  // namespace mmlio::log
