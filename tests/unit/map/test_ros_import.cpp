#include "map/ros_import.hpp"

#include "geometry/polygon.hpp"
#include "support/shared_dir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace staa {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// Builds a grid from text drawn as the image looks: first string = TOP row.
// '#' occupied, '?' unknown, anything else free.
OccupancyGrid gridFromArt(const std::vector<std::string>& art, double resolution, Pose2 origin = {}) {
  OccupancyGrid grid;
  grid.height = static_cast<int>(art.size());
  grid.width = static_cast<int>(art.front().size());
  grid.resolution = resolution;
  grid.origin = origin;
  grid.cells.resize(static_cast<std::size_t>(grid.width) * grid.height);
  for (int row = 0; row < grid.height; ++row) {
    const std::string& line = art[static_cast<std::size_t>(grid.height - 1 - row)];
    for (int col = 0; col < grid.width; ++col) {
      const char ch = line[static_cast<std::size_t>(col)];
      grid.cells[static_cast<std::size_t>(row) * grid.width + col] =
          ch == '#' ? OccupancyGrid::kOccupied : ch == '?' ? OccupancyGrid::kUnknown : OccupancyGrid::kFree;
    }
  }
  return grid;
}

bool blockedAt(const PolygonMap& map, const Vec2& p) {
  for (const Polygon& poly : map.obstacles) {
    if (pointInPolygon(p, poly)) return true;
  }
  return false;
}

// Centre of cell (col, row) of an unrotated grid.
Vec2 cellCentre(const OccupancyGrid& g, int col, int row) {
  return g.origin.transform({(col + 0.5) * g.resolution, (row + 0.5) * g.resolution});
}

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const MapError& e) {
    return e.what();
  }
  return "<no MapError thrown>";
}

// A fresh folder per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("staa_ros_import_" + std::string(info->name()) + "_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  std::filesystem::path write(const std::string& name, const std::string& bytes) const {
    const std::filesystem::path p = path_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

void expectValidSimplePolygons(const PolygonMap& map) {
  for (std::size_t i = 0; i < map.obstacles.size(); ++i) {
    const Polygon& p = map.obstacles[i];
    ASSERT_GE(p.size(), 3u) << "polygon " << i;
    EXPECT_GT(std::abs(signedArea(p)), 0.0) << "polygon " << i;
    EXPECT_FALSE(findSelfIntersection(p).has_value()) << "polygon " << i << " is not simple";
  }
}

// ---- tracing synthetic grids --------------------------------------------------------------

TEST(RosImport, SingleBlockedCellBecomesOneSquareOfOneCellAtItsPlace) {
  const OccupancyGrid grid = gridFromArt({".....",  //
                                          ".....",  //
                                          "..#..",  // row 1 from the bottom
                                          "....."},
                                         0.1, {1.0, 2.0, 0.0});
  for (const double simplify : {0.0, 0.05, 0.1}) {
    SCOPED_TRACE(simplify);
    // Exact without simplification; with it the region grows by 2/1024 of a cell (see
    // reuniteSimplified), and the one-cell square must not collapse.
    const double tol = simplify == 0.0 ? 1e-9 : 0.1 * 2.5 / 1024.0;
    const PolygonMap map = importOccupancyGrid(grid, {simplify}, "cell");
    ASSERT_EQ(map.obstacles.size(), 1u);
    const Polygon& sq = map.obstacles[0];
    ASSERT_EQ(sq.size(), 4u);
    EXPECT_NEAR(std::abs(signedArea(sq)), 0.01, simplify == 0.0 ? 1e-12 : 4 * 0.1 * tol);
    const Box b = boundingBox(sq);
    EXPECT_NEAR(b.min.x(), 1.2, tol);
    EXPECT_NEAR(b.max.x(), 1.3, tol);
    EXPECT_NEAR(b.min.y(), 2.1, tol);
    EXPECT_NEAR(b.max.y(), 2.2, tol);
    ASSERT_TRUE(map.bounds.has_value());
    EXPECT_NEAR(map.bounds->min.x(), 1.0, 1e-12);
    EXPECT_NEAR(map.bounds->min.y(), 2.0, 1e-12);
    EXPECT_NEAR(map.bounds->max.x(), 1.5, 1e-12);
    EXPECT_NEAR(map.bounds->max.y(), 2.4, 1e-12);
    EXPECT_EQ(map.name, "cell");
  }
}

