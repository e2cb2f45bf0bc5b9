#include "mmlio/core/log.hpp"

#include <unistd.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <mutex>

namespace mmlio::log {
namespace {
struct State {
  Level min_level = Level::kInfo;
  Sink sink;
  std::mutex mutex;
};
State& state() {
  static State s;
  return s;
}
const char* prefix(Level level) {
  switch (level) {
    case Level::kDebug:
      return "debug: ";
    case Level::kInfo:
      return "";
    case Level::kWarn:
      return "warning: ";
    case Level::kError:
      return "error: ";
    default:
      return "";
  }
}
}  // namespace

void configure(Level min_level, Sink sink) {
  std::lock_guard<std::mutex> lock(state().mutex);
  state().min_level = min_level;
  state().sink = std::move(sink);
}

Level minLevel() { return state().min_level; }

std::string stampText(std::int64_t stamp_ns) {
  // Integer arithmetic: a double holds an epoch stamp's nanoseconds only to ~0.2 us, and rounding
  // must not turn 0.9995 s into "0.1000".
  const std::int64_t ms = (stamp_ns >= 0 ? stamp_ns + 500000 : stamp_ns - 500000) / 1000000;
  char text[32];
  std::snprintf(text, sizeof text, "%s%" PRId64 ".%03" PRId64, ms < 0 ? "-" : "",
                static_cast<std::int64_t>(std::llabs(ms) / 1000), static_cast<std::int64_t>(std::llabs(ms) % 1000));
  return text;
}

void write(Level level, const std::string& message) {
  std::lock_guard<std::mutex> lock(state().mutex);
  if (state().sink) {
    state().sink(level, message);
  } else {
    // On a terminal a progress bar may own the current line (redrawn with \r): the message takes
    // the line from its start instead of being glued to the bar's end; the bar redraws below it.
    static const bool terminal = isatty(fileno(stderr)) != 0;
    std::cerr << (terminal ? "\r\033[K" : "") << prefix(level) << message << '\n';
  }
}

}  // namespace mmlio::log
