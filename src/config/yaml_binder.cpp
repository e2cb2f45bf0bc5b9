#include "mmlio/config/yaml_binder.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <sstream>

#include "mmlio/core/error.hpp"
#include "mmlio/core/log.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::config {

namespace {

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Sequence:
      return "a sequence";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    default:
      return "an undefined node";
  }
}

[[noreturn]] void typeError(const YAML::Node& node, const std::string& where, const std::string& expected) {
  throw Error(where + ": expected " + expected + ", got " + describe(node));
}

/// A scalar yaml-cpp converts to T, else the type error naming what was expected.
template <class T> void decodeScalar(const YAML::Node& node, const std::string& where, const char* expected, T& value) {
  if (!node.IsScalar()) typeError(node, where, expected);
  try {
    value = node.as<T>();
  } catch (const YAML::Exception&) {
    typeError(node, where, expected);
  }
}

}  // namespace

std::string yamlLocation(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.is_null() || mark.line < 0) return file;
  return file + ":" + std::to_string(mark.line + 1);
}

void decodeYaml(const YAML::Node& node, const std::string& where, bool& value) {
  decodeScalar(node, where, "true or false", value);
}

void decodeYaml(const YAML::Node& node, const std::string& where, int& value) {
  decodeScalar(node, where, "an integer", value);
}

void decodeYaml(const YAML::Node& node, const std::string& where, double& value) {
  decodeScalar(node, where, "a number", value);
}

void decodeYaml(const YAML::Node& node, const std::string& where, std::string& value) {
  if (!node.IsScalar()) typeError(node, where, "a string");
  value = node.Scalar();
}

void decodeYaml(const YAML::Node& node, const std::string& where, std::vector<double>& value) {
  if (!node.IsSequence()) typeError(node, where, "a sequence of numbers");
  std::vector<double> out(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) decodeYaml(node[i], where + "[" + std::to_string(i) + "]", out[i]);
  value = std::move(out);
}

