#include "mmlio/pipeline/json.hpp"

#include <cstdio>

namespace mmlio::pipeline {

std::string plainText(const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_number_float()) {  // for people: 6 significant digits, as the terminal tables
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.6g", value.get<double>());
    return buf;
  }
  return value.dump();
}

}  // namespace mmlio::pipeline
