// MCAP reader (https://mcap.dev/spec), written from the specification: the file is scanned once, front to back, so that
// a file without summary or index, or cut short, reads like a complete one. Messages are then streamed in log-time
// order from the chunks (none, zstd or lz4) and from messages written outside chunks.
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>

#include "decompress.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "ros2_bag.hpp"

namespace mmlio::io::detail {
namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Op : std::uint8_t {
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kDataEnd = 0x0F
};
constexpr std::size_t kRecordHeader = 9;    // opcode + uint64 length
constexpr std::size_t kMessageHeader = 22;  // channel id, sequence, log time, publish time

/// Little-endian fields of one record's content; every read is bounds-checked.
class Fields {
 public:
  Fields(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  template <class T> T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, p_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string string() {
    const auto len = get<std::uint32_t>();
    need(len);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), len);
    pos_ += len;
    return s;
  }
  /// uint64-length-prefixed bytes, returned in place.
  std::pair<const std::uint8_t*, std::size_t> bytes64() {
    const auto len = get<std::uint64_t>();
    need(len);
    const auto* at = p_ + pos_;
    pos_ += len;
    return {at, static_cast<std::size_t>(len)};
  }
  std::size_t pos() const { return pos_; }

 private:
  void need(std::uint64_t k) const {
    if (k > n_ - pos_) throw Error("MCAP record field runs past the record");
  }
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
};

/// Calls f(opcode, content, length) for each complete record of `data`; false when a record's length runs past the end
/// (damage).
template <class F> bool forEachRecord(const std::uint8_t* data, std::size_t size, F&& f) {
  std::size_t pos = 0;
  while (pos < size) {
    if (size - pos < kRecordHeader) return false;
    const std::uint8_t op = data[pos];
    std::uint64_t len;
    std::memcpy(&len, data + pos + 1, 8);
    if (len > size - pos - kRecordHeader) return false;
    f(op, data + pos + kRecordHeader, static_cast<std::size_t>(len));
    pos += kRecordHeader + len;
  }
  return true;
}

class McapBag final : public Ros2Bag {
 public:
  explicit McapBag(const std::string& path) : path_(path), file_(path, std::ios::binary) {
    if (!file_) throw Error("cannot read " + path + " (permission denied?)");
    file_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(file_.tellg());
    const bool indexed = openFromSummary();
    if (!indexed) scan();
    std::string comp;
    for (const auto& [c, n] : compressions_) comp += (comp.empty() ? "" : ", ") + std::to_string(n) + " " + c;
    format_ = "ROS 2 mcap (" + (comp.empty() ? std::string("no chunks") : comp + " chunks") +
              (indexed ? ", indexed" : ", scanned") + ")";
    std::vector<std::size_t> all(topics_.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    restart(all);
  }

  void restart(const std::vector<std::size_t>& topics) override {
    selected_.assign(topics_.size(), false);
    for (std::size_t t : topics) selected_.at(t) = true;
    next_unit_ = 0;
    pending_.clear();
    sequence_ = 0;
  }

  bool next(Ros2Message* out) override {
    while (true) {
      if (!pending_.empty() &&
          (next_unit_ == units_.size() || pending_.front().time_ns < units_[next_unit_].start_ns)) {
        std::pop_heap(pending_.begin(), pending_.end(), Later{});
        *out = std::move(pending_.back().message);
        pending_.pop_back();
        return true;
      }
      if (next_unit_ == units_.size()) return false;
      load(units_[next_unit_++]);
    }
  }

 private:
  /// A chunk, or one message written outside chunks: the units messages are loaded in.
  struct Unit {
    std::uint64_t offset = 0,
                  size = 0;  // chunk: its compressed records; message: its whole content
    Stamp start_ns = 0;      // earliest log time inside
    bool chunk = false;
    std::string compression;
    std::uint64_t uncompressed_size = 0;
    std::uint32_t crc = 0;
    std::uint64_t topics = 0;  // bit i: topic i (< 64) has messages inside; all bits for more topics
  };
  struct Pending {
    Stamp time_ns;
    std::size_t order;  // load order: ties keep file order
    Ros2Message message;
  };
  struct Later {
    bool operator()(const Pending& a, const Pending& b) const {
      return a.time_ns != b.time_ns ? a.time_ns > b.time_ns : a.order > b.order;
    }
  };

  std::vector<std::uint8_t> readAt(std::uint64_t offset, std::uint64_t size) {
    std::vector<std::uint8_t> buf(size);
    file_.clear();
    file_.seekg(static_cast<std::streamoff>(offset));
    file_.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(size));
    if (static_cast<std::uint64_t>(file_.gcount()) != size)
      throw Error("cannot read " + path_ + " at byte " + std::to_string(offset));
    return buf;
  }

