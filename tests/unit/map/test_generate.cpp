#include "map/generate.hpp"

#include "geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

// Facts asserted here are docs/paper-worlds.md's, restated from the document rather than from the
// generator, so that a slip in either shows up as a failure.

namespace staa {
namespace {

// A point is blocked when it lies inside or on the boundary of any obstacle.
bool blocked(const PolygonMap& m, const Vec2& p) {
  return std::any_of(m.obstacles.begin(), m.obstacles.end(),
                     [&](const Polygon& o) { return locatePoint(p, o) != Containment::kOutside; });
}

// Distance from a free point to the nearest obstacle edge.
double clearance(const PolygonMap& m, const Vec2& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const Polygon& o : m.obstacles) d = std::min(d, distanceToEdges(p, o));
  return d;
}

// The obstacle containing p (inside, not on the boundary), or nullptr.
const Polygon* obstacleAt(const PolygonMap& m, const Vec2& p) {
  for (const Polygon& o : m.obstacles) {
    if (pointInPolygon(p, o)) return &o;
  }
  return nullptr;
}

bool sameBits(const Vec2& a, const Vec2& b) {
  return std::bit_cast<std::uint64_t>(a.x()) == std::bit_cast<std::uint64_t>(b.x()) &&
         std::bit_cast<std::uint64_t>(a.y()) == std::bit_cast<std::uint64_t>(b.y());
}

bool identical(const PolygonMap& a, const PolygonMap& b) {
  if (a.name != b.name || a.bounds.has_value() != b.bounds.has_value() || a.obstacles.size() != b.obstacles.size() ||
      a.goals.size() != b.goals.size()) {
    return false;
  }
  if (a.bounds && (!sameBits(a.bounds->min, b.bounds->min) || !sameBits(a.bounds->max, b.bounds->max))) return false;
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    if (a.obstacles[i].size() != b.obstacles[i].size()) return false;
    for (std::size_t k = 0; k < a.obstacles[i].size(); ++k) {
      if (!sameBits(a.obstacles[i][k], b.obstacles[i][k])) return false;
    }
  }
  for (std::size_t i = 0; i < a.goals.size(); ++i) {
    if (!sameBits(a.goals[i], b.goals[i])) return false;
  }
  return true;
}

// ---- office ----

enum class Door { kBottom, kTop, kLeft, kRight };
struct Room {
  int i, j;
  Door door;
};

// docs/paper-worlds.md's room lists, plus cell (0, 1) that we close as a room without a goal.
std::vector<Room> officeRooms(bool with_closed_cell) {
  std::vector<Room> r;
  for (int i = 1; i <= 7; ++i) r.push_back({i, 0, Door::kTop});
  for (int i = 1; i <= 7; ++i) r.push_back({i, 8, Door::kBottom});
  for (int j = 1; j <= 7; ++j) r.push_back({8, j, Door::kLeft});
  for (int j = 2; j <= 7; ++j) r.push_back({0, j, Door::kRight});
  for (int i = 3; i <= 5; ++i) r.push_back({i, 2, Door::kBottom});
  for (int i = 3; i <= 5; ++i) r.push_back({i, 6, Door::kTop});
  for (int j = 2; j <= 6; ++j) r.push_back({2, j, Door::kLeft});
  for (int j = 2; j <= 6; ++j) r.push_back({6, j, Door::kRight});
  if (with_closed_cell) r.push_back({0, 1, Door::kRight});
  return r;
}

Vec2 centre(int i, int j) { return {3.0 * i + 1.5, 3.0 * j + 1.5}; }

// The midpoint of a room's wall on `side` (0.06 m inside the cell edge: the wall's centre
// line) and the unit vector along that wall.
struct WallLine {
  Vec2 mid;
  Vec2 along;
};
WallLine wallLine(int i, int j, Door side) {
  const Vec2 c = centre(i, j);
  switch (side) {
    case Door::kBottom: return {c + Vec2(0, -1.44), Vec2(1, 0)};
    case Door::kTop: return {c + Vec2(0, 1.44), Vec2(1, 0)};
    case Door::kLeft: return {c + Vec2(-1.44, 0), Vec2(0, 1)};
    case Door::kRight: return {c + Vec2(1.44, 0), Vec2(0, 1)};
  }
  return {};
}
Vec2 outward(Door side) {
  switch (side) {
    case Door::kBottom: return {0, -1};
    case Door::kTop: return {0, 1};
    case Door::kLeft: return {-1, 0};
    case Door::kRight: return {1, 0};
  }
  return {};
}

