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

Json matrixRows(const Eigen::Isometry3d& T) {
  Json rows = Json::array();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) rows.push_back(T.matrix()(r, c));
  return rows;
}

}  // namespace mmlio::pipeline
