#include "raw_bag_scanner.hpp"

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>

#include "mmlio/core/error.hpp"

namespace mmlio::io::detail {
namespace {

constexpr std::uint8_t kOpMessage = 0x02, kOpChunk = 0x05, kOpConnection = 0x07;

using Fields = std::map<std::string, std::string>;

std::uint32_t u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

/// name=value fields of a record header (or of a connection header).
bool parseFields(const std::uint8_t* p, std::size_t n, Fields* out) {
  std::size_t i = 0;
  while (i + 4 <= n) {
    const std::uint32_t len = u32(p + i);
    i += 4;
    if (len > n - i) return false;
    const std::string f(reinterpret_cast<const char*>(p + i), len);
    i += len;
    const std::size_t eq = f.find('=');
    if (eq == std::string::npos) return false;
    (*out)[f.substr(0, eq)] = f.substr(eq + 1);
  }
  return i == n;
}

std::uint8_t op(const Fields& f) {
  const auto it = f.find("op");
  return it == f.end() || it->second.empty() ? 0 : static_cast<std::uint8_t>(it->second[0]);
}

std::uint32_t fieldU32(const Fields& f, const char* name) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.size() < 4) return 0;
  return u32(reinterpret_cast<const std::uint8_t*>(it->second.data()));
}

Stamp fieldTime(const Fields& f) {
  const auto it = f.find("time");
  if (it == f.end() || it->second.size() < 8) return 0;
  const auto* p = reinterpret_cast<const std::uint8_t*>(it->second.data());
  return static_cast<Stamp>(u32(p)) * 1'000'000'000LL + static_cast<Stamp>(u32(p + 4));
}

/// Calls f(offset, fields, data_offset, data_len) for each intact record of a chunk payload of n
/// bytes, in order, until the first damaged one (lengths running past the payload, unparsable
/// header). read(offset, len, dst) copies payload bytes; only the records' headers are read.
template <class Read, class F> void walkRecords(std::size_t n, Read read, F f) {
  std::vector<std::uint8_t> header;
  std::uint8_t len4[4];
  for (std::size_t i = 0; i + 4 <= n;) {
    if (!read(i, 4, len4)) return;
    const std::uint32_t hl = u32(len4);
    if (hl > n - i - 4) return;
    header.resize(hl);
    Fields fields;
    if (!read(i + 4, hl, header.data()) || !parseFields(header.data(), hl, &fields)) return;
    const std::size_t dpos = i + 4 + hl + 4;
    if (dpos > n || !read(i + 4 + hl, 4, len4)) return;
    const std::uint32_t dl = u32(len4);
    if (dl > n - dpos) return;
    f(i, fields, dpos, dl);
    i = dpos + dl;
  }
}

/// walkRecords' reader of a payload in memory.
auto payloadReader(const std::vector<std::uint8_t>& payload) {
  return [p = payload.data()](std::size_t offset, std::size_t len, std::uint8_t* dst) {
    std::memcpy(dst, p + offset, len);
    return true;
  };
}

/// walkRecords over a payload in memory; f gets a pointer to each record's data.
template <class F> void forEachRecord(const std::vector<std::uint8_t>& payload, F f) {
  walkRecords(payload.size(), payloadReader(payload),
              [&](std::size_t i, const Fields& fields, std::size_t dpos, std::uint32_t dl) {
                f(i, fields, payload.data() + dpos, dl);
              });
}

}  // namespace

