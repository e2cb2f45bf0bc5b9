#pragma once
// Split and merge (paper, "Spatial-temporal Calibration"; Chen et al. 2021 backpack): the
// reference LiDAR's sweeps define time windows [start, end); every LiDAR's points are queued by
// absolute time and cut into those windows, so one output sweep holds every LiDAR's points of
// the same time span, with time_s relative to the window start.
//
// Windows are contiguous: each starts where the previous one ended (the reference's inter-sweep
// gap goes to the next window), so no point between two windows is lost. A window is released
// once every sensor seen so far has delivered data past its end (a sensor silent for longer than
// reference_timeout_s is not waited for), or when the newest data of any sensor is max_wait_s past
// it, so a late or dead LiDAR does not stall the pipeline. Nothing is released during the first
// max_wait_s of data, so that every LiDAR has time to show up.

#include <cstddef>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "mmlio/core/types.hpp"

namespace mmlio::lidar {

struct AlignedSweep {
  Stamp start_ns = 0, end_ns = 0;  // window [start_ns, end_ns)
  std::vector<LidarScan> scans;    // one per sensor with points in the window, reference first; time_s from start_ns
};

class SweepAligner {
 public:
  struct Config {
    std::string reference;    // name of the LiDAR whose sweeps define the windows
    double max_wait_s = 0.3;  // how long (data time) to wait for other sensors' points past a window end
    double reference_timeout_s =
        0.5;  // reference silent this long -> windows from the next sensor's own frames (logged)
  };

  explicit SweepAligner(Config cfg);

  /// A scan whose start_ns is already in the common clock (sensor clock offset applied).
  void add(const LidarScan& scan);
  /// Next complete window, in time order. False when none is ready.
  bool pop(AlignedSweep* out);
  /// End of stream: every remaining window, complete or not.
  std::vector<AlignedSweep> flush();

  /// Points dropped because they arrived before the window they belong to (too late) or before
  /// the first window.
  std::size_t droppedPoints() const { return dropped_points_; }
  bool usingFallback() const { return fallback_; }

 private:
  struct TimedPoint {
    Stamp t_ns;
    Point p;
  };
  struct SensorQueue {
    std::vector<TimedPoint> points;              // sorted by t_ns; a window's are its front (from head)
    std::size_t head = 0;                        // points before it were cut; dropped now and then
    std::deque<std::pair<Stamp, Stamp>> frames;  // [start, end) of its own frames not yet windowed
    Stamp latest_ns = 0;                         // newest point time received
    std::size_t order = 0;                       // first-seen rank
  };
  struct Window {
    Stamp start_ns, end_ns;
  };

  void pushWindow(Stamp start_ns, Stamp end_ns);
  void updateFallback();
  void windowsFromFallbackFrames();
  bool complete(const Window& w) const;
  AlignedSweep cut(const Window& w);

  Config cfg_;
  std::map<std::string, SensorQueue> sensors_;
  std::deque<Window> windows_;
  bool have_window_ = false;
  Stamp last_window_end_ns_ = 0;
  Stamp newest_ns_ = 0;  // newest point time over all sensors
  bool have_data_ = false;
  Stamp first_data_ns_ = 0;
  Stamp reference_mark_ns_ = 0;  // end of the newest reference sweep (or first data time)
  bool fallback_ = false;
  bool fallback_logged_ = false;
  bool resume_logged_ = false;
  std::string fallback_sensor_;
  std::size_t dropped_points_ = 0;
};

}  // namespace mmlio::lidar
