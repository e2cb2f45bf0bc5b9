#pragma once
// Private helper of src/io: a ROS 2 bag — a rosbag2 sqlite3 folder (metadata.yaml + .db3 files, uncompressed or zstd
// per file or per message), one .db3 file, or an .mcap file — as a stream of serialised (CDR) messages in receive-time
// order. Needs no ROS 2 installation.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::io::detail {

enum class Ros2Format { kNone, kFolder, kSqlite3, kMcap };

/// Which ROS 2 container `path` is (kFolder: a rosbag2 folder), from whether it is a folder and from the file's magic
/// bytes (SQLite, MCAP, zstd for a per-file compressed .db3.zstd); kNone for anything else.
Ros2Format ros2Format(const std::string& path);

struct Ros2Topic {
  std::string name, type;  // type as ROS 2 spells it: "sensor_msgs/msg/Imu"
  std::size_t messages = 0;
  Stamp begin_ns = 0, end_ns = 0;  // receive time of its first and last message
};

struct Ros2Message {
  std::size_t topic = 0;           // index into Ros2Bag::topics()
  Stamp time_ns = 0;               // receive (log) time
  std::vector<std::uint8_t> data;  // CDR, decompressed
};

class Ros2Bag {
 public:
  virtual ~Ros2Bag() = default;

  const std::vector<Ros2Topic>& topics() const { return topics_; }
  /// "ROS 2 mcap (zstd chunks)", "ROS 2 sqlite3 (2 files)": for messages and `mmlio info`.
  const std::string& formatName() const { return format_; }
  /// Read only these topics (indices into topics()) from the start again; all topics after open.
  virtual void restart(const std::vector<std::size_t>& topics) = 0;
  /// Next message of the selected topics in time order (ties in file order); false at the end. A damaged stretch is
  /// skipped (counted in damagedStretches()), never thrown.
  virtual bool next(Ros2Message* message) = 0;
  /// The file ends inside a record (recording killed): read up to the last complete one.
  bool truncated() const { return truncated_; }
  /// Chunks / database pages that could not be read and were skipped.
  std::size_t damagedStretches() const { return damaged_; }

 protected:
  std::vector<Ros2Topic> topics_;
  std::string format_;
  bool truncated_ = false;
  std::size_t damaged_ = 0;
};

/// Opens and indexes the bag at `path` (a folder, .db3, .db3.zstd or .mcap; an MCAP file is scanned once, front to
/// back). Throws mmlio::Error with one line: not a ROS 2 bag, a folder without metadata.yaml or data files, a file
/// metadata.yaml lists but that is missing, an unreadable database.
std::unique_ptr<Ros2Bag> openRos2Bag(const std::string& path);
/// The readers behind openRos2Bag: one .mcap file; .db3 (or .db3.zstd) files of one bag.
std::unique_ptr<Ros2Bag> openMcap(const std::string& path);
std::unique_ptr<Ros2Bag> openSqlite3(const std::vector<std::string>& files);

}  // namespace mmlio::io::detail
