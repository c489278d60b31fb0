// pectus: integer grid keys and a flat hash map from them, the storage of sparse voxel grids (the
// partition-of-unity cells of the RBF implicit, the corners and cubes of marching cubes).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "shape/core/error.h"

namespace pectus {

/// Grid coordinates (i, j, k) packed into 63 bits: 21 bits per axis, each offset by 2^20, so an axis
/// holds indices in [-2^20, 2^20). Neighbours differ by 1, 2^21 or 2^42.
using GridKey = std::uint64_t;

inline constexpr std::int64_t kGridKeyOffset = std::int64_t{1} << 20;
inline constexpr GridKey kGridKeyStepX = 1;
inline constexpr GridKey kGridKeyStepY = GridKey{1} << 21;
inline constexpr GridKey kGridKeyStepZ = GridKey{1} << 42;

/// True if every index is in the range a GridKey holds.
inline bool GridIndexInRange(std::int64_t i, std::int64_t j, std::int64_t k) {
  return i >= -kGridKeyOffset && i < kGridKeyOffset && j >= -kGridKeyOffset && j < kGridKeyOffset &&
         k >= -kGridKeyOffset && k < kGridKeyOffset;
}

/// Packs (i, j, k); the caller checks GridIndexInRange first.
inline GridKey PackGridKey(std::int64_t i, std::int64_t j, std::int64_t k) {
  return static_cast<GridKey>(i + kGridKeyOffset) | (static_cast<GridKey>(j + kGridKeyOffset) << 21) |
         (static_cast<GridKey>(k + kGridKeyOffset) << 42);
}

/// Unpacks a key into (i, j, k).
inline Eigen::Matrix<std::int64_t, 3, 1> UnpackGridKey(GridKey key) {
  constexpr GridKey mask = (GridKey{1} << 21) - 1;
  return {static_cast<std::int64_t>(key & mask) - kGridKeyOffset,
          static_cast<std::int64_t>((key >> 21) & mask) - kGridKeyOffset,
          static_cast<std::int64_t>((key >> 42) & mask) - kGridKeyOffset};
}

/// Throws Error(kUsage) if a grid of cell `spacing` (mm) over `extent_mm` would overflow a GridKey.
/// @param[in] what  the name of the grid in the message ("marching cubes grid")
inline void CheckGridFits(double extent_mm, double spacing, const std::string& what) {
  if (!(spacing > 0.0) || !std::isfinite(spacing) || extent_mm / spacing >= double(kGridKeyOffset)) {
    ThrowUsage(what + ": spacing " + std::to_string(spacing) + " mm is too fine for an object " +
               std::to_string(extent_mm) + " mm across (at most 2^20 cells per axis)");
  }
}

/// An open-addressing (linear probing) hash map from GridKey to a small trivially copyable value. Keys
/// are never erased. Reads are thread-safe when nothing writes.
template <class Value>
class GridKeyMap {
 public:
  explicit GridKeyMap(std::size_t expected = 1024) { Rehash(Capacity(expected)); }

  std::size_t size() const { return size_; }

  /// The value of `key`, or nullptr.
  const Value* Find(GridKey key) const {
    std::size_t slot = Hash(key) & mask_;
    while (true) {
      const GridKey k = keys_[slot];
      if (k == key) return &values_[slot];
      if (k == kEmpty) return nullptr;
      slot = (slot + 1) & mask_;
    }
  }
  Value* Find(GridKey key) { return const_cast<Value*>(static_cast<const GridKeyMap*>(this)->Find(key)); }

  /// Inserts (key, value) if the key is new. Returns the stored value and whether it was inserted.
  std::pair<Value*, bool> Insert(GridKey key, const Value& value) {
    if ((size_ + 1) * 2 > keys_.size()) Rehash(keys_.size() * 2);
    std::size_t slot = Hash(key) & mask_;
    while (true) {
      const GridKey k = keys_[slot];
      if (k == key) return {&values_[slot], false};
      if (k == kEmpty) {
        keys_[slot] = key;
        values_[slot] = value;
        ++size_;
        return {&values_[slot], true};
      }
      slot = (slot + 1) & mask_;
    }
  }

  /// Calls f(key, value&) for every entry, in no particular order.
  template <class F>
  void ForEach(F&& f) {
    for (std::size_t s = 0; s < keys_.size(); ++s) {
      if (keys_[s] != kEmpty) f(keys_[s], values_[s]);
    }
  }

 private:
  static constexpr GridKey kEmpty = ~GridKey{0};  // never a packed key (bit 63 is always 0)

  static std::size_t Capacity(std::size_t expected) {
    std::size_t c = 16;
    while (c < expected * 2) c *= 2;
    return c;
  }
  static std::size_t Hash(GridKey x) {  // splitmix64 finaliser
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return static_cast<std::size_t>(x);
  }
  void Rehash(std::size_t capacity) {
    std::vector<GridKey> old_keys(capacity, kEmpty);
    std::vector<Value> old_values(capacity);
    old_keys.swap(keys_);
    old_values.swap(values_);
    mask_ = capacity - 1;
    size_ = 0;
    for (std::size_t s = 0; s < old_keys.size(); ++s) {
      if (old_keys[s] != kEmpty) Insert(old_keys[s], old_values[s]);
    }
  }

  std::vector<GridKey> keys_;
  std::vector<Value> values_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
};

}  // namespace pectus
