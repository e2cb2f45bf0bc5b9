#include "mmlio/io/pcd_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "mmlio/core/error.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::io {

std::size_t PcdHeader::pointStepBytes() const {
  std::size_t step = 0;
  for (const auto& f : fields) step += static_cast<std::size_t>(f.size) * f.count;
  return step;
}

bool PcdCloud::has(const std::string& field) const {
  for (const auto& f : fields)
    if (f == field) return true;
  return false;
}

const std::vector<double>& PcdCloud::column(const std::string& field) const {
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (fields[i] == field) return columns[i];
  std::string known;
  for (const auto& f : fields) known += (known.empty() ? "" : " ") + f;
  throw Error("PCD has no field '" + field + "' (fields: " + known + ")");
}

std::string pcdBinaryHeader(std::size_t num_points) {
  const std::string n = std::to_string(num_points);
  return "# .PCD v0.7 - Point Cloud Data file format\n"
         "VERSION 0.7\n"
         "FIELDS x y z intensity\n"
         "SIZE 4 4 4 4\n"
         "TYPE F F F F\n"
         "COUNT 1 1 1 1\n"
         "WIDTH " +
         n +
         "\n"
         "HEIGHT 1\n"
         "VIEWPOINT 0 0 0 1 0 0 0\n"
         "POINTS " +
         n +
         "\n"
         "DATA binary\n";
}

void writePcdBinary(const std::string& path, const std::vector<Point>& points) {
  writeFileAtomically(path, [&](std::ostream& out) {
    out << pcdBinaryHeader(points.size());
    std::vector<float> buffer;
    constexpr std::size_t kChunk = 1 << 16;
    for (std::size_t begin = 0; begin < points.size(); begin += kChunk) {
      const std::size_t end = std::min(points.size(), begin + kChunk);
      buffer.clear();
      for (std::size_t i = begin; i < end; ++i) {
        const Point& p = points[i];
        buffer.insert(buffer.end(), {p.xyz.x(), p.xyz.y(), p.xyz.z(), p.intensity});
      }
      out.write(reinterpret_cast<const char*>(buffer.data()),
                static_cast<std::streamsize>(buffer.size() * sizeof(float)));
    }
  });
}

namespace {

void encodeValue(double value, const PcdField& f, char* out) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) {
        const float v = static_cast<float>(value);
        std::memcpy(out, &v, 4);
        return;
      }
      std::memcpy(out, &value, 8);
      return;
    case 'U': {
      const std::uint64_t v = static_cast<std::uint64_t>(std::llround(std::max(0.0, value)));
      std::memcpy(out, &v, static_cast<std::size_t>(f.size));  // little endian: low bytes first
      return;
    }
    default: {
      const std::int64_t v = std::llround(value);
      std::memcpy(out, &v, static_cast<std::size_t>(f.size));
      return;
    }
  }
}

}  // namespace

void writePcdFieldsBinary(const std::string& path, const PcdCloud& cloud) {
  if (cloud.header.fields.size() != cloud.fields.size() || cloud.fields.size() != cloud.columns.size())
    throw Error("writing PCD '" + path + "': header.fields, fields and columns differ in length");
  for (std::size_t i = 0; i < cloud.fields.size(); ++i) {
    if (cloud.header.fields[i].name != cloud.fields[i])
      throw Error("writing PCD '" + path + "': field '" + cloud.header.fields[i].name + "' must match its column");
    if (cloud.columns[i].size() != cloud.size())
      throw Error("writing PCD '" + path + "': column '" + cloud.fields[i] + "' has a different length");
  }
  std::size_t p = 0;
  writePcdFieldsBinary(path, cloud.header.fields, cloud.size(), [&](double* values) {
    for (std::size_t i = 0; i < cloud.columns.size(); ++i) values[i] = cloud.columns[i][p];
    ++p;
  });
}

