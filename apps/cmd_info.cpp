// `mmlio info BAG [--json]`: topics, types, counts, rates, time span, point fields and mean
// points per message of cloud topics, and the guessed IMU acceleration unit.
#include <iostream>
#include <string>

#include "commands.hpp"
#include "mmlio/io/bag_info.hpp"
#include "mmlio/pipeline/json.hpp"

namespace mmlio::apps {
namespace {

pipeline::Json toJson(const io::BagInfo& info) {
  using pipeline::Json;
  Json j = Json::object();
  j["path"] = info.path;
  // Strings: pipeline::Json keeps numbers as double, which would lose the nanoseconds.
  j["begin_ns"] = std::to_string(info.begin_ns);
  j["end_ns"] = std::to_string(info.end_ns);
  j["duration_s"] = toSec(info.end_ns - info.begin_ns);
  j["imu_unit_guess"] = info.imu_unit_guess;
  Json topics = Json::array();
  for (const io::TopicInfo& t : info.topics) {
    Json o = Json::object();
    o["topic"] = t.topic;
    o["type"] = t.type;
    o["messages"] = t.messages;
    o["rate_hz"] = t.rate_hz;
    if (!t.fields.empty()) {
      Json f = Json::array();
      for (const std::string& s : t.fields) f.push_back(s);
      o["fields"] = f;
      o["mean_points"] = t.mean_points;
    }
    topics.push_back(o);
  }
  j["topics"] = topics;
  return j;
}

}  // namespace

void registerInfoCommand(CLI::App& app) {
  auto bag = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd =
      app.add_subcommand("info", "Describe a ROS 1 or ROS 2 bag: topics, types, rates, point fields, IMU unit");
  cmd->add_option("bag", *bag, "ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3")->required();
  cmd->add_flag("--json", *json, "one JSON object instead of the table");
  cmd->callback([bag, json] {
    const io::BagInfo info = io::describeBag(*bag);
    if (*json)
      std::cout << toJson(info).dump(-1) << '\n';
    else
      std::cout << io::formatBagInfo(info);
  });
}

}  // namespace mmlio::apps
