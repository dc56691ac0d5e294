#pragma once
// Exact orientation: the sign of the determinant | b - a, c - a | decided exactly for any
// finite double inputs, so visibility, containment and tangency give the same answer on
// every platform and under any conforming floating-point evaluation (with or without fused
// multiply-adds). Shewchuk's floating-point filter decides almost every call (Shewchuk,
// "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates",
// 1997); the rest, near-collinear triples, are summed exactly. Underflow is not handled:
// coordinates are metres, and differences below 1e-150 m do not occur.

#include "geometry/types.hpp"

#include <cmath>

namespace staa {

namespace detail {
// The exact sign by error-free products and sums (out of line: the filter's rare miss).
int orientSignExact(const Vec2& a, const Vec2& b, const Vec2& c);
// Shewchuk's ccwerrboundA, (3 + 16 eps) eps with eps = 2^-53: bounds the error of the
// evaluation below from the input coordinates, the rounding of the differences included.
inline constexpr double kOrientErrorBound = (3.0 + 16.0 * 0x1p-53) * 0x1p-53;
}  // namespace detail

// +1 when (a, b, c) turn counter-clockwise, -1 clockwise, 0 when exactly collinear.
inline int orientSign(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double left = (a.x() - c.x()) * (b.y() - c.y());
  const double right = (a.y() - c.y()) * (b.x() - c.x());
  const double det = left - right;
  // Opposite signs (or a zero) cannot cancel: the sign of the rounded result is exact.
  if ((left > 0.0 && right <= 0.0) || (left < 0.0 && right >= 0.0) || left == 0.0) {
    return (det > 0.0) - (det < 0.0);
  }
  const double bound = detail::kOrientErrorBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return detail::orientSignExact(a, b, c);
}

}  // namespace staa