  /// A complete file with a summary (schemas, channels, statistics, chunk indexes) and message
  /// indexes: topics, counts and chunks from those, without decompressing a chunk. False (nothing
  /// kept) when any of it is missing or does not add up; the file is then scanned.
  bool openFromSummary() {
    try {
      constexpr std::uint64_t kFooterRecord = kRecordHeader + 20;
      if (size_ < 8 + kFooterRecord + 8 || std::memcmp(readAt(size_ - 8, 8).data(), kMagic, 8) != 0) return false;
      const auto footer = readAt(size_ - 8 - kFooterRecord, kFooterRecord);
      if (footer[0] != kFooter) return false;
      Fields ff(footer.data() + kRecordHeader, 20);
      const auto summary_start = ff.get<std::uint64_t>();
      if (summary_start < 8 || summary_start >= size_ - 8 - kFooterRecord) return false;
      const auto summary = readAt(summary_start, size_ - 8 - kFooterRecord - summary_start);
      struct ChunkIndex {
        Stamp start_ns;
        std::uint64_t offset, length;
        std::vector<std::pair<std::uint16_t, std::uint64_t>> message_indexes;  // channel, offset
      };
      std::vector<ChunkIndex> chunks;
      std::uint64_t message_count = 0;
      bool have_statistics = false;
      const bool intact =
          forEachRecord(summary.data(), summary.size(), [&](std::uint8_t op, const std::uint8_t* p, std::size_t n) {
            if (op == kSchema || op == kChannel) {
              definition(op, p, n);
            } else if (op == kStatistics) {
              message_count = Fields(p, n).get<std::uint64_t>();
              have_statistics = true;
            } else if (op == kChunkIndex) {
              Fields f(p, n);
              ChunkIndex c;
              c.start_ns = static_cast<Stamp>(f.get<std::uint64_t>());
              f.get<std::uint64_t>();
              c.offset = f.get<std::uint64_t>();
              c.length = f.get<std::uint64_t>();
              const auto map_bytes = f.get<std::uint32_t>();
              for (std::uint32_t k = 0; k + 10 <= map_bytes; k += 10) {
                const auto channel = f.get<std::uint16_t>();
                c.message_indexes.emplace_back(channel, f.get<std::uint64_t>());
              }
              chunks.push_back(std::move(c));
            }
          });
      if (!intact || !have_statistics || chunks.empty()) return forgetSummary();
      std::uint64_t indexed_messages = 0;
      for (const ChunkIndex& c : chunks) {
        Unit u;
        u.chunk = true;
        u.start_ns = c.start_ns;
        if (c.length < kRecordHeader || c.offset + c.length > summary_start) return forgetSummary();
        chunkHeader(c.offset + kRecordHeader, c.length - kRecordHeader, &u);
        for (const auto& [channel, offset] : c.message_indexes) {
          const auto t = channel_topic_.find(channel);
          if (t == channel_topic_.end()) return forgetSummary();
          indexed_messages += messageIndex(offset, t->second);
          u.topics |= t->second < 64 ? std::uint64_t{1} << t->second : ~std::uint64_t{0};
        }
        ++compressions_[u.compression.empty() ? "uncompressed" : u.compression];
        if (u.topics) units_.push_back(u);
      }
      if (indexed_messages != message_count) return forgetSummary();
      std::stable_sort(units_.begin(), units_.end(),
                       [](const Unit& a, const Unit& b) { return a.start_ns < b.start_ns; });
      return true;
    } catch (const Error&) {
      return forgetSummary();
    }
  }

  bool forgetSummary() {
    schemas_.clear();
    channel_topic_.clear();
    compressions_.clear();
    topics_.clear();
    units_.clear();
    return false;
  }

  /// The fields of a Chunk record before its records; u gets where they are and how to read them.
  void chunkHeader(std::uint64_t content, std::uint64_t len, Unit* u) {
    const auto head = readAt(content, std::min<std::uint64_t>(len, 28 + 4));
    Fields f(head.data(), head.size());
    f.get<std::uint64_t>();
    f.get<std::uint64_t>();
    u->uncompressed_size = f.get<std::uint64_t>();
    u->crc = f.get<std::uint32_t>();
    const std::uint64_t name_len = f.get<std::uint32_t>();
    if (32 + name_len + 8 > len) throw Error("chunk header runs past the chunk");
    const auto rest = readAt(content + 32, name_len + 8);
    u->compression.assign(reinterpret_cast<const char*>(rest.data()), name_len);
    std::uint64_t records = 0;
    std::memcpy(&records, rest.data() + name_len, 8);
    u->offset = content + 32 + name_len + 8;
    u->size = records;
    if (records > len - 32 - name_len - 8) throw Error("chunk records run past the chunk");
  }

