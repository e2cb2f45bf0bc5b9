#pragma once
// JSON of the run report and the command outputs: nlohmann's ordered_json, so report.json reads
// top-down like report.md (members keep insertion order). Non-finite numbers are written as null.
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>

namespace mmlio::pipeline {

using Json = nlohmann::ordered_json;

/// A value as report.md shows it: strings unquoted, floating-point numbers to 6 significant digits
/// ("0.25", "hvi", "true", "null"); objects and arrays as one line of JSON.
std::string plainText(const Json& value);

/// A rigid transform as its 16 matrix entries, row-major (as calibration files write it).
Json matrixRows(const Eigen::Isometry3d& T);

}  // namespace mmlio::pipeline
