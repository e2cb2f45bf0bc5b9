#pragma once
// PCD (Point Cloud Data, v0.7) files without PCL.
//
// Writing: `writePcdBinary` writes x y z intensity as float32, `DATA binary`, with the header
// PCL's own writer produces, so pcl::io::loadPCDFile, CloudCompare and pcl_viewer read it.
// Reading: ascii, binary and binary_compressed (LZF, column-major per field, as PCL writes it),
// any fields of type F/U/I and size 1/2/4/8. Fields named "_" are PCL padding and skipped.
// Little-endian host assumed (as PCL does).

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::io {

struct PcdField {
  std::string name;
  int size = 4;     // bytes per element: 1, 2, 4 or 8
  char type = 'F';  // 'F' float, 'U' unsigned, 'I' signed
  int count = 1;    // elements per point
};

struct PcdHeader {
  std::string version = "0.7";
  std::vector<PcdField> fields;
  std::size_t width = 0;
  std::size_t height = 1;
  std::array<double, 7> viewpoint{0, 0, 0, 1, 0, 0, 0};  // tx ty tz qw qx qy qz
  std::size_t points = 0;
  std::string data = "binary";  // "ascii" | "binary" | "binary_compressed"
  std::size_t data_offset = 0;  // byte offset of the data section in the file

  std::size_t pointStepBytes() const;  // packed size of one point
};

/// Every field of a PCD file, one column of doubles per field. A field with COUNT k > 1 gives k
/// columns named `name[0]` ... `name[k-1]`. 8-byte integers lose precision beyond 2^53.
struct PcdCloud {
  PcdHeader header;
  std::vector<std::string> fields;           // column names, file order
  std::vector<std::vector<double>> columns;  // columns[i][point]

  std::size_t size() const { return columns.empty() ? 0 : columns.front().size(); }
  bool has(const std::string& field) const;
  /// Throws mmlio::Error naming the file's fields when `field` is absent.
  const std::vector<double>& column(const std::string& field) const;
};

/// The header text writePcdBinary emits for `num_points` points (exactly PCL's layout).
std::string pcdBinaryHeader(std::size_t num_points);

/// Writes x y z intensity (float32, binary), atomically. Throws mmlio::Error naming the path.
void writePcdBinary(const std::string& path, const std::vector<Point>& points);

/// Writes any fields, `DATA binary`, atomically: one column per entry of cloud.header.fields (COUNT
/// 1, names equal to cloud.fields), each stored with its field's TYPE and SIZE (values converted
/// from double, integers rounded). Width = size(), height 1. E.g. a scan with ring (U2) and time
/// (F4) fields for other tools. Throws mmlio::Error naming the path on inconsistent input.
void writePcdFieldsBinary(const std::string& path, const PcdCloud& cloud);
/// The same, with the values of each of the `points` rows asked for in file order (row(values):
/// one value per field) instead of held in columns: a large cloud needs no copy.
void writePcdFieldsBinary(const std::string& path, const std::vector<PcdField>& fields, std::size_t points,
                          const std::function<void(double* values)>& row);

/// Parses the header only. Throws mmlio::Error naming the path on a malformed header.
PcdHeader readPcdHeader(const std::string& path);

/// Reads all fields. Throws mmlio::Error naming the path on malformed or truncated data.
PcdCloud readPcdFields(const std::string& path);

/// Reads points: x y z (required), intensity (if present), ring (field "ring", if present),
/// time_s (field "time", seconds since sweep start, if present). Points with a non-finite
/// coordinate (PCL's organised-cloud holes) are dropped. Other fields: use readPcdFields.
std::vector<Point> readPcd(const std::string& path);

/// LZF decompression (liblzf format, as used by PCL's binary_compressed). Returns the number of
/// bytes written, or 0 on corrupt input or when the output does not fit in `out_capacity`.
std::size_t lzfDecompress(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out, std::size_t out_capacity);

}  // namespace mmlio::io