TEST(RosImport, WallRingKeepsTheRoomFreeAndTheWallsBlocked) {
  const OccupancyGrid grid = gridFromArt({"##########",  //
                                          "#........#",  //
                                          "#........#",  //
                                          "#........#",  //
                                          "#........#",  //
                                          "#........#",  //
                                          "##########"},
                                         0.1);
  for (const double simplify : {0.0, 0.05}) {
    SCOPED_TRACE(simplify);
    const PolygonMap map = importOccupancyGrid(grid, {simplify}, "room");
    expectValidSimplePolygons(map);
    EXPECT_GE(map.obstacles.size(), 2u);  // the hole had to be cut open
    for (int row = 0; row < grid.height; ++row) {
      for (int col = 0; col < grid.width; ++col) {
        EXPECT_EQ(blockedAt(map, cellCentre(grid, col, row)), grid.blocked(col, row)) << col << "," << row;
      }
    }
    EXPECT_FALSE(blockedAt(map, {0.5, 0.35}));  // the room's centre
    const ImportAgreement a = measureAgreement(grid, map, 0);
    EXPECT_EQ(a.cells_compared, 70u);
    EXPECT_EQ(a.cells_agreeing, 70u);
    EXPECT_DOUBLE_EQ(a.fraction, 1.0);
  }
}

TEST(RosImport, CellsOnTheImageBorderTouchTheBounds) {
  const OccupancyGrid grid = gridFromArt({"...#",  //
                                          "....",  //
                                          "#..."},
                                         0.5, {-1.0, -1.0, 0.0});
  const PolygonMap map = importOccupancyGrid(grid, {0.0}, "border");
  ASSERT_EQ(map.obstacles.size(), 2u);
  std::vector<Box> boxes{boundingBox(map.obstacles[0]), boundingBox(map.obstacles[1])};
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.min.x() < b.min.x(); });
  EXPECT_NEAR(boxes[0].min.x(), -1.0, 1e-9);
  EXPECT_NEAR(boxes[0].min.y(), -1.0, 1e-9);
  EXPECT_NEAR(boxes[0].max.x(), -0.5, 1e-9);
  EXPECT_NEAR(boxes[0].max.y(), -0.5, 1e-9);
  EXPECT_NEAR(boxes[1].min.x(), 0.5, 1e-9);
  EXPECT_NEAR(boxes[1].min.y(), 0.0, 1e-9);
  EXPECT_NEAR(boxes[1].max.x(), 1.0, 1e-9);
  EXPECT_NEAR(boxes[1].max.y(), 0.5, 1e-9);
  EXPECT_NEAR(map.bounds->max.x(), 1.0, 1e-12);
  EXPECT_NEAR(map.bounds->max.y(), 0.5, 1e-12);
}

TEST(RosImport, UnknownCellsAreBlockedLikeOccupiedOnes) {
  const OccupancyGrid grid = gridFromArt({"??##",  //
                                          "??..",  //
                                          "...."},
                                         1.0);
  const PolygonMap map = importOccupancyGrid(grid, {0.0}, "unknown");
  ASSERT_EQ(map.obstacles.size(), 1u);
  EXPECT_EQ(map.obstacles[0].size(), 6u);  // an L of 6 cells
  EXPECT_NEAR(std::abs(signedArea(map.obstacles[0])), 6.0, 1e-9);
  EXPECT_TRUE(blockedAt(map, {0.5, 1.5}));
  EXPECT_FALSE(blockedAt(map, {2.5, 1.5}));
}

