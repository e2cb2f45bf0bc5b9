#pragma once
// Private helper of src/io: the two compressions ROS 2 bags use, through Debian's libzstd and liblz4.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mmlio::io::detail {

/// True when `data` starts with a zstd frame's magic number.
bool isZstdFrame(const std::uint8_t* data, std::size_t size);

/// Decompresses one or more concatenated zstd frames (content size known or not). `expected_size` (0: unknown) only
/// reserves memory. Throws mmlio::Error with `what` in the message on damage.
std::vector<std::uint8_t> zstdDecompress(const std::uint8_t* data, std::size_t size, std::size_t expected_size,
                                         const std::string& what);

/// Decompresses an LZ4 frame (the LZ4 frame format, as MCAP chunks use). Throws mmlio::Error.
std::vector<std::uint8_t> lz4FrameDecompress(const std::uint8_t* data, std::size_t size, std::size_t expected_size,
                                             const std::string& what);

/// Streams the zstd file `from` decompressed into `to` (rosbag2's per-file compression). Throws mmlio::Error.
void zstdDecompressFile(const std::string& from, const std::string& to);

}  // namespace mmlio::io::detail
