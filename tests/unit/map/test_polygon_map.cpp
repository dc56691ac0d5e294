#include "map/polygon_map.hpp"

#include "geometry/polygon.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <typeinfo>

namespace staa {
namespace {

namespace fs = std::filesystem;

// A file with every feature of the format: bounds, a thin wall, a non-convex polygon, a
// clockwise one, and goals, one of them inside the wall (kept: reachability is not the
// loader's business).
const std::string kValid = R"(format: staa-polygon-map/1
name: office
bounds: [0, 0, 10, 8]
obstacles:
  - [[0.0, 0.0], [1.0, 0.0], [1.0, 0.2], [0.0, 0.2]]
  - [[2, 2], [4, 2], [4, 4], [3, 3], [2, 4]]   # an arrow: non-convex
  - [[5, 5], [5, 6], [6, 6], [6, 5]]           # clockwise
goals:
  - [2.5, 4.0]
  - [0.5, 0.1]
)";

// Each test gets its own folder under the system's temporary directory.
class MapFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("staa-test-polygon-map-" + std::to_string(std::random_device{}()) + "-" + info->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  // The message of the MapError that loading `text` from a file called `name` raises.
  std::string loadError(const std::string& name, const std::string& text) const {
    const fs::path p = write(name, text);
    try {
      loadPolygonMap(p);
    } catch (const MapError& e) {
      return e.what();
    }
    ADD_FAILURE() << name << " loaded although it should be rejected:\n" << text;
    return "";
  }

  // A minimal file with the given obstacles list; its first item is on line 4.
  static std::string withObstacles(const std::string& obstacles) {
    return "format: staa-polygon-map/1\nname: office\nobstacles:\n" + obstacles;
  }

  fs::path dir_;
};

std::string path(const fs::path& dir, const char* name) { return (dir / name).string(); }

bool sameBits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

// Bit-for-bit equality of two maps, reporting the first difference.
::testing::AssertionResult identical(const PolygonMap& a, const PolygonMap& b) {
  if (a.name != b.name) return ::testing::AssertionFailure() << "name '" << a.name << "' vs '" << b.name << "'";
  if (a.bounds.has_value() != b.bounds.has_value()) return ::testing::AssertionFailure() << "bounds presence differs";
  if (a.bounds) {
    for (int k = 0; k < 2; ++k) {
      if (!sameBits(a.bounds->min[k], b.bounds->min[k]) || !sameBits(a.bounds->max[k], b.bounds->max[k])) {
        return ::testing::AssertionFailure() << "bounds differ";
      }
    }
  }
  if (a.obstacles.size() != b.obstacles.size()) return ::testing::AssertionFailure() << "obstacle counts differ";
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    if (a.obstacles[i].size() != b.obstacles[i].size()) return ::testing::AssertionFailure() << "obstacles[" << i << "] sizes differ";
    for (std::size_t k = 0; k < a.obstacles[i].size(); ++k) {
      for (int c = 0; c < 2; ++c) {
        if (!sameBits(a.obstacles[i][k][c], b.obstacles[i][k][c])) {
          return ::testing::AssertionFailure() << "obstacles[" << i << "][" << k << "] differ: " << a.obstacles[i][k][c]
                                               << " vs " << b.obstacles[i][k][c];
        }
      }
    }
  }
  if (a.goals.size() != b.goals.size()) return ::testing::AssertionFailure() << "goal counts differ";
  for (std::size_t i = 0; i < a.goals.size(); ++i) {
    if (!sameBits(a.goals[i].x(), b.goals[i].x()) || !sameBits(a.goals[i].y(), b.goals[i].y())) {
      return ::testing::AssertionFailure() << "goals[" << i << "] differ";
    }
  }
  return ::testing::AssertionSuccess();
}

// ---- loading ----

