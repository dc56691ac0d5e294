#pragma once
// Random polygon scenes for property tests: rectangles and star-shaped non-convex polygons
// that may overlap, optionally snapped to a coarse lattice so that edges are collinear and
// corners touch (the degenerate cases).

#include "geometry/types.hpp"

#include <cmath>
#include <random>
#include <vector>

namespace staa::test {

struct RandomScene {
  std::vector<Polygon> polygons;
};

inline RandomScene makeRandomScene(std::mt19937_64& rng, bool lattice, int min_polys, int max_polys, double extent) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto coord = [&](double lo, double hi) {
    const double v = lo + (hi - lo) * u(rng);
    return lattice ? std::round(v * 2.0) / 2.0 : v;
  };
  RandomScene scene;
  const int count = min_polys + static_cast<int>(u(rng) * (max_polys - min_polys + 1));
  for (int k = 0; k < count; ++k) {
    if (u(rng) < 0.4) {
      const double x = coord(0, extent - 1), y = coord(0, extent - 1);
      const double w = 0.5 + coord(0, 2.5), h = 0.5 + coord(0, 2.5);
      scene.polygons.push_back({{x, y}, {x + w, y}, {x + w, y + h}, {x, y + h}});
    } else {
      const Vec2 c{coord(1, extent - 1), coord(1, extent - 1)};
      const int n = 5 + static_cast<int>(u(rng) * 7);
      Polygon p;
      for (int i = 0; i < n; ++i) {
        const double ang = 2.0 * kPi * (i + 0.2 + 0.6 * u(rng)) / n;
        const double r = lattice ? 1.0 + std::round(u(rng) * 2.0) / 2.0 : 0.3 + 1.7 * u(rng);
        p.push_back(c + r * Vec2(std::cos(ang), std::sin(ang)));
      }
      if (u(rng) < 0.5) std::reverse(p.begin(), p.end());  // either winding
      scene.polygons.push_back(p);
    }
  }
  return scene;
}

}  // namespace staa::test