  /// Counts the messages a MessageIndex record lists for `topic`; returns how many.
  std::uint64_t messageIndex(std::uint64_t offset, std::size_t topic) {
    if (offset + kRecordHeader > size_) throw Error("message index past the end");
    const auto head = readAt(offset, kRecordHeader);
    std::uint64_t len = 0;
    std::memcpy(&len, head.data() + 1, 8);
    if (head[0] != kMessageIndex || len > size_ - offset - kRecordHeader) throw Error("not a message index");
    const auto rec = readAt(offset + kRecordHeader, len);
    Fields f(rec.data(), rec.size());
    f.get<std::uint16_t>();
    const auto bytes = f.get<std::uint32_t>();
    Ros2Topic& t = topics_[topic];
    std::uint64_t n = 0;
    for (std::uint32_t k = 0; k + 16 <= bytes; k += 16, ++n) {
      const auto log_time = static_cast<Stamp>(f.get<std::uint64_t>());
      f.get<std::uint64_t>();
      if (t.messages++ == 0) t.begin_ns = t.end_ns = log_time;
      t.begin_ns = std::min(t.begin_ns, log_time);
      t.end_ns = std::max(t.end_ns, log_time);
    }
    return n;
  }

  void scan() {
    if (size_ < 8 || std::memcmp(readAt(0, 8).data(), kMagic, 8) != 0)
      throw Error(path_ + " is not an MCAP file (bad magic bytes)");
    std::uint64_t pos = 8;
    while (true) {
      if (size_ - pos < kRecordHeader) {
        truncated_ = pos < size_ || !saw_end_;
        break;
      }
      const auto head = readAt(pos, kRecordHeader);
      std::uint64_t len;
      std::memcpy(&len, head.data() + 1, 8);
      if (len > size_ - pos - kRecordHeader) {
        truncated_ = true;
        break;
      }
      const std::uint64_t content = pos + kRecordHeader;
      const std::uint8_t op = head[0];
      if (op == kDataEnd || op == kFooter) {
        saw_end_ = true;
        break;
      }
      if (op == kSchema || op == kChannel) {
        const auto rec = readAt(content, len);
        definition(op, rec.data(), rec.size());
      } else if (op == kMessage && len >= kMessageHeader) {
        const auto rec = readAt(content, kMessageHeader);
        Unit u;
        u.offset = content;
        u.size = len;
        u.start_ns = message(rec.data(), len, &u.topics);
        if (u.topics) units_.push_back(u);
      } else if (op == kChunk) {
        scanChunk(content, len);
      }
      pos = content + len;
    }
    std::stable_sort(units_.begin(), units_.end(),
                     [](const Unit& a, const Unit& b) { return a.start_ns < b.start_ns; });
    if (truncated_) {
      log::warn(path_, " ends inside a record (recording cut short?): reading it up to its last complete ",
                units_.empty() ? "record" : "chunk or message");
    }
  }

  void scanChunk(std::uint64_t content, std::uint64_t len) {
    Unit u;
    u.chunk = true;
    try {
      chunkHeader(content, len, &u);
      const auto records = readAt(u.offset, u.size);
      const auto data = decompress(u, records.data(), records.size());
      Stamp start = std::numeric_limits<Stamp>::max();
      const bool intact =
          forEachRecord(data.data(), data.size(), [&](std::uint8_t op, const std::uint8_t* p, std::size_t n) {
            if (op == kSchema || op == kChannel)
              definition(op, p, n);
            else if (op == kMessage && n >= kMessageHeader)
              start = std::min(start, message(p, n, &u.topics));
          });
      if (!intact) throw Error("a record runs past the chunk's end");
      u.start_ns = start;
      ++compressions_[u.compression.empty() ? "uncompressed" : u.compression];
      if (u.topics) units_.push_back(u);
    } catch (const Error& e) {
      if (damaged_++ == 0) log::warn("skipping a damaged chunk of ", path_, " at byte ", content, ": ", e.what());
    }
  }

