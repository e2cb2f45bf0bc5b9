#include "mmlio/pipeline/progress.hpp"

#include <cmath>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace mmlio::pipeline {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled), tty_(isatty(fileno(stderr)) != 0) {}

void ProgressBar::update(double fraction, const std::string& status) {
  if (!enabled_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  if (tty_) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_draw_ < std::chrono::milliseconds(200)) return;
    last_draw_ = now;
    draw(fraction, status, false);
  } else {
    const int decile = static_cast<int>(fraction * 10);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    draw(fraction, status, true);
  }
}

void ProgressBar::finish(const std::string& status) {
  if (!enabled_) return;
  draw(1.0, status, true);
}

void ProgressBar::draw(double fraction, const std::string& status, bool final_line) {
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(std::lround(fraction * kWidth));
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(kWidth - filled), '.');
  std::fprintf(stderr, "%s%s [%s] %3.0f%% %s%s", tty_ ? "\r\033[K" : "", label_.c_str(), bar.c_str(), fraction * 100.0,
               status.c_str(), (final_line || !tty_) ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace mmlio::pipeline
