#pragma once
// Test helper: writes the ROS 2 twin of a ROS 1 bag — the same messages, CDR-encoded as the ROS 2 drivers publish them,
// in an .mcap file or a rosbag2 sqlite3 folder — so that tests can check that both read the same. Its CDR encoder, MCAP
// and rosbag2 writers are written here from the formats' specifications, independently of the reader in src/io (which
// decodes through Fast CDR).
#include <lz4frame.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <sqlite3.h>
#include <zlib.h>
#include <zstd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "mmlio/io/livox_msg.hpp"

namespace mmlio::testing {

/// Little-endian CDR with the 4-byte encapsulation header; alignment counted after the header.
class CdrWriter {
 public:
  CdrWriter() : b_{0x00, 0x01, 0x00, 0x00} {}
  template <class T> void put(T v) {
    while ((b_.size() - 4) % sizeof(T) != 0) b_.push_back(0);
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b_.insert(b_.end(), p, p + sizeof(T));
  }
  void string(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    b_.insert(b_.end(), s.begin(), s.end());
    b_.push_back(0);
  }
  void header(const std_msgs::Header& h) {
    put<std::int32_t>(static_cast<std::int32_t>(h.stamp.sec));
    put<std::uint32_t>(h.stamp.nsec);
    string(h.frame_id);
  }
  std::vector<std::uint8_t> take() { return std::move(b_); }

 private:
  std::vector<std::uint8_t> b_;
};

inline std::vector<std::uint8_t> encodeCdr(const sensor_msgs::Imu& m) {
  CdrWriter w;
  w.header(m.header);
  for (double v : {m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w}) w.put(v);
  for (double v : m.orientation_covariance) w.put(v);
  for (double v : {m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z}) w.put(v);
  for (double v : m.angular_velocity_covariance) w.put(v);
  for (double v : {m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z}) w.put(v);
  for (double v : m.linear_acceleration_covariance) w.put(v);
  return w.take();
}

inline std::vector<std::uint8_t> encodeCdr(const sensor_msgs::PointCloud2& m) {
  CdrWriter w;
  w.header(m.header);
  w.put(m.height);
  w.put(m.width);
  w.put(static_cast<std::uint32_t>(m.fields.size()));
  for (const auto& f : m.fields) {
    w.string(f.name);
    w.put(f.offset);
    w.put(f.datatype);
    w.put(f.count);
  }
  w.put(m.is_bigendian);
  w.put(m.point_step);
  w.put(m.row_step);
  w.put(static_cast<std::uint32_t>(m.data.size()));
  for (std::uint8_t v : m.data) w.put(v);
  w.put(m.is_dense);
  return w.take();
}

inline std::vector<std::uint8_t> encodeCdr(const io::LivoxCustomMsg& m) {
  CdrWriter w;
  w.header(m.header);
  w.put(m.timebase);
  w.put(m.point_num);
  w.put(m.lidar_id);
  for (std::uint8_t v : m.rsvd) w.put(v);
  w.put(static_cast<std::uint32_t>(m.points.size()));
  for (const auto& p : m.points) {
    w.put(p.offset_time);
    w.put(p.x);
    w.put(p.y);
    w.put(p.z);
    w.put(p.reflectivity);
    w.put(p.tag);
    w.put(p.line);
  }
  return w.take();
}

struct Ros2Record {
  std::string topic, type;  // ROS 2 type name
  std::uint64_t time_ns = 0;
  std::vector<std::uint8_t> cdr;
};

/// Every message of a ROS 1 bag (Imu, PointCloud2, Livox CustomMsg) in bag order, CDR-encoded.
inline std::vector<Ros2Record> ros2Records(const std::string& ros1_bag, const std::string& livox_type) {
  rosbag::Bag bag(ros1_bag, rosbag::bagmode::Read);
  std::vector<Ros2Record> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    Ros2Record r;
    r.topic = m.getTopic();
    r.time_ns = m.getTime().toNSec();
    if (const auto imu = m.instantiate<sensor_msgs::Imu>()) {
      r.type = "sensor_msgs/msg/Imu";
      r.cdr = encodeCdr(*imu);
    } else if (const auto cloud = m.instantiate<sensor_msgs::PointCloud2>()) {
      r.type = "sensor_msgs/msg/PointCloud2";
      r.cdr = encodeCdr(*cloud);
    } else if (const auto livox = m.instantiate<io::LivoxCustomMsg>()) {
      r.type = livox_type;
      r.cdr = encodeCdr(*livox);
    } else {
      continue;
    }
    out.push_back(std::move(r));
  }
  return out;
}

