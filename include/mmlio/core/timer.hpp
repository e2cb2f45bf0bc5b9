#pragma once
// Wall-clock stopwatch for per-stage timing (reported, never asserted on).
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace mmlio {

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double elapsedMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }
  /// Milliseconds since construction or the previous lap.
  double lapMs() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

/// Stage name -> milliseconds spent in it for one sweep, in pipeline order.
using StageTimes = std::vector<std::pair<std::string, double>>;

}  // namespace mmlio
