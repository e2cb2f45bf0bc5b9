#include <gtest/gtest.h>

#include <limits>

#include "mmlio/pipeline/json.hpp"

using mmlio::pipeline::Json;

TEST(Json, ObjectsKeepInsertionOrderAndEscapeStrings) {
  Json j = Json::object();
  j["zeta"] = 1;
  j["alpha"] = "a\"b\n";
  j["nested"]["x"] = 0.5;
  EXPECT_EQ(j.dump(-1), R"({"zeta":1,"alpha":"a\"b\n","nested":{"x":0.5}})");
}

TEST(Json, NonFiniteNumbersBecomeNull) {
  Json j = Json::array();
  j.push_back(std::numeric_limits<double>::quiet_NaN());
  j.push_back(true);
  j.push_back(std::size_t{42});
  EXPECT_EQ(j.dump(-1), "[null,true,42]");
}
