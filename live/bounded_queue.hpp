#pragma once
// Hand-off between the ROS callbacks (producers, never blocked) and the one processing thread
// (consumer). Bounded per class of item: a burst of point clouds while a slow sweep is being
// estimated is dropped (and counted) instead of growing memory or stalling the spinner, and IMU
// samples have their own, larger budget so they are not crowded out by clouds. A class that evicts
// its oldest drops the oldest waiting item for a new one (a node that falls behind then works on
// the newest sweeps, at a bounded lag); the others drop the new item at the door.
#include <algorithm>
#include <array>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>

namespace mmlio::live {

template <class T, std::size_t NumClasses> class BoundedQueue {
 public:
  /// capacity[c]: most items of class c waiting at once; evicts_oldest[c]: a full class c drops
  /// its oldest waiting item for a new one (else the new one).
  explicit BoundedQueue(std::array<std::size_t, NumClasses> capacity, std::array<bool, NumClasses> evicts_oldest = {})
      : capacity_(capacity), evicts_oldest_(evicts_oldest) {}

  /// False when `item` was dropped: class `c` is full and keeps what waits, or the queue is
  /// closed. An eviction of an older item returns true. Every drop for want of room counts for its
  /// class; what arrives after close() (the node is stopping, the drivers are not) is refused
  /// uncounted. Never blocks on the consumer.
  bool push(std::size_t c, T item) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!closed_ && queued_[c] >= capacity_[c] && evicts_oldest_[c] && capacity_[c] > 0) {
        const auto oldest = std::find_if(items_.begin(), items_.end(), [c](const Entry& e) { return e.cls == c; });
        items_.erase(oldest);
        --queued_[c];
        ++dropped_[c];
      }
      if (closed_) return false;
      if (queued_[c] >= capacity_[c]) {
        ++dropped_[c];
        return false;
      }
      items_.push_back({c, std::move(item)});
      ++queued_[c];
    }
    ready_.notify_one();
    return true;
  }

  /// Waits for the oldest item; false once the queue is closed and empty.
  bool pop(T* out) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (items_.empty()) return false;
    *out = std::move(items_.front().item);
    --queued_[items_.front().cls];
    items_.pop_front();
    return true;
  }

  /// Refuses further pushes; pop() still returns what is queued, then false.
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  std::size_t dropped(std::size_t c) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_[c];
  }
  std::size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }

 private:
  struct Entry {
    std::size_t cls;
    T item;
  };
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Entry> items_;
  std::array<std::size_t, NumClasses> capacity_;
  std::array<bool, NumClasses> evicts_oldest_;
  std::array<std::size_t, NumClasses> queued_{};
  std::array<std::size_t, NumClasses> dropped_{};
  bool closed_ = false;
};

}  // namespace mmlio::live