TEST(RosImport, RotatedOriginRotatesTheCellsAndBlocksTheBoxCornersOutsideTheImage) {
  const OccupancyGrid grid = gridFromArt({"......",  //
                                          "..##..",  //
                                          "......",  //
                                          "#....."},
                                         0.5, {2.0, 1.0, kPi / 6.0});
  const PolygonMap map = importOccupancyGrid(grid, {0.0}, "rotated");
  expectValidSimplePolygons(map);
  // Cell (0, 0) is the unit square at the origin turned by 30 degrees.
  const Pose2& o = grid.origin;
  EXPECT_TRUE(blockedAt(map, o.transform({0.25, 0.25})));
  EXPECT_TRUE(blockedAt(map, o.transform({1.25, 1.25})));
  EXPECT_FALSE(blockedAt(map, o.transform({1.5, 0.75})));
  // The bounds hold the whole turned image; what lies outside it is an obstacle.
  const Vec2 far_corner = o.transform({3.0, 2.0});
  EXPECT_NEAR(map.bounds->max.y(), far_corner.y(), 1e-9);
  EXPECT_NEAR(map.bounds->min.y(), 1.0, 1e-9);
  EXPECT_TRUE(blockedAt(map, {map.bounds->max.x() - 0.01, map.bounds->min.y() + 0.01}));
  EXPECT_TRUE(blockedAt(map, {map.bounds->min.x() + 0.01, map.bounds->min.y() + 0.01}));
  const ImportAgreement a = measureAgreement(grid, map, 0);
  EXPECT_EQ(a.cells_compared, 24u);
  EXPECT_EQ(a.cells_agreeing, 24u);
}

TEST(RosImport, SimplificationStraightensAStaircaseWithinTheTolerance) {
  // A 40-cell staircase diagonal: every step is two corners unsimplified.
  std::vector<std::string> art;
  for (int r = 0; r < 40; ++r) art.push_back(std::string(static_cast<std::size_t>(r + 1), '#') + std::string(static_cast<std::size_t>(39 - r), '.'));
  const OccupancyGrid grid = gridFromArt(art, 0.05);
  const PolygonMap exact = importOccupancyGrid(grid, {0.0}, "stairs");
  ASSERT_EQ(exact.obstacles.size(), 1u);
  EXPECT_EQ(exact.obstacles[0].size(), 2u * 40u + 2u);  // 40 steps plus the two far corners
  const PolygonMap simple = importOccupancyGrid(grid, {0.05}, "stairs");
  ASSERT_EQ(simple.obstacles.size(), 1u);
  EXPECT_LE(simple.obstacles[0].size(), 6u);
  expectValidSimplePolygons(simple);
  const ImportAgreement a = measureAgreement(grid, simple, defaultBorderCells(0.05, 0.05));
  EXPECT_EQ(defaultBorderCells(0.05, 0.05), 2);
  EXPECT_GT(a.cells_compared, 1000u);
  EXPECT_DOUBLE_EQ(a.fraction, 1.0);
  // Everywhere, not just away from the edge, the staircase cells disagree at most one per row.
  EXPECT_LE(measureAgreement(grid, simple, 0).cells_compared - measureAgreement(grid, simple, 0).cells_agreeing, 40u);
}

TEST(RosImport, AgreementCountsBothKindsOfDisagreement) {
  const OccupancyGrid grid = gridFromArt({"....",  //
                                          ".##.",  //
                                          "...."},
                                         1.0);
  PolygonMap map;
  map.obstacles.push_back({{0.0, 0.0}, {2.0, 0.0}, {2.0, 1.0}, {0.0, 1.0}});  // 2 free cells blocked
  const ImportAgreement a = measureAgreement(grid, map, 0);
  EXPECT_EQ(a.cells_compared, 12u);
  EXPECT_EQ(a.free_as_blocked, 2u);
  EXPECT_EQ(a.blocked_as_free, 2u);
  EXPECT_EQ(a.cells_agreeing, 8u);
  EXPECT_NEAR(a.fraction, 8.0 / 12.0, 1e-12);
}

