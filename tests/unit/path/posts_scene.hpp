#pragma once
// Three 0.1 m posts about `c` (1.02 m apart) whose shapes grown by the paper agent's
// circumradius (0.472 m) close the gaps between them but leave a small hole in the middle:
// M''s free space there is a sliver cut off from the rest. Used by the nudged-start tests.

#include "map/polygon_map.hpp"

namespace staa::test {

inline PolygonMap postsAroundAHole(const Vec2& c) {
  const auto post = [](const Vec2& p) {
    return Polygon{p + Vec2(-0.05, -0.05), p + Vec2(0.05, -0.05), p + Vec2(0.05, 0.05), p + Vec2(-0.05, 0.05)};
  };
  PolygonMap m;
  m.name = "posts";
  m.bounds = Box{{0, 0}, {10, 5}};
  m.obstacles = {post(c + Vec2(-0.51, -0.2945)), post(c + Vec2(0.51, -0.2945)), post(c + Vec2(0.0, 0.589))};
  return m;
}

// Just below the hole: inside M', its nearest free point in the hole.
inline Vec2 startBelowTheHole(const Vec2& c) { return c + Vec2(0.0, -0.13); }

}  // namespace staa::test
