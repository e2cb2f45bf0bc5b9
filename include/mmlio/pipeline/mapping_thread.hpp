#pragma once
// The mapping back end off the odometry's critical path: sweeps go to a MappingBackend on its own
// thread through a bounded queue. Loop search, ICP verification, pose-graph optimisation and
// submap bookkeeping then overlap with the next sweeps' odometry instead of delaying them.
//
// Deterministic by construction: the back end's results never feed back into the odometry, and it
// sees the same sweeps in the same order whatever the timing. A full queue blocks the producer
// (an offline run loses nothing; the queue bounds the memory a slow back end can hold).
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "mmlio/backend/mapping_backend.hpp"
#include "mmlio/pipeline/stage_stats.hpp"

namespace mmlio::pipeline {

class MappingThread {
 public:
  explicit MappingThread(backend::MappingBackend::Config cfg, std::size_t capacity = 16);
  ~MappingThread();
  MappingThread(const MappingThread&) = delete;
  MappingThread& operator=(const MappingThread&) = delete;

  /// Queues a tracked sweep (blocks while the queue is full).
  void addSweep(estimator::SweepResult sweep);
  /// Waits until every queued sweep is processed, stops the thread and runs the back end's final
  /// loop check. Rethrows what the back end threw. The back end may be read afterwards.
  backend::MappingBackend& finish();
  /// The back end itself; read it only after finish() (also when finish() threw).
  backend::MappingBackend& backend() { return backend_; }
  /// Milliseconds the back end spent per sweep (on its own thread); a copy, safe while running.
  StageStats timing() const;
  /// Most sweeps queued at once (at most the capacity) and the capacity.
  std::size_t queueHighWater() const;
  std::size_t capacity() const { return capacity_; }
  /// Runs f(backend) between two of the back end's sweeps, for live queries from another thread
  /// (corrected path, map); the back end waits meanwhile.
  template <class F> auto read(F&& f) const {
    std::lock_guard<std::mutex> lock(backend_mutex_);
    return f(static_cast<const backend::MappingBackend&>(backend_));
  }
  /// The same to change it (what a run starts from, before its first sweep).
  template <class F> auto update(F&& f) {
    std::lock_guard<std::mutex> lock(backend_mutex_);
    return f(backend_);
  }

 private:
  void run();

  const backend::MappingBackend::Config cfg_;
  std::size_t handed_ = 0;  // sweeps queued so far (the producer's count)
  backend::MappingBackend backend_;
  std::size_t capacity_;
  static constexpr std::size_t kTrimEveryKeyframes = 10;
  std::size_t keyframes_ = 0;  // seen by the worker
  std::deque<estimator::SweepResult> queue_;
  std::size_t queue_high_water_ = 0;
  mutable std::mutex mutex_;          // the queue
  mutable std::mutex backend_mutex_;  // the back end and its timing
  std::condition_variable not_empty_, not_full_;
  bool closing_ = false, finished_ = false;
  std::exception_ptr error_;
  StageStats timing_;
  std::thread worker_;  // last: started once everything above exists
};

}  // namespace mmlio::pipeline
