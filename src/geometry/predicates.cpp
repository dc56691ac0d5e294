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

}  // namespace

int orientSignExact(const Vec2& a, const Vec2& b, const Vec2& c) {
  // (a - c) x (b - c) expanded into products of the inputs (the c.x * c.y terms cancel);
  // each product is p + fma(x, y, -p) exactly, whatever the hardware.
  const double xs[6] = {a.x(), -a.x(), -c.x(), -a.y(), a.y(), c.y()};
  const double ys[6] = {b.y(), c.y(), b.y(), b.x(), c.x(), b.x()};
  std::array<double, 12> e{};
  std::size_t n = 0;
  for (int k = 0; k < 6; ++k) {
    const double p = xs[k] * ys[k];
    grow(e, n, p);
    grow(e, n, std::fma(xs[k], ys[k], -p));
  }
  for (std::size_t i = n; i-- > 0;) {
    if (e[i] != 0.0) return e[i] > 0.0 ? 1 : -1;
  }
  return 0;
}

}  // namespace staa::detail
