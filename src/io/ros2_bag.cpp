// Which ROS 2 container a path is, and a rosbag2 folder's files (from metadata.yaml, or without it every .db3 / .mcap
// inside), split .mcap files merged into one time-ordered stream.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "decompress.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "ros2_bag.hpp"

namespace mmlio::io::detail {
namespace {

namespace fs = std::filesystem;

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// A rosbag2 folder split into several .mcap files: their messages merged in time order (ties: earlier file first),
/// topics matched by name.
class SplitBag final : public Ros2Bag {
 public:
  explicit SplitBag(std::vector<std::unique_ptr<Ros2Bag>> parts) : parts_(std::move(parts)) {
    for (const auto& part : parts_) {
      std::vector<std::size_t> map;
      for (const Ros2Topic& t : part->topics()) {
        auto it = std::find_if(topics_.begin(), topics_.end(), [&](const Ros2Topic& u) { return u.name == t.name; });
        if (it == topics_.end()) {
          topics_.push_back(t);
          it = topics_.end() - 1;
        } else if (t.messages > 0) {
          it->begin_ns = it->messages ? std::min(it->begin_ns, t.begin_ns) : t.begin_ns;
          it->end_ns = it->messages ? std::max(it->end_ns, t.end_ns) : t.end_ns;
          it->messages += t.messages;
        }
        map.push_back(static_cast<std::size_t>(it - topics_.begin()));
      }
      topic_map_.push_back(std::move(map));
      truncated_ = truncated_ || part->truncated();
    }
    format_ = parts_.front()->formatName() + " x " + std::to_string(parts_.size()) + " files";
    heads_.resize(parts_.size());
    has_head_.assign(parts_.size(), false);
    std::vector<std::size_t> all(topics_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    restart(all);
  }

  void restart(const std::vector<std::size_t>& topics) override {
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      std::vector<std::size_t> local;
      for (std::size_t i = 0; i < topic_map_[p].size(); ++i)
        if (std::find(topics.begin(), topics.end(), topic_map_[p][i]) != topics.end()) local.push_back(i);
      parts_[p]->restart(local);
      has_head_[p] = !local.empty() && parts_[p]->next(&heads_[p]);
    }
  }

  bool next(Ros2Message* out) override {
    std::size_t best = parts_.size();
    for (std::size_t p = 0; p < parts_.size(); ++p)
      if (has_head_[p] && (best == parts_.size() || heads_[p].time_ns < heads_[best].time_ns)) best = p;
    if (best == parts_.size()) {
      damaged_ = 0;
      for (const auto& part : parts_) damaged_ += part->damagedStretches();
      return false;
    }
    *out = std::move(heads_[best]);
    out->topic = topic_map_[best][out->topic];
    has_head_[best] = parts_[best]->next(&heads_[best]);
    return true;
  }

 private:
  std::vector<std::unique_ptr<Ros2Bag>> parts_;
  std::vector<std::vector<std::size_t>> topic_map_;  // per part: its topic index -> ours
  std::vector<Ros2Message> heads_;
  std::vector<bool> has_head_;
};

/// The data files of a rosbag2 folder, from its metadata.yaml or, without one, every .db3 / .mcap in it.
std::vector<std::string> folderFiles(const fs::path& dir, std::string* storage) {
  const fs::path meta = dir / "metadata.yaml";
  std::vector<std::string> files;
  if (fs::exists(meta)) {
    try {
      const YAML::Node info = YAML::LoadFile(meta.string())["rosbag2_bagfile_information"];
      if (!info) throw Error("no rosbag2_bagfile_information");
      *storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "sqlite3";
      for (const auto& f : info["relative_file_paths"]) files.push_back((dir / f.as<std::string>()).string());
    } catch (const std::exception& e) {
      throw Error("cannot read " + meta.string() + ": " + e.what());
    }
    if (files.empty()) throw Error(meta.string() + " lists no files (relative_file_paths is empty)");
    for (const std::string& f : files)
      if (!fs::exists(f)) throw Error(f + " is listed in " + meta.string() + " but missing");
    return files;
  }
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (endsWith(name, ".db3") || endsWith(name, ".db3.zstd")) files.push_back(e.path().string());
  }
  *storage = "sqlite3";
  if (files.empty()) {
    for (const auto& e : fs::directory_iterator(dir))
      if (endsWith(e.path().filename().string(), ".mcap")) files.push_back(e.path().string());
    *storage = "mcap";
  }
  if (files.empty())
    throw Error(dir.string() + " is a folder without metadata.yaml, .db3 or .mcap files: not a rosbag2 bag");
  std::sort(files.begin(), files.end());
  log::warn(dir.string(), " has no metadata.yaml: reading its ", files.size(), " ", *storage, " file(s) in name order");
  return files;
}

}  // namespace

Ros2Format ros2Format(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    return fs::exists(fs::path(path) / "metadata.yaml") || !fs::is_empty(path, ec) ? Ros2Format::kFolder
                                                                                   : Ros2Format::kNone;
  std::uint8_t head[16] = {};
  std::size_t got = 0;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    got = std::fread(head, 1, sizeof(head), f);
    std::fclose(f);
  }
  if (got >= 16 && std::memcmp(head, "SQLite format 3", 16) == 0) return Ros2Format::kSqlite3;
  if (got >= 8 && std::memcmp(head, "\x89MCAP0\r\n", 8) == 0) return Ros2Format::kMcap;
  if (isZstdFrame(head, got) && endsWith(path, ".db3.zstd")) return Ros2Format::kSqlite3;
  return Ros2Format::kNone;
}

std::unique_ptr<Ros2Bag> openRos2Bag(const std::string& path) {
  switch (ros2Format(path)) {
    case Ros2Format::kSqlite3:
      return openSqlite3({path});
    case Ros2Format::kMcap:
      return openMcap(path);
    case Ros2Format::kFolder: {
      std::string storage;
      const std::vector<std::string> files = folderFiles(path, &storage);
      if (storage == "mcap") {
        if (files.size() == 1) return openMcap(files.front());
        std::vector<std::unique_ptr<Ros2Bag>> parts;
        parts.reserve(files.size());
        for (const std::string& f : files) parts.push_back(openMcap(f));
        return std::make_unique<SplitBag>(std::move(parts));
      }
      if (storage != "sqlite3")
        throw Error(path + ": rosbag2 storage '" + storage + "' is not read (sqlite3 and mcap are)");
      return openSqlite3(files);
    }
    case Ros2Format::kNone:
      break;
  }
  throw Error(path + " is not a ROS 2 bag");
}

}  // namespace mmlio::io::detail