// ---- PGM and metadata ----------------------------------------------------------------------

RosMapInfo info(double occupied = 0.65, double free = 0.196, bool negate = false,
                RosMapInfo::Mode mode = RosMapInfo::Mode::kTrinary) {
  RosMapInfo i;
  i.occupied_thresh = occupied;
  i.free_thresh = free;
  i.negate = negate;
  i.mode = mode;
  return i;
}

TEST(RosImport, ClassifiesPixelsPerMapServerAndPutsTheTopImageRowAtTheTop) {
  // Top row: black, white, map_server grey 205 (occ 0.196078 > 0.196: unknown).
  const std::string bytes = std::string("P5\n3 2\n255\n") + std::string("\x00\xfe\xcd", 3) + std::string("\xfe\xfe\x00", 3);
  const PgmImage image = parsePgm(bytes, "t.pgm");
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 2);
  EXPECT_EQ(image.pixels, (std::vector<std::uint16_t>{0, 254, 205, 254, 254, 0}));
  const OccupancyGrid g = classifyImage(image, info());
  EXPECT_EQ(g.at(0, 1), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.at(1, 1), OccupancyGrid::kFree);
  EXPECT_EQ(g.at(2, 1), OccupancyGrid::kUnknown);
  EXPECT_EQ(g.at(0, 0), OccupancyGrid::kFree);
  EXPECT_EQ(g.at(2, 0), OccupancyGrid::kOccupied);
  // depot.yaml's free_thresh 0.25 makes the same grey free.
  EXPECT_EQ(classifyImage(image, info(0.65, 0.25)).at(2, 1), OccupancyGrid::kFree);
}

TEST(RosImport, NegateMakesWhiteOccupiedAndBlackFree) {
  const PgmImage image = parsePgm(std::string("P5 2 1 255 ") + std::string("\x00\xff", 2), "n.pgm");
  const OccupancyGrid g = classifyImage(image, info(0.65, 0.196, true));
  EXPECT_EQ(g.at(0, 0), OccupancyGrid::kFree);
  EXPECT_EQ(g.at(1, 0), OccupancyGrid::kOccupied);
}

TEST(RosImport, Reads16BitP5BigEndian) {
  // 0xff00 is nearly white (free); read little-endian it would be 0x00ff, nearly black.
  const std::string raster("\x00\x00\xff\x00\x80\x00\xff\xff", 8);
  const PgmImage image = parsePgm("P5\n# sixteen bits\n4 1\n65535\n" + raster, "w.pgm");
  EXPECT_EQ(image.maxval, 65535);
  EXPECT_EQ(image.pixels, (std::vector<std::uint16_t>{0, 0xff00, 0x8000, 0xffff}));
  const OccupancyGrid g = classifyImage(image, info());
  EXPECT_EQ(g.cells, (std::vector<std::uint8_t>{OccupancyGrid::kOccupied, OccupancyGrid::kFree,
                                                OccupancyGrid::kUnknown, OccupancyGrid::kFree}));
}

TEST(RosImport, ReadsAsciiP2WithComments) {
  const PgmImage image = parsePgm("P2\n# made by hand\n3 2 # width height\n15\n0 15 7\n# mid-raster\n15 15 0\n", "a.pgm");
  EXPECT_EQ(image.maxval, 15);
  EXPECT_EQ(image.pixels, (std::vector<std::uint16_t>{0, 15, 7, 15, 15, 0}));
  const OccupancyGrid g = classifyImage(image, info());
  EXPECT_EQ(g.at(0, 1), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.at(2, 1), OccupancyGrid::kUnknown);  // occ = 8/15 = 0.53
  EXPECT_EQ(g.at(2, 0), OccupancyGrid::kOccupied);
  EXPECT_EQ(g.at(1, 0), OccupancyGrid::kFree);
}

