#include "geometry/predicates.hpp"

#include <array>
#include <cstddef>

namespace staa::detail {

namespace {

// a + b = sum + err exactly (Knuth's TwoSum: no multiplication, so no contraction applies).
inline void twoSum(double a, double b, double& sum, double& err) {
  sum = a + b;
  const double bv = sum - a;
  const double av = sum - bv;
  err = (a - av) + (b - bv);
}

// a - b = diff + err exactly.
inline void twoDiff(double a, double b, double& diff, double& err) {
  diff = a - b;
  const double bv = a - diff;
  const double av = diff + bv;
  err = (a - av) + (bv - b);
}

// a * b = prod + err exactly. With a fused multiply-add in hardware, fma gives the error;
// without one, Dekker's split does, and then nothing can be contracted (glibc's software fma
// costs a hundred instructions a call).
inline void twoProduct(double a, double b, double& prod, double& err) {
  prod = a * b;
#ifdef FP_FAST_FMA
  err = std::fma(a, b, -prod);
#else
  constexpr double kSplitter = 134217729.0;  // 2^27 + 1
  const double ca = kSplitter * a, cb = kSplitter * b;
  const double ahi = ca - (ca - a), bhi = cb - (cb - b);
  const double alo = a - ahi, blo = b - bhi;
  err = alo * blo - (((prod - ahi * bhi) - alo * bhi) - ahi * blo);
#endif
}

// Adds x to a nonoverlapping expansion (components in increasing magnitude), keeping it so
// (Shewchuk's Grow-Expansion). The expansion's sign is that of its largest component.
template <std::size_t N>
inline void grow(std::array<double, N>& e, std::size_t& n, double x) {
  double q = x;
  for (std::size_t i = 0; i < n; ++i) {
    double sum = 0.0, err = 0.0;
    twoSum(q, e[i], sum, err);
    q = sum;
    e[i] = err;
  }
  e[n++] = q;
}

template <std::size_t N>
int expansionSign(const std::array<double, N>& e, std::size_t n) {
  for (std::size_t i = n; i-- > 0;) {
    if (e[i] != 0.0) return e[i] > 0.0 ? 1 : -1;
  }
  return 0;
}

}  // namespace

int orientSignExact(const Vec2& a, const Vec2& b, const Vec2& c) {
  double dx1 = 0.0, dy2 = 0.0, dy1 = 0.0, dx2 = 0.0, t1 = 0.0, t2 = 0.0, t3 = 0.0, t4 = 0.0;
  twoDiff(b.x(), a.x(), dx1, t1);
  twoDiff(c.y(), a.y(), dy2, t2);
  twoDiff(b.y(), a.y(), dy1, t3);
  twoDiff(c.x(), a.x(), dx2, t4);
  if (t1 == 0.0 && t2 == 0.0 && t3 == 0.0 && t4 == 0.0) {
    // Exact differences (the usual case for nearby points): the sign of dx1 dy2 - dy1 dx2.
    // Rounding is monotonic, so rounded products that differ are ordered as the exact ones;
    // only equal ones need their rounding errors (whose difference rounds with its sign).
    const double l = dx1 * dy2, r = dy1 * dx2;
    if (l != r) return l > r ? 1 : -1;
    double lp = 0.0, le = 0.0, rp = 0.0, re = 0.0;
    twoProduct(dx1, dy2, lp, le);
    twoProduct(dy1, dx2, rp, re);
    return (le > re) - (le < re);
  }
  // (b - a) x (c - a) expanded into products of the inputs (the a.x * a.y terms cancel).
  const double xs[6] = {b.x(), -b.x(), -a.x(), -b.y(), b.y(), a.y()};
  const double ys[6] = {c.y(), a.y(), c.y(), c.x(), a.x(), c.x()};
  std::array<double, 12> e{};
  std::size_t n = 0;
  for (int k = 0; k < 6; ++k) {
    double p = 0.0, pe = 0.0;
    twoProduct(xs[k], ys[k], p, pe);
    grow(e, n, p);
    grow(e, n, pe);
  }
  return expansionSign(e, n);
}

}  // namespace staa::detail