TEST_F(MapFiles, LoadsEveryPartOfAValidFile) {
  const PolygonMap m = loadPolygonMap(write("office.yaml", kValid));
  EXPECT_EQ(m.name, "office");
  ASSERT_TRUE(m.bounds.has_value());
  EXPECT_EQ(m.bounds->min, Vec2(0, 0));
  EXPECT_EQ(m.bounds->max, Vec2(10, 8));
  ASSERT_EQ(m.obstacles.size(), 3u);
  EXPECT_EQ(m.obstacles[0], (Polygon{{0, 0}, {1, 0}, {1, 0.2}, {0, 0.2}}));
  ASSERT_EQ(m.obstacles[1].size(), 5u);
  EXPECT_EQ(m.obstacles[1][3], Vec2(3, 3));
  EXPECT_DOUBLE_EQ(signedArea(m.obstacles[1]), 3.0);   // 2 x 2 square minus the notch of 1
  EXPECT_DOUBLE_EQ(signedArea(m.obstacles[2]), -1.0);  // clockwise winding is kept as written
  ASSERT_EQ(m.goals.size(), 2u);
  EXPECT_EQ(m.goals[0], Vec2(2.5, 4.0));
  // The second goal lies inside obstacle 0 and is kept.
  EXPECT_EQ(m.goals[1], Vec2(0.5, 0.1));
  EXPECT_TRUE(pointInPolygon(m.goals[1], m.obstacles[0]));
}

TEST_F(MapFiles, BoundsGoalsAndNameAreOptional) {
  const PolygonMap m = loadPolygonMap(write("bare.yaml", "format: staa-polygon-map/1\nobstacles:\n  - [[0, 0], [1, 0], [0, 1]]\n"));
  EXPECT_EQ(m.name, "");
  EXPECT_FALSE(m.bounds.has_value());
  ASSERT_EQ(m.obstacles.size(), 1u);
  EXPECT_DOUBLE_EQ(signedArea(m.obstacles[0]), 0.5);
  EXPECT_TRUE(m.goals.empty());
  // An empty map is a map.
  EXPECT_TRUE(parsePolygonMap("format: staa-polygon-map/1\nobstacles: []\n", "empty.yaml").obstacles.empty());
}

// ---- every kind of error names the file, the polygon's index and the problem ----

TEST_F(MapFiles, RejectsAMissingOrUnknownFormat) {
  EXPECT_EQ(loadError("a.yaml", "name: x\nobstacles: []\n"), path(dir_, "a.yaml") + ": format: missing (expected staa-polygon-map/1)");
  EXPECT_EQ(loadError("b.yaml", "format: staa-polygon-map/2\nobstacles: []\n"),
            path(dir_, "b.yaml") + ":1: format: unknown format, expected staa-polygon-map/1, got 'staa-polygon-map/2'");
  EXPECT_EQ(loadError("c.yaml", "format: [1, 2]\n"),
            path(dir_, "c.yaml") + ":1: format: unknown format, expected staa-polygon-map/1, got a list of 2 items");
}

TEST_F(MapFiles, RejectsDocumentsThatAreNotAMapping) {
  EXPECT_EQ(loadError("empty.yaml", ""),
            path(dir_, "empty.yaml") +
                ": expected a mapping {format, name, bounds, obstacles, goals} (a staa-polygon-map/1 document), got nothing");
  EXPECT_EQ(loadError("text.yaml", "just some text\n"),
            path(dir_, "text.yaml") +
                ": expected a mapping {format, name, bounds, obstacles, goals} (a staa-polygon-map/1 document), got 'just some text'");
}

TEST_F(MapFiles, RejectsUnknownAndDuplicateKeys) {
  // A misspelt key would otherwise load as an empty map.
  EXPECT_EQ(loadError("typo.yaml", "format: staa-polygon-map/1\nobstacle:\n  - [[0, 0], [1, 0], [0, 1]]\n"),
            path(dir_, "typo.yaml") + ":2: obstacle: unknown key (expected format, name, bounds, obstacles, goals)");
  EXPECT_EQ(loadError("dup.yaml", "format: staa-polygon-map/1\ngoals: []\ngoals: []\n"),
            path(dir_, "dup.yaml") + ":3: goals: given twice (first on line 2)");
}

