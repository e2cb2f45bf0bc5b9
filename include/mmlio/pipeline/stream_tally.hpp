#pragma once
// Accounts for every sensor stream (each LiDAR, the IMU): messages received and messages missing.
// A transport that loses clouds, a driver that skips sweeps, a bag recorded with holes and scans
// without a single valid point (dropped by the decoder) look the same from here: an interval of k
// periods between two messages means k - 1 are missing. Nothing else would notice: the estimator
// bridges a missing sweep, and the IMU's preintegration a missing sample.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::pipeline {

class StreamTally {
 public:
  struct Gap {
    Stamp after_ns = 0;  // the last scan before it
    std::size_t missing = 0;
  };
  struct Stream {
    std::size_t received = 0, missing = 0;
    double period_s = 0.0;  // median of the latest intervals
    Stamp first_ns = 0, last_ns = 0;
    std::vector<Gap> gaps;  // the first kMaxListed
    std::size_t expected() const { return received + missing; }
  };
  static constexpr std::size_t kMaxListed = 20;
  static constexpr int kPeriodWindow = 16;   // intervals the period is the median of
  static constexpr int kLearnIntervals = 5;  // before the first judgement

  /// A sensor the run uses: listed even if it never sends a message.
  void expect(const std::string& sensor) { streams_[sensor]; }
  /// One accepted message of `sensor` (in order), stamped stamp_ns (a scan's start).
  void add(const std::string& sensor, Stamp stamp_ns);
  /// The streams as of `end_ns`, the stream's end: a sensor that stopped before the others did
  /// misses the messages it would have sent since (0: as of its own last message).
  std::map<std::string, Stream> streamsUntil(Stamp end_ns) const;

 private:
  struct State {
    std::vector<Stamp> intervals;  // ring of the latest kPeriodWindow (gaps left out)
    std::vector<Stamp> learning;   // where the first kLearnIntervals intervals began
    std::size_t next = 0;
  };
  static Stamp period(const State& s);
  static void recordMissing(Stream* st, Stamp after_ns, std::size_t missing);
  /// Counts the scans missing in an interval of this many periods; true if any were.
  static bool judge(Stream* st, Stamp after_ns, Stamp interval, Stamp period);

  std::map<std::string, Stream> streams_;
  std::map<std::string, State> state_;
};

}  // namespace mmlio::pipeline
