#pragma once
// Open addressing over 64-bit keys (packed voxel keys, voxel_key.hpp): key -> 32-bit index into
// the caller's dense storage, or a set of keys. Linear probing at load <= 1/2 in one flat array:
// voxel grids look up millions of mostly neighbouring keys per run, and std::unordered_map's
// node per entry (allocation, pointer chasing) was most of that cost.
#include <algorithm>
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
  /// Starts loading key's slot into the cache: a batch of lookups into a large index overlaps its
  /// cache misses when each key is prefetched a few lookups ahead.
  void prefetch(std::uint64_t key) const { __builtin_prefetch(&slots_[slotOf(key) & (slots_.size() - 1)]); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  void clear() {
    slots_.assign(kInitialSlots, Slot{});
    size_ = 0;
  }
  /// Empties it but keeps its slots: an index refilled with about as many keys again (a voxel
  /// filter per sweep, a submap per keyframe) neither grows step by step nor page-faults anew.
  /// Slots that the last fill left mostly unused (under 1/16) are given back.
  void reset() {
    if (16 * size_ < slots_.size() && slots_.size() > kInitialSlots) {
      std::size_t n = kInitialSlots;
      while (n < 4 * size_) n *= 2;
      slots_.assign(n, Slot{});
    } else {
      std::fill(slots_.begin(), slots_.end(), Slot{});
    }
    size_ = 0;
  }

 private:
  struct Slot {
    std::uint64_t key = 0;
    std::uint32_t value = kNone;
  };
  static constexpr std::size_t kInitialSlots = 1024;

  friend class FlatKeySet;
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

/// A set of 64-bit keys, open addressing like FlatKeyIndex but 8 bytes per slot instead of 16:
/// the back end's voxel sets hold a key per 5 cm of mapped surface (millions in a hall).
class FlatKeySet {
 public:
  FlatKeySet() { clear(); }
  /// True when key was not in the set yet.
  bool insert(std::uint64_t key) {
    if (key == kEmpty) return !std::exchange(has_empty_key_, true);
    if (2 * (size_ + 1) > slots_.size()) grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = FlatKeyIndex::slotOf(key) & mask;; i = (i + 1) & mask) {
      if (slots_[i] == kEmpty) {
        slots_[i] = key;
        ++size_;
        return true;
      }
      if (slots_[i] == key) return false;
    }
  }
  bool contains(std::uint64_t key) const {
    if (key == kEmpty) return has_empty_key_;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = FlatKeyIndex::slotOf(key) & mask;; i = (i + 1) & mask) {
      if (slots_[i] == key) return true;
      if (slots_[i] == kEmpty) return false;
    }
  }
  /// As FlatKeyIndex::prefetch.
  void prefetch(std::uint64_t key) const {
    __builtin_prefetch(&slots_[FlatKeyIndex::slotOf(key) & (slots_.size() - 1)]);
  }
  std::size_t size() const { return size_ + (has_empty_key_ ? 1 : 0); }
  bool empty() const { return size() == 0; }
  void clear() {
    slots_.assign(kInitialSlots, kEmpty);
    size_ = 0;
    has_empty_key_ = false;
  }

 private:
  // Marks a free slot; the key with this value (never a packed voxel key: those use 63 bits) is
  // kept in has_empty_key_.
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static constexpr std::size_t kInitialSlots = 1024;

  void grow() {
    std::vector<std::uint64_t> old(slots_.size() * 2, kEmpty);
    old.swap(slots_);
    size_ = 0;
    const bool had_empty_key = has_empty_key_;
    for (std::uint64_t key : old)
      if (key != kEmpty) insert(key);
    has_empty_key_ = had_empty_key;
  }

  std::vector<std::uint64_t> slots_;
  std::size_t size_ = 0;  // keys in slots_
  bool has_empty_key_ = false;
};

}  // namespace mmlio