namespace {

// A rotation typed by hand with 4-6 digits is off by up to ~1e-4: taken as the nearest rotation,
// with a warning. Farther off than this it is a mistake (a wrong entry, a transposed row), not rounding.
constexpr double kNearlyOrthonormal = 1e-2;

double orthonormalityError(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

std::vector<double> numbersOf(const YAML::Node& node, const std::string& where, std::size_t count, const char* what) {
  std::vector<double> numbers;
  decodeYaml(node, where, numbers);
  if (numbers.size() != count)
    throw Error(where + ": expected " + std::to_string(count) + " numbers (" + what + "), got " +
                std::to_string(numbers.size()));
  return numbers;
}

// {xyz: [x, y, z], rpy_deg: [roll, pitch, yaw]} (ROS / URDF: R = Rz(yaw) Ry(pitch) Rx(roll)) or
// {xyz: [...], quaternion: [qx, qy, qz, qw]} (ROS order).
Eigen::Isometry3d decodeXyzRotation(const YAML::Node& node, const std::string& where) {
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    if (key != "xyz" && key != "rpy_deg" && key != "quaternion")
      throw Error(where + ": unknown key '" + key + "' (expected xyz with rpy_deg or quaternion, or 16 numbers)");
  }
  if (!node["xyz"]) throw Error(where + ": missing xyz (translation, m)");
  if (static_cast<bool>(node["rpy_deg"]) == static_cast<bool>(node["quaternion"]))
    throw Error(where + ": give exactly one of rpy_deg [roll, pitch, yaw] and quaternion [qx, qy, qz, qw]");
  const std::vector<double> xyz = numbersOf(node["xyz"], where + ".xyz", 3, "x, y, z in m");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  if (node["rpy_deg"]) {
    const std::vector<double> rpy = numbersOf(node["rpy_deg"], where + ".rpy_deg", 3, "roll, pitch, yaw in degrees");
    const double k = M_PI / 180.0;
    T.linear() = (Eigen::AngleAxisd(rpy[2] * k, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(rpy[1] * k, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(rpy[0] * k, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  } else {
    const std::vector<double> q = numbersOf(node["quaternion"], where + ".quaternion", 4, "qx, qy, qz, qw");
    Eigen::Quaterniond quaternion(q[3], q[0], q[1], q[2]);
    const double norm = quaternion.norm();
    if (!std::isfinite(norm) || std::abs(norm - 1.0) > kNearlyOrthonormal)
      throw Error(where + ".quaternion: not a unit quaternion (norm " + io::formatDouble(norm) + ")");
    if (std::abs(norm - 1.0) > 1e-6)
      log::warn(where, ".quaternion: norm ", norm, ", normalised (give 7 or more significant digits to silence this)");
    T.linear() = quaternion.normalized().toRotationMatrix();
  }
  if (!T.matrix().allFinite()) throw Error(where + ": transform has non-finite entries");
  return T;
}

}  // namespace

void decodeYaml(const YAML::Node& node, const std::string& where, Eigen::Isometry3d& value) {
  if (node.IsMap()) {
    value = decodeXyzRotation(node, where);
    return;
  }
  const std::vector<double> numbers = numbersOf(node, where, 16, "4x4 row-major, or xyz with rpy_deg or quaternion");
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) m(k / 4, k % 4) = numbers[k];
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double error = m.allFinite() ? orthonormalityError(R) : 0.0;
  if (error > 1e-6 && error <= kNearlyOrthonormal && R.determinant() > 0) {
    // The nearest rotation in the Frobenius norm: U V^T of R's singular value decomposition.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    m.topLeftCorner<3, 3>() = svd.matrixU() * svd.matrixV().transpose();
    log::warn(where, ": rotation re-orthonormalised (max |R^T R - I| was ", error,
              "; give 7 or more significant digits to silence this)");
  }
  validateRigidTransform(m, where);
  value.matrix() = m;
}

void validateRigidTransform(const Eigen::Matrix4d& m, const std::string& where) {
  if (!m.allFinite()) throw Error(where + ": transform has non-finite entries");
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0)
    throw Error(where + ": bottom row must be 0 0 0 1");
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  const double orthonormality_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthonormality_error > 1e-6) {
    std::ostringstream os;
    os << where << ": rotation is not orthonormal (max |R^T R - I| = " << orthonormality_error
       << "; up to 0.01 is taken as rounding and re-orthonormalised): check the entries";
    throw Error(os.str());
  }
  if (R.determinant() < 0) throw Error(where + ": rotation has determinant -1 (a reflection, not a rotation)");
}

std::string encodeYaml(bool value, int) { return value ? "true" : "false"; }
std::string encodeYaml(int value, int) { return std::to_string(value); }

std::string encodeYaml(double value, int) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  std::string text = io::formatDouble(value);
  if (text.find_first_of(".e") == std::string::npos) text += ".0";  // keep it visibly a float
  return text;
}

std::string encodeYaml(const std::string& value, int) {
  YAML::Emitter emitter;
  emitter << value;
  return emitter.c_str();
}

std::string encodeYaml(const std::vector<double>& value, int) {
  std::string text = "[";
  for (std::size_t i = 0; i < value.size(); ++i) text += (i ? ", " : "") + encodeYaml(value[i], 0);
  return text + "]";
}

std::string encodeYaml(const Eigen::Isometry3d& value, int indent) {
  // One matrix row per line, continuation lines aligned under the first number.
  const Eigen::Matrix4d& m = value.matrix();
  std::string text = "[";
  for (int r = 0; r < 4; ++r) {
    if (r > 0) text += ",\n" + std::string(static_cast<std::size_t>(indent), ' ');
    for (int c = 0; c < 4; ++c) text += (c ? ", " : "") + io::formatDouble(m(r, c));
  }
  return text + "]";
}

