#include "bag_open.hpp"

#include "raw_bag_scanner.hpp"

#include <rosbag/exceptions.h>
#include <rosbag/view.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "mmlio/core/error.hpp"

namespace mmlio::io::detail {

namespace {

void checkFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw Error("bag not found: " + path);
  if (std::filesystem::is_directory(path, ec)) throw Error("bag path is a directory, not a file: " + path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read bag " + path + " (permission denied?)");
  char magic[13] = {};
  in.read(magic, 13);
  const std::string head(magic, static_cast<std::size_t>(in.gcount()));
  if (head.rfind("#ROSBAG V2.0", 0) != 0) {
    if (head.rfind("#ROSBAG V", 0) == 0)
      throw Error(path + " is an old ROS bag format (" + head.substr(1, 11) + "): run `rosbag fix` to convert it");
    throw Error(path +
                " is not a bag: neither ROS 1 (#ROSBAG V2.0 header) nor ROS 2 (rosbag2 folder, .db3 or .mcap file)");
  }
}

}  // namespace

std::string reindexHint(const std::string& path, const std::string& why) {
  return "cannot read bag " + path + " (" + why + "): it is truncated or unindexed; run `rosbag reindex " + path + "`";
}

bool tryOpenIndexed(rosbag::Bag& bag, const std::string& path, std::string* why) {
  checkFile(path);
  try {
    bag.open(path, rosbag::bagmode::Read);
    if (indexLooksSound(path, why)) return true;
  } catch (const rosbag::BagUnindexedException&) {
    *why = "no index";
  } catch (const std::exception& e) {
    *why = e.what();
  }
  try {
    bag.close();
  } catch (...) {
  }
  return false;
}

void openBagForReading(rosbag::Bag& bag, const std::string& path) {
  std::string why;
  if (!tryOpenIndexed(bag, path, &why)) throw Error(reindexHint(path, why));
}

std::string normalizeTopic(const std::string& topic) {
  return (!topic.empty() && topic.front() == '/') ? topic : "/" + topic;
}

std::string listTopics(rosbag::Bag& bag) {
  std::map<std::string, std::string> topics;
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections()) topics[normalizeTopic(c->topic)] = c->datatype;
  if (topics.empty()) return "(none)";
  std::string out;
  for (const auto& [t, type] : topics) out += (out.empty() ? "" : ", ") + t + " (" + type + ")";
  return out;
}

}  // namespace mmlio::io::detail
