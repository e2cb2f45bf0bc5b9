#pragma once
// Private helper of src/io: opening a ROS1 bag for reading with one-line, actionable errors.
#include <rosbag/bag.h>

#include <string>
#include <vector>

namespace mmlio::io::detail {

/// Opens `path` read-only. Throws mmlio::Error: missing file, not a bag, unindexed/truncated bag
/// (suggesting `rosbag reindex`), unreadable.
void openBagForReading(rosbag::Bag& bag, const std::string& path);
/// Same, but an unindexed/truncated bag returns false with the reason in `why` instead of throwing.
bool tryOpenIndexed(rosbag::Bag& bag, const std::string& path, std::string* why);
/// The one-line error for a bag neither rosbag nor the chunk scanner can read.
std::string reindexHint(const std::string& path, const std::string& why);

/// "/a" and "a" name the same topic.
std::string normalizeTopic(const std::string& topic);

/// Sorted, comma-separated topic names of the bag with their types: "/imu (sensor_msgs/Imu), ...".
std::string listTopics(rosbag::Bag& bag);

}  // namespace mmlio::io::detail