TEST_F(MapFiles, RejectsAPolygonWithFewerThanThreeVertices) {
  const std::string msg = loadError("office.yaml", withObstacles("  - [[0, 0], [1, 0], [0, 1]]\n  - [[0, 0], [1, 0]]\n"));
  EXPECT_EQ(msg, path(dir_, "office.yaml") + ":5: obstacles[1]: has 2 vertices, needs at least 3");
  EXPECT_EQ(loadError("flat.yaml", withObstacles("  - []\n")),
            path(dir_, "flat.yaml") + ":4: obstacles[0]: has 0 vertices, needs at least 3");
}

TEST_F(MapFiles, RejectsAVertexThatIsNotAPairOfNumbers) {
  const std::string ok = "  - [[0, 0], [1, 0], [0, 1]]\n";
  EXPECT_EQ(loadError("office.yaml", withObstacles(ok + ok + "  - [[0, 0], [1, 2, 3], [0, 1]]\n")),
            path(dir_, "office.yaml") + ":6: obstacles[2][1]: expected [x, y], got a list of 3 items");
  EXPECT_EQ(loadError("word.yaml", withObstacles("  - [[0, 0], [1, abc], [0, 1]]\n")),
            path(dir_, "word.yaml") + ":4: obstacles[0][1][1]: expected a number, got 'abc'");
  EXPECT_EQ(loadError("scalar.yaml", withObstacles(ok + "  - [[0, 0], 7, [0, 1]]\n")),
            path(dir_, "scalar.yaml") + ":5: obstacles[1][1]: expected [x, y], got '7'");
  EXPECT_EQ(loadError("huge.yaml", withObstacles("  - [[0, 0], [1e400, 0], [0, 1]]\n")),
            path(dir_, "huge.yaml") + ":4: obstacles[0][1][0]: expected a number, got '1e400'");
  EXPECT_EQ(loadError("poly.yaml", withObstacles("  - {x: 1}\n")),
            path(dir_, "poly.yaml") + ":4: obstacles[0]: expected a list of [x, y] vertices, got a mapping");
}

TEST_F(MapFiles, RejectsNonFiniteAndOutOfRangeNumbers) {
  const std::string ok = "  - [[0, 0], [1, 0], [0, 1]]\n";
  EXPECT_EQ(loadError("nan.yaml", withObstacles(ok + "  - [[0, 0], [1, 0], [.nan, 0.2]]\n")),
            path(dir_, "nan.yaml") + ":5: obstacles[1][2][0]: must be finite, got .nan");
  EXPECT_EQ(loadError("inf.yaml", withObstacles("  - [[0, 0], [1, -.inf], [0, 1]]\n")),
            path(dir_, "inf.yaml") + ":4: obstacles[0][1][1]: must be finite, got -.inf");
  EXPECT_EQ(loadError("far.yaml", withObstacles("  - [[0, 0], [1, 0], [0, 2e6]]\n")),
            path(dir_, "far.yaml") + ":4: obstacles[0]: vertex 2 is out of range (0, 2e+06) (|x|, |y| <= 1e+06 m)");
  EXPECT_EQ(loadError("goal.yaml", "format: staa-polygon-map/1\nobstacles: []\ngoals:\n  - [1, 2]\n  - [.inf, 2]\n"),
            path(dir_, "goal.yaml") + ":5: goals[1][0]: must be finite, got .inf");
}

