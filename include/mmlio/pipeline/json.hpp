#pragma once
// A minimal ordered JSON value for the run report: objects keep insertion order so
// report.json reads top-down like report.md. Numbers that are not finite become null.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace mmlio::pipeline {

class Json {
 public:
  Json() = default;  // null
  Json(double v) : kind_(Kind::kNumber), number_(v) {}
  Json(int v) : kind_(Kind::kNumber), number_(v), integer_(true) {}
  Json(std::int64_t v) : kind_(Kind::kNumber), number_(static_cast<double>(v)), integer_(true) {}
  Json(std::size_t v) : kind_(Kind::kNumber), number_(static_cast<double>(v)), integer_(true) {}
  Json(bool v) : kind_(Kind::kBool), bool_(v) {}
  Json(const char* v) : kind_(Kind::kString), string_(v) {}
  Json(std::string v) : kind_(Kind::kString), string_(std::move(v)) {}

  static Json object() { Json j; j.kind_ = Kind::kObject; return j; }
  static Json array() { Json j; j.kind_ = Kind::kArray; return j; }

  /// Object member access; creates the member (and turns null into an object).
  Json& operator[](const std::string& key);
  void push_back(Json value);

  bool isObject() const { return kind_ == Kind::kObject; }
  bool isScalar() const { return kind_ != Kind::kObject && kind_ != Kind::kArray; }
  /// Members of an object in insertion order (empty for other kinds).
  const std::vector<std::pair<std::string, Json>>& members() const { return members_; }
  /// Text of a scalar without JSON quoting ("0.25", "hvi", "true", "null").
  std::string text() const;

  /// Serialises; indent < 0 gives one line.
  std::string dump(int indent = 2) const;

 private:
  enum class Kind { kNull, kNumber, kBool, kString, kObject, kArray };
  void dumpTo(std::string& out, int indent, int depth) const;

  Kind kind_ = Kind::kNull;
  double number_ = 0.0;
  bool integer_ = false;
  bool bool_ = false;
  std::string string_;
  std::vector<std::pair<std::string, Json>> members_;
  std::vector<Json> items_;
};

}  // namespace mmlio::pipeline
