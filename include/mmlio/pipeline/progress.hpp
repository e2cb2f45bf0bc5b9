#pragma once
// A progress bar on stderr for long bags: redrawn at most every 0.2 s of wall time,
// silent when stderr is not a terminal except for a line every 10 %.
#include <chrono>
#include <string>

namespace mmlio::pipeline {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true);
  /// fraction in [0, 1]; status is a short text shown after the bar (e.g. "812 sweeps, 14.2x rt").
  void update(double fraction, const std::string& status);
  void finish(const std::string& status);

 private:
  void draw(double fraction, const std::string& status, bool final_line);
  std::string label_;
  bool enabled_;
  bool tty_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace mmlio::pipeline