TEST(RosImport, RawModeReadsValuesAsOccupancyPercent) {
  const PgmImage image = parsePgm("P2 5 1 255 0 10 50 100 255", "r.pgm");
  const OccupancyGrid g = classifyImage(image, info(0.65, 0.196, false, RosMapInfo::Mode::kRaw));
  EXPECT_EQ(g.cells, (std::vector<std::uint8_t>{OccupancyGrid::kFree, OccupancyGrid::kFree, OccupancyGrid::kUnknown,
                                                OccupancyGrid::kOccupied, OccupancyGrid::kUnknown}));
}

TEST(RosImport, MalformedPgmFilesAreRejectedWithTheFileAndTheProblem) {
  const std::vector<std::pair<std::string, std::string>> cases{
      {"", "not a PGM image"},
      {"GIF89a", "not a PGM image"},
      {"P6\n1 1\n255\n\x01\x02\x03", "unsupported image type 'P6'"},
      {"P5\n3 2\n", "missing maxval"},
      {"P5\n3", "missing height"},
      {"P5\n0 2\n255\n", "width 0 out of range"},
      {"P5\n3x 2\n255\n", "width '3x' is not a number"},
      {"P5\n3 2\n70000\n", "maxval 70000 out of range"},
      {"P5\n3 2\n255", "no pixel data"},
      {"P5\n3 2\n255\n\x01\x02\x03\x04", "need 6 bytes of pixel data, found 4"},
      {"P5\n2 1\n65535\n\x01\x02\x03", "need 4 bytes of pixel data, found 3"},
      {"P5\n2 1\n100\n\x01\xc8", "pixel value 200 at column 1, row 0 exceeds maxval 100"},
      {"P5\n99999999999999999999 2\n255\n", "width 99999999999999999999 out of range"},
      {"P2\n2 2\n255\n1 2 x 4", "pixel 2 of 4 is not a number"},
      {"P2\n2 2\n255\n1 2 3 ", "missing pixel 3 of 4"},
      {"P2\n20 20\n255\n1 2", "20 x 20 pixels cannot fit in the 4 bytes left"},
      {"P2\n2 1\n15\n3 16", "pixel value 16 at column 1, row 0 exceeds maxval 15"},
  };
  for (const auto& [bytes, problem] : cases) {
    EXPECT_THAT(errorOf([&] { parsePgm(bytes, "bad.pgm"); }), AllOf(HasSubstr("bad.pgm: "), HasSubstr(problem)))
        << "input: " << bytes;
  }
  TempDir dir;
  const auto file = dir.write("short.pgm", "P5\n4 4\n255\nabc");
  EXPECT_THAT(errorOf([&] { loadPgm(file); }), AllOf(HasSubstr(file.string()), HasSubstr("truncated")));
  EXPECT_THAT(errorOf([&] { loadPgm(dir.path() / "absent.pgm"); }), HasSubstr("absent.pgm: cannot open"));
}

