#include "map/generate.hpp"

#include "geometry/polygon.hpp"

#include <array>
#include <random>
#include <string>
#include <utility>

namespace staa {
namespace {

// Axis-aligned box x0-x1 by y0-y1 as a counter-clockwise polygon (the paper's set-up gives every
// wall and piece of furniture in this form).
Polygon box(double x0, double x1, double y0, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

// ---- office (docs/paper-worlds.md, "Office") ----

constexpr double kCell = 3.0;          // 9 x 9 grid of 3 m cells
constexpr double kWall = 0.12;         // walls lie inside the room's cell along its edges
constexpr double kDoorPiece = 0.825;   // a door wall: 0.825 m piece, 1.35 m gap, 0.825 m piece
enum class Side { kBottom, kTop, kLeft, kRight };

// One wall, a box x0-x1 by y0-y1; with a door it becomes two 0.825 m pieces at its ends,
// split along its long side, leaving the centred 1.35 m gap.
void addWall(std::vector<Polygon>& out, double x0, double x1, double y0, double y1, bool door) {
  if (!door) {
    out.push_back(box(x0, x1, y0, y1));
  } else if (x1 - x0 > y1 - y0) {
    out.push_back(box(x0, x0 + kDoorPiece, y0, y1));
    out.push_back(box(x1 - kDoorPiece, x1, y0, y1));
  } else {
    out.push_back(box(x0, x1, y0, y0 + kDoorPiece));
    out.push_back(box(x0, x1, y1 - kDoorPiece, y1));
  }
}

// The four walls of room (i, j), inside its cell, the one on `door` with the door. Walls run
// the full cell edge and overlap at the corners (the format allows overlap), so a door
// wall's pieces are exactly 0.825 m long as the paper's setup builds them.
void addRoom(std::vector<Polygon>& out, int i, int j, Side door) {
  const double x0 = kCell * i, x1 = x0 + kCell, y0 = kCell * j, y1 = y0 + kCell;
  addWall(out, x0, x1, y0, y0 + kWall, door == Side::kBottom);
  addWall(out, x0, x1, y1 - kWall, y1, door == Side::kTop);
  addWall(out, x0, x0 + kWall, y0, y1, door == Side::kLeft);
  addWall(out, x1 - kWall, x1, y0, y1, door == Side::kRight);
}

// A room of the paper's, with its goal at the cell centre (3i + 1.5, 3j + 1.5).
void addRoomWithGoal(PolygonMap& map, int i, int j, Side door) {
  addRoom(map.obstacles, i, j, door);
  map.goals.push_back({kCell * i + 0.5 * kCell, kCell * j + 0.5 * kCell});
}

// ---- clutter (docs/paper-worlds.md, "Clutter") ----

// Uniform in [a, b) from the top 53 bits of one mt19937_64 draw. std::mt19937_64's output
// is fixed by the standard, unlike std::uniform_real_distribution's, so a seed gives the
// same map with every standard library.
double uniform(std::mt19937_64& rng, double a, double b) {
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return a + (b - a) * u;
}

}  // namespace

PolygonMap generateOfficeMap() {
  PolygonMap map;
  map.name = "office";
  map.bounds = Box{{0.0, 0.0}, {27.0, 27.0}};
  auto& obs = map.obstacles;

  // The four corner cells are solid 3 x 3 m blocks.
  for (const auto& [i, j] : std::array<std::pair<int, int>, 4>{{{0, 0}, {8, 0}, {0, 8}, {8, 8}}}) {
    obs.push_back(box(kCell * i, kCell * i + kCell, kCell * j, kCell * j + kCell));
  }

  // Rooms, each with its door towards the corridor. Goals are the centres of the paper's 43
  // rooms: 27 in the outer ring (7 + 7 + 7 + 6) and 16 in the inner ring (3 + 3 + 5 + 5).
  // Outer ring, doors facing inwards; the bottom row j = 0 opens upwards, and so on.
  for (int i = 1; i <= 7; ++i) addRoomWithGoal(map, i, 0, Side::kTop);
  for (int i = 1; i <= 7; ++i) addRoomWithGoal(map, i, 8, Side::kBottom);
  for (int j = 1; j <= 7; ++j) addRoomWithGoal(map, 8, j, Side::kLeft);
  for (int j = 2; j <= 7; ++j) addRoomWithGoal(map, 0, j, Side::kRight);
  // Cell (0, 1) is a 3 m hole in the outer boundary in the original; we close it by building
  // it like its neighbours in column i = 0 (a room with its door onto the corridor corner
  // (1, 1)), but it is not one of the paper's rooms, so it gets no goal and the goal set
  // stays the paper's 43.
  addRoom(obs, 0, 1, Side::kRight);

  // Inner ring, doors facing the corridor (cells with i or j in {1, 7}, left free).
  for (int i = 3; i <= 5; ++i) addRoomWithGoal(map, i, 2, Side::kBottom);
  for (int i = 3; i <= 5; ++i) addRoomWithGoal(map, i, 6, Side::kTop);
  for (int j = 2; j <= 6; ++j) addRoomWithGoal(map, 2, j, Side::kLeft);
  for (int j = 2; j <= 6; ++j) addRoomWithGoal(map, 6, j, Side::kRight);

  // The centre, cells 3..5 x 3..5, is one solid block.
  obs.push_back(box(9.0, 18.0, 9.0, 18.0));
  return map;
}

PolygonMap generateApartmentMap() {
  PolygonMap map;
  map.name = "apartment";
  // The outer walls' extent: 0-24.4 x 0-20.4 (a 12 x 10 m plan scaled 2x, walls 0.4 m).
  map.bounds = Box{{0.0, 0.0}, {24.4, 20.4}};
  // x0, x1, y0, y1 exactly as the paper's published set-up lists them (docs/paper-worlds.md): outer walls, inner walls, furniture.
  constexpr double kBoxes[][4] = {
      // outer walls
      {24, 24.4, 0.2, 20.2}, {0, 0.4, 0.2, 20.2}, {0.2, 24.2, 0, 0.4}, {0.2, 24.2, 20, 20.4},
      // inner walls
      {0.2, 4.2, 10, 10.4}, {7.2, 14.2, 10, 10.4}, {14, 14.4, 0.2, 10.2}, {0.2, 2.2, 14, 14.4},
      {4.6, 16.6, 14, 14.4}, {12, 12.4, 14.2, 20.2}, {8.4, 8.8, 14.2, 17.6}, {19, 24.2, 14, 14.4},
      {19, 24.2, 10, 10.4}, {17.4, 24.2, 6, 6.4}, {14.2, 15.4, 6, 6.4}, {19, 19.4, 9.2, 11.2},
      {19, 19.4, 13.2, 14.2}, {19, 19.4, 6.2, 7.2},
      // furniture
      {6.1, 7.9, 1.2, 5.2}, {3, 7, 5.7, 7.5}, {1, 1.4, 1.2, 4.4}, {3, 4.6, 2.4, 4},
      {10.2, 12.2, 3.6, 6.8}, {10.8, 11.6, 7, 7.8}, {10.8, 11.6, 2.6, 3.4}, {12.4, 13.2, 5.6, 6.4},
      {12.4, 13.2, 4, 4.8}, {9.2, 10, 5.6, 6.4}, {9.2, 10, 4, 4.8}, {0.5, 1.9, 14.5, 19.9},
      {0.5, 5.9, 18.5, 19.9}, {7.9, 8.3, 15, 17.4}, {5.8, 8.2, 14.5, 14.9}, {11.1, 11.9, 14.5, 19.9},
      {9.2, 11.2, 14.4, 15}, {12.4, 16.4, 18.1, 19.9}, {19.9, 23.9, 18.1, 19.9}, {19.9, 23.9, 4.1, 5.9},
      {12.6, 13.8, 15, 17.4}, {14, 14.8, 15.8, 16.6}, {22.8, 24, 15, 17.4}, {21.8, 22.6, 15.8, 16.6},
      {21, 23.4, 0.4, 1.6}, {21.8, 22.6, 1.8, 2.6}, {17.6, 19.6, 5.32, 5.88}, {14.5, 15.3, 1.2, 5.2},
      {16.8, 19.6, 0.6, 1.8}, {14.5, 15.1, 6.8, 9.6}, {23.2, 24, 8.8, 9.6}, {22.4, 24, 6.4, 8},
      {20.4, 21.6, 6.5, 7.1}, {21.4, 22.2, 13.2, 14}, {22.8, 24, 10.8, 13.6}, {20.4, 21.6, 10.5, 11.1},
  };
  for (const auto& b : kBoxes) map.obstacles.push_back(box(b[0], b[1], b[2], b[3]));
  map.goals = {{3, 1.5},       {9.6, 2},      {12.7, 2},    {4.8, 1.4},   {12.7, 8.7},  {5.6, 8.9},   {8.5, 8.2},
               {2.2, 8.7},     {2.2, 12.2},   {5.2, 12.2},  {8.2, 12.2},  {11.2, 12.2}, {14.2, 12.2}, {17.2, 12.2},
               {3.2, 15.2},    {3.2, 17.2},   {6.7, 15.8},  {8.7, 18.7},  {9.9, 16.3},  {4.8, 16.5},  {18.2, 18.3},
               {16.2, 16.2},   {18.2, 16.2},  {20.2, 16.2}, {20.26, 12.24}, {16.27, 9.2}, {21, 8.24},  {16.6, 4.3},
               {20.3, 2.8},    {16.3, 2.7},   {18, 3.5},    {23.1, 3.2}};
  return map;
}

PolygonMap generateClutterMap(std::uint64_t seed) {
  constexpr double kSide = 20.0;         // 20 x 20 m square, no boundary walls, so no bounds
  constexpr int kGoals = 10;
  constexpr double kGoalSpacing = 1.0;   // goals at least 1 m apart
  constexpr int kOctagons = 150;
  constexpr double kScaleMin = 0.03, kScaleMax = 0.2;  // half-extents in x and y
  constexpr double kGoalClearance = 1.1;  // an octagon grown by 1.1 m must not contain a goal
  // The unit octagon (+-0.5, +-1), (+-1, +-0.5), counter-clockwise.
  static constexpr double kUnit[8][2] = {{1, -0.5}, {1, 0.5}, {0.5, 1}, {-0.5, 1}, {-1, 0.5}, {-1, -0.5}, {-0.5, -1}, {0.5, -1}};

  PolygonMap map;
  map.name = "clutter";
  std::mt19937_64 rng(seed);

  // Goals first, by rejection: each draw is x then y.
  while (static_cast<int>(map.goals.size()) < kGoals) {
    const double x = uniform(rng, 0.0, kSide);
    const double y = uniform(rng, 0.0, kSide);
    const Vec2 g{x, y};
    bool spaced = true;
    for (const Vec2& other : map.goals) spaced = spaced && (g - other).norm() >= kGoalSpacing;
    if (spaced) map.goals.push_back(g);
  }

  // Then octagons, by rejection: each draw is scale x, scale y, rotation, centre x, centre y.
  // (The goals are bit-identical everywhere; the vertices pass through sin and cos, which a
  // libm may round an ulp differently.)
  // The exclusion discs cover about 10 * pi * 1.3^2 = 53 of the 400 m^2, so this ends quickly.
  while (static_cast<int>(map.obstacles.size()) < kOctagons) {
    const double sx = uniform(rng, kScaleMin, kScaleMax);
    const double sy = uniform(rng, kScaleMin, kScaleMax);
    const Pose2 pose{0.0, 0.0, uniform(rng, -kPi, kPi)};
    const double cx = uniform(rng, 0.0, kSide);
    const double cy = uniform(rng, 0.0, kSide);
    Polygon oct;
    oct.reserve(8);
    for (const auto& v : kUnit) oct.push_back(pose.transform({sx * v[0], sy * v[1]}) + Vec2{cx, cy});
    bool clear = true;
    for (const Vec2& g : map.goals) {
      clear = clear && locatePoint(g, oct) == Containment::kOutside && distanceToEdges(g, oct) >= kGoalClearance;
    }
    if (clear) map.obstacles.push_back(std::move(oct));
  }
  return map;
}

PolygonMap generatePaperMap(std::string_view name, std::uint64_t seed) {
  if (name == "office") return generateOfficeMap();
  if (name == "apartment") return generateApartmentMap();
  if (name == "clutter") return generateClutterMap(seed);
  throw MapError("generate: unknown map '" + std::string(name) + "' (valid names: office, apartment, clutter)");
}

}  // namespace staa
