// The functions the descriptors call per pixel and per point, cheaper than libm's: the
// build targets baseline x86-64 (no SSE4.1 round instruction), where std::floor is a call, and
// std::atan2 was the largest share of the HOG's time.
#pragma once

#include <cmath>

namespace stac::descriptors {

inline constexpr float kPi = 3.14159265358979323846f;

// std::floor(v), exactly, bit for bit: through int below 2^31 in magnitude; larger floats are
// integers already, NaN stays NaN, and an integral v (-0 too) is returned as it is.
inline float floor_exact(float v) noexcept {
  if (!(std::fabs(v) < 2147483648.0f)) return v;
  const auto t = static_cast<float>(static_cast<int>(v));  // toward zero
  if (t == v) return v;
  return t > v ? t - 1.0f : t;
}

// floor(v) as an index, without a branch (a pixel or bin index of a point, checked against the
// image's size by the caller): exactly std::floor(v) for -2^31 <= v < 2^31 - 128; below that, and
// for NaN, INT_MIN; above, 2147483520 (so that a range check rejects them all as std::floor's
// value would be rejected).
inline int floor_index(float v) noexcept {
  constexpr float kLo = -2147483648.0f, kHi = 2147483520.0f;  // representable ints
  const float c = !(v >= kLo) ? kLo : (v > kHi ? kHi : v);
  const int t = static_cast<int>(c);  // toward zero
  return t - (static_cast<float>(t) > c ? 1 : 0);
}

// atan2(y, x) in [0, 2 pi) as cv::cartToPolar gives it, (x, y) not both zero: an odd
// polynomial of degree 9 for atan on [0, 1] (Abramowitz and Stegun 4.4.49, given as 1e-5 rad; in
// float, |error| < 1.2e-5 rad, largest on the diagonals: 2.3e-5 of a 30 degree HOG bin) put in
// its octant. Test: FastMath.AngleOfIsAtan2WithinTheStatedErrorOnAllOctants.
inline float angle_of(float y, float x) noexcept {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const bool steep = ay > ax;
  // Selections only, no branch and one division: loops over pixels can do several at once.
  const float a = (steep ? ax : ay) / (steep ? ay : ax);
  const float s = a * a;
  float r =
      ((((0.0208351f * s - 0.0851330f) * s + 0.1801410f) * s - 0.3302995f) * s + 0.9998660f) * a;
  r = steep ? 0.5f * kPi - r : r;
  r = x < 0 ? kPi - r : r;
  r = y < 0 ? 2 * kPi - r : r;
  return r;
}

}  // namespace stac::descriptors