TEST(RosImport, MetadataErrorsNameTheFileTheKeyAndTheValue) {
  TempDir dir;
  dir.write("m.pgm", "P2 1 1 255 254");
  const std::string good_tail = "resolution: 0.05\norigin: [0, 0, 0]\n";
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases{
      {good_tail, {": image: missing"}},
      {"image: m.pgm\norigin: [0, 0, 0]\n", {": resolution: missing"}},
      {"image: m.pgm\nresolution: 0\norigin: [0, 0, 0]\n", {":2: resolution: ", "> 0", "got 0"}},
      {"image: m.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n", {":2: resolution: ", "got -0.05"}},
      {"image: m.pgm\nresolution: fine\norigin: [0, 0, 0]\n", {":2: resolution: ", "got 'fine'"}},
      {"image: m.pgm\n" + good_tail + "occupied_thresh: 1.5\n", {":4: occupied_thresh: ", "[0, 1]", "got 1.5"}},
      {"image: m.pgm\n" + good_tail + "free_thresh: -0.1\n", {":4: free_thresh: ", "got -0.1"}},
      {"image: m.pgm\n" + good_tail + "occupied_thresh: 0.6\nfree_thresh: 0.7\n", {":5: free_thresh: ", "0.7", "0.6"}},
      {"image: m.pgm\n" + good_tail + "mode: fuzzy\n", {":4: mode: ", "trinary, scale or raw", "got 'fuzzy'"}},
      {"image: m.pgm\n" + good_tail + "negate: 2\n", {":4: negate: ", "got 2"}},
      {"image: m.pgm\nresolution: 0.05\norigin: [1, 2]\n", {":3: origin: ", "3 numbers", "got a list of 2 items"}},
      {"image: m.pgm\nresolution: 0.05\norigin: [1, 2, yaw]\n", {":3: origin[2]: ", "got 'yaw'"}},
      {"image: m.pgm\nresolution: 0.05\n", {": origin: missing"}},
      {"image: nothere.pgm\n" + good_tail, {":1: image: ", "nothere.pgm", "not found"}},
      {"image: m.pgm\n" + good_tail + "image: n.pgm\n", {":4: image: given twice (first on line 1)"}},
      {"image: [m.pgm\n", {"not valid YAML"}},
      {"- just a list\n", {"expected a map_server YAML mapping"}},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto yaml = dir.write("case" + std::to_string(i) + ".yaml", cases[i].first);
    const std::string message = errorOf([&] { loadRosMapInfo(yaml); });
    EXPECT_THAT(message, HasSubstr(yaml.string())) << cases[i].first;
    for (const std::string& part : cases[i].second) EXPECT_THAT(message, HasSubstr(part)) << cases[i].first;
  }
}

TEST(RosImport, LoadsYamlAndPgmAndRespectsTheOriginOffset) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "img");
  // 4 x 3 ASCII map: an occupied top-left cell and an unknown bottom-right cell.
  dir.write("img/small.pgm", "P2\n4 3\n255\n0 254 254 254\n254 254 254 254\n254 254 254 205\n");
  const auto yaml = dir.write("small.yaml",
                              "image: img/small.pgm\nresolution: 0.25\norigin: [-10.0, 5.0, 0.0]\nnegate: 0\n"
                              "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n");
  const RosMapInfo meta = loadRosMapInfo(yaml);
  EXPECT_EQ(meta.image, dir.path() / "img/small.pgm");
  EXPECT_DOUBLE_EQ(meta.resolution, 0.25);
  EXPECT_DOUBLE_EQ(meta.origin.x, -10.0);
  EXPECT_DOUBLE_EQ(meta.origin.y, 5.0);
  EXPECT_FALSE(meta.negate);

  const PolygonMap map = importRosMap(yaml, {0.0});
  EXPECT_EQ(map.name, "small");
  ASSERT_EQ(map.obstacles.size(), 2u);
  EXPECT_TRUE(blockedAt(map, {-9.875, 5.625}));   // top-left cell: column 0, grid row 2
  EXPECT_TRUE(blockedAt(map, {-9.125, 5.125}));   // bottom-right cell: column 3, grid row 0
  EXPECT_FALSE(blockedAt(map, {-9.375, 5.375}));
  EXPECT_NEAR(map.bounds->min.x(), -10.0, 1e-12);
  EXPECT_NEAR(map.bounds->min.y(), 5.0, 1e-12);
  EXPECT_NEAR(map.bounds->max.x(), -9.0, 1e-12);
  EXPECT_NEAR(map.bounds->max.y(), 5.75, 1e-12);
}

// ---- the real maps (../shared/maps/ros) -----------------------------------------------------

