// PNG encoding of a Canvas with libpng: the one place the eval module touches files.
#include <png.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <unistd.h>

#include "mmlio/core/error.hpp"
#include "mmlio/eval/canvas.hpp"

namespace mmlio::eval {
namespace {

// libpng reports errors by longjmp: keep every C++ object with a destructor out of this function
// so the jump skips none, and turn the jump into a false return.
bool encode(std::FILE* file, int width, int height, const std::uint8_t* rgb, std::string& error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) {
    error = "png_create_write_struct failed";
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    error = "png_create_info_struct failed";
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    error = "libpng error while encoding";
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Plots are mostly flat colour: the left-neighbour filter and a light deflate keep them small
  // for a fifth of the work of libpng's default (every filter tried per row, deflate level 6).
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, 3);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y)
    png_write_row(png, const_cast<png_bytep>(rgb + static_cast<size_t>(y) * static_cast<size_t>(width) * 3));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

void Canvas::savePng(const std::string& path) const {
  // Write beside the target and rename, so a failed write never leaves a truncated PNG.
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (!file) throw Error("cannot write plot '" + path + "': " + std::strerror(errno));
  std::string error;
  const bool encoded = encode(file, width_, height_, rgb_.data(), error);
  const bool closed = std::fclose(file) == 0;
  if (!encoded || !closed) {
    std::remove(tmp.c_str());
    throw Error("cannot write plot '" + path + "': " + (encoded ? std::string(std::strerror(errno)) : error));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    std::remove(tmp.c_str());
    throw Error("cannot write plot '" + path + "': " + reason);
  }
}

}  // namespace mmlio::eval