namespace {

/// A record at `pos`: its header fields and where its data lies. False when what is there is not
/// a well-formed record header (damage) or runs past the end of the file.
struct Record {
  Fields fields;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
};
bool readRecord(std::ifstream& in, std::uint64_t pos, std::uint64_t file_size, Record* r) {
  if (pos + 4 > file_size) return false;
  std::uint8_t len4[4];
  in.clear();
  in.seekg(static_cast<std::streamoff>(pos));
  if (!in.read(reinterpret_cast<char*>(len4), 4)) return false;
  const std::uint32_t header_len = u32(len4);
  if (header_len < 4 || header_len > std::min<std::uint64_t>(1u << 20, file_size - pos - 4)) return false;
  std::vector<std::uint8_t> header(header_len);
  if (!in.read(reinterpret_cast<char*>(header.data()), header_len)) return false;
  r->fields.clear();
  if (!parseFields(header.data(), header.size(), &r->fields) || op(r->fields) == 0) return false;
  r->data_pos = pos + 4 + header_len + 4;
  if (r->data_pos > file_size || !in.read(reinterpret_cast<char*>(len4), 4)) return false;
  r->data_len = u32(len4);
  return true;
}

bool plausibleChunk(const Record& r) {
  const auto c = r.fields.find("compression");
  const std::string compression = c == r.fields.end() ? "none" : c->second;
  return op(r.fields) == kOpChunk && (compression == "none" || compression == "lz4" || compression == "bz2") &&
         fieldU32(r.fields, "size") > 0;
}

/// The next chunk record after damage at `from`: rosbag writes a chunk header's fields sorted, so
/// its "op" field (length 4, "op=\x05") lies within the first few dozen bytes; candidates are
/// checked as whole records. file_size if none.
std::uint64_t nextChunkAfter(std::ifstream& in, std::uint64_t from, std::uint64_t file_size) {
  static const std::uint8_t kOpField[] = {4, 0, 0, 0, 'o', 'p', '=', kOpChunk};
  constexpr std::size_t kBlock = 1 << 20;
  std::vector<std::uint8_t> buf;
  for (std::uint64_t base = from; base < file_size; base += kBlock) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(kBlock + 64, file_size - base));
    buf.resize(n);
    in.clear();
    in.seekg(static_cast<std::streamoff>(base));
    if (!in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n))) return file_size;
    for (auto it = std::search(buf.begin(), buf.end(), std::begin(kOpField), std::end(kOpField)); it != buf.end();
         it = std::search(it + 1, buf.end(), std::begin(kOpField), std::end(kOpField))) {
      const std::uint64_t field = base + static_cast<std::uint64_t>(it - buf.begin());
      for (std::uint64_t back = 4; back <= 64 && back <= field - from; ++back) {
        Record r;
        if (readRecord(in, field - back, file_size, &r) && plausibleChunk(r)) return field - back;
      }
    }
  }
  return file_size;
}

}  // namespace

