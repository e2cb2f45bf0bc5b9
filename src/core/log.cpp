#include "mmlio/core/log.hpp"

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
    case Level::kDebug: return "debug: ";
    case Level::kInfo: return "";
    case Level::kWarn: return "warning: ";
    case Level::kError: return "error: ";
    default: return "";
  }
}
}  // namespace

void configure(Level min_level, Sink sink) {
  std::lock_guard<std::mutex> lock(state().mutex);
  state().min_level = min_level;
  state().sink = std::move(sink);
}

Level minLevel() { return state().min_level; }

void write(Level level, const std::string& message) {
  std::lock_guard<std::mutex> lock(state().mutex);
  if (state().sink) {
    state().sink(level, message);
  } else {
    std::cerr << prefix(level) << message << '\n';
  }
}

}  // namespace mmlio::log
