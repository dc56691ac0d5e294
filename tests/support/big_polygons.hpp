#pragma once
// The big polygons of issue 18's tests and benchmark (geometry/simplify, the path around a
// big polygon), all centred at the origin.

#include "geometry/types.hpp"

#include <cmath>
#include <cstddef>

namespace staa::test {

// n vertices round the origin, alternately at r_even and r_odd: a toothed ring (5.0, 4.9),
// a spiky star (5.0, 0.5), a fine circle (5.0, 5.0).
inline Polygon alternating(std::size_t n, double r_even, double r_odd) {
  Polygon p;
  p.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 2.0 * kPi * static_cast<double>(k) / static_cast<double>(n);
    const double r = k % 2 == 0 ? r_even : r_odd;
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return p;
}

// A round room's wall as a CAD export gives it: an annulus (5.0 to 5.2 m) with a 1 m door
// at angle 0, per_arc vertices along each arc; the outer arc is convex, the inner one concave.
inline Polygon roundRoomWall(std::size_t per_arc) {
  const double r_in = 5.0, r_out = 5.2;
  const double half_in = 0.5 / r_in, half_out = 0.5 / r_out;  // the door's half-angle on each arc
  Polygon p;
  p.reserve(2 * per_arc);
  for (std::size_t k = 0; k < per_arc; ++k) {
    const double a = half_out + (2.0 * kPi - 2.0 * half_out) * static_cast<double>(k) / static_cast<double>(per_arc - 1);
    p.push_back({r_out * std::cos(a), r_out * std::sin(a)});
  }
  for (std::size_t k = 0; k < per_arc; ++k) {
    const double a = 2.0 * kPi - half_in - (2.0 * kPi - 2.0 * half_in) * static_cast<double>(k) / static_cast<double>(per_arc - 1);
    p.push_back({r_in * std::cos(a), r_in * std::sin(a)});
  }
  return p;
}

}  // namespace staa::test