bool indexLooksSound(const std::string& path, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return true;  // the indexed open reports it
  in.seekg(0, std::ios::end);
  const std::uint64_t file_size = static_cast<std::uint64_t>(in.tellg());
  constexpr std::uint8_t kOpIndexData = 0x04, kOpChunkInfo = 0x06;
  std::set<std::uint64_t> chunk_positions;
  std::set<std::uint32_t> record_starts;  // of the chunk the index records follow
  std::uint32_t chunk_size = 0;
  const auto fail = [&](const std::string& what) {
    *why = what;
    return false;
  };
  for (std::uint64_t pos = 13; pos + 4 <= file_size;) {
    Record r;
    if (!readRecord(in, pos, file_size, &r)) return true;  // damage here is the readers' business
    if (r.data_pos + r.data_len > file_size) return true;
    const std::uint8_t kind = op(r.fields);
    if (kind == kOpChunk) {
      chunk_positions.insert(pos);
      chunk_size = fieldU32(r.fields, "size");
      // Where its records start, walked with bounds checks: the index may only point there (rosbag
      // trusts each record's lengths and reads past its buffer on damaged ones).
      record_starts.clear();
      RawChunk c;
      c.data_offset = r.data_pos;
      c.data_size = r.data_len;
      c.compression = r.fields.count("compression") ? r.fields.at("compression") : "none";
      c.uncompressed_size = chunk_size;
      const auto recordStart = [&](std::size_t offset, const Fields&, std::size_t, std::uint32_t) {
        record_starts.insert(static_cast<std::uint32_t>(offset));
      };
      if (c.compression == "none") {
        // Headers only, read in place: the messages' data is the bulk of a bag (1.5 GB for the
        // simulated hall), and this check runs before every read of it. A record's header follows
        // its length without a seek (a seek drops the stream's buffer): one per record, over its data.
        std::uint64_t at = std::numeric_limits<std::uint64_t>::max();
        const auto read = [&](std::size_t offset, std::size_t len, std::uint8_t* dst) {
          const std::uint64_t pos = c.data_offset + offset;
          if (pos != at) {
            in.clear();
            in.seekg(static_cast<std::streamoff>(pos));
          }
          const bool ok = static_cast<bool>(in.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(len)));
          at = ok ? pos + len : std::numeric_limits<std::uint64_t>::max();
          return ok;
        };
        walkRecords(c.data_size, read, recordStart);
      } else {
        std::vector<std::uint8_t> payload;
        try {
          payload = readChunkPayload(in, c, path);
        } catch (const Error& e) {
          return fail(e.what());
        }
        walkRecords(payload.size(), payloadReader(payload), recordStart);
      }
    } else if (kind == kOpIndexData) {
      const std::uint32_t count = fieldU32(r.fields, "count");
      if (fieldU32(r.fields, "ver") != 1 || static_cast<std::uint64_t>(count) * 12 != r.data_len)
        return fail("damaged index record at byte " + std::to_string(pos));
      std::vector<std::uint8_t> entries(r.data_len);
      in.clear();
      in.seekg(static_cast<std::streamoff>(r.data_pos));
      if (!in.read(reinterpret_cast<char*>(entries.data()), static_cast<std::streamsize>(entries.size()))) return true;
      for (std::uint32_t k = 0; k < count; ++k)
        if (!record_starts.count(u32(&entries[12 * k + 8])))
          return fail("index entry points at no intact record of its chunk (byte " + std::to_string(pos) + ")");
    } else if (kind == kOpChunkInfo) {
      const auto it = r.fields.find("chunk_pos");
      std::uint64_t chunk_pos = 0;
      if (it == r.fields.end() || it->second.size() != 8)
        return fail("damaged chunk info at byte " + std::to_string(pos));
      std::memcpy(&chunk_pos, it->second.data(), 8);
      if (!chunk_positions.count(chunk_pos))
        return fail("chunk info names no chunk (byte " + std::to_string(pos) + ")");
    }
    pos = r.data_pos + r.data_len;
  }
  return true;
}

RawBagScanner::RawBagScanner(const std::string& path) : path_(path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read bag " + path);
  in.seekg(0, std::ios::end);
  const std::uint64_t file_size = static_cast<std::uint64_t>(in.tellg());
  std::uint64_t pos = 13;  // after "#ROSBAG V2.0\n"
  while (pos + 4 <= file_size) {
    Record r;
    if (!readRecord(in, pos, file_size, &r)) {
      // Damage (overwritten bytes) or the cut end of the file: go on at the next chunk, if any.
      const std::uint64_t next = nextChunkAfter(in, pos + 1, file_size);
      if (next >= file_size) break;
      ++damaged_chunks_;
      pos = next;
      continue;
    }
    const std::uint64_t present = std::min<std::uint64_t>(r.data_len, file_size - r.data_pos);
    if (op(r.fields) == kOpChunk) {
      RawChunk c;
      c.data_offset = r.data_pos;
      c.data_size = present;
      c.compression = r.fields.count("compression") ? r.fields.at("compression") : "none";
      c.uncompressed_size = fieldU32(r.fields, "size");
      // A partial chunk is only usable uncompressed (its complete records are parsed).
      if (c.compression == "none" || present == r.data_len) {
        try {
          parsePayload(chunkPayload(c), nullptr, &c, &connections_);
          if (c.messages > 0) chunks_.push_back(c);
        } catch (const Error&) {
          ++damaged_chunks_;  // a compressed payload that does not decompress
        }
      }
    }
    if (present < r.data_len) break;
    pos = r.data_pos + r.data_len;
  }
}

