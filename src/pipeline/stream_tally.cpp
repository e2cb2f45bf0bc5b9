#include "mmlio/pipeline/stream_tally.hpp"

#include <algorithm>
#include <cmath>

namespace mmlio::pipeline {

Stamp StreamTally::period(const State& s) {
  if (s.intervals.empty()) return 0;
  std::vector<Stamp> v = s.intervals;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

void StreamTally::recordMissing(Stream* st, Stamp after_ns, std::size_t missing) {
  st->missing += missing;
  if (st->gaps.size() < kMaxListed) st->gaps.push_back({after_ns, missing});
}

void StreamTally::add(const std::string& sensor, Stamp stamp_ns) {
  Stream& st = streams_[sensor];
  State& s = state_[sensor];
  if (st.received == 0) st.first_ns = stamp_ns;
  ++st.received;
  const Stamp last_ns = st.last_ns;
  st.last_ns = stamp_ns;
  if (st.received == 1) return;
  const Stamp interval = stamp_ns - last_ns;
  if (s.intervals.size() < static_cast<std::size_t>(kLearnIntervals)) {
    // The period is learnt from the first intervals (their median: one of them may be a gap
    // itself), which are then judged by it like every later one.
    s.intervals.push_back(interval);
    s.learning.push_back(last_ns);
    if (s.intervals.size() < static_cast<std::size_t>(kLearnIntervals)) return;
    const Stamp p = period(s);
    for (std::size_t k = 0; k < s.intervals.size(); ++k) judge(&st, s.learning[k], s.intervals[k], p);
    s.learning.clear();
    st.period_s = toSec(p);
    return;
  }
  const Stamp p = period(s);
  if (!judge(&st, last_ns, interval, p)) {
    if (s.intervals.size() < static_cast<std::size_t>(kPeriodWindow)) {
      s.intervals.push_back(interval);
    } else {
      s.intervals[s.next] = interval;
      s.next = (s.next + 1) % kPeriodWindow;
    }
  }
  st.period_s = toSec(period(s));
}

bool StreamTally::judge(Stream* st, Stamp after_ns, Stamp interval, Stamp period) {
  if (period <= 0) return false;
  const double periods = static_cast<double>(interval) / static_cast<double>(period);
  if (periods < 1.5) return false;
  recordMissing(st, after_ns, static_cast<std::size_t>(std::lround(periods)) - 1);
  return true;
}

std::map<std::string, StreamTally::Stream> StreamTally::streamsUntil(Stamp end_ns) const {
  std::map<std::string, Stream> out = streams_;
  for (auto& [sensor, st] : out) {
    const auto state = state_.find(sensor);
    const Stamp p = state == state_.end() ? 0 : period(state->second);
    if (p <= 0 || end_ns <= st.last_ns) continue;
    // The last scan itself lasts a period; a stream that ends within another one is whole.
    const double periods = static_cast<double>(end_ns - st.last_ns) / static_cast<double>(p);
    if (periods >= 2.5) recordMissing(&st, st.last_ns, static_cast<std::size_t>(std::floor(periods - 1.0)));
  }
  return out;
}

}  // namespace mmlio::pipeline
