#include "mmlio/pipeline/mapping_thread.hpp"

#include <malloc.h>

#include <algorithm>

#include "mmlio/core/timer.hpp"

namespace mmlio::pipeline {

MappingThread::MappingThread(backend::MappingBackend::Config cfg, std::size_t capacity)
    : cfg_(std::move(cfg)), backend_(cfg_), capacity_(std::max<std::size_t>(1, capacity)), worker_([this] { run(); }) {}

MappingThread::~MappingThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  not_empty_.notify_all();
  not_full_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void MappingThread::addSweep(estimator::SweepResult sweep) {
  backend::MappingBackend::keepWhatTheMapTakes(&sweep, handed_++, cfg_);
  std::unique_lock<std::mutex> lock(mutex_);
  not_full_.wait(lock, [this] { return queue_.size() < capacity_ || closing_; });
  if (closing_) return;
  queue_.push_back(std::move(sweep));
  queue_high_water_ = std::max(queue_high_water_, queue_.size());
  lock.unlock();
  not_empty_.notify_one();
}

void MappingThread::run() {
  while (true) {
    estimator::SweepResult sweep;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      not_empty_.wait(lock, [this] { return !queue_.empty() || closing_; });
      if (queue_.empty()) return;  // closing and drained
      sweep = std::move(queue_.front());
      queue_.pop_front();
    }
    not_full_.notify_one();
    if (error_) continue;  // the back end failed: drain without work, finish() reports it
    std::lock_guard<std::mutex> lock(backend_mutex_);
    Stopwatch watch;
    try {
      backend_.addSweep(sweep);
    } catch (...) {
      error_ = std::current_exception();
    }
    // glibc keeps what threads free in their arenas: on long runs that, not live data, made the
    // resident memory grow. Returning it every few keyframes costs well under a millisecond.
    if (sweep.keyframe && ++keyframes_ % kTrimEveryKeyframes == 0) malloc_trim(0);
    timing_.add({{"mapping_backend", watch.elapsedMs()}});
  }
}

StageStats MappingThread::timing() const {
  std::lock_guard<std::mutex> lock(backend_mutex_);
  return timing_;
}

std::size_t MappingThread::queueHighWater() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_high_water_;
}

backend::MappingBackend& MappingThread::finish() {
  if (!finished_) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    not_empty_.notify_all();
    if (worker_.joinable()) worker_.join();
    finished_ = true;
    if (error_) std::rethrow_exception(error_);
    std::lock_guard<std::mutex> lock(backend_mutex_);
    backend_.finish();
  }
  return backend_;
}

}  // namespace mmlio::pipeline