TEST_F(MapFiles, RejectsASelfIntersectingPolygonNamingTheEdges) {
  const std::string ok = "  - [[0, 0], [1, 0], [0, 1]]\n";
  // Edge 1 runs (0,0)-(1,1), edge 3 runs (1,0)-(0,1): they cross at (0.5, 0.5).
  EXPECT_EQ(loadError("office.yaml", withObstacles(ok + ok + ok + "  - [[0, 1], [0, 0], [1, 1], [1, 0]]\n")),
            path(dir_, "office.yaml") + ":7: obstacles[3]: self-intersecting (edges 1 and 3 cross)");
  // A vertex on a non-adjacent edge touches without crossing.
  EXPECT_EQ(loadError("touch.yaml", withObstacles("  - [[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]]\n")),
            path(dir_, "touch.yaml") + ":4: obstacles[0]: self-intersecting (edges 0 and 2 touch)");
  EXPECT_EQ(loadError("repeat.yaml", withObstacles("  - [[0, 0], [1, 0], [1, 0], [0, 1]]\n")),
            path(dir_, "repeat.yaml") + ":4: obstacles[0]: vertex 2 repeats vertex 1 (1, 0) (zero-length edge 1)");
}

TEST_F(MapFiles, RejectsAPolygonOfZeroArea) {
  EXPECT_EQ(loadError("line.yaml", withObstacles("  - [[0, 0], [1, 0], [0, 1]]\n  - [[0, 0], [1, 1], [2, 2]]\n")),
            path(dir_, "line.yaml") + ":5: obstacles[1]: has zero area (all vertices on one line)");
  // Collinear in decimal but not exactly in binary: still zero area, relative to its size.
  EXPECT_EQ(loadError("line2.yaml", withObstacles("  - [[0.1, 0.1], [0.2, 0.2], [0.3, 0.3]]\n")),
            path(dir_, "line2.yaml") + ":4: obstacles[0]: has zero area (all vertices on one line)");
}

TEST_F(MapFiles, RejectsBadBounds) {
  EXPECT_EQ(loadError("x.yaml", "format: staa-polygon-map/1\nbounds: [5, 0, 3, 8]\n"),
            path(dir_, "x.yaml") + ":2: bounds: xmin (5) must be less than xmax (3)");
  EXPECT_EQ(loadError("y.yaml", "format: staa-polygon-map/1\nbounds: [0, 8, 3, 8]\n"),
            path(dir_, "y.yaml") + ":2: bounds: ymin (8) must be less than ymax (8)");
  EXPECT_EQ(loadError("three.yaml", "format: staa-polygon-map/1\nbounds: [0, 0, 1]\n"),
            path(dir_, "three.yaml") + ":2: bounds: expected 4 numbers [xmin, ymin, xmax, ymax], got a list of 3 items");
  EXPECT_EQ(loadError("word.yaml", "format: staa-polygon-map/1\nbounds: [0, 0, 1, big]\n"),
            path(dir_, "word.yaml") + ":2: bounds[3]: expected a number, got 'big'");
  EXPECT_EQ(loadError("nan.yaml", "format: staa-polygon-map/1\nbounds: [0, .nan, 1, 1]\n"),
            path(dir_, "nan.yaml") + ":2: bounds[1]: must be finite, got .nan");
}

TEST_F(MapFiles, RejectsGoalsThatAreNotPairs) {
  EXPECT_EQ(loadError("g.yaml", "format: staa-polygon-map/1\ngoals:\n  - [1, 2]\n  - [3]\n"),
            path(dir_, "g.yaml") + ":4: goals[1]: expected [x, y], got a list of 1 items");
  EXPECT_EQ(loadError("h.yaml", "format: staa-polygon-map/1\ngoals: [1, 2]\n"),
            path(dir_, "h.yaml") + ":2: goals[0]: expected [x, y], got '1'");
  EXPECT_EQ(loadError("i.yaml", "format: staa-polygon-map/1\ngoals: here\n"),
            path(dir_, "i.yaml") + ":2: goals: expected a list of [x, y] points, got 'here'");
}