void writePcdFieldsBinary(const std::string& path, const std::vector<PcdField>& fields, std::size_t points,
                          const std::function<void(double* values)>& row) {
  for (const PcdField& f : fields) {
    const bool ok_type =
        (f.type == 'F' && (f.size == 4 || f.size == 8)) ||
        ((f.type == 'U' || f.type == 'I') && (f.size == 1 || f.size == 2 || f.size == 4 || f.size == 8));
    if (f.count != 1 || !ok_type)
      throw Error("writing PCD '" + path + "': field '" + f.name + "' must be COUNT 1, TYPE F4/F8/U*/I*");
  }
  std::string names, sizes, types, counts;
  std::size_t step = 0;
  for (const auto& f : fields) {
    names += " " + f.name;
    sizes += " " + std::to_string(f.size);
    types += std::string(" ") + f.type;
    counts += " 1";
    step += static_cast<std::size_t>(f.size);
  }
  writeFileAtomically(path, [&](std::ostream& out) {
    out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS" << names << "\nSIZE" << sizes << "\nTYPE"
        << types << "\nCOUNT" << counts << "\nWIDTH " << points << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS "
        << points << "\nDATA binary\n";
    std::vector<char> bytes(step);
    std::vector<double> values(fields.size());
    for (std::size_t p = 0; p < points; ++p) {
      row(values.data());
      std::size_t offset = 0;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        encodeValue(values[i], fields[i], bytes.data() + offset);
        offset += static_cast<std::size_t>(fields[i].size);
      }
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
  });
}

std::size_t lzfDecompress(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out, std::size_t out_capacity) {
  const std::uint8_t* ip = in;
  const std::uint8_t* const in_end = in + in_size;
  std::uint8_t* op = out;
  std::uint8_t* const out_end = out + out_capacity;
  while (ip < in_end) {
    unsigned ctrl = *ip++;
    if (ctrl < (1u << 5)) {  // literal run of ctrl + 1 bytes
      const std::size_t len = ctrl + 1;
      if (op + len > out_end || ip + len > in_end) return 0;
      std::memcpy(op, ip, len);
      op += len;
      ip += len;
    } else {  // back reference: length (ctrl >> 5) + 2, offset from the low bits and the next byte
      std::size_t len = ctrl >> 5;
      if (len == 7) {
        if (ip >= in_end) return 0;
        len += *ip++;
      }
      len += 2;
      if (ip >= in_end) return 0;
      const std::size_t offset = ((static_cast<std::size_t>(ctrl & 0x1f) << 8) | *ip++) + 1;
      if (offset > static_cast<std::size_t>(op - out) || op + len > out_end) return 0;
      const std::uint8_t* ref = op - offset;
      for (std::size_t k = 0; k < len; ++k) *op++ = *ref++;  // may overlap: byte by byte
    }
  }
  return static_cast<std::size_t>(op - out);
}

namespace {

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open PCD '" + path + "' for reading (missing file?)");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream is(line);
  std::string t;
  while (is >> t) out.push_back(t);
  return out;
}

std::size_t toCount(const std::string& path, const std::string& key, const std::string& text) {
  try {
    std::size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used != text.size() || v < 0) throw std::invalid_argument(text);
    return static_cast<std::size_t>(v);
  } catch (const std::exception&) {
    throw Error("PCD '" + path + "': bad " + key + " value '" + text + "'");
  }
}