  std::vector<std::uint8_t> decompress(const Unit& u, const std::uint8_t* p, std::size_t n) const {
    const std::string what = "MCAP chunk of " + path_;
    std::vector<std::uint8_t> out;
    if (u.compression.empty())
      out.assign(p, p + n);
    else if (u.compression == "zstd")
      out = zstdDecompress(p, n, u.uncompressed_size, what);
    else if (u.compression == "lz4")
      out = lz4FrameDecompress(p, n, u.uncompressed_size, what);
    else
      throw Error(what + ": unsupported compression '" + u.compression + "' (none, zstd and lz4 are read)");
    if (out.size() != u.uncompressed_size)
      throw Error("chunk decompresses to " + std::to_string(out.size()) + " bytes, not " +
                  std::to_string(u.uncompressed_size));
    if (u.crc != 0 && crc32(0L, out.data(), static_cast<uInt>(out.size())) != u.crc) throw Error("chunk CRC mismatch");
    return out;
  }

  /// Schema or Channel record.
  void definition(std::uint8_t op, const std::uint8_t* p, std::size_t n) {
    Fields f(p, n);
    if (op == kSchema) {
      const auto id = f.get<std::uint16_t>();
      schemas_[id] = f.string();
      return;
    }
    const auto id = f.get<std::uint16_t>();
    const auto schema = f.get<std::uint16_t>();
    const std::string topic = f.string();
    const std::string encoding = f.string();
    if (channel_topic_.count(id)) return;
    std::string type = schemas_.count(schema) ? schemas_[schema] : "(no schema)";
    if (encoding != "cdr") type += " (" + encoding + " encoded)";
    auto it = std::find_if(topics_.begin(), topics_.end(), [&](const Ros2Topic& t) { return t.name == topic; });
    if (it == topics_.end()) {
      Ros2Topic t;
      t.name = topic;
      t.type = type;
      topics_.push_back(t);
      it = topics_.end() - 1;
    }
    channel_topic_[id] = static_cast<std::size_t>(it - topics_.begin());
  }

  /// Counts a Message record for its topic; returns its log time.
  Stamp message(const std::uint8_t* p, std::size_t n, std::uint64_t* topic_bits) {
    Fields f(p, n);
    const auto channel = f.get<std::uint16_t>();
    f.get<std::uint32_t>();
    const auto log_time = static_cast<Stamp>(f.get<std::uint64_t>());
    const auto c = channel_topic_.find(channel);
    if (c == channel_topic_.end()) return log_time;  // channel never declared: not readable
    Ros2Topic& t = topics_[c->second];
    if (t.messages++ == 0) t.begin_ns = t.end_ns = log_time;
    t.begin_ns = std::min(t.begin_ns, log_time);
    t.end_ns = std::max(t.end_ns, log_time);
    *topic_bits |= c->second < 64 ? std::uint64_t{1} << c->second : ~std::uint64_t{0};
    return log_time;
  }

  bool wanted(const Unit& u) const {
    for (std::size_t t = 0; t < selected_.size(); ++t)
      if (selected_[t] && (t >= 64 || (u.topics >> t) & 1)) return true;
    return false;
  }

  void push(const std::uint8_t* p, std::size_t n) {
    Fields f(p, n);
    const auto channel = f.get<std::uint16_t>();
    f.get<std::uint32_t>();
    const auto log_time = static_cast<Stamp>(f.get<std::uint64_t>());
    const auto c = channel_topic_.find(channel);
    if (c == channel_topic_.end() || !selected_[c->second]) return;
    Pending m{log_time, sequence_++, {}};
    m.message.topic = c->second;
    m.message.time_ns = log_time;
    m.message.data.assign(p + kMessageHeader, p + n);
    pending_.push_back(std::move(m));
    std::push_heap(pending_.begin(), pending_.end(), Later{});
  }

  void load(const Unit& u) {
    if (!wanted(u)) return;
    try {
      const auto raw = readAt(u.offset, u.size);
      if (!u.chunk) return push(raw.data(), raw.size());
      const auto data = decompress(u, raw.data(), raw.size());
      forEachRecord(data.data(), data.size(), [&](std::uint8_t op, const std::uint8_t* p, std::size_t n) {
        if (op == kMessage && n >= kMessageHeader) push(p, n);
      });
    } catch (const Error& e) {
      if (damaged_++ == 0) log::warn("skipping a damaged chunk of ", path_, ": ", e.what());
    }
  }

  std::string path_;
  std::ifstream file_;
  std::uint64_t size_ = 0;
  bool saw_end_ = false;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, std::size_t> channel_topic_;
  std::map<std::string, std::size_t> compressions_;
  std::vector<Unit> units_;
  std::vector<bool> selected_;
  std::size_t next_unit_ = 0, sequence_ = 0;
  std::vector<Pending> pending_;  // heap, earliest first
};

}  // namespace

std::unique_ptr<Ros2Bag> openMcap(const std::string& path) { return std::make_unique<McapBag>(path); }

}  // namespace mmlio::io::detail