// ---- MCAP
// -----------------------------------------------------------------------------------

struct McapOptions {
  bool chunked = true;
  std::string compression;  // "", "zstd", "lz4"
  std::size_t chunk_bytes = 1 << 20;
  bool summary = true;  // summary section with schemas, channels and statistics
};

class McapBytes {
 public:
  template <class T> void put(T v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
  }
  void string(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  }
  void record(std::uint8_t op, const McapBytes& content) {
    put(op);
    put<std::uint64_t>(content.b.size());
    b.insert(b.end(), content.b.begin(), content.b.end());
  }
  std::vector<std::uint8_t> b;
};

inline std::vector<std::uint8_t> compress(const std::vector<std::uint8_t>& in, const std::string& how) {
  std::vector<std::uint8_t> out;
  if (how == "zstd") {
    out.resize(ZSTD_compressBound(in.size()));
    out.resize(ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3));
  } else if (how == "lz4") {
    out.resize(LZ4F_compressFrameBound(in.size(), nullptr));
    out.resize(LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr));
  } else {
    out = in;
  }
  return out;
}

inline void writeMcap(const std::vector<Ros2Record>& records, const std::string& path, const McapOptions& o) {
  McapBytes file;
  const std::uint8_t magic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
  file.b.assign(magic, magic + 8);
  McapBytes header;
  header.string("ros2");
  header.string("mmlio test writer");
  file.record(0x01, header);

  std::map<std::string, std::uint16_t> schema_of_type, channel_of_topic;
  std::vector<McapBytes> definitions;  // for the summary
  std::map<std::uint16_t, std::uint64_t> counts;
  McapBytes chunk;
  std::uint64_t chunk_start = 0, chunk_end = 0, first = ~0ull, last = 0;
  std::size_t chunks = 0;
  auto out = [&]() -> McapBytes& { return o.chunked ? chunk : file; };
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index;  // channel: time, offset
  std::vector<McapBytes> chunk_indexes;                                                       // for the summary
  auto flush = [&] {
    if (!o.chunked || chunk.b.empty()) return;
    McapBytes c;
    c.put(chunk_start);
    c.put(chunk_end);
    c.put<std::uint64_t>(chunk.b.size());
    c.put<std::uint32_t>(static_cast<std::uint32_t>(crc32(0L, chunk.b.data(), static_cast<uInt>(chunk.b.size()))));
    c.string(o.compression);
    const auto data = compress(chunk.b, o.compression);
    c.put<std::uint64_t>(data.size());
    c.b.insert(c.b.end(), data.begin(), data.end());
    const std::uint64_t chunk_offset = file.b.size();
    file.record(0x06, c);
    const std::uint64_t chunk_length = file.b.size() - chunk_offset;
    // Message indexes after the chunk, one per channel, and the chunk's index for the summary.
    McapBytes offsets;
    const std::uint64_t indexes_start = file.b.size();
    for (const auto& [channel, entries] : chunk_index) {
      offsets.put(channel);
      offsets.put<std::uint64_t>(file.b.size());
      McapBytes mi;
      mi.put(channel);
      mi.put<std::uint32_t>(static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [t, at] : entries) {
        mi.put(t);
        mi.put(at);
      }
      file.record(0x07, mi);
    }
    McapBytes ci;
    ci.put(chunk_start);
    ci.put(chunk_end);
    ci.put(chunk_offset);
    ci.put(chunk_length);
    ci.put<std::uint32_t>(static_cast<std::uint32_t>(offsets.b.size()));
    ci.b.insert(ci.b.end(), offsets.b.begin(), offsets.b.end());
    ci.put<std::uint64_t>(file.b.size() - indexes_start);
    ci.string(o.compression);
    ci.put<std::uint64_t>(data.size());
    ci.put<std::uint64_t>(chunk.b.size());
    chunk_indexes.emplace_back().record(0x08, ci);
    chunk_index.clear();
    chunk.b.clear();
    ++chunks;
  };
  for (const Ros2Record& r : records) {
    if (!schema_of_type.count(r.type)) {
      const auto id = static_cast<std::uint16_t>(schema_of_type.size() + 1);
      schema_of_type[r.type] = id;
      McapBytes s;
      s.put(id);
      s.string(r.type);
      s.string("ros2msg");
      s.string("");
      out().record(0x03, s);
      definitions.emplace_back().record(0x03, s);
    }
    if (!channel_of_topic.count(r.topic)) {
      const auto id = static_cast<std::uint16_t>(channel_of_topic.size());
      channel_of_topic[r.topic] = id;
      McapBytes c;
      c.put(id);
      c.put(schema_of_type[r.type]);
      c.string(r.topic);
      c.string("cdr");
      c.put<std::uint32_t>(0);  // empty metadata map
      out().record(0x04, c);
      definitions.emplace_back().record(0x04, c);
    }
    if (chunk.b.empty()) chunk_start = r.time_ns;
    chunk_end = r.time_ns;
    first = std::min(first, r.time_ns);
    last = std::max(last, r.time_ns);
    const std::uint16_t channel = channel_of_topic[r.topic];
    McapBytes m;
    m.put(channel);
    m.put<std::uint32_t>(static_cast<std::uint32_t>(counts[channel]++));
    m.put(r.time_ns);
    m.put(r.time_ns);
    m.b.insert(m.b.end(), r.cdr.begin(), r.cdr.end());
    if (o.chunked) chunk_index[channel].emplace_back(r.time_ns, chunk.b.size());
    out().record(0x05, m);
    if (chunk.b.size() >= o.chunk_bytes) flush();
  }
  flush();
  McapBytes data_end;
  data_end.put<std::uint32_t>(0);
  file.record(0x0F, data_end);
  std::uint64_t summary_start = 0;
  if (o.summary) {
    summary_start = file.b.size();
    for (const McapBytes& d : definitions) file.b.insert(file.b.end(), d.b.begin(), d.b.end());
    for (const McapBytes& d : chunk_indexes) file.b.insert(file.b.end(), d.b.begin(), d.b.end());
    McapBytes stats;
    stats.put<std::uint64_t>(records.size());
    stats.put<std::uint16_t>(static_cast<std::uint16_t>(schema_of_type.size()));
    stats.put<std::uint32_t>(static_cast<std::uint32_t>(channel_of_topic.size()));
    stats.put<std::uint32_t>(0);  // attachments
    stats.put<std::uint32_t>(0);  // metadata
    stats.put<std::uint32_t>(static_cast<std::uint32_t>(chunks));
    stats.put(first);
    stats.put(last);
    stats.put<std::uint32_t>(static_cast<std::uint32_t>(counts.size() * 10));
    for (const auto& [c, n] : counts) {
      stats.put(c);
      stats.put(n);
    }
    file.record(0x0B, stats);
  }
  McapBytes footer;
  footer.put(summary_start);
  footer.put<std::uint64_t>(0);
  footer.put<std::uint32_t>(0);
  file.record(0x02, footer);
  file.b.insert(file.b.end(), magic, magic + 8);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(file.b.data()), static_cast<std::streamsize>(file.b.size()));
  if (!f) throw std::runtime_error("cannot write " + path);
}

