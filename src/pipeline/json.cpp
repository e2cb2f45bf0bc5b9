#include "mmlio/pipeline/json.hpp"

#include <cmath>
#include <cstdio>

namespace mmlio::pipeline {

Json& Json::operator[](const std::string& key) {
  if (kind_ == Kind::kNull) kind_ = Kind::kObject;
  for (auto& [k, v] : members_)
    if (k == key) return v;
  members_.emplace_back(key, Json());
  return members_.back().second;
}

void Json::push_back(Json value) {
  if (kind_ == Kind::kNull) kind_ = Kind::kArray;
  items_.push_back(std::move(value));
}

std::string Json::dump(int indent) const {
  std::string out;
  dumpTo(out, indent, 0);
  return out;
}

namespace {
void escape(std::string& out, const std::string& s) {
  out += '"';
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  out += '"';
}
void newline(std::string& out, int indent, int depth) {
  if (indent < 0) return;
  out += '\n';
  out.append(static_cast<std::size_t>(indent * depth), ' ');
}
}  // namespace

void Json::dumpTo(std::string& out, int indent, int depth) const {
  switch (kind_) {
    case Kind::kNull: out += "null"; break;
    case Kind::kBool: out += bool_ ? "true" : "false"; break;
    case Kind::kString: escape(out, string_); break;
    case Kind::kNumber: {
      if (!std::isfinite(number_)) { out += "null"; break; }
      char buf[32];
      if (integer_) std::snprintf(buf, sizeof(buf), "%.0f", number_);
      else std::snprintf(buf, sizeof(buf), "%.6g", number_);
      out += buf;
      break;
    }
    case Kind::kObject: {
      out += '{';
      bool first = true;
      for (const auto& [k, v] : members_) {
        if (!first) out += ',';
        first = false;
        newline(out, indent, depth + 1);
        escape(out, k);
        out += indent < 0 ? ":" : ": ";
        v.dumpTo(out, indent, depth + 1);
      }
      if (!members_.empty()) newline(out, indent, depth);
      out += '}';
      break;
    }
    case Kind::kArray: {
      out += '[';
      for (std::size_t i = 0; i < items_.size(); ++i) {
        if (i) out += indent < 0 ? "," : ", ";
        items_[i].dumpTo(out, -1, depth + 1);
      }
      out += ']';
      break;
    }
  }
}

}  // namespace mmlio::pipeline

namespace mmlio::pipeline {

std::string Json::text() const {
  if (kind_ == Kind::kString) return string_;
  return dump(-1);
}

}  // namespace mmlio::pipeline