TEST_F(MapFiles, ReportsYamlSyntaxErrorsWithTheirLine) {
  // The flow list opened on line 4 is never closed.
  const std::string msg = loadError("broken.yaml", "format: staa-polygon-map/1\nname: x\nobstacles:\n  - [[0, 0], [1, 0], [0, 1]\ngoals: []\n");
  EXPECT_EQ(msg.rfind(path(dir_, "broken.yaml") + ":5:1: not valid YAML: ", 0), 0u) << msg;
  const std::string tab = loadError("tab.yaml", "format: staa-polygon-map/1\nobstacles:\n  - [[0, 0], [1, 0], [0, 1]]\n - ]\n");
  EXPECT_NE(tab.find(path(dir_, "tab.yaml") + ":4:"), std::string::npos) << tab;
  EXPECT_NE(tab.find("not valid YAML"), std::string::npos) << tab;
}

TEST_F(MapFiles, ReportsAMissingFileAndADirectory) {
  try {
    loadPolygonMap(dir_ / "nowhere.yaml");
    FAIL() << "a missing file loaded";
  } catch (const MapError& e) {
    EXPECT_EQ(std::string(e.what()), path(dir_, "nowhere.yaml") + ": map file not found");
  }
  try {
    loadPolygonMap(dir_);
    FAIL() << "a directory loaded";
  } catch (const MapError& e) {
    EXPECT_EQ(std::string(e.what()), dir_.string() + ": is a directory, not a map file");
  }
}

TEST(PolygonMapValidate, NamesTheSourceAndIndexForMapsBuiltInMemory) {
  PolygonMap m;
  m.obstacles = {{{0, 0}, {1, 0}, {0, 1}}, {{0, 1}, {0, 0}, {1, 1}, {1, 0}}};
  try {
    validatePolygonMap(m, "importer");
    FAIL() << "a bow tie passed validation";
  } catch (const MapError& e) {
    EXPECT_EQ(std::string(e.what()), "importer: obstacles[1]: self-intersecting (edges 1 and 3 cross)");
  }
  m.obstacles.pop_back();
  m.bounds = Box{{0, 0}, {-1, 1}};
  EXPECT_THROW(validatePolygonMap(m, "importer"), MapError);
  m.bounds = Box{{0, 0}, {1, 1}};
  m.goals = {{0.2, 0.2}};  // inside the triangle: allowed
  EXPECT_NO_THROW(validatePolygonMap(m, "importer"));
}

// ---- writing ----

TEST(PolygonMapYaml, WritesTheDocumentedLayout) {
  PolygonMap m;
  m.name = "office";
  m.bounds = Box{{0, 0}, {27, 27}};
  m.obstacles = {{{0, 0}, {1, 0}, {1, 0.2}, {0, 0.2}}};
  m.goals = {{2.5, 4}};
  EXPECT_EQ(toYaml(m),
            "format: staa-polygon-map/1\n"
            "name: \"office\"\n"
            "bounds: [0, 0, 27, 27]\n"
            "obstacles:\n"
            "  - [[0, 0], [1, 0], [1, 0.2], [0, 0.2]]\n"
            "goals:\n"
            "  - [2.5, 4]\n");
  // Bounds and goals appear only when present.
  m.bounds.reset();
  m.goals.clear();
  m.obstacles.clear();
  EXPECT_EQ(toYaml(m), "format: staa-polygon-map/1\nname: \"office\"\nobstacles: []\n");
}

