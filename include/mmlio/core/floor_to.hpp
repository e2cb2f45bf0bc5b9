#pragma once
// floor() straight to an integer. Without SSE4.1 (the x86-64 baseline Debian builds for) std::floor
// compiles to a sequence of ~17 instructions, and voxel keys and range-image pixels ask for it for
// every point; truncation and one compare do the same.

namespace mmlio {

/// static_cast<Int>(std::floor(v)), for every finite v whose floor Int holds.
template <typename Int, typename Real> inline Int floorTo(Real v) {
  const Int truncated = static_cast<Int>(v);  // toward zero
  return truncated - static_cast<Int>(v < static_cast<Real>(truncated));
}

}  // namespace mmlio
