// rosbag2's sqlite3 storage: one or more .db3 files (split bags), each with tables topics(id, name, type, ...) and
// messages(id, topic_id, timestamp, data). Compression as rosbag2 writes it: zstd per file (.db3.zstd, decompressed to
// a temporary copy) or per message (each blob a zstd frame, recognised by its magic bytes).
#include <sqlite3.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <map>
#include <unistd.h>

#include "decompress.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "ros2_bag.hpp"

namespace mmlio::io::detail {
namespace {

namespace fs = std::filesystem;

/// One .db3 file and its cursor over the selected topics.
struct Database {
  std::string path;
  sqlite3* db = nullptr;
  sqlite3_stmt* rows = nullptr;
  std::map<std::int64_t, std::size_t> topic_of_id;  // topics.id -> index into Ros2Bag::topics()
  bool has_row = false;
  Stamp row_time = 0;

  ~Database() {
    sqlite3_finalize(rows);
    sqlite3_close(db);
  }
  std::string error() const { return path + ": " + sqlite3_errmsg(db); }
};

class Sqlite3Bag final : public Ros2Bag {
 public:
  explicit Sqlite3Bag(const std::vector<std::string>& files) {
    for (const std::string& f : files) openDatabase(f);
    format_ = "ROS 2 sqlite3 (" + std::to_string(files.size()) + (files.size() == 1 ? " file" : " files") +
              (compressed_files_ ? ", zstd per file" : "") + ")";
    std::vector<std::size_t> all(topics_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    restart(all);
  }
  ~Sqlite3Bag() override {
    dbs_.clear();
    for (const std::string& t : temporaries_) {
      std::error_code ec;
      fs::remove(t, ec);
    }
  }

  void restart(const std::vector<std::size_t>& topics) override {
    for (auto& d : dbs_) {
      sqlite3_finalize(d->rows);
      d->rows = nullptr;
      d->has_row = false;
      std::string ids;
      for (const auto& [id, t] : d->topic_of_id)
        if (std::find(topics.begin(), topics.end(), t) != topics.end())
          ids += (ids.empty() ? "" : ",") + std::to_string(id);
      if (ids.empty()) continue;
      const std::string sql =
          "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" + ids + ") ORDER BY timestamp, id";
      if (sqlite3_prepare_v2(d->db, sql.c_str(), -1, &d->rows, nullptr) != SQLITE_OK) {
        damaged(*d, d->error());
        continue;
      }
      step(*d);
    }
  }

  bool next(Ros2Message* out) override {
    Database* best = nullptr;
    for (auto& d : dbs_)
      if (d->has_row && (!best || d->row_time < best->row_time)) best = d.get();
    if (!best) return false;
    sqlite3_stmt* r = best->rows;
    out->topic = best->topic_of_id.at(sqlite3_column_int64(r, 0));
    out->time_ns = best->row_time;
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(r, 2));
    const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(r, 2));
    if (isZstdFrame(blob, bytes)) {
      try {
        out->data = zstdDecompress(blob, bytes, 0, "message in " + best->path);
      } catch (const Error& e) {
        out->data.clear();  // the decoder counts it as a payload too short for
                            // its fields
        if (damaged_++ == 0) log::warn(e.what());
      }
    } else {
      out->data.assign(blob, blob + bytes);
    }
    step(*best);
    return true;
  }

 private:
  void openDatabase(const std::string& file) {
    std::string path = file;
    std::uint8_t head[4] = {};
    if (std::FILE* f = std::fopen(file.c_str(), "rb")) {
      const std::size_t got = std::fread(head, 1, 4, f);
      std::fclose(f);
      if (isZstdFrame(head, got)) {
        // One copy per open bag: `calibration: auto` and the run may hold the same bag open at once.
        static std::atomic<unsigned> copies{0};
        path = (fs::temp_directory_path() / ("mmlio-" + std::to_string(::getpid()) + "-" + std::to_string(copies++) +
                                             "-" + fs::path(file).stem().string()))
                   .string();
        temporaries_.push_back(path);
        log::info("decompressing ", file, " to ", path);
        zstdDecompressFile(file, path);
        ++compressed_files_;
      }
    } else {
      throw Error("cannot read " + file + " (permission denied?)");
    }
    auto d = std::make_unique<Database>();
    d->path = file;
    if (sqlite3_open_v2(path.c_str(), &d->db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
      throw Error("cannot open " + d->error());
    readTopics(*d);
    dbs_.push_back(std::move(d));
  }

  void readTopics(Database& d) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(d.db, "SELECT id, name, type FROM topics", -1, &s, nullptr) != SQLITE_OK)
      throw Error("cannot read " + d.error() + " (not a rosbag2 sqlite3 database?)");
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      const std::string name = reinterpret_cast<const char*>(sqlite3_column_text(s, 1));
      const std::string type = reinterpret_cast<const char*>(sqlite3_column_text(s, 2));
      auto it = std::find_if(topics_.begin(), topics_.end(), [&](const Ros2Topic& t) { return t.name == name; });
      if (it == topics_.end()) {
        topics_.push_back(Ros2Topic{name, type, 0, 0, 0});
        it = topics_.end() - 1;
      }
      d.topic_of_id[sqlite3_column_int64(s, 0)] = static_cast<std::size_t>(it - topics_.begin());
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) throw Error("cannot read the topics of " + d.error());
    if (sqlite3_prepare_v2(d.db,
                           "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id",
                           -1, &s, nullptr) != SQLITE_OK)
      throw Error("cannot read " + d.error() + " (not a rosbag2 sqlite3 database?)");
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      const auto t = d.topic_of_id.find(sqlite3_column_int64(s, 0));
      if (t == d.topic_of_id.end()) continue;
      Ros2Topic& topic = topics_[t->second];
      const Stamp first = sqlite3_column_int64(s, 2), last = sqlite3_column_int64(s, 3);
      topic.begin_ns = topic.messages == 0 ? first : std::min(topic.begin_ns, first);
      topic.end_ns = topic.messages == 0 ? last : std::max(topic.end_ns, last);
      topic.messages += static_cast<std::size_t>(sqlite3_column_int64(s, 1));
    }
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) damaged(d, d.error());
  }

  void step(Database& d) {
    const int rc = sqlite3_step(d.rows);
    d.has_row = rc == SQLITE_ROW;
    if (d.has_row) {
      d.row_time = sqlite3_column_int64(d.rows, 1);
      if (d.topic_of_id.count(sqlite3_column_int64(d.rows, 0))) return;
      d.has_row = false;
    }
    if (rc != SQLITE_DONE) damaged(d, d.error());
  }

  void damaged(Database& d, const std::string& why) {
    truncated_ = true;
    if (damaged_++ == 0) log::warn("stopped reading ", d.path, " early: ", why);
  }

  std::vector<std::unique_ptr<Database>> dbs_;
  std::vector<std::string> temporaries_;
  std::size_t compressed_files_ = 0;
};

}  // namespace

std::unique_ptr<Ros2Bag> openSqlite3(const std::vector<std::string>& files) {
  return std::make_unique<Sqlite3Bag>(files);
}

}  // namespace mmlio::io::detail