PcdHeader parseHeader(const std::string& path, const std::string& bytes) {
  PcdHeader h;
  h.height = 1;
  bool have_points = false, have_width = false, have_data = false;
  std::vector<std::string> names, sizes, types, counts;
  std::size_t pos = 0;
  while (pos < bytes.size() && !have_data) {
    std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    const std::string line = bytes.substr(pos, eol - pos);
    pos = std::min(bytes.size(), eol + 1);
    const auto t = tokens(line);
    if (t.empty() || t[0][0] == '#') continue;
    const std::string& key = t[0];
    const std::vector<std::string> values(t.begin() + 1, t.end());
    if (key == "VERSION") {
      if (!values.empty()) h.version = values[0];
    } else if (key == "FIELDS" || key == "COLUMNS") {
      names = values;
    } else if (key == "SIZE") {
      sizes = values;
    } else if (key == "TYPE") {
      types = values;
    } else if (key == "COUNT") {
      counts = values;
    } else if (key == "WIDTH" && values.size() == 1) {
      h.width = toCount(path, key, values[0]);
      have_width = true;
    } else if (key == "HEIGHT" && values.size() == 1) {
      h.height = toCount(path, key, values[0]);
    } else if (key == "VIEWPOINT") {
      if (values.size() != 7) throw Error("PCD '" + path + "': VIEWPOINT needs 7 numbers");
      for (int k = 0; k < 7; ++k) h.viewpoint[k] = std::strtod(values[k].c_str(), nullptr);
    } else if (key == "POINTS" && values.size() == 1) {
      h.points = toCount(path, key, values[0]);
      have_points = true;
    } else if (key == "DATA" && values.size() == 1) {
      h.data = values[0];
      have_data = true;
    } else {
      throw Error("PCD '" + path + "': unexpected header line '" + line + "'");
    }
  }
  if (!have_data) throw Error("PCD '" + path + "': no DATA line (not a PCD file?)");
  if (h.data != "ascii" && h.data != "binary" && h.data != "binary_compressed")
    throw Error("PCD '" + path + "': unknown DATA format '" + h.data + "' (ascii, binary, binary_compressed)");
  if (names.empty()) throw Error("PCD '" + path + "': no FIELDS line");
  if (sizes.size() != names.size() || types.size() != names.size() ||
      (!counts.empty() && counts.size() != names.size()))
    throw Error("PCD '" + path + "': FIELDS, SIZE, TYPE and COUNT have different lengths");
  for (std::size_t i = 0; i < names.size(); ++i) {
    PcdField f;
    f.name = names[i];
    f.size = static_cast<int>(toCount(path, "SIZE", sizes[i]));
    f.type = types[i].size() == 1 ? types[i][0] : '?';
    f.count = counts.empty() ? 1 : static_cast<int>(toCount(path, "COUNT", counts[i]));
    const bool ok_type =
        (f.type == 'F' && (f.size == 4 || f.size == 8)) ||
        ((f.type == 'U' || f.type == 'I') && (f.size == 1 || f.size == 2 || f.size == 4 || f.size == 8));
    if (!ok_type || f.count < 1)
      throw Error("PCD '" + path + "': field '" + f.name + "' has unsupported TYPE " + types[i] + " SIZE " + sizes[i]);
    h.fields.push_back(f);
  }
  if (!have_width && !have_points) throw Error("PCD '" + path + "': neither WIDTH nor POINTS given");
  if (!have_points) h.points = h.width * h.height;
  if (!have_width) h.width = h.points, h.height = 1;
  if (h.width * h.height != h.points)
    throw Error("PCD '" + path + "': WIDTH * HEIGHT = " + std::to_string(h.width * h.height) +
                " but POINTS = " + std::to_string(h.points));
  h.data_offset = pos;
  return h;
}

