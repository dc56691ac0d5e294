#pragma once
// Exact orientation: the sign of the determinant | b - a, c - a | decided exactly for any
// finite double inputs, so visibility, containment and tangency give the same answer on
// every platform and under any conforming floating-point evaluation (with or without fused
// multiply-adds). Shewchuk's floating-point filter decides almost every call (Shewchuk,
// "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates",
// 1997); the rest, near-collinear triples, are summed exactly. Underflow is not handled:
// coordinates are metres, and differences below 1e-150 m do not occur.

#include "geometry/types.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace staa {

namespace detail {
// The exact sign by error-free products and sums (out of line and cold: the filter's rare
// miss, kept out of the hot loops' code).
[[gnu::cold]] int orientSignExact(const Vec2& a, const Vec2& b, const Vec2& c);
// Shewchuk's ccwerrboundA, (3 + 16 eps) eps with eps = 2^-53: bounds the error of the
// evaluation below from the input coordinates, the rounding of the differences included.
inline constexpr double kOrientErrorBound = (3.0 + 16.0 * 0x1p-53) * 0x1p-53;
}  // namespace detail

// +1 when (a, b, c) turn counter-clockwise, -1 clockwise, 0 when exactly collinear.
inline int orientSign(const Vec2& a, const Vec2& b, const Vec2& c) {
  // Pivoting on a as orient() does: calls that share a and b share the difference b - a.
  const double left = (b.x() - a.x()) * (c.y() - a.y());
  const double right = (b.y() - a.y()) * (c.x() - a.x());
  const double det = left - right;
  const double bound = detail::kOrientErrorBound * (std::abs(left) + std::abs(right));
  // Branch-free on the common path: the signs of random triples would mispredict. A bound
  // of 0 means both products are 0, so a difference is exactly 0 and so is the determinant.
  const int sign = (det > bound) - (det < -bound);
  if (sign != 0 || bound == 0.0) [[likely]] return sign;
  // Two equal points (a corner asked about its own neighbour, a segment's end on an edge's
  // end): the triangle is degenerate, exactly 0 without the exact stage.
  if (c == b || c == a || a == b) return 0;
  return detail::orientSignExact(a, b, c);
}

// The largest coordinate magnitude of a point (for orientStaticBound).
inline double maxAbsCoordinate(const Vec2& p) { return std::max(std::abs(p.x()), std::abs(p.y())); }

// A bound that orientSign's filter never exceeds for points whose coordinates all lie in
// [-m, m] (a static filter, as CGAL's): with m rounded up to a power of two p, the
// differences stay within 2p, the products within 4p^2 and their sum within 8p^2, all
// exactly, so the filter's bound is at most kOrientErrorBound * 8p^2. Infinite for a
// non-finite or huge m (then the static test never decides); tiny m are raised to 2^-400 so
// that p^2 does not underflow.
inline double orientStaticBound(double m) {
  if (!(m < 0x1p500)) return std::numeric_limits<double>::infinity();
  // p: the power of two of m's exponent field, doubled (>= m).
  const auto bits = std::bit_cast<std::uint64_t>(std::max(m, 0x1p-400)) & 0x7ff0000000000000ULL;
  const double p = 2.0 * std::bit_cast<double>(bits);
  return detail::kOrientErrorBound * 8.0 * p * p;
}

// The determinant as orientSign evaluates it (rounded; its sign is only trusted beyond a
// filter's bound). Written once so that tests of one triple share the expression.
inline double orientDeterminant(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// orientSign for points within the coordinate bound `static_bound` was made for
// (orientStaticBound): a determinant beyond it needs no further test, so the hot loops of
// the path search pay about what the plain orientation costs.
inline int orientSign(const Vec2& a, const Vec2& b, const Vec2& c, double static_bound) {
  const double det = orientDeterminant(a, b, c);
  const int sign = (det > static_bound) - (det < -static_bound);
  if (sign != 0) [[likely]] return sign;
  return orientSign(a, b, c);
}

// orientSign(a, b, c, bound) * orientSign(a, b, d, bound): the sides of the line ab that c
// and d lie on (+1 the same, -1 opposite, 0 one on it). The tangency tests ask this of most
// node pairs; one branch decides it when the static filter decides both signs.
inline int orientSignProduct(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d, double static_bound) {
  const double dc = orientDeterminant(a, b, c);
  const double dd = orientDeterminant(a, b, d);
  if (std::min(std::abs(dc), std::abs(dd)) > static_bound) [[likely]] return (dc > 0.0) == (dd > 0.0) ? 1 : -1;
  return orientSign(a, b, c) * orientSign(a, b, d);
}

// Whether c and d lie strictly on the same side of the line ab, as far as the static filter
// can tell without the exact stage: true only when both signs are decided and equal.
inline bool strictlySameSideFiltered(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d,
                                     double static_bound) {
  const double dc = orientDeterminant(a, b, c);
  const double dd = orientDeterminant(a, b, d);
  return std::min(dc, dd) > static_bound || std::max(dc, dd) < -static_bound;
}

}  // namespace staa
