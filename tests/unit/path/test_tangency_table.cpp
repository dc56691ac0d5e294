#include "path/tangency_table.hpp"

#include "geometry/clipper_ops.hpp"
#include "map/generate.hpp"
#include "path/minimal_construct.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace staa {
namespace {

// The office's obstacles as the global path sees them (M': grown by the paper agent's
// circumradius, rounded corners), and as they are (rectangles meeting exactly).
std::vector<Polygon> officeGrown() { return inflateEachToSimple(generateOfficeMap().obstacles, 0.38, 0.01); }

PolygonSet setOf(const std::vector<Polygon>& polygons) {
  PolygonSet set;
  set.assign(polygons, PolygonSet::Options{});
  return set;
}

TEST(TangencyTable, EveryPairOfTheOfficesCornersAnswersAsBothTangencyTests) {
  for (const std::vector<Polygon>& polygons : {generateOfficeMap().obstacles, officeGrown()}) {
    const PolygonSet set = setOf(polygons);
    const std::shared_ptr<const TangencyTable> table = TangencyTable::forSet(set);
    ASSERT_TRUE(table);
    std::vector<std::size_t> corners;
    for (std::size_t v = 0; v < set.vertexCount(); ++v) {
      if (set.isConvexCorner(v)) {
        EXPECT_EQ(table->cornerOf(v), static_cast<std::int32_t>(corners.size()));
        corners.push_back(v);
      } else {
        EXPECT_EQ(table->cornerOf(v), -1);
      }
    }
    ASSERT_EQ(table->corners(), corners.size());
    ASSERT_GT(corners.size(), 300U);
    // The bound of the plain filter (not the table's): the exact answers must agree anyway.
    const double bound = orientStaticBound(1e3);
    std::size_t joinable = 0;
    for (std::size_t a = 0; a < corners.size(); ++a) {
      const std::size_t va = corners[a];
      for (std::size_t b = 0; b < corners.size(); ++b) {
        const std::size_t vb = corners[b];
        const bool expected =
            tangentAt(set.vertex(va), set.vertex(vb), set.vertex(set.prevVertex(va)), set.vertex(set.nextVertex(va)), bound) &&
            tangentAt(set.vertex(vb), set.vertex(va), set.vertex(set.prevVertex(vb)), set.vertex(set.nextVertex(vb)), bound);
        ASSERT_EQ(table->joinable(static_cast<std::int32_t>(a), static_cast<std::int32_t>(b)), expected)
            << "corners " << a << " and " << b;
        joinable += expected ? 1 : 0;
      }
    }
    // A real table: most pairs fail (a corner's tangent cones are narrow), some pass.
    EXPECT_GT(joinable, corners.size());
    EXPECT_LT(joinable, corners.size() * corners.size() / 2);
  }
}

TEST(TangencyTable, EqualSetsShareOneTableAndADifferentSetGetsItsOwn) {
  const std::vector<Polygon> grown = officeGrown();
  const PolygonSet a = setOf(grown), b = setOf(grown);
  const auto ta = TangencyTable::forSet(a), tb = TangencyTable::forSet(b);
  EXPECT_EQ(ta.get(), tb.get());
  std::vector<Polygon> moved = grown;
  moved[3][0].x() += 1e-9;
  const auto tm = TangencyTable::forSet(setOf(moved));
  EXPECT_NE(tm.get(), ta.get()) << "one coordinate differs by a nanometre";
}

TEST(TangencyTable, TooManyCornersGetNoTableAndTheSearchStillFindsThePath) {
  // 33 x 32 squares: 4,224 convex corners, over kMaxCorners.
  std::vector<Polygon> squares;
  for (int i = 0; i < 33; ++i) {
    for (int j = 0; j < 32; ++j) {
      const double x = 2.0 * i, y = 2.0 * j;
      squares.push_back({{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}});
    }
  }
  EXPECT_FALSE(TangencyTable::forSet(setOf(squares)));
  MinimalConstruct mc;
  mc.setStaticObstacles(squares);
  // Along the gap between the first two rows: straight.
  const MinimalConstruct::Result row = mc.query({-0.5, 1.5}, {65.5, 1.5}, false);
  ASSERT_EQ(row.status, MinimalConstruct::Status::kFound);
  EXPECT_DOUBLE_EQ(row.length, 66.0);
  // Past the first square, from its left side's middle to its right side's: round two of its
  // corners (either side, as long).
  const MinimalConstruct::Result round = mc.query({-0.5, 0.5}, {1.5, 0.5}, false);
  ASSERT_EQ(round.status, MinimalConstruct::Status::kFound);
  EXPECT_NEAR(round.length, 1.0 + 2.0 * std::hypot(0.5, 0.5), 1e-12);
  ASSERT_EQ(round.path.size(), 4U);
}

// The table changes no answer: across the office, queries with and without it return the same
// path to the bit, after the same expansions and edge checks (kept trees included: queries
// to one goal in a row).
TEST(TangencyTable, TheOfficesPathsAreTheSameToTheBitWithAndWithoutIt) {
  const std::vector<Polygon> grown = officeGrown();
  MinimalConstruct a, b;
  b.setTangencyTable(false);
  a.setStaticObstacles(grown);
  b.setStaticObstacles(grown);
  const PolygonSet set = setOf(grown);
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> u(0.5, 27.5);
  int found = 0;
  Vec2 goal{25.5, 22.5};
  for (int q = 0; q < 120; ++q) {
    if (q % 6 == 0) {
      do { goal = {u(rng), u(rng)}; } while (set.pointBlocked(goal));
    }
    Vec2 start;
    do { start = {u(rng), u(rng)}; } while (set.pointBlocked(start));
    const MinimalConstruct::Result ra = a.query(start, goal, false);
    const MinimalConstruct::Result rb = b.query(start, goal, false);
    ASSERT_EQ(ra.status, rb.status) << "query " << q;
    EXPECT_EQ(ra.expansions, rb.expansions) << "query " << q;
    EXPECT_EQ(ra.edge_checks, rb.edge_checks) << "query " << q;
    ASSERT_EQ(ra.path.size(), rb.path.size()) << "query " << q;
    EXPECT_EQ(std::memcmp(&ra.length, &rb.length, sizeof(double)), 0) << "query " << q;
    for (std::size_t i = 0; i < ra.path.size(); ++i) {
      EXPECT_EQ(std::memcmp(ra.path[i].data(), rb.path[i].data(), 2 * sizeof(double)), 0) << "query " << q << " vertex " << i;
    }
    found += ra.status == MinimalConstruct::Status::kFound ? 1 : 0;
  }
  EXPECT_GT(found, 100);
}

}  // namespace
}  // namespace staa
