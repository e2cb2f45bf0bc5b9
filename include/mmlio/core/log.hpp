#pragma once
// One logger with levels. The core reports degradations through it (never prints
// directly); the CLI decides the sink and the level.

#include <cstdint>
#include <functional>
#include <sstream>
#include <string>

namespace mmlio::log {

enum class Level { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3, kOff = 4 };

using Sink = std::function<void(Level, const std::string&)>;

/// Replaces the sink (default: stderr with a level prefix) and the minimum level.
void configure(Level min_level, Sink sink = nullptr);
Level minLevel();
void write(Level level, const std::string& message);

/// A bag stamp (ns) as seconds with millisecond digits, "1700000012.967": a log line's default
/// float format would print 1.7e+09, the same for every stamp of a run.
std::string stampText(std::int64_t stamp_ns);

template <typename... Args> void emit(Level level, const Args&... args) {
  if (level < minLevel()) return;
  std::ostringstream os;
  (os << ... << args);
  write(level, os.str());
}
template <typename... Args> void debug(const Args&... a) { emit(Level::kDebug, a...); }
template <typename... Args> void info(const Args&... a) { emit(Level::kInfo, a...); }
template <typename... Args> void warn(const Args&... a) { emit(Level::kWarn, a...); }
template <typename... Args> void error(const Args&... a) { emit(Level::kError, a...); }

}  // namespace mmlio::log
