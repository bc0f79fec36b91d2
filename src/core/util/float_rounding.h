// Rounding a double to a float in a chosen direction: the core's float boxes, windows and limits
// contain the exact double ones because every bound is rounded this way, outward.
#pragma once

#include <cstdint>
#include <cstring>

namespace laser_raycast {
namespace core {

// The float nearest to x in the direction of -inf (floatBelow) or +inf (floatAbove) that is not
// beyond x: x itself if it is a float; beyond the largest float, that float (or the infinity on the
// far side); NaN stays NaN.
inline float floatBelow(double x) {
  const float f = static_cast<float>(x);
  // Stepping one float towards -inf is adding one to the bits of a negative float and subtracting
  // one from those of a positive one; +0 steps as -0 does, to the negative smallest subnormal.
  // Without branches: whether f rounded above x is a coin toss that a branch would mispredict.
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  const std::uint32_t signed_bits = bits | (static_cast<std::uint32_t>(f == 0) << 31);
  const std::uint32_t stepped = signed_bits + ((signed_bits >> 31) << 1) - 1;
  const std::uint32_t above = 0u - static_cast<std::uint32_t>(f > x);  // all ones or none
  const std::uint32_t result = bits ^ ((bits ^ stepped) & above);
  float g;
  std::memcpy(&g, &result, sizeof g);
  return g;
}
inline float floatAbove(double x) { return -floatBelow(-x); }

}  // namespace core
}  // namespace laser_raycast