double decodeValue(const std::uint8_t* p, const PcdField& f) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
      {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    case 'U':
      switch (f.size) {
        case 1:
          return *p;
        case 2: {
          std::uint16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          std::uint32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          std::uint64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
    default:
      switch (f.size) {
        case 1:
          return static_cast<std::int8_t>(*p);
        case 2: {
          std::int16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          std::int32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          std::int64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
  }
}

}  // namespace

PcdHeader readPcdHeader(const std::string& path) {
  // Headers are short; read a bounded prefix so this stays cheap on large maps.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open PCD '" + path + "' for reading (missing file?)");
  std::string prefix(4096, '\0');
  in.read(&prefix[0], static_cast<std::streamsize>(prefix.size()));
  prefix.resize(static_cast<std::size_t>(in.gcount()));
  return parseHeader(path, prefix);
}

PcdCloud readPcdFields(const std::string& path) {
  const std::string bytes = readWholeFile(path);
  PcdCloud cloud;
  cloud.header = parseHeader(path, bytes);
  const PcdHeader& h = cloud.header;
  const std::size_t n = h.points;

  // Column index of each (field, element); -1 for padding fields.
  std::vector<int> first_column;
  for (const auto& f : h.fields) {
    if (f.name == "_") {
      first_column.push_back(-1);
      continue;
    }
    first_column.push_back(static_cast<int>(cloud.fields.size()));
    for (int k = 0; k < f.count; ++k)
      cloud.fields.push_back(f.count == 1 ? f.name : f.name + "[" + std::to_string(k) + "]");
  }
  cloud.columns.assign(cloud.fields.size(), std::vector<double>(n));

  const std::size_t step = h.pointStepBytes();
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data()) + h.data_offset;
  const std::size_t available = bytes.size() - h.data_offset;

  if (h.data == "ascii") {
    std::istringstream is(bytes.substr(h.data_offset));
    std::string line;
    std::size_t point = 0;
    while (point < n && std::getline(is, line)) {
      const auto t = tokens(line);
      if (t.empty() || t[0][0] == '#') continue;
      std::size_t expected = 0;
      for (const auto& f : h.fields) expected += f.count;
      if (t.size() != expected)
        throw Error("PCD '" + path + "': ascii point " + std::to_string(point) + " has " + std::to_string(t.size()) +
                    " values, header declares " + std::to_string(expected));
      std::size_t token = 0;
      for (std::size_t fi = 0; fi < h.fields.size(); ++fi) {
        for (int k = 0; k < h.fields[fi].count; ++k, ++token) {
          if (first_column[fi] < 0) continue;
          char* end = nullptr;
          const double v = std::strtod(t[token].c_str(), &end);
          if (end == t[token].c_str() || *end != '\0')
            throw Error("PCD '" + path + "': ascii point " + std::to_string(point) + ": bad number '" + t[token] + "'");
          cloud.columns[first_column[fi] + k][point] = v;
        }
      }
      ++point;
    }
    if (point != n)
      throw Error("PCD '" + path + "': truncated, " + std::to_string(point) + " of " + std::to_string(n) + " points");
  } else if (h.data == "binary") {
    if (available < n * step)
      throw Error("PCD '" + path + "': truncated, " + std::to_string(available) + " data bytes for " +
                  std::to_string(n) + " points of " + std::to_string(step) + " bytes");
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint8_t* p = data + i * step;
      for (std::size_t fi = 0; fi < h.fields.size(); ++fi) {
        const PcdField& f = h.fields[fi];
        for (int k = 0; k < f.count; ++k, p += f.size)
          if (first_column[fi] >= 0) cloud.columns[first_column[fi] + k][i] = decodeValue(p, f);
      }
    }
  } else {  // binary_compressed: u32 compressed size, u32 uncompressed size, LZF of field-major data
    if (available < 8) throw Error("PCD '" + path + "': truncated compressed data header");
    std::uint32_t compressed = 0, uncompressed = 0;
    std::memcpy(&compressed, data, 4);
    std::memcpy(&uncompressed, data + 4, 4);
    if (available - 8 < compressed)
      throw Error("PCD '" + path + "': truncated, compressed size " + std::to_string(compressed) + " but only " +
                  std::to_string(available - 8) + " bytes follow");
    if (uncompressed < n * step)
      throw Error("PCD '" + path + "': uncompressed size " + std::to_string(uncompressed) + " < " + std::to_string(n) +
                  " points x " + std::to_string(step) + " bytes");
    std::vector<std::uint8_t> raw(uncompressed);
    if (n > 0 && lzfDecompress(data + 8, compressed, raw.data(), raw.size()) != uncompressed)
      throw Error("PCD '" + path + "': corrupt LZF data");
    const std::uint8_t* block = raw.data();
    for (std::size_t fi = 0; fi < h.fields.size(); ++fi) {
      const PcdField& f = h.fields[fi];
      const std::size_t elem = static_cast<std::size_t>(f.size);
      if (first_column[fi] >= 0) {
        for (std::size_t i = 0; i < n; ++i)
          for (int k = 0; k < f.count; ++k)
            cloud.columns[first_column[fi] + k][i] = decodeValue(block + (i * f.count + k) * elem, f);
      }
      block += n * elem * f.count;
    }
  }
  return cloud;
}

std::vector<Point> readPcd(const std::string& path) {
  const PcdCloud cloud = readPcdFields(path);
  for (const char* required : {"x", "y", "z"})
    if (!cloud.has(required)) throw Error("PCD '" + path + "' has no field '" + required + "'");
  const auto& x = cloud.column("x");
  const auto& y = cloud.column("y");
  const auto& z = cloud.column("z");
  const std::vector<double>* intensity = cloud.has("intensity") ? &cloud.column("intensity") : nullptr;
  const std::vector<double>* ring = cloud.has("ring") ? &cloud.column("ring") : nullptr;
  const std::vector<double>* time = cloud.has("time") ? &cloud.column("time") : nullptr;
  std::vector<Point> points;
  points.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(z[i])) continue;
    Point p;
    p.xyz = Eigen::Vector3f(static_cast<float>(x[i]), static_cast<float>(y[i]), static_cast<float>(z[i]));
    if (intensity) p.intensity = static_cast<float>((*intensity)[i]);
    if (ring) p.ring = static_cast<std::uint16_t>((*ring)[i]);
    if (time) p.time_s = static_cast<float>((*time)[i]);
    points.push_back(p);
  }
  return points;
}

}  // namespace mmlio::io