TEST(OfficeMap, HasTheDocumentedFrameAndPassesValidation) {
  const PolygonMap m = generateOfficeMap();
  EXPECT_EQ(m.name, "office");
  ASSERT_TRUE(m.bounds.has_value());
  EXPECT_EQ(m.bounds->min, Vec2(0, 0));
  EXPECT_EQ(m.bounds->max, Vec2(27, 27));
  EXPECT_NO_THROW(validatePolygonMap(m, "office"));
  // 4 corner blocks + 44 rooms x 5 wall boxes (3 solid walls, 2 door pieces) + the centre.
  EXPECT_EQ(m.obstacles.size(), 4u + 44u * 5u + 1u);
}

TEST(OfficeMap, HasTheFortyThreeRoomCentresAsGoals) {
  const PolygonMap m = generateOfficeMap();
  ASSERT_EQ(m.goals.size(), 43u);
  // 27 outer rooms (7 + 7 + 7 + 6) and 16 inner ones (3 + 3 + 5 + 5): the paper's 43.
  const auto rooms = officeRooms(false);
  ASSERT_EQ(rooms.size(), 43u);
  for (const Room& r : rooms) {
    EXPECT_NE(std::find(m.goals.begin(), m.goals.end(), centre(r.i, r.j)), m.goals.end()) << "room " << r.i << "," << r.j;
  }
  // The closed cell (0, 1) is not one of the paper's rooms.
  EXPECT_EQ(std::find(m.goals.begin(), m.goals.end(), centre(0, 1)), m.goals.end());
  for (const Vec2& g : m.goals) {
    EXPECT_FALSE(blocked(m, g)) << g.transpose();
    // From the centre of a 3 m cell to its 0.12 m walls: 1.5 - 0.12 = 1.38 m, well over 0.5.
    EXPECT_NEAR(clearance(m, g), 1.38, 1e-9) << g.transpose();
  }
}

TEST(OfficeMap, EveryRoomHasOnePassableDoorOfOnePointThreeFiveMetres) {
  const PolygonMap m = generateOfficeMap();
  for (const Room& r : officeRooms(true)) {
    SCOPED_TRACE("room " + std::to_string(r.i) + "," + std::to_string(r.j));
    const WallLine door = wallLine(r.i, r.j, r.door);
    // The gap is 1.35 m, centred: free to +-0.67 m, walled from +-0.68 m.
    EXPECT_FALSE(blocked(m, door.mid));
    EXPECT_FALSE(blocked(m, door.mid + 0.67 * door.along));
    EXPECT_FALSE(blocked(m, door.mid - 0.67 * door.along));
    EXPECT_TRUE(blocked(m, door.mid + 0.68 * door.along));
    EXPECT_TRUE(blocked(m, door.mid - 0.68 * door.along));
    // The two pieces: 0.825 m long each, 0.12 m thick, their inner ends 1.35 m apart.
    const Polygon* lo = obstacleAt(m, door.mid - 1.0 * door.along);
    const Polygon* hi = obstacleAt(m, door.mid + 1.0 * door.along);
    ASSERT_NE(lo, nullptr);
    ASSERT_NE(hi, nullptr);
    const Box blo = boundingBox(*lo), bhi = boundingBox(*hi);
    const int a = door.along.x() != 0.0 ? 0 : 1;  // the axis along the wall
    EXPECT_NEAR(blo.max[a] - blo.min[a], 0.825, 1e-12);
    EXPECT_NEAR(bhi.max[a] - bhi.min[a], 0.825, 1e-12);
    EXPECT_NEAR(blo.max[1 - a] - blo.min[1 - a], 0.12, 1e-12);
    EXPECT_NEAR(bhi.min[a] - blo.max[a], 1.35, 1e-12);
    EXPECT_NEAR(0.5 * (bhi.min[a] + blo.max[a]), door.mid[a], 1e-12);
    // Walking from the room's centre straight out through the door into the corridor.
    const Vec2 c = centre(r.i, r.j);
    for (double s = 0.0; s <= 2.5; s += 0.05) EXPECT_FALSE(blocked(m, c + s * outward(r.door))) << "at " << s << " m";
    // The other three walls are solid at their midpoints.
    for (Door side : {Door::kBottom, Door::kTop, Door::kLeft, Door::kRight}) {
      if (side != r.door) {
        EXPECT_TRUE(blocked(m, wallLine(r.i, r.j, side).mid));
      }
    }
  }
}

