#pragma once
// Private helper of src/io: reads the chunks of a ROS1 bag (format 2.0) record by record, without
// its index, so that a truncated, unindexed or damaged bag (recording killed, bytes overwritten)
// can still be streamed: up to its last complete message, and past a damaged stretch from the next
// intact chunk on. Uncompressed, lz4 and bz2 chunks (a cut compressed chunk is lost).
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::io::detail {

struct RawConnection {
  std::string topic, datatype, md5sum;
};

struct RawMessage {
  std::uint32_t conn = 0;
  Stamp time_ns = 0;
  std::vector<std::uint8_t> data;  // serialised message
};

struct RawChunk {
  std::uint64_t data_offset = 0;  // file offset of the chunk payload
  std::uint64_t data_size = 0;    // bytes of payload present in the file
  std::string compression;        // none | lz4 | bz2
  std::uint32_t uncompressed_size = 0;
  Stamp begin_ns = 0, end_ns = 0;
  std::size_t messages = 0;
};

/// Checks that the bag's index matches its chunks (every index entry at an intact record of its
/// chunk, every chunk info naming a chunk): rosbag trusts its index and each record's lengths and
/// reads out of bounds (crashes) where they are damaged. Reads every chunk once. False with the
/// reason otherwise.
bool indexLooksSound(const std::string& path, std::string* why);

/// The (decompressed) payload of chunk c. Throws mmlio::Error naming `path`.
std::vector<std::uint8_t> readChunkPayload(std::ifstream& in, const RawChunk& c, const std::string& path);

class RawBagScanner {
 public:
  /// Scans every chunk once (connections, times, counts). Throws mmlio::Error when not a bag.
  explicit RawBagScanner(const std::string& path);
  const std::map<std::uint32_t, RawConnection>& connections() const { return connections_; }
  const std::vector<RawChunk>& chunks() const { return chunks_; }
  std::size_t messages() const;
  Stamp beginNs() const;
  Stamp endNs() const;
  /// Damaged stretches or chunks skipped (the reader went on at the next intact chunk).
  std::size_t damagedChunks() const { return damaged_chunks_; }
  /// Messages of chunk i in time order.
  std::vector<RawMessage> readChunk(std::size_t i) const;

 private:
  std::vector<std::uint8_t> chunkPayload(const RawChunk& c) const;
  /// Parses the records of a chunk payload; complete records only.
  static void parsePayload(const std::vector<std::uint8_t>& payload, std::vector<RawMessage>* messages, RawChunk* chunk,
                           std::map<std::uint32_t, RawConnection>* connections);

  std::string path_;
  std::map<std::uint32_t, RawConnection> connections_;
  std::vector<RawChunk> chunks_;
  std::size_t damaged_chunks_ = 0;
};

}  // namespace mmlio::io::detail
