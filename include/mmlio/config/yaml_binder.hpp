#pragma once
// YamlBinder: declare each config field once — key, member (whose initial value is the default)
// and a one-line doc — and use the same declaration to
//   * read YAML strictly: a wrong type is an error naming `file:line: key.path`, and finish()
//     rejects keys nobody declared (typos never pass silently); absent keys keep the default;
//   * emit documented YAML: every field with its doc as a comment and its current value.
//
//   void bind(YamlBinder& b, LoopConfig& c) {
//     b.field("enabled", c.enabled, "close loops in the back end");
//     b.field("search_radius_m", c.search_radius_m, "candidate search radius, m");
//   }
//   YamlBinder reader(node, "rig.yaml");  bind(reader, cfg);  reader.finish();
//   std::string text = documentedYaml(cfg, bind);   // doc comments end with "(default: X)"
//
// Supported field types: bool, int, double, std::string, std::vector<double>, Eigen::Isometry3d
// (a flow sequence of 16 numbers, 4x4 row-major, validated as a rigid transform). Nested structs
// go through section(), lists of structs through list(), enums (named values) through choice().

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <map>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace mmlio::config {

// ---- scalar conversions (reading throws mmlio::Error prefixed with `where`) -------------------
void decodeYaml(const YAML::Node& node, const std::string& where, bool& value);
void decodeYaml(const YAML::Node& node, const std::string& where, int& value);
void decodeYaml(const YAML::Node& node, const std::string& where, double& value);
void decodeYaml(const YAML::Node& node, const std::string& where, std::string& value);
void decodeYaml(const YAML::Node& node, const std::string& where, std::vector<double>& value);
/// A rigid transform: 16 numbers (4x4 row-major; a rotation off by up to 0.01 from orthonormal, as
/// hand-typed digits leave it, is replaced by the nearest rotation with a warning), or a map
/// {xyz: [x, y, z], rpy_deg: [roll, pitch, yaw]} (R = Rz(yaw) Ry(pitch) Rx(roll), as ROS and URDF)
/// or {xyz: [...], quaternion: [qx, qy, qz, qw]}.
void decodeYaml(const YAML::Node& node, const std::string& where, Eigen::Isometry3d& value);

/// YAML text of a value; `indent` is the column continuation lines start at (used by matrices).
std::string encodeYaml(bool value, int indent);
std::string encodeYaml(int value, int indent);
std::string encodeYaml(double value, int indent);
std::string encodeYaml(const std::string& value, int indent);
std::string encodeYaml(const std::vector<double>& value, int indent);
std::string encodeYaml(const Eigen::Isometry3d& value, int indent);

/// Checks that a 4x4 matrix is a rigid transform: orthonormal rotation within 1e-6, det +1,
/// bottom row 0 0 0 1. Throws mmlio::Error prefixed with `where`.
void validateRigidTransform(const Eigen::Matrix4d& m, const std::string& where);

/// `file:line` of a node (line 1-based), or just `file` when the node has no position.
std::string yamlLocation(const std::string& file, const YAML::Node& node);

class YamlBinder {
 public:
  using Defaults = std::map<std::string, std::string>;  // key path ("lidars[].name") -> text

  /// Reading `node` (a map, or null/absent for "all defaults") from `file`; key paths in errors
  /// start with `prefix` (e.g. "lidars[1].").
  YamlBinder(const YAML::Node& node, std::string file, std::string prefix = "");
  /// Emitting documented YAML to `out` with keys at column `indent`. With `defaults` (from a
  /// recording pass), each doc comment ends with "(default: X)".
  explicit YamlBinder(std::ostream& out, int indent = 0, const Defaults* defaults = nullptr, std::string prefix = "");
  /// Recording: stores the text of every field's value in `record` (list items under "key[].").
  explicit YamlBinder(Defaults* record, std::string prefix = "");

  bool reading() const { return mode_ == Mode::kRead; }

  template <typename T> YamlBinder& field(const std::string& key, T& value, const std::string& doc) {
    switch (mode_) {
      case Mode::kRead: {
        const YAML::Node child = lookup(key);
        if (child) decodeYaml(child, where(key, child), value);
        break;
      }
      case Mode::kRecord:
        (*record_)[prefix_ + key] = defaultText(value);
        break;
      case Mode::kEmit:
        emitKey(key, withDefault(key, doc), " " + encodeYaml(value, keyColumn() + static_cast<int>(key.size()) + 3));
        break;
    }
    return *this;
  }

  /// A value spelled in YAML as one of `spellings` ({value, name}), e.g. an enum; reading any
  /// other name is an error listing the valid ones.
  template <typename E> YamlBinder& choice(const std::string& key, E& value,
                                           const std::vector<std::pair<E, std::string>>& spellings,
                                           const std::string& doc) {
    if (mode_ != Mode::kRead) {
      std::string text;
      for (const auto& [v, name] : spellings)
        if (v == value) text = name;
      return field(key, text, doc);
    }
    const YAML::Node child = lookup(key);
    if (!child) return *this;
    std::string text;
    decodeYaml(child, where(key, child), text);
    std::string valid;
    for (const auto& [v, name] : spellings) {
      if (name == text) {
        value = v;
        return *this;
      }
      valid += (valid.empty() ? "" : ", ") + name;
    }
    throwChoice(where(key, child), valid, text);
    return *this;
  }

  /// A nested map bound by `bind(YamlBinder&, T&)`.
  template <typename T, typename BindFn>
  YamlBinder& section(const std::string& key, T& sub, BindFn bind, const std::string& doc) {
    switch (mode_) {
      case Mode::kRead: {
        const YAML::Node child = lookup(key);
        if (child) {
          YamlBinder nested(child, file_, prefix_ + key + ".");
          bind(nested, sub);
          nested.finish();
        }
        break;
      }
      case Mode::kRecord: {
        YamlBinder nested(record_, prefix_ + key + ".");
        bind(nested, sub);
        break;
      }
      case Mode::kEmit: {
        emitKey(key, doc, "");
        YamlBinder nested(*out_, indent_ + 2, defaults_, prefix_ + key + ".");
        bind(nested, sub);
        break;
      }
    }
    return *this;
  }

  /// A sequence of maps, each bound by `bind(YamlBinder&, T&)` starting from a default T. When
  /// the key is present the list replaces the default list entirely.
  template <typename T, typename BindFn>
  YamlBinder& list(const std::string& key, std::vector<T>& items, BindFn bind, const std::string& doc) {
    switch (mode_) {
      case Mode::kRead: {
        const YAML::Node child = lookup(key);
        if (!child) break;
        if (!child.IsSequence() && !child.IsNull()) throwNotA("a sequence", key, child);
        items.clear();
        for (std::size_t i = 0; child.IsSequence() && i < child.size(); ++i) {
          T item{};
          YamlBinder nested(child[i], file_, prefix_ + key + "[" + std::to_string(i) + "].");
          bind(nested, item);
          nested.finish();
          items.push_back(std::move(item));
        }
        break;
      }
      case Mode::kRecord: {  // per-item defaults come from a default-constructed T
        T item{};
        YamlBinder nested(record_, prefix_ + key + "[].");
        bind(nested, item);
        break;
      }
      case Mode::kEmit: {
        emitKey(key, doc, items.empty() ? " []" : "");
        for (auto& item : items) {
          YamlBinder nested(*out_, indent_ + 2, defaults_, prefix_ + key + "[].");
          nested.list_item_pending_ = true;
          bind(nested, item);
        }
        break;
      }
    }
    return *this;
  }

  /// Reading: throws mmlio::Error naming the first key that no field/section/list declared (with
  /// the declared keys as the fix) or that appears twice. Otherwise a no-op.
  void finish() const;

  /// Reading: whether the node holds `key` (a field left out takes its default).
  bool has(const std::string& key) const;
  /// "file:line" of the node being read, for messages about it as a whole.
  std::string location() const;
  /// Key path of `key` for messages, e.g. "lidars[1].topic".
  std::string path(const std::string& key) const { return prefix_ + key; }
  const std::string& file() const { return file_; }

 private:
  enum class Mode { kRead, kEmit, kRecord };

  template <typename T> static std::string defaultText(const T& value) { return encodeYaml(value, 0); }
  static std::string defaultText(const Eigen::Isometry3d& value);

  YAML::Node lookup(const std::string& key);       // child(key), and key counts as declared (finish())
  YAML::Node child(const std::string& key) const;  // the node under key, Undefined if absent
  [[noreturn]] static void throwChoice(const std::string& where, const std::string& valid, const std::string& got);
  std::string where(const std::string& key, const YAML::Node& node) const;
  [[noreturn]] void throwNotA(const std::string& what, const std::string& key, const YAML::Node& node) const;
  std::string withDefault(const std::string& key, const std::string& doc) const;
  void emitKey(const std::string& key, const std::string& doc, const std::string& value_text);
  int keyColumn() const { return indent_ + (list_item_pending_ ? 2 : 0); }

  Mode mode_;
  std::string prefix_;
  // reading
  YAML::Node node_;
  std::string file_;
  std::vector<std::string> declared_;
  // emitting
  std::ostream* out_ = nullptr;
  int indent_ = 0;
  bool list_item_pending_ = false;  // next key opens a "- " sequence item
  const Defaults* defaults_ = nullptr;
  // recording
  Defaults* record_ = nullptr;
};

/// Documented YAML of `value` (every field, its doc and "(default: X)" from a default T).
template <typename T, typename BindFn> std::string documentedYaml(T& value, BindFn bind) {
  YamlBinder::Defaults defaults;
  T default_value{};
  YamlBinder recorder(&defaults);
  bind(recorder, default_value);
  std::ostringstream os;
  YamlBinder writer(os, 0, &defaults);
  bind(writer, value);
  return os.str();
}

}  // namespace mmlio::config