TEST_F(MapFiles, RoundTripsBitForBit) {
  PolygonMap m;
  // Names YAML would otherwise read as null, a boolean, a mapping or a comment.
  m.name = "~ \"quoted\" a: b # not a comment\n\ttab \\ bureau \xc3\xa9";
  m.bounds = Box{{-0.1, 1.0 / 3.0}, {std::nextafter(27.0, 30.0), 1e5 + 0.123456789012}};
  const double denorm = std::numeric_limits<double>::denorm_min();
  m.obstacles = {
      {{denorm, -0.0}, {1.0 / 3.0, 0.0}, {std::sqrt(2.0), kPi}, {-2.0 / 7.0, 1.0 - 1e-16}},
      {{0.1, 0.2}, {0.3, 0.2}, {0.3, 0.7000000000000001}},
      {{123456.789, -98765.4321}, {123457.0, -98765.4321}, {123457.0, -98765.0}},
  };
  m.goals = {{1e-300, 2.5}, {-0.0, 6.02214076e5}};
  const fs::path p = dir_ / "round.yaml";
  savePolygonMap(m, p);
  const PolygonMap back = loadPolygonMap(p);
  EXPECT_TRUE(identical(m, back));
  EXPECT_TRUE(std::signbit(back.obstacles[0][0].y()));  // -0.0 stays negative zero
  EXPECT_EQ(back.obstacles[0][0].x(), denorm);
  // Saving again gives the same bytes.
  EXPECT_EQ(toYaml(back), toYaml(m));

  // Without bounds and goals they are absent from the text and from the loaded map.
  m.bounds.reset();
  m.goals.clear();
  savePolygonMap(m, p);
  const PolygonMap bare = loadPolygonMap(p);
  EXPECT_TRUE(identical(m, bare));
  EXPECT_EQ(toYaml(m).find("bounds"), std::string::npos);
  EXPECT_EQ(toYaml(m).find("goals"), std::string::npos);
}

TEST_F(MapFiles, RefusesToSaveAnInvalidMap) {
  PolygonMap m;
  m.obstacles = {{{0, 0}, {1, 0}, {0, 1}}, {{0, 0}, {std::nan(""), 0}, {0, 1}}};
  const fs::path p = dir_ / "bad.yaml";
  try {
    savePolygonMap(m, p);
    FAIL() << "an invalid map was saved";
  } catch (const MapError& e) {
    EXPECT_EQ(std::string(e.what()), p.string() + ": obstacles[1]: vertex 1 is not finite (.nan, 0)");
  }
  EXPECT_FALSE(fs::exists(p));
}

// ---- never crash: every mutation of a valid file loads as a valid map or is a MapError ----

TEST(PolygonMapFuzz, MutatedAndTruncatedFilesLoadOrFailCleanly) {
  std::mt19937_64 rng(20240607);
  const auto pick = [&rng](std::size_t n) { return static_cast<std::size_t>(rng() % n); };
  std::string alphabet = "[]{},:-.#'\"\n \t0123456789e+~!&*|>?.nainf";
  alphabet += '\0';
  alphabet += '\xff';

  std::vector<std::string> inputs;
  // Every truncation of the valid file.
  for (std::size_t n = 0; n <= kValid.size(); n += 2) inputs.push_back(kValid.substr(0, n));
  // Random byte edits, deletions and line duplications, one to three per input.
  for (int k = 0; k < 400; ++k) {
    std::string s = kValid;
    const int edits = 1 + static_cast<int>(pick(3));
    for (int e = 0; e < edits && !s.empty(); ++e) {
      switch (pick(4)) {
        case 0: s[pick(s.size())] = alphabet[pick(alphabet.size())]; break;
        case 1: s.insert(pick(s.size()), 1, alphabet[pick(alphabet.size())]); break;
        case 2: s.erase(pick(s.size()), 1 + pick(6)); break;
        default: {
          const std::size_t a = pick(s.size()), b = pick(s.size());
          s.insert(std::max(a, b), s.substr(std::min(a, b), 1 + std::max(a, b) - std::min(a, b)));
        }
      }
    }
    inputs.push_back(s);
  }
  // Hostile shapes: very deep nesting, binary, a huge vertex list.
  inputs.push_back("format: staa-polygon-map/1\nobstacles: " + std::string(5000, '[') + "\n");
  inputs.push_back(std::string("\x00\x01\x02\xfe\xff", 5));
  {
    std::ostringstream big;
    big << "format: staa-polygon-map/1\nobstacles:\n  - [";
    for (int i = 0; i < 2000; ++i) big << (i ? ", " : "") << "[" << std::cos(i * 2 * kPi / 2000) << ", " << std::sin(i * 2 * kPi / 2000) << "]";
    big << "]\n";
    inputs.push_back(big.str());
  }

  int loaded = 0, rejected = 0;
  for (const std::string& text : inputs) {
    try {
      const PolygonMap m = parsePolygonMap(text, "fuzz.yaml");
      // Whatever loads is a valid map, and it survives its own round trip.
      EXPECT_NO_THROW(validatePolygonMap(m, "fuzz.yaml")) << text;
      EXPECT_TRUE(identical(m, parsePolygonMap(toYaml(m), "again.yaml"))) << text;
      ++loaded;
    } catch (const MapError& e) {
      // "fuzz.yaml:LINE: ..." or, for the document as a whole, "fuzz.yaml: ...".
      EXPECT_THAT(std::string(e.what()), ::testing::ContainsRegex("^fuzz\\.yaml(:[0-9]+)*: ")) << e.what();
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "escaped as " << typeid(e).name() << ": " << e.what() << "\ninput:\n" << text;
    }
  }
  EXPECT_EQ(loaded + rejected, static_cast<int>(inputs.size()));
  // Both outcomes occur, so the mutations did exercise the checks and the happy path.
  EXPECT_GT(loaded, 20);
  EXPECT_GT(rejected, 100);
}


