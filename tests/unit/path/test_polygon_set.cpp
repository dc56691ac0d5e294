#include "path/polygon_set.hpp"

#include "visibility_reference.hpp"

#include <gtest/gtest.h>

#include <random>

namespace staa {
namespace {

PolygonSet makeSet(const std::vector<Polygon>& polys, double cell = 0.0) {
  PolygonSet set;
  set.assign(std::span<const Polygon>(polys), PolygonSet::Options{cell});
  return set;
}

const Polygon kSquare{{1, 1}, {2, 1}, {2, 2}, {1, 2}};
// A U whose pocket opens upwards (clockwise on purpose).
const Polygon kU{{0, 0}, {0, 3}, {1, 3}, {1, 1}, {2, 1}, {2, 3}, {3, 3}, {3, 0}};

TEST(PolygonSet, SegmentThroughTheInteriorIsBlockedTouchingIsNot) {
  for (double cell : {0.0, 0.5}) {
    const PolygonSet set = makeSet({kSquare}, cell);
    EXPECT_TRUE(set.segmentBlocked({0, 1.5}, {3, 1.5}));     // straight through
    EXPECT_FALSE(set.segmentBlocked({0, 0.5}, {3, 0.5}));    // below
    EXPECT_FALSE(set.segmentBlocked({0, 1}, {3, 1}));        // slides along the bottom edge
    EXPECT_TRUE(set.segmentBlocked({0, 0}, {3, 3}));         // the diagonal through two corners
    EXPECT_TRUE(set.segmentBlocked({0, 3}, {3, 0}));         // corner (1,2) to corner (2,1) inside
    EXPECT_FALSE(set.segmentBlocked({0, 2}, {2, 0}));        // touches the corner (1,1) only
    EXPECT_TRUE(set.segmentBlocked({1, 1}, {2, 2}));         // corner to corner through the inside
    EXPECT_FALSE(set.segmentBlocked({1, 1}, {2, 1}));        // along an edge, corner to corner
    EXPECT_FALSE(set.segmentBlocked({1, 2}, {0, 3}));        // leaves a corner outwards
    EXPECT_TRUE(set.segmentBlocked({1.5, 1}, {1.5, 3}));     // from inside an edge into the polygon
    EXPECT_FALSE(set.segmentBlocked({1.5, 1}, {1.5, 0}));    // from inside an edge away from it
  }
}

TEST(PolygonSet, NonConvexPocketAndReflexCorners) {
  const PolygonSet set = makeSet({kU});
  EXPECT_FALSE(set.segmentBlocked({1.5, 3.5}, {1.5, 1}));  // down into the pocket to its floor
  EXPECT_TRUE(set.segmentBlocked({1.5, 3.5}, {1.5, 0.5})); // through the floor
  EXPECT_FALSE(set.segmentBlocked({1, 1}, {2, 1}));        // along the floor, reflex to reflex
  EXPECT_TRUE(set.segmentBlocked({0.5, 2}, {2.5, 2}));     // across both arms
  // Along the left inner wall past the reflex corner (1,1) into the base.
  EXPECT_TRUE(set.segmentBlocked({1, 2}, {1, 0.5}));
  EXPECT_FALSE(set.segmentBlocked({1, 2}, {1, 1}));
  EXPECT_TRUE(set.pointBlocked({0.5, 0.5}));
  EXPECT_FALSE(set.pointBlocked({1.5, 2}));
  EXPECT_FALSE(set.pointBlocked({0, 0}));  // boundary is free
}

TEST(PolygonSet, BlockersListEachBlockingPolygonOnce) {
  const std::vector<Polygon> polys{kSquare, {{4, 1}, {5, 1}, {5, 2}, {4, 2}}, {{1, 5}, {2, 5}, {2, 6}, {1, 6}}};
  for (double cell : {0.0, 0.3}) {
    const PolygonSet set = makeSet(polys, cell);
    std::uint32_t out[8];
    const std::size_t n = set.segmentBlockers({0, 1.5}, {6, 1.5}, out);
    ASSERT_EQ(n, 2u);
    EXPECT_EQ(std::min(out[0], out[1]), 0u);
    EXPECT_EQ(std::max(out[0], out[1]), 1u);
  }
}

TEST(PolygonSet, NearestFreePointLeavesOverlappingPolygons) {
  // Two overlapping squares: the nearest boundary point of the first lies inside the second.
  const std::vector<Polygon> polys{{{0, 0}, {2, 0}, {2, 2}, {0, 2}}, {{1.5, -1}, {4, -1}, {4, 3}, {1.5, 3}}};
  const PolygonSet set = makeSet(polys);
  Vec2 out;
  ASSERT_TRUE(set.nearestFreePoint({1.8, 1.0}, out));
  // Right (0.2), left of the second (0.3), down and up (1.0) all end inside the other square;
  // the first free boundary point is on the left side x = 0, 1.8 away.
  EXPECT_NEAR(out.x(), 0.0, 1e-5);
  EXPECT_NEAR(out.y(), 1.0, 1e-5);
  EXPECT_FALSE(set.pointBlocked(out));
  // Inside only the second square: its right side x = 4 is 0.5 away.
  ASSERT_TRUE(set.nearestFreePoint({3.5, 1.0}, out));
  EXPECT_NEAR(out.x(), 4.0, 1e-5);
}

// Random segments between random points and corners against random non-convex polygons,
// some on a coarse lattice to force collinear and touching contacts: the library's local
// edge test must agree with the brute-force split-and-sample reference whenever both
// endpoints are not strictly inside a polygon.
TEST(PolygonSet, SegmentTestAgreesWithReferenceOnRandomScenes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0, blocked = 0;
  for (int scene = 0; scene < 300; ++scene) {
    const bool lattice = scene % 2 == 0;
    auto coord = [&](double lo, double hi) {
      const double v = lo + (hi - lo) * u(rng);
      return lattice ? std::round(v * 2.0) / 2.0 : v;
    };
    std::vector<Polygon> polys;
    const int count = 2 + static_cast<int>(u(rng) * 4);
    for (int k = 0; k < count; ++k) {
      if (u(rng) < 0.5) {
        const double x = coord(0, 8), y = coord(0, 8), w = 0.5 + coord(0, 2), h = 0.5 + coord(0, 2);
        polys.push_back({{x, y}, {x + w, y}, {x + w, y + h}, {x, y + h}});
      } else {
        // Star-shaped (simple, usually non-convex).
        const Vec2 c{coord(1, 9), coord(1, 9)};
        const int n = 5 + static_cast<int>(u(rng) * 6);
        Polygon p;
        for (int i = 0; i < n; ++i) {
          const double ang = 2.0 * kPi * (i + 0.2 + 0.6 * u(rng)) / n;
          const double r = lattice ? 1.0 + std::round(u(rng) * 2.0) / 2.0 : 0.4 + 1.6 * u(rng);
          p.push_back(c + r * Vec2(std::cos(ang), std::sin(ang)));
        }
        polys.push_back(p);
      }
    }
    const PolygonSet set = makeSet(polys, scene % 3 == 0 ? 0.0 : 0.7);
    std::vector<Vec2> pts;
    for (const Polygon& p : polys) pts.insert(pts.end(), p.begin(), p.end());
    for (int i = 0; i < 20; ++i) pts.push_back({coord(-1, 11), coord(-1, 11)});
    for (const Vec2& a : pts) {
      if (!test::referencePointFree(a, polys)) continue;
      for (int j = 0; j < 12; ++j) {
        const Vec2& b = pts[static_cast<std::size_t>(u(rng) * pts.size()) % pts.size()];
        if (!test::referencePointFree(b, polys)) continue;
        const bool ref = !test::referenceSegmentFree(a, b, polys);
        ASSERT_EQ(set.segmentBlocked(a, b), ref)
            << "scene " << scene << " segment (" << a.transpose() << ") -> (" << b.transpose() << ")";
        ++compared;
        blocked += ref;
      }
    }
  }
  EXPECT_GT(compared, 20000);
  EXPECT_GT(blocked, compared / 5);  // the scenes really exercise blocking
}

}  // namespace
}  // namespace staa