YamlBinder::YamlBinder(const YAML::Node& node, std::string file, std::string prefix)
    : mode_(Mode::kRead), prefix_(std::move(prefix)), node_(node), file_(std::move(file)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    const std::string name = prefix_.empty() ? std::string("top level") : prefix_.substr(0, prefix_.size() - 1);
    throw Error(yamlLocation(file_, node_) + ": " + name + ": expected a map of keys, got " + describe(node_));
  }
}

YamlBinder::YamlBinder(std::ostream& out, int indent, const Defaults* defaults, std::string prefix)
    : mode_(Mode::kEmit), prefix_(std::move(prefix)), out_(&out), indent_(indent), defaults_(defaults) {}

YamlBinder::YamlBinder(Defaults* record, std::string prefix)
    : mode_(Mode::kRecord), prefix_(std::move(prefix)), record_(record) {}

std::string YamlBinder::defaultText(const Eigen::Isometry3d& value) {
  if (value.matrix().isIdentity(0.0)) return "identity";
  std::string text = encodeYaml(value, 0);
  for (char& c : text)
    if (c == '\n') c = ' ';
  return text;
}

std::string YamlBinder::withDefault(const std::string& key, const std::string& doc) const {
  if (!defaults_) return doc;
  const auto it = defaults_->find(prefix_ + key);
  if (it == defaults_->end() || it->second.empty() || it->second == "\"\"") return doc;
  return doc + " (default: " + it->second + ")";
}

YAML::Node YamlBinder::lookup(const std::string& key) {
  declared_.push_back(key);
  return child(key);
}

YAML::Node YamlBinder::child(const std::string& key) const {
  if (!node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node& map = node_;  // const: operator[] must not insert
  for (auto it = map.begin(); it != map.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == key) return it->second;
  return YAML::Node(YAML::NodeType::Undefined);
}

void YamlBinder::throwChoice(const std::string& where, const std::string& valid, const std::string& got) {
  throw Error(where + ": must be one of " + valid + ", got '" + got + "'");
}

bool YamlBinder::has(const std::string& key) const { return mode_ == Mode::kRead && child(key).IsDefined(); }

std::string YamlBinder::location() const { return yamlLocation(file_, node_); }

std::string YamlBinder::where(const std::string& key, const YAML::Node& node) const {
  return yamlLocation(file_, node) + ": " + path(key);
}

void YamlBinder::throwNotA(const std::string& what, const std::string& key, const YAML::Node& node) const {
  typeError(node, where(key, node), what);
}

void YamlBinder::finish() const {
  if (!reading() || !node_.IsMap()) return;
  std::vector<std::string> seen;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : "<non-scalar key>";
    for (const auto& s : seen)
      if (s == key) throw Error(yamlLocation(file_, it->first) + ": duplicate key '" + path(key) + "'");
    seen.push_back(key);
    bool known = false;
    for (const auto& d : declared_) known = known || d == key;
    if (known) continue;
    std::string keys;
    for (const auto& d : declared_) keys += (keys.empty() ? "" : ", ") + d;
    throw Error(yamlLocation(file_, it->first) + ": unknown key '" + path(key) + "' (known keys" +
                (prefix_.empty() ? std::string() : " in " + prefix_.substr(0, prefix_.size() - 1)) + ": " + keys + ")");
  }
}

void YamlBinder::emitKey(const std::string& key, const std::string& doc, const std::string& value_text) {
  std::ostream& out = *out_;
  const std::string pad(static_cast<std::size_t>(indent_), ' ');
  std::istringstream doc_lines(doc);
  for (std::string line; std::getline(doc_lines, line);) out << pad << "# " << line << '\n';
  if (list_item_pending_) {
    out << pad << "- " << key << ':' << value_text << '\n';
    list_item_pending_ = false;
    indent_ += 2;  // the item's remaining keys align with the first one
  } else {
    out << pad << key << ':' << value_text << '\n';
  }
}

}  // namespace mmlio::config
