#pragma once
// Open addressing over 64-bit keys (packed voxel keys, voxel_key.hpp): key -> 32-bit index into
// the caller's dense storage, or a set of keys. Linear probing at load <= 1/2 in one flat array:
// voxel grids look up millions of mostly neighbouring keys per run, and std::unordered_map's
// node per entry (allocation, pointer chasing) was most of that cost.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace mmlio {

class FlatKeyIndex {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  FlatKeyIndex() { clear(); }
  /// The value stored for key, or kNone.
  std::uint32_t find(std::uint64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = slotOf(key) & mask;; i = (i + 1) & mask) {
      const Slot& s = slots_[i];
      if (s.value == kNone || s.key == key) return s.value;
    }
  }
  /// The value stored for key and false; or, when absent, `value` stored and true.
  std::pair<std::uint32_t, bool> insert(std::uint64_t key, std::uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = slotOf(key) & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (s.value == kNone) {
        s = {key, value};
        ++size_;
        return {value, true};
      }
      if (s.key == key) return {s.value, false};
    }
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  void clear() {
    slots_.assign(kInitialSlots, Slot{});
    size_ = 0;
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t value = kNone;
  };
  static constexpr std::size_t kInitialSlots = 1024;

  // splitmix64 finaliser: neighbouring voxels land in unrelated slots.
  static std::size_t slotOf(std::uint64_t h) {
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    h ^= h >> 31;
    return static_cast<std::size_t>(h);
  }
  void grow() {
    std::vector<Slot> old(slots_.size() * 2);
    old.swap(slots_);
    size_ = 0;
    for (const Slot& s : old)
      if (s.value != kNone) insert(s.key, s.value);
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

/// A set of 64-bit keys on FlatKeyIndex.
class FlatKeySet {
 public:
  /// True when key was not in the set yet.
  bool insert(std::uint64_t key) { return index_.insert(key, 0).second; }
  bool contains(std::uint64_t key) const { return index_.find(key) != FlatKeyIndex::kNone; }
  std::size_t size() const { return index_.size(); }
  bool empty() const { return index_.empty(); }
  void clear() { index_.clear(); }

 private:
  FlatKeyIndex index_;
};

}  // namespace mmlio