TEST(OfficeMap, TheCorridorRingIsFree) {
  const PolygonMap m = generateOfficeMap();
  int cells = 0, samples = 0;
  for (int i = 1; i <= 7; ++i) {
    for (int j = 1; j <= 7; ++j) {
      if (i != 1 && i != 7 && j != 1 && j != 7) continue;
      ++cells;
      // The whole cell, up to 1 cm from its edges (the neighbours' walls start at the edge).
      for (double x = 0.01; x < 3.0; x += 0.1) {
        for (double y = 0.01; y < 3.0; y += 0.1) {
          EXPECT_FALSE(blocked(m, {3.0 * i + x, 3.0 * j + y})) << i << "," << j << " + " << x << "," << y;
          ++samples;
        }
      }
    }
  }
  EXPECT_EQ(cells, 24);  // the 7 x 7 ring minus its 5 x 5 inside
  EXPECT_EQ(samples, 24 * 30 * 30);
}

TEST(OfficeMap, CornersAndCentreAreSolidAndTheOuterBoundaryIsClosed) {
  const PolygonMap m = generateOfficeMap();
  for (const Vec2& p : {Vec2(1.5, 1.5), Vec2(25.5, 1.5), Vec2(1.5, 25.5), Vec2(25.5, 25.5), Vec2(0.1, 0.1),
                        Vec2(2.9, 2.9), Vec2(26.9, 24.1)}) {
    EXPECT_TRUE(blocked(m, p)) << p.transpose();
  }
  for (double x = 9.05; x < 18.0; x += 0.5) {
    for (double y = 9.05; y < 18.0; y += 0.5) EXPECT_TRUE(blocked(m, {x, y})) << x << "," << y;
  }
  // 6 cm inside each outer edge, all the way round: the original's hole at cell (0, 1)
  // (x = 0, y = 3..6) is closed too.
  for (double s = 0.0; s <= 27.0; s += 0.05) {
    EXPECT_TRUE(blocked(m, {0.06, s})) << "west " << s;
    EXPECT_TRUE(blocked(m, {26.94, s})) << "east " << s;
    EXPECT_TRUE(blocked(m, {s, 0.06})) << "south " << s;
    EXPECT_TRUE(blocked(m, {s, 26.94})) << "north " << s;
  }
  // The closed cell is a room like its neighbours: free inside, door on the corridor side.
  EXPECT_FALSE(blocked(m, centre(0, 1)));
  EXPECT_FALSE(blocked(m, {2.94, 4.5}));
}

// ---- apartment ----

TEST(ApartmentMap, HasTheDocumentedWallsFurnitureAndGoals) {
  const PolygonMap m = generateApartmentMap();
  EXPECT_EQ(m.name, "apartment");
  ASSERT_TRUE(m.bounds.has_value());
  EXPECT_EQ(m.bounds->min, Vec2(0, 0));
  EXPECT_EQ(m.bounds->max, Vec2(24.4, 20.4));
  EXPECT_NO_THROW(validatePolygonMap(m, "apartment"));
  // 4 outer walls + 14 inner walls + 36 pieces of furniture, all boxes.
  ASSERT_EQ(m.obstacles.size(), 54u);
  for (const Polygon& o : m.obstacles) EXPECT_EQ(o.size(), 4u);

  // Spot checks, each box's extent exactly as listed.
  const auto hasBox = [&](double x0, double x1, double y0, double y1) {
    return std::any_of(m.obstacles.begin(), m.obstacles.end(), [&](const Polygon& o) {
      const Box b = boundingBox(o);
      return b.min == Vec2(x0, y0) && b.max == Vec2(x1, y1) && signedArea(o) > 0.0;
    });
  };
  EXPECT_TRUE(hasBox(24, 24.4, 0.2, 20.2));      // east outer wall
  EXPECT_TRUE(hasBox(0.2, 24.2, 20, 20.4));      // north outer wall
  EXPECT_TRUE(hasBox(14, 14.4, 0.2, 10.2));      // inner wall
  EXPECT_TRUE(hasBox(19, 19.4, 6.2, 7.2));       // the last inner wall listed
  EXPECT_TRUE(hasBox(6.1, 7.9, 1.2, 5.2));       // the first piece of furniture
  EXPECT_TRUE(hasBox(17.6, 19.6, 5.32, 5.88));   // the thinnest piece
  EXPECT_TRUE(hasBox(20.4, 21.6, 10.5, 11.1));   // the last piece
  // Through the door between the inner walls 0.2-4.2 and 7.2-14.2 at y = 10-10.4.
  EXPECT_TRUE(blocked(m, {4.1, 10.2}));
  EXPECT_FALSE(blocked(m, {5.7, 10.2}));
  EXPECT_TRUE(blocked(m, {7.3, 10.2}));
  EXPECT_TRUE(blocked(m, {7.0, 3.0}));  // inside the furniture 6.1-7.9 x 1.2-5.2

  ASSERT_EQ(m.goals.size(), 32u);
  EXPECT_EQ(m.goals.front(), Vec2(3, 1.5));
  EXPECT_EQ(m.goals[24], Vec2(20.26, 12.24));
  EXPECT_EQ(m.goals.back(), Vec2(23.1, 3.2));
  for (const Vec2& g : m.goals) {
    EXPECT_FALSE(blocked(m, g)) << g.transpose();
    EXPECT_TRUE(m.bounds->contains(g));
  }
}