// ---- input bounds (docs/ARCHITECTURE.md, "Input bounds") ----

// A regular polygon of n vertices on a circle of radius 5.
Polygon circle(std::size_t n) {
  Polygon p;
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    p.push_back({5.0 * std::cos(a), 5.0 * std::sin(a)});
  }
  return p;
}

TEST_F(MapFiles, APolygonOfAMillionVerticesLoadsAndOneMoreIsRefusedNamingTheBound) {
  PolygonMap map;
  map.obstacles.push_back(circle(kMaxPolygonVertices));
  const fs::path file = dir_ / "million.yaml";
  savePolygonMap(map, file);
  EXPECT_EQ(loadPolygonMap(file).obstacles.front().size(), kMaxPolygonVertices);
  // One more vertex, written by hand (savePolygonMap refuses it).
  std::string text = "format: staa-polygon-map/1\nobstacles:\n  - [";
  for (std::size_t k = 0; k <= kMaxPolygonVertices; ++k) text += k ? ", [" + std::to_string(k) + ", 0]" : "[0, 1]";
  text += "]\n";
  EXPECT_EQ(loadError("million-and-one.yaml", text),
            path(dir_, "million-and-one.yaml") + ":3: obstacles[0]: has 1000001 points, beyond the bound of 1000000 vertices per polygon");
  map.obstacles.front().push_back({0.0, 0.0});
  EXPECT_THROW(savePolygonMap(map, dir_ / "refused.yaml"), MapError);
}

TEST_F(MapFiles, AHundredThousandPolygonsAndGoalsLoadAndOneMoreIsRefusedNamingTheBound) {
  const auto text = [](std::size_t polygons, std::size_t goals) {
    std::string t = "format: staa-polygon-map/1\nobstacles:\n";
    for (std::size_t i = 0; i < polygons; ++i) t += "  - [[0, 0], [1, 0], [0, 1]]\n";
    t += "goals:\n";
    for (std::size_t i = 0; i < goals; ++i) t += "  - [2, 2]\n";
    return t;
  };
  const PolygonMap map = loadPolygonMap(write("inside.yaml", text(kMaxMapPolygons, kMaxMapGoals)));
  EXPECT_EQ(map.obstacles.size(), kMaxMapPolygons);
  EXPECT_EQ(map.goals.size(), kMaxMapGoals);
  EXPECT_EQ(loadError("polygons.yaml", text(kMaxMapPolygons + 1, 1)),
            path(dir_, "polygons.yaml") + ":3: obstacles: has 100001 polygons, beyond the bound of 100000 per map");
  EXPECT_EQ(loadError("goals.yaml", text(1, kMaxMapGoals + 1)),
            path(dir_, "goals.yaml") + ":5: goals: has 100001 goals, beyond the bound of 100000 per map");
}

}  // namespace
}  // namespace staa
