#include "raw_bag_scanner.hpp"

#include <roslz4/lz4s.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>

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

}  // namespace

RawBagScanner::RawBagScanner(const std::string& path) : path_(path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read bag " + path);
  in.seekg(0, std::ios::end);
  const std::uint64_t file_size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(13);  // "#ROSBAG V2.0\n"
  std::uint64_t pos = 13;
  while (pos + 4 <= file_size) {
    std::uint8_t len4[4];
    in.seekg(static_cast<std::streamoff>(pos));
    if (!in.read(reinterpret_cast<char*>(len4), 4)) break;
    const std::uint32_t header_len = u32(len4);
    if (header_len > file_size - pos - 4) break;
    std::vector<std::uint8_t> header(header_len);
    if (!in.read(reinterpret_cast<char*>(header.data()), header_len)) break;
    Fields fields;
    if (!parseFields(header.data(), header.size(), &fields)) break;
    const std::uint64_t data_pos = pos + 4 + header_len + 4;
    if (data_pos > file_size || !in.read(reinterpret_cast<char*>(len4), 4)) break;
    const std::uint32_t data_len = u32(len4);
    const std::uint64_t present = std::min<std::uint64_t>(data_len, file_size - data_pos);
    if (op(fields) == kOpChunk) {
      RawChunk c;
      c.data_offset = data_pos;
      c.data_size = present;
      c.compression = fields.count("compression") ? fields.at("compression") : "none";
      c.uncompressed_size = fieldU32(fields, "size");
      // A partial chunk is only usable uncompressed (its complete records are parsed).
      if (c.compression == "none" || (c.compression == "lz4" && present == data_len)) {
        try {
          parsePayload(chunkPayload(c), nullptr, &c, &connections_);
        } catch (const Error&) {
          break;
        }
        if (c.messages > 0) chunks_.push_back(c);
      } else {
        break;  // bz2 or a cut compressed chunk: the readable part ends here
      }
    }
    if (present < data_len) break;
    pos = data_pos + data_len;
  }
}

std::vector<std::uint8_t> RawBagScanner::chunkPayload(const RawChunk& c) const {
  std::ifstream in(path_, std::ios::binary);
  std::vector<std::uint8_t> raw(c.data_size);
  in.seekg(static_cast<std::streamoff>(c.data_offset));
  if (!in.read(reinterpret_cast<char*>(raw.data()), static_cast<std::streamsize>(raw.size())))
    throw Error("cannot read a chunk of " + path_);
  if (c.compression == "none") return raw;
  std::vector<std::uint8_t> out(c.uncompressed_size);
  unsigned int out_size = c.uncompressed_size;
  if (roslz4_buffToBuffDecompress(reinterpret_cast<char*>(raw.data()), static_cast<unsigned int>(raw.size()),
                                  reinterpret_cast<char*>(out.data()), &out_size) != ROSLZ4_OK)
    throw Error("cannot decompress an lz4 chunk of " + path_);
  out.resize(out_size);
  return out;
}

void RawBagScanner::parsePayload(const std::vector<std::uint8_t>& payload, std::vector<RawMessage>* messages,
                                 RawChunk* chunk, std::map<std::uint32_t, RawConnection>* connections) {
  const std::uint8_t* p = payload.data();
  const std::size_t n = payload.size();
  std::size_t i = 0;
  chunk->messages = 0;
  chunk->begin_ns = std::numeric_limits<Stamp>::max();
  chunk->end_ns = std::numeric_limits<Stamp>::min();
  while (i + 4 <= n) {
    const std::uint32_t hl = u32(p + i);
    if (hl > n - i - 4) break;
    Fields f;
    if (!parseFields(p + i + 4, hl, &f)) break;
    const std::size_t dpos = i + 4 + hl + 4;
    if (dpos > n) break;
    const std::uint32_t dl = u32(p + i + 4 + hl);
    if (dl > n - dpos) break;
    if (op(f) == kOpConnection && connections) {
      Fields ch;
      if (parseFields(p + dpos, dl, &ch)) {
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
      if (messages) messages->push_back({fieldU32(f, "conn"), t, std::vector<std::uint8_t>(p + dpos, p + dpos + dl)});
    }
    i = dpos + dl;
  }
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
  std::stable_sort(out.begin(), out.end(), [](const RawMessage& a, const RawMessage& b) { return a.time_ns < b.time_ns; });
  return out;
}

}  // namespace mmlio::io::detail