// ---- clutter ----

TEST(ClutterMap, HasTenSpacedGoalsAndOneHundredFiftySmallOctagonsClearOfThem) {
  const PolygonMap m = generateClutterMap(42);
  EXPECT_EQ(m.name, "clutter");
  EXPECT_FALSE(m.bounds.has_value());  // no boundary walls
  EXPECT_NO_THROW(validatePolygonMap(m, "clutter"));
  ASSERT_EQ(m.goals.size(), 10u);
  for (std::size_t a = 0; a < m.goals.size(); ++a) {
    EXPECT_TRUE(Box({0, 0}, {20, 20}).contains(m.goals[a]));
    for (std::size_t b = a + 1; b < m.goals.size(); ++b) EXPECT_GE((m.goals[a] - m.goals[b]).norm(), 1.0);
  }
  ASSERT_EQ(m.obstacles.size(), 150u);
  for (const Polygon& o : m.obstacles) {
    ASSERT_EQ(o.size(), 8u);
    Vec2 c = Vec2::Zero();
    for (const Vec2& v : o) c += v / 8.0;
    EXPECT_TRUE(Box({0, 0}, {20, 20}).contains(c));
    // The unit octagon's edge (1, -0.5)-(1, 0.5) has its midpoint at (1, 0), scaled to
    // (sx, 0); edge (0.5, 1)-(-0.5, 1) at (0, sy): the half-extents, in U(0.03, 0.2).
    const double sx = (0.5 * (o[0] + o[1]) - c).norm(), sy = (0.5 * (o[2] + o[3]) - c).norm();
    EXPECT_GE(sx, 0.03 - 1e-12);
    EXPECT_LE(sx, 0.2 + 1e-12);
    EXPECT_GE(sy, 0.03 - 1e-12);
    EXPECT_LE(sy, 0.2 + 1e-12);
    EXPECT_GT(signedArea(o), 0.0);
    for (const Vec2& g : m.goals) {
      EXPECT_EQ(locatePoint(g, o), Containment::kOutside);
      EXPECT_GE(distanceToEdges(g, o), 1.1);
    }
  }
}

TEST(ClutterMap, TheSameSeedGivesTheSameMapAndAnotherSeedAnother) {
  EXPECT_TRUE(identical(generateClutterMap(7), generateClutterMap(7)));
  EXPECT_FALSE(identical(generateClutterMap(7), generateClutterMap(8)));
  const PolygonMap a = generateClutterMap(7), b = generateClutterMap(8);
  EXPECT_NE(a.goals[0], b.goals[0]);
  EXPECT_NE(a.obstacles[0][0], b.obstacles[0][0]);
}

TEST(ClutterMap, SeedFortyTwoGivesThePinnedMap) {
  // mt19937_64 and our uniform mapping are fully specified, so these values hold with any
  // standard library; a change here changes every clutter experiment.
  const PolygonMap m = generateClutterMap(42);
  // Goals use no libm call and are exact; octagon vertices pass through sin and cos, which
  // a libm may round an ulp differently, hence the tolerance there.
  EXPECT_EQ(m.goals[0], Vec2(15.103110659090779, 12.780627877093949));
  EXPECT_EQ(m.goals[9].x(), 0.93606034841975161);
  EXPECT_NEAR(m.obstacles[149][0].x(), 13.780914249287866, 1e-12);
}

// ---- by name, and through the file format ----

TEST(PaperMaps, DispatchByNameAndRejectUnknownNames) {
  EXPECT_EQ(generatePaperMap("office", 0).goals.size(), 43u);
  EXPECT_EQ(generatePaperMap("apartment", 0).goals.size(), 32u);
  EXPECT_TRUE(identical(generatePaperMap("clutter", 3), generateClutterMap(3)));
  try {
    generatePaperMap("kitchen", 0);
    FAIL() << "an unknown map name was accepted";
  } catch (const MapError& e) {
    EXPECT_EQ(std::string(e.what()), "generate: unknown map 'kitchen' (valid names: office, apartment, clutter)");
  }
}

TEST(PaperMaps, SurviveTheYamlRoundTripBitForBit) {
  for (const PolygonMap& m : {generateOfficeMap(), generateApartmentMap(), generateClutterMap(1)}) {
    EXPECT_TRUE(identical(m, parsePolygonMap(toYaml(m), m.name + ".yaml"))) << m.name;
  }
}

}  // namespace
}  // namespace staa