std::vector<std::uint8_t> RawBagScanner::chunkPayload(const RawChunk& c) const {
  std::ifstream in(path_, std::ios::binary);
  return readChunkPayload(in, c, path_);
}

std::vector<std::uint8_t> readChunkPayload(std::ifstream& in, const RawChunk& c, const std::string& path_) {
  std::vector<std::uint8_t> raw(c.data_size);
  in.clear();
  in.seekg(static_cast<std::streamoff>(c.data_offset));
  if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size())))
    throw Error("cannot read a chunk of " + path_);
  if (c.compression == "none") return raw;
  std::vector<std::uint8_t> out(c.uncompressed_size);
  unsigned int out_size = c.uncompressed_size;
  const bool ok =
      c.compression == "bz2"
          ? BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &out_size,
                                       reinterpret_cast<char*>(raw.data()), static_cast<unsigned int>(raw.size()), 0,
                                       0) == BZ_OK
          : roslz4_buffToBuffDecompress(reinterpret_cast<char*>(raw.data()), static_cast<unsigned int>(raw.size()),
                                        reinterpret_cast<char*>(out.data()), &out_size) == ROSLZ4_OK;
  if (!ok) throw Error("cannot decompress a " + c.compression + " chunk of " + path_);
  out.resize(out_size);
  return out;
}

void RawBagScanner::parsePayload(const std::vector<std::uint8_t>& payload, std::vector<RawMessage>* messages,
                                 RawChunk* chunk, std::map<std::uint32_t, RawConnection>* connections) {
  chunk->messages = 0;
  chunk->begin_ns = std::numeric_limits<Stamp>::max();
  chunk->end_ns = std::numeric_limits<Stamp>::min();
  forEachRecord(payload, [&](std::size_t, const Fields& f, const std::uint8_t* data, std::uint32_t dl) {
    if (op(f) == kOpConnection && connections) {
      Fields ch;
      if (parseFields(data, dl, &ch)) {
        RawConnection c;
        c.topic = f.count("topic") ? f.at("topic") : ch["topic"];
        c.datatype = ch["type"];
        c.md5sum = ch["md5sum"];
        (*connections)[fieldU32(f, "conn")] = c;
      }
    } else if (op(f) == kOpMessage) {
      const Stamp t = fieldTime(f);
      ++chunk->messages;
      chunk->begin_ns = std::min(chunk->begin_ns, t);
      chunk->end_ns = std::max(chunk->end_ns, t);
      if (messages) messages->push_back({fieldU32(f, "conn"), t, std::vector<std::uint8_t>(data, data + dl)});
    }
  });
}

std::size_t RawBagScanner::messages() const {
  std::size_t n = 0;
  for (const RawChunk& c : chunks_) n += c.messages;
  return n;
}
Stamp RawBagScanner::beginNs() const {
  Stamp t = std::numeric_limits<Stamp>::max();
  for (const RawChunk& c : chunks_) t = std::min(t, c.begin_ns);
  return chunks_.empty() ? 0 : t;
}
Stamp RawBagScanner::endNs() const {
  Stamp t = 0;
  for (const RawChunk& c : chunks_) t = std::max(t, c.end_ns);
  return t;
}

std::vector<RawMessage> RawBagScanner::readChunk(std::size_t i) const {
  std::vector<RawMessage> out;
  RawChunk c = chunks_.at(i);
  parsePayload(chunkPayload(c), &out, &c, nullptr);
  std::stable_sort(out.begin(), out.end(),
                   [](const RawMessage& a, const RawMessage& b) { return a.time_ns < b.time_ns; });
  return out;
}

}  // namespace mmlio::io::detail