/// A rosbag2 folder with storage mcap, split into `files` .mcap files by message count.
inline void writeSplitMcap(const std::vector<Ros2Record>& records, const std::string& dir, int files) {
  namespace fs = std::filesystem;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream meta(fs::path(dir) / "metadata.yaml");
  meta << "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n  relative_file_paths:\n";
  const std::size_t per = (records.size() + static_cast<std::size_t>(files) - 1) / static_cast<std::size_t>(files);
  for (int f = 0; f < files; ++f) {
    const std::string name = "part_" + std::to_string(f) + ".mcap";
    const auto first = records.begin() + static_cast<long>(std::min(records.size(), f * per));
    const auto last = records.begin() + static_cast<long>(std::min(records.size(), (f + 1) * per));
    writeMcap({first, last}, (fs::path(dir) / name).string(), {true, "zstd", 1 << 20, true});
    meta << "    - " << name << "\n";
  }
}

// ---- rosbag2 sqlite3
// ------------------------------------------------------------------------

struct Db3Options {
  std::string compression;  // "" | "file" | "message": zstd as rosbag2 writes it
  int files = 1;            // split into this many .db3 files by message count
  bool metadata = true;     // write metadata.yaml
};

inline void exec(sqlite3* db, const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string why = err ? err : "?";
    sqlite3_free(err);
    throw std::runtime_error("sqlite: " + why + " in " + sql);
  }
}