struct RealImport {
  OccupancyGrid grid;
  PolygonMap map;
  ImportAgreement agreement;
  double import_ms = 0.0;
};

RealImport importReal(const std::string& name) {
  const std::filesystem::path yaml = test::sharedDir() / "maps/ros" / (name + ".yaml");
  RealImport r;
  r.grid = loadOccupancyGrid(yaml);
  const ImportOptions options;  // the default simplification
  const auto t0 = std::chrono::steady_clock::now();
  r.map = importRosMap(yaml, options);
  r.import_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  r.agreement = measureAgreement(r.grid, r.map, defaultBorderCells(options.simplify_m, r.grid.resolution));
  const ImportAgreement everywhere = measureAgreement(r.grid, r.map, 0);
  std::size_t vertices = 0;
  for (const Polygon& p : r.map.obstacles) vertices += p.size();
  std::cout << "[ros-import] " << name << ": " << r.grid.width << " x " << r.grid.height << " px, agreement "
            << 100.0 * r.agreement.fraction << " % of " << r.agreement.cells_compared << " cells (blocked as free "
            << r.agreement.blocked_as_free << ", free as blocked " << r.agreement.free_as_blocked << "; "
            << 100.0 * everywhere.fraction << " % over all cells), "
            << r.map.obstacles.size() << " polygons, " << vertices << " vertices, import " << r.import_ms
            << " ms (YAML + PGM + trace + simplify + validate)\n";
  ::testing::Test::RecordProperty("agreement_percent", std::to_string(100.0 * r.agreement.fraction));
  ::testing::Test::RecordProperty("agreement_all_cells_percent", std::to_string(100.0 * everywhere.fraction));
  ::testing::Test::RecordProperty("polygons", static_cast<int>(r.map.obstacles.size()));
  ::testing::Test::RecordProperty("vertices", static_cast<int>(vertices));
  ::testing::Test::RecordProperty("import_ms", std::to_string(r.import_ms));
  return r;
}

TEST(RosImportRealMaps, DepotImportsWithAtLeast98PercentAgreement) {
  STAA_REQUIRE_SHARED_FILE(test::sharedDir() / "maps/ros/depot.yaml");
  const RealImport r = importReal("depot");
  EXPECT_EQ(r.grid.width, 604);
  EXPECT_EQ(r.grid.height, 307);
  EXPECT_GE(r.agreement.fraction, 0.98);
  EXPECT_GT(r.agreement.cells_compared, 100000u);
  EXPECT_GT(r.map.obstacles.size(), 10u);
  expectValidSimplePolygons(r.map);
  EXPECT_NEAR(r.map.bounds->max.x(), 604 * 0.05, 1e-9);
  EXPECT_NEAR(r.map.bounds->max.y(), 307 * 0.05, 1e-9);
}

TEST(RosImportRealMaps, WarehouseImportsWithAtLeast98PercentAgreement) {
  STAA_REQUIRE_SHARED_FILE(test::sharedDir() / "maps/ros/warehouse.yaml");
  const RealImport r = importReal("warehouse");
  EXPECT_EQ(r.grid.width, 1006);
  EXPECT_EQ(r.grid.height, 1674);
  EXPECT_GE(r.agreement.fraction, 0.98);
  EXPECT_GT(r.agreement.cells_compared, 1000000u);
  EXPECT_GT(r.map.obstacles.size(), 10u);
  expectValidSimplePolygons(r.map);
  EXPECT_NEAR(r.map.bounds->min.x(), -15.1, 1e-9);
  EXPECT_NEAR(r.map.bounds->min.y(), -25.0, 1e-9);
}

