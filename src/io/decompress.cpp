#include "decompress.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <fstream>
#include <memory>

#include "mmlio/core/error.hpp"

namespace mmlio::io::detail {
namespace {

constexpr std::size_t kMaxReserve = std::size_t{1} << 30;  // a damaged size field must not reserve more

struct ZstdStream {
  ZSTD_DStream* s = ZSTD_createDStream();
  ~ZstdStream() { ZSTD_freeDStream(s); }
};

struct Lz4Context {
  LZ4F_dctx* c = nullptr;
  Lz4Context() { LZ4F_createDecompressionContext(&c, LZ4F_VERSION); }
  ~Lz4Context() { LZ4F_freeDecompressionContext(c); }
};

}  // namespace

bool isZstdFrame(const std::uint8_t* data, std::size_t size) {
  return size >= 4 && data[0] == 0x28 && data[1] == 0xB5 && data[2] == 0x2F && data[3] == 0xFD;
}

std::vector<std::uint8_t> zstdDecompress(const std::uint8_t* data, std::size_t size, std::size_t expected_size,
                                         const std::string& what) {
  std::vector<std::uint8_t> out;
  out.reserve(std::min(expected_size > 0 ? expected_size : size * 4, kMaxReserve));
  ZstdStream z;
  ZSTD_inBuffer in{data, size, 0};
  std::vector<std::uint8_t> block(ZSTD_DStreamOutSize());
  std::size_t left = 0;  // 0 once a frame is complete
  while (true) {
    ZSTD_outBuffer o{block.data(), block.size(), 0};
    left = ZSTD_decompressStream(z.s, &o, &in);
    if (ZSTD_isError(left)) throw Error(what + ": zstd: " + ZSTD_getErrorName(left));
    out.insert(out.end(), block.data(), block.data() + o.pos);
    if (in.pos == in.size && o.pos < o.size) break;  // input used up and nothing held back
  }
  if (left != 0) throw Error(what + ": zstd data ends inside a frame (truncated)");
  return out;
}

std::vector<std::uint8_t> lz4FrameDecompress(const std::uint8_t* data, std::size_t size, std::size_t expected_size,
                                             const std::string& what) {
  std::vector<std::uint8_t> out;
  out.reserve(std::min(expected_size > 0 ? expected_size : size * 4, kMaxReserve));
  Lz4Context ctx;
  if (!ctx.c) throw Error(what + ": cannot create an lz4 decompression context");
  std::vector<std::uint8_t> block(std::size_t{1} << 18);
  std::size_t pos = 0, left = 1;  // left: 0 once the frame is complete
  while (left != 0) {
    std::size_t produced = block.size(), consumed = size - pos;
    left = LZ4F_decompress(ctx.c, block.data(), &produced, data + pos, &consumed, nullptr);
    if (LZ4F_isError(left)) throw Error(what + ": lz4: " + LZ4F_getErrorName(left));
    pos += consumed;
    out.insert(out.end(), block.data(), block.data() + produced);
    if (pos == size && produced < block.size()) break;  // input used up and nothing held back
  }
  if (left != 0) throw Error(what + ": lz4 data ends inside a frame (truncated)");
  return out;
}

void zstdDecompressFile(const std::string& from, const std::string& to) {
  std::ifstream in(from, std::ios::binary);
  if (!in) throw Error("cannot read " + from);
  std::ofstream out(to, std::ios::binary | std::ios::trunc);
  if (!out) throw Error("cannot write the decompressed copy of " + from + " to " + to);
  ZstdStream z;
  std::vector<char> ibuf(ZSTD_DStreamInSize()), obuf(ZSTD_DStreamOutSize());
  std::size_t last = 0;
  while (in) {
    in.read(ibuf.data(), static_cast<std::streamsize>(ibuf.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (n == 0) break;
    ZSTD_inBuffer i{ibuf.data(), n, 0};
    while (i.pos < i.size) {
      ZSTD_outBuffer o{obuf.data(), obuf.size(), 0};
      last = ZSTD_decompressStream(z.s, &o, &i);
      if (ZSTD_isError(last)) throw Error(from + ": zstd: " + ZSTD_getErrorName(last));
      out.write(obuf.data(), static_cast<std::streamsize>(o.pos));
    }
  }
  if (last != 0) throw Error(from + ": zstd data ends inside a frame (truncated file)");
  if (!out) throw Error("cannot write " + to + " (disk full?)");
}

}  // namespace mmlio::io::detail