inline void compressFileZstd(const std::string& from, const std::string& to) {
  std::ifstream in(from, std::ios::binary);
  const std::vector<std::uint8_t> raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto data = compress(raw, "zstd");
  std::ofstream(to, std::ios::binary)
      .write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
}

inline void writeRosbag2(const std::vector<Ros2Record>& records, const std::string& dir, const Db3Options& o) {
  namespace fs = std::filesystem;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<std::string> names;
  std::map<std::string, std::size_t> per_topic;
  std::map<std::string, std::string> type_of;
  const std::size_t per_file =
      (records.size() + static_cast<std::size_t>(o.files) - 1) / static_cast<std::size_t>(o.files);
  for (int f = 0; f < o.files; ++f) {
    const std::string name = fs::path(dir).filename().string() + "_" + std::to_string(f) + ".db3";
    const std::string path = (fs::path(dir) / name).string();
    sqlite3* db = nullptr;
    sqlite3_open(path.c_str(), &db);
    exec(db,
         "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format "
         "TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)");
    exec(db,
         "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data "
         "BLOB NOT NULL)");
    exec(db, "CREATE INDEX timestamp_idx ON messages (timestamp ASC)");
    exec(db, "BEGIN");
    std::map<std::string, std::int64_t> ids;
    sqlite3_stmt* ins = nullptr;
    sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)", -1, &ins, nullptr);
    for (std::size_t i = f * per_file; i < std::min(records.size(), (f + 1) * per_file); ++i) {
      const Ros2Record& r = records[i];
      if (!ids.count(r.topic)) {
        // Reversed ids per file: the reader must match topics by name, not by id.
        const std::int64_t id = 100 - static_cast<std::int64_t>(ids.size()) - f;
        ids[r.topic] = id;
        exec(db,
             "INSERT INTO topics VALUES(" + std::to_string(id) + ", '" + r.topic + "', '" + r.type + "', 'cdr', '')");
      }
      ++per_topic[r.topic];
      type_of[r.topic] = r.type;
      const auto blob = o.compression == "message" ? compress(r.cdr, "zstd") : r.cdr;
      sqlite3_bind_int64(ins, 1, ids[r.topic]);
      sqlite3_bind_int64(ins, 2, static_cast<std::int64_t>(r.time_ns));
      sqlite3_bind_blob(ins, 3, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
      if (sqlite3_step(ins) != SQLITE_DONE) throw std::runtime_error("sqlite insert failed");
      sqlite3_reset(ins);
    }
    sqlite3_finalize(ins);
    exec(db, "COMMIT");
    sqlite3_close(db);
    if (o.compression == "file") {
      compressFileZstd(path, path + ".zstd");
      fs::remove(path);
      names.push_back(name + ".zstd");
    } else {
      names.push_back(name);
    }
  }
  if (!o.metadata) return;
  std::ofstream meta(fs::path(dir) / "metadata.yaml");
  meta << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
       << "  duration:\n    nanoseconds: " << (records.back().time_ns - records.front().time_ns) << "\n"
       << "  starting_time:\n    nanoseconds_since_epoch: " << records.front().time_ns << "\n"
       << "  message_count: " << records.size() << "\n  topics_with_message_count:\n";
  for (const auto& [t, n] : per_topic) {
    meta << "    - topic_metadata:\n        name: " << t << "\n        type: " << type_of[t]
         << "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: " << n
         << "\n";
  }
  meta << "  compression_format: \"" << (o.compression.empty() ? "" : "zstd") << "\"\n"
       << "  compression_mode: \""
       << (o.compression == "file"      ? "FILE"
           : o.compression == "message" ? "MESSAGE"
                                        : "")
       << "\"\n  relative_file_paths:\n";
  for (const std::string& n : names) meta << "    - " << n << "\n";
}

}  // namespace mmlio::testing