TEST(RosImportRealMaps, Tb3SandboxKeepsItsArenaFreeAndItsUnknownSurroundBlocked) {
  STAA_REQUIRE_SHARED_FILE(test::sharedDir() / "maps/ros/tb3_sandbox.yaml");
  const RealImport r = importReal("tb3_sandbox");
  EXPECT_EQ(r.grid.width, 384);
  EXPECT_EQ(r.grid.height, 384);
  EXPECT_GE(r.agreement.fraction, 0.98);
  expectValidSimplePolygons(r.map);

  // The free cell nearest the image centre whose 5 x 5 neighbourhood is free too.
  const int mid = 192;
  int best_col = -1, best_row = -1;
  for (int radius = 0; radius < 100 && best_col < 0; ++radius) {
    for (int row = mid - radius; row <= mid + radius && best_col < 0; ++row) {
      for (int col = mid - radius; col <= mid + radius && best_col < 0; ++col) {
        bool all_free = true;
        for (int dr = -2; dr <= 2; ++dr) {
          for (int dc = -2; dc <= 2; ++dc) all_free = all_free && !r.grid.blocked(col + dc, row + dr);
        }
        if (all_free) best_col = col, best_row = row;
      }
    }
  }
  ASSERT_GE(best_col, 0) << "no free cell near the centre of tb3_sandbox";
  EXPECT_LT(std::abs(best_col - mid) + std::abs(best_row - mid), 40);
  EXPECT_FALSE(blockedAt(r.map, cellCentre(r.grid, best_col, best_row)));
  // The image's corners are unknown space, so blocked.
  ASSERT_EQ(r.grid.at(0, 0), OccupancyGrid::kUnknown);
  ASSERT_EQ(r.grid.at(383, 383), OccupancyGrid::kUnknown);
  EXPECT_TRUE(blockedAt(r.map, cellCentre(r.grid, 0, 0)));
  EXPECT_TRUE(blockedAt(r.map, cellCentre(r.grid, 383, 383)));
  EXPECT_TRUE(blockedAt(r.map, cellCentre(r.grid, 10, 370)));
}


// ---- input bounds (docs/ARCHITECTURE.md, "Input bounds") ----

TEST(RosImportBounds, ASideOf65536PixelsReadsAnd65537IsRefusedNamingTheBound) {
  const PgmImage wide = parsePgm("P5\n65536 1\n255\n" + std::string(65536, '\x10'), "wide.pgm");
  EXPECT_EQ(wide.width, 65536);
  EXPECT_EQ(errorOf([] { parsePgm("P5\n65537 1\n255\n" + std::string(65537, '\x10'), "wider.pgm"); }),
            "wider.pgm: malformed PGM: width 65537 out of range [1, 65536]");
  EXPECT_EQ(errorOf([] { parsePgm("P5\n1 65537\n255\n", "taller.pgm"); }), "taller.pgm: malformed PGM: height 65537 out of range [1, 65536]");
}

TEST(RosImportBounds, AnImageMustFitInTheFilesRealSize) {
  // 100,000 x 100,000 pixels claimed by a file of a few bytes: refused before any allocation.
  EXPECT_THAT(errorOf([] { parsePgm("P5\n65536 65536\n255\n\x01\x02", "huge.pgm"); }),
              HasSubstr("need 4294967296 bytes of pixel data, found 2"));
  EXPECT_EQ(parsePgm("P5\n2 2\n255\n\x01\x02\x03\x04", "exact.pgm").pixels.size(), 4u);
}

TEST(RosImportBounds, AFileOf256MiBIsReadAndOneByteMoreIsRefusedNamingTheBound) {
  TempDir dir;
  // Sparse files: no disk space used. Just inside, the bytes are read and judged as a PGM.
  const auto file = dir.write("big.pgm", "P5\n1 1\n255\n\x01");
  std::filesystem::resize_file(file, kMaxPgmFileBytes);
  EXPECT_EQ(loadPgm(file).width, 1);
  std::filesystem::resize_file(file, kMaxPgmFileBytes + 1);
  EXPECT_EQ(errorOf([&] { loadPgm(file); }), file.string() + ": 268435457 bytes, beyond the bound of 268435456 bytes for a PGM image");
}

}  // namespace
}  // namespace staa
