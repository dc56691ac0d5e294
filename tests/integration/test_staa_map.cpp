// staa-map run for real: exit codes, stdout, stderr and the files it writes; and the SVG
// canvas it draws with.

#include "map/polygon_map.hpp"
#include "shared_dir.hpp"
#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"

#include "read_file.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace staa {
namespace {

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

using staa::test::readFile;

// The text between single quotes, as error messages show values. Strings here are built by
// appending: GCC 12 at -O3 warns falsely (-Wrestrict) on "'" + s + "'" and " " + s.
std::string inQuotes(const std::string& s) {
  std::string q;
  q.reserve(s.size() + 2);
  q.push_back('\'');
  q.append(s);
  q.push_back('\'');
  return q;
}

// Shell-quoted: a single quote inside becomes '\''.
std::string quote(const std::string& arg) {
  std::string q;
  q.push_back('\'');
  for (char c : arg) {
    if (c == '\'') {
      q.append("'\\''");
    } else {
      q.push_back(c);
    }
  }
  q.push_back('\'');
  return q;
}

// A fresh folder per test, removed at the end.
class StaaMapTool : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("staa-map-test-" + std::to_string(rd()) + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Runs the real binary with `args` (each shell-quoted), stdout and stderr captured apart.
  RunResult run(const std::vector<std::string>& args) const {
    std::string cmd = quote(STAA_MAP_EXE);
    for (const auto& a : args) {
      cmd.push_back(' ');
      cmd.append(quote(a));
    }
    const fs::path err_file = dir_ / "stderr.txt";
    cmd.append(" 2>");
    cmd.append(quote(err_file.string()));
    RunResult r;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (pipe == nullptr) return r;
    char buf[4096];
    std::size_t n = 0;
    while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
    const int status = pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = readFile(err_file);
    return r;
  }

  fs::path path(const std::string& name) const { return dir_ / name; }

  // The office map written by `staa-map generate office`.
  fs::path office() {
    const fs::path p = path("office.yaml");
    if (!fs::exists(p)) {
      const RunResult r = run({"generate", "office", "-o", p.string()});
      EXPECT_EQ(r.exit_code, 0) << r.err;
    }
    return p;
  }

  nlohmann::json pathJson(const std::vector<std::string>& extra) {
    std::vector<std::string> args{"path", office().string()};
    args.insert(args.end(), extra.begin(), extra.end());
    args.push_back("--json");
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  }

  fs::path dir_;
};

TEST_F(StaaMapTool, GeneratedOfficeInfoReports43GoalsAndItsBounds) {
  const RunResult r = run({"info", office().string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["name"], "office");
  EXPECT_EQ(j["goals"], 43);
  EXPECT_EQ(j["bounds"], nlohmann::json::array({0.0, 0.0, 27.0, 27.0}));
  const std::size_t polygons = j["polygons"];
  EXPECT_EQ(polygons, loadPolygonMap(office()).obstacles.size());
  EXPECT_EQ(j["vertices"], 4 * polygons);  // every piece of the office is a box
  EXPECT_EQ(j["convex"], polygons);
  EXPECT_EQ(j["non_convex"], 0);
  // The union is less than 27 x 27 and more than the centre block alone (9 x 9).
  EXPECT_GT(j["obstacle_area_m2"].get<double>(), 81.0);
  EXPECT_LT(j["obstacle_area_m2"].get<double>(), 27.0 * 27.0);

  const RunResult human = run({"info", office().string()});
  ASSERT_EQ(human.exit_code, 0) << human.err;
  EXPECT_NE(human.out.find("goals:     43"), std::string::npos) << human.out;
}

TEST_F(StaaMapTool, PathAcrossTheOfficeIsFoundAndJoinsTheRequestedPoints) {
  // Room 0 (bottom row) to room 13 (top row, far right): around the centre block.
  const Vec2 from{4.5, 1.5}, to{22.5, 25.5};
  const auto j = pathJson({"--from", "4.5,1.5", "--to", "22.5,25.5"});
  ASSERT_TRUE(j["found"].get<bool>()) << j.dump();
  EXPECT_EQ(j["status"], "found");
  const double euclid = (to - from).norm();
  const double length = j["length"];
  EXPECT_GE(length, euclid);
  EXPECT_LT(length, 3.0 * euclid);
  const auto& path = j["path"];
  ASSERT_GE(path.size(), 3u);  // the walls are in the way of a straight line
  EXPECT_EQ(path.front()[0].get<double>(), from.x());
  EXPECT_EQ(path.front()[1].get<double>(), from.y());
  EXPECT_EQ(path.back()[0].get<double>(), to.x());
  EXPECT_EQ(path.back()[1].get<double>(), to.y());
  double sum = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    sum += std::hypot(path[k][0].get<double>() - path[k - 1][0].get<double>(),
                      path[k][1].get<double>() - path[k - 1][1].get<double>());
  }
  EXPECT_NEAR(sum, length, 1e-6);
  EXPECT_GE(j["time_us"].get<double>(), 0.0);
  EXPECT_GE(j["build_us"].get<double>(), 0.0);
  EXPECT_FALSE(j["start_moved"].get<bool>());
  EXPECT_FALSE(j["goal_moved"].get<bool>());
  EXPECT_GT(j["expansions"].get<int>(), 0);
  EXPECT_TRUE(j.contains("edge_checks"));

  // The same query without --json: one human-readable line with the length.
  const RunResult human = run({"path", office().string(), "--from", "4.5,1.5", "--to", "22.5,25.5"});
  ASSERT_EQ(human.exit_code, 0) << human.err;
  EXPECT_NE(human.out.find("length"), std::string::npos) << human.out;
}

TEST_F(StaaMapTool, DoorNarrowerThanTwiceTheInflationClosesTheRoom) {
  // From the corridor (cell (1, 1)) into room 1 at (4.5, 1.5): its 1.35 m door is open to a
  // 0.3 m robot and closed to a 0.8 m one (2 * 0.8 > 1.35).
  const auto open = pathJson({"--from", "4.5,4.5", "--to", "4.5,1.5", "--inflate", "0.3"});
  EXPECT_TRUE(open["found"].get<bool>()) << open.dump();
  const auto closed = pathJson({"--from", "4.5,4.5", "--to", "4.5,1.5", "--inflate", "0.8"});
  EXPECT_FALSE(closed["found"].get<bool>()) << closed.dump();
  EXPECT_EQ(closed["status"], "no path");
  EXPECT_TRUE(closed["path"].empty());
}

// Issue 16: with --robot the route is planned as the control cycle plans it. The building's
// doors, narrowed to 0.75-0.8 m, are closed in M' (the 0.5 x 0.65 m robot's circumradius,
// 0.41 m) and open in the passage map (its inscribed radius + 1 cm).
TEST_F(StaaMapTool, RobotPlansThroughPassagesTheCircumradiusCloses) {
  const std::string map = (fs::path(STAA_SOURCE_DIR) / "docs/results/passages/building.yaml").string();
  const std::string robot = (fs::path(STAA_SOURCE_DIR) / "docs/results/passages/amr.yaml").string();
  const RunResult wide = run({"path", map, "--from", "1.5,2", "--to", "14.5,2", "--inflate", "0.41", "--json"});
  ASSERT_EQ(wide.exit_code, 0) << wide.err;
  EXPECT_EQ(nlohmann::json::parse(wide.out)["status"], "no path");
  const RunResult r = run({"path", map, "--from", "1.5,2", "--to", "14.5,2", "--robot", robot, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["found"].get<bool>()) << r.out;
  EXPECT_TRUE(j["passage"].get<bool>());
  EXPECT_NEAR(j["inflate_m"].get<double>(), std::hypot(0.325, 0.25), 1e-12);
  EXPECT_NEAR(j["passage_inflate_m"].get<double>(), 0.26, 1e-12);
  EXPECT_GT(j["band_m"].get<double>(), 1.0);  // three doors
  EXPECT_LT(j["length"].get<double>(), 13.5);
  // A slot narrower than the robot: the footprint's reason.
  std::ofstream(path("slot.yaml")) << "format: staa-polygon-map/1\nname: slot\nbounds: [0, 0, 8, 4]\nobstacles:\n"
                                      "  - [[3.9, 0], [4.1, 0], [4.1, 1.8], [3.9, 1.8]]\n"
                                      "  - [[3.9, 2.2], [4.1, 2.2], [4.1, 4], [3.9, 4]]\n";
  const RunResult slot = run({"path", path("slot.yaml").string(), "--from", "1,2", "--to", "7,2", "--robot", robot, "--json"});
  ASSERT_EQ(slot.exit_code, 0) << slot.err;
  EXPECT_EQ(nlohmann::json::parse(slot.out)["status"], "no passage wider than the footprint");
  // --robot and --inflate exclude each other; a bad profile is named.
  const RunResult both = run({"path", map, "--from", "1.5,2", "--to", "14.5,2", "--robot", robot, "--inflate", "0.3"});
  EXPECT_EQ(both.exit_code, 2);
  const RunResult missing = run({"path", map, "--from", "1.5,2", "--to", "14.5,2", "--robot", path("none.yaml").string()});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("none.yaml"), std::string::npos) << missing.err;
  // The picture shows both maps.
  const RunResult svg = run({"svg", map, "-o", path("b.svg").string(), "--from", "1.5,2", "--to", "14.5,2", "--robot", robot});
  ASSERT_EQ(svg.exit_code, 0) << svg.err;
  const std::string text = test::readFile(path("b.svg"));
  EXPECT_NE(text.find("passage map"), std::string::npos);
  EXPECT_NE(text.find("through M&apos;&apos;"), std::string::npos);
}

TEST_F(StaaMapTool, GoalInsideAWallIsAnAnswerNotAnError) {
  // x = 3.06 lies in the 0.12 m wall between rooms 0 and 1.
  const RunResult r = run({"path", office().string(), "--from", "4.5,4.5", "--to", "3.06,1.5", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["found"].get<bool>());
  EXPECT_EQ(j["status"], "goal inside an obstacle");
  EXPECT_NE(r.err.find("inside an obstacle"), std::string::npos) << r.err;
}

TEST_F(StaaMapTool, BadNumberIsRejectedNamingTheOptionAndTheValue) {
  const RunResult r = run({"path", office().string(), "--from", "1,x", "--to", "4.5,1.5"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--from"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("'1,x'"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());

  for (const std::string bad : {"1,2x", "1,inf", "nan,1", "1", ",", "1,2,3", ""}) {
    const RunResult b = run({"path", office().string(), "--from", "4.5,4.5", "--to", bad});
    EXPECT_EQ(b.exit_code, 2) << "--to " << inQuotes(bad);
    EXPECT_NE(b.err.find(inQuotes(bad)), std::string::npos) << b.err;
  }
  const RunResult inflate = run({"path", office().string(), "--from", "4.5,4.5", "--to", "4.5,1.5", "--inflate", "-1"});
  EXPECT_EQ(inflate.exit_code, 2);
  EXPECT_NE(inflate.err.find("--inflate"), std::string::npos) << inflate.err;
}

TEST_F(StaaMapTool, MissingMapFileIsNamedOnStderr) {
  const std::string missing = path("no-such-map.yaml").string();
  for (const std::string sub : {"info", "path", "svg"}) {
    std::vector<std::string> args{sub, missing};
    if (sub == "path") args.insert(args.end(), {"--from", "1,1", "--to", "2,2"});
    if (sub == "svg") args.insert(args.end(), {"-o", path("x.svg").string()});
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 2) << sub;
    EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("terminate"), std::string::npos) << r.err;
  }
}

TEST_F(StaaMapTool, SelfIntersectingPolygonIsRejectedWithItsIndex) {
  const fs::path bad = path("bowtie.yaml");
  std::ofstream(bad) << "format: staa-polygon-map/1\nname: bowtie\nobstacles:\n"
                        "  - [[0, 0], [1, 0], [1, 1], [0, 1]]\n"
                        "  - [[2, 0], [3, 1], [3, 0], [2, 1]]\n";
  const RunResult r = run({"info", bad.string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find('1'), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(StaaMapTool, UnknownMapNameAndSubcommandAreRejected) {
  const RunResult r = run({"generate", "castle", "-o", path("castle.yaml").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("castle"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("castle.yaml")));

  const RunResult sub = run({"draw"});
  EXPECT_EQ(sub.exit_code, 2);
  EXPECT_NE(sub.err.find("draw"), std::string::npos) << sub.err;

  const RunResult seed = run({"generate", "clutter", "--seed", "12a", "-o", path("c.yaml").string()});
  EXPECT_EQ(seed.exit_code, 2);
  EXPECT_NE(seed.err.find("'12a'"), std::string::npos) << seed.err;
}

TEST_F(StaaMapTool, EverySubcommandHasHelp) {
  for (const std::string sub : {"info", "import", "generate", "goals", "path", "svg"}) {
    const RunResult r = run({sub, "--help"});
    EXPECT_EQ(r.exit_code, 0) << sub;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(sub), std::string::npos) << r.out;
  }
}

TEST_F(StaaMapTool, GeneratedMapsLoadAndClutterFollowsTheSeed) {
  for (const std::string name : {"office", "apartment", "clutter"}) {
    const fs::path out = path(name + ".yaml");
    const RunResult r = run({"generate", name, "--seed", "7", "-o", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(loadPolygonMap(out).name, name);
  }
  ASSERT_EQ(run({"generate", "clutter", "--seed", "7", "-o", path("c7b.yaml").string()}).exit_code, 0);
  ASSERT_EQ(run({"generate", "clutter", "--seed", "8", "-o", path("c8.yaml").string()}).exit_code, 0);
  EXPECT_EQ(readFile(path("clutter.yaml")), readFile(path("c7b.yaml")));
  EXPECT_NE(readFile(path("clutter.yaml")), readFile(path("c8.yaml")));
}

TEST_F(StaaMapTool, SvgDrawsTheMapAndTheRoute) {
  const fs::path out = path("office.svg");
  const RunResult r =
      run({"svg", office().string(), "-o", out.string(), "--from", "4.5,1.5", "--to", "22.5,25.5", "--scale", "20"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string svg = readFile(out);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);  // the route
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_LT(svg.size(), 200u * 1024u);
  // 27 m at 20 px/m plus margins.
  EXPECT_NE(svg.find("width=\"572\""), std::string::npos) << svg.substr(0, 300);

  // An unwritable output names the path.
  const std::string unwritable = path("no-such-dir/x.svg").string();
  const RunResult w = run({"svg", office().string(), "-o", unwritable});
  EXPECT_EQ(w.exit_code, 2);
  EXPECT_NE(w.err.find(unwritable), std::string::npos) << w.err;

  const RunResult half = run({"svg", office().string(), "-o", out.string(), "--from", "1,1"});
  EXPECT_EQ(half.exit_code, 2);
  EXPECT_NE(half.err.find("--to"), std::string::npos) << half.err;
}

// A 40 x 30 px map_server image at 0.1 m/px: a 1-px black border and a 6 x 4 px black block.
void writeTinyRosMap(const fs::path& dir) {
  const int w = 40, h = 30;
  std::string pixels(static_cast<std::size_t>(w * h), static_cast<char>(254));
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const bool border = r == 0 || c == 0 || r == h - 1 || c == w - 1;
      const bool block = r >= 10 && r < 14 && c >= 20 && c < 26;
      if (border || block) pixels[static_cast<std::size_t>(r * w + c)] = 0;
    }
  }
  std::ofstream(dir / "tiny.pgm", std::ios::binary) << "P5\n" << w << ' ' << h << "\n255\n" << pixels;
  std::ofstream(dir / "tiny.yaml") << "image: tiny.pgm\nresolution: 0.1\norigin: [-1.0, -1.0, 0.0]\n"
                                      "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

TEST_F(StaaMapTool, ImportsATinyRosMapIntoALoadableMap) {
  writeTinyRosMap(dir_);
  const fs::path out = path("tiny-polygons.yaml");
  const RunResult r = run({"import", path("tiny.yaml").string(), "-o", out.string(), "--simplify", "0.05"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("polygons"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" ms"), std::string::npos) << r.out;
  const PolygonMap map = loadPolygonMap(out);
  EXPECT_FALSE(map.obstacles.empty());
  ASSERT_TRUE(map.bounds.has_value());
  EXPECT_NEAR(map.bounds->min.x(), -1.0, 1e-9);
  EXPECT_NEAR(map.bounds->max.x(), 3.0, 1e-9);
  EXPECT_NEAR(map.bounds->max.y(), 2.0, 1e-9);

  // The block (x 1.0-1.6, y 0.6-1.0 in the map frame) is an obstacle: a path past it is
  // longer than the straight line.
  const RunResult p = run({"path", out.string(), "--from", "0.5,0.8", "--to", "2.2,0.8", "--inflate", "0.1", "--json"});
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const auto j = nlohmann::json::parse(p.out);
  ASSERT_TRUE(j["found"].get<bool>()) << p.out;
  EXPECT_GT(j["length"].get<double>(), 1.7 + 1e-3);

  const RunResult bad = run({"import", path("tiny.yaml").string(), "-o", out.string(), "--simplify", "-0.1"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--simplify"), std::string::npos) << bad.err;
}

// A 10 x 8 m hall at 0.05 m/px: a 2-px black border and a 1 x 1 m black pillar in the middle.
void writeHallRosMap(const fs::path& dir) {
  const int w = 200, h = 160;
  std::string pixels(static_cast<std::size_t>(w * h), static_cast<char>(254));
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const bool border = r < 2 || c < 2 || r >= h - 2 || c >= w - 2;
      const bool pillar = r >= 70 && r < 90 && c >= 90 && c < 110;
      if (border || pillar) pixels[static_cast<std::size_t>(r * w + c)] = 0;
    }
  }
  std::ofstream(dir / "hall.pgm", std::ios::binary) << "P5\n" << w << ' ' << h << "\n255\n" << pixels;
  std::ofstream(dir / "hall.yaml") << "image: hall.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
                                      "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

TEST_F(StaaMapTool, ImportWithGoalsWritesThatManyGoalsWithTheirClearance) {
  writeHallRosMap(dir_);
  const fs::path out = path("hall-polygons.yaml");
  const RunResult r = run({"import", path("hall.yaml").string(), "-o", out.string(), "--goals", "20"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("placed 20 goals (clearance 0.60 m, spacing 1.50 m, seed 1)"), std::string::npos) << r.out;
  const PolygonMap map = loadPolygonMap(out);
  ASSERT_EQ(map.goals.size(), 20U);
  for (const Vec2& g : map.goals) {
    // Off the 0.1 m border walls and the pillar [4.5, 5.5] x [3.5, 4.5] by 0.6 m.
    EXPECT_GE(std::min({g.x() - 0.1, 9.9 - g.x(), g.y() - 0.1, 7.9 - g.y()}), 0.6 - 1e-6) << g.transpose();
    const double dx = std::max({4.5 - g.x(), 0.0, g.x() - 5.5}), dy = std::max({3.5 - g.y(), 0.0, g.y() - 4.5});
    EXPECT_GE(std::hypot(dx, dy), 0.6 - 1e-6) << g.transpose();
  }

  // A larger clearance: fewer places, each at least that far from the walls.
  const RunResult wide = run({"import", path("hall.yaml").string(), "-o", out.string(), "--goals", "20",
                              "--goal-clearance", "1.5"});
  ASSERT_EQ(wide.exit_code, 0) << wide.err;
  for (const Vec2& g : loadPolygonMap(out).goals) {
    EXPECT_GE(std::min({g.x() - 0.1, 9.9 - g.x(), g.y() - 0.1, 7.9 - g.y()}), 1.5 - 1e-6) << g.transpose();
  }

  // No room at all: bad input naming the file.
  const RunResult none = run({"import", path("hall.yaml").string(), "-o", path("none.yaml").string(), "--goals", "5",
                              "--goal-clearance", "4.5"});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find(path("hall.yaml").string()), std::string::npos) << none.err;
  EXPECT_NE(none.err.find("no free place"), std::string::npos) << none.err;
  EXPECT_FALSE(fs::exists(path("none.yaml")));

  struct Bad {
    std::vector<std::string> extra;
    std::string option, value;
  };
  for (const Bad& b : std::vector<Bad>{{{"--goals", "x"}, "--goals", "'x'"},
                                       {{"--goals", "-3"}, "--goals", "'-3'"},
                                       {{"--goals", "5", "--goal-clearance", "-1"}, "--goal-clearance", "'-1'"},
                                       {{"--goal-clearance", "0.5"}, "--goal-clearance", "--goals"}}) {
    std::vector<std::string> args{"import", path("hall.yaml").string(), "-o", path("bad.yaml").string()};
    args.insert(args.end(), b.extra.begin(), b.extra.end());
    const RunResult e = run(args);
    EXPECT_EQ(e.exit_code, 2) << b.extra[0] << " " << b.extra[1];
    EXPECT_NE(e.err.find(b.option), std::string::npos) << e.err;
    EXPECT_NE(e.err.find(b.value), std::string::npos) << e.err;
    EXPECT_FALSE(fs::exists(path("bad.yaml")));
  }
}

TEST_F(StaaMapTool, GoalsSubcommandReplacesTheGoalsOfAMap) {
  const fs::path out = path("office-goals.yaml");
  const RunResult r = run({"goals", office().string(), "-o", out.string(), "--count", "30"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("placed 30 goals"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("replacing 43"), std::string::npos) << r.out;
  const PolygonMap placed = loadPolygonMap(out);
  const PolygonMap original = loadPolygonMap(office());
  ASSERT_EQ(placed.goals.size(), 30U);
  EXPECT_EQ(placed.obstacles.size(), original.obstacles.size());  // only the goals change
  EXPECT_NE(placed.goals, std::vector<Vec2>(original.goals.begin(), original.goals.begin() + 30));
  for (std::size_t i = 0; i < placed.goals.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) EXPECT_GE((placed.goals[i] - placed.goals[j]).norm(), 1.5 - 1e-9);
  }

  // The seed picks the first goal: the same seed the same file, another seed other goals.
  ASSERT_EQ(run({"goals", office().string(), "-o", path("s1.yaml").string(), "--count", "30"}).exit_code, 0);
  ASSERT_EQ(run({"goals", office().string(), "-o", path("s2.yaml").string(), "--count", "30", "--seed", "2"}).exit_code,
            0);
  EXPECT_EQ(readFile(out), readFile(path("s1.yaml")));
  EXPECT_NE(readFile(out), readFile(path("s2.yaml")));

  // More than fit gives fewer, said on stdout.
  const RunResult few = run({"goals", office().string(), "-o", out.string(), "--count", "500", "--spacing", "3"});
  ASSERT_EQ(few.exit_code, 0) << few.err;
  EXPECT_NE(few.out.find(" of 500 goals"), std::string::npos) << few.out;
  EXPECT_LT(loadPolygonMap(out).goals.size(), 500U);

  struct Bad {
    std::vector<std::string> extra;
    std::string option, value;
  };
  for (const Bad& b : std::vector<Bad>{{{"--count", "0"}, "--count", "'0'"},
                                       {{"--count", "many"}, "--count", "'many'"},
                                       {{"--clearance", "abc"}, "--clearance", "'abc'"},
                                       {{"--clearance", "-0.5"}, "--clearance", "'-0.5'"},
                                       {{"--spacing", "0"}, "--spacing", "'0'"},
                                       {{"--seed", "1.5"}, "--seed", "'1.5'"}}) {
    std::vector<std::string> args{"goals", office().string(), "-o", path("bad.yaml").string()};
    args.insert(args.end(), b.extra.begin(), b.extra.end());
    const RunResult e = run(args);
    EXPECT_EQ(e.exit_code, 2) << b.extra[0] << " " << b.extra[1];
    EXPECT_NE(e.err.find(b.option), std::string::npos) << e.err;
    EXPECT_NE(e.err.find(b.value), std::string::npos) << e.err;
    EXPECT_FALSE(fs::exists(path("bad.yaml")));
  }

  // A map with no free place: exit 2 naming the file.
  const fs::path tight = path("tight.yaml");
  std::ofstream(tight) << "format: staa-polygon-map/1\nname: tight\nbounds: [0, 0, 1, 1]\nobstacles: []\n";
  const RunResult none = run({"goals", tight.string(), "-o", path("bad.yaml").string()});
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find(tight.string()), std::string::npos) << none.err;
  EXPECT_NE(none.err.find("'tight'"), std::string::npos) << none.err;
}

TEST_F(StaaMapTool, ImportsTheDepotAndPlansAcrossIt) {
  const fs::path depot = test::sharedDir() / "maps" / "ros" / "depot.yaml";
  STAA_REQUIRE_SHARED_FILE(depot);
  const fs::path out = path("depot.yaml");
  const RunResult r = run({"import", depot.string(), "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PolygonMap map = loadPolygonMap(out);
  ASSERT_TRUE(map.bounds.has_value());

  const RunResult info = run({"info", out.string(), "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_GT(nlohmann::json::parse(info.out)["polygons"].get<int>(), 0);

  // Across the depot: among points on a coarse lattice that are free, take the farthest
  // pair for which a path exists (the depot's free space is one connected hall).
  const Box b = *map.bounds;
  const Vec2 a{b.min.x() + 0.2 * b.width(), b.min.y() + 0.2 * b.height()};
  const Vec2 c{b.min.x() + 0.8 * b.width(), b.min.y() + 0.8 * b.height()};
  auto xy = [](const Vec2& p) { return std::to_string(p.x()) + "," + std::to_string(p.y()); };
  const RunResult p = run({"path", out.string(), "--from", xy(a), "--to", xy(c), "--inflate", "0.2", "--json"});
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const auto j = nlohmann::json::parse(p.out);
  if (j["status"] == "goal inside an obstacle" || j["status"] == "no free space near the start") {
    GTEST_SKIP() << "the chosen points fall on shelving in this depot: " << p.out;
  }
  ASSERT_TRUE(j["found"].get<bool>()) << p.out;
  EXPECT_GE(j["length"].get<double>(), (c - a).norm() - 1e-6);
  EXPECT_LT(j["length"].get<double>(), 3.0 * (c - a).norm());
}

// ---- the canvas ----

TEST(SvgCanvas, WorldOriginLandsAtTheBottomLeftMarginAndYFlips) {
  SvgCanvasOptions o;
  o.px_per_m = 10.0;
  o.margin_px = 20.0;
  o.footer_px = 30.0;
  const SvgCanvas canvas(Box{{0.0, 0.0}, {5.0, 4.0}}, o);
  EXPECT_DOUBLE_EQ(canvas.widthPx(), 2 * 20.0 + 50.0);
  EXPECT_DOUBLE_EQ(canvas.heightPx(), 2 * 20.0 + 40.0 + 30.0);
  const Vec2 origin = canvas.toPixel({0.0, 0.0});
  EXPECT_DOUBLE_EQ(origin.x(), 20.0);
  EXPECT_DOUBLE_EQ(origin.y(), 20.0 + 40.0);
  const Vec2 up = canvas.toPixel({0.0, 1.0});
  EXPECT_DOUBLE_EQ(up.y(), origin.y() - 10.0);  // up in the world is up on the screen
  const Vec2 corner = canvas.toPixel({5.0, 4.0});
  EXPECT_DOUBLE_EQ(corner.x(), 70.0);
  EXPECT_DOUBLE_EQ(corner.y(), 20.0);
}

TEST(SvgCanvas, OffsetWorldBoxMapsItsMinCorner) {
  SvgCanvasOptions o;
  o.px_per_m = 2.0;
  o.margin_px = 5.0;
  o.header_px = 7.0;
  const SvgCanvas canvas(Box{{-10.0, -3.0}, {10.0, 7.0}}, o);
  EXPECT_DOUBLE_EQ(canvas.toPixel({-10.0, -3.0}).x(), 5.0);
  EXPECT_DOUBLE_EQ(canvas.toPixel({-10.0, -3.0}).y(), 5.0 + 7.0 + 20.0);
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (auto p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

TEST(SvgCanvas, PolygonEmitsOnePointPerVertexRoundedTo3Decimals) {
  SvgCanvasOptions o;
  o.px_per_m = 1.0;
  o.margin_px = 0.0;
  SvgCanvas canvas(Box{{0.0, 0.0}, {10.0, 10.0}}, o);
  canvas.polygon(Polygon{{0.0, 0.0}, {1.23456, 0.0}, {1.0, 1.0}, {0.0, 1.0}, {-0.5, 0.5}}, svgFill("#444"));
  const std::string svg = canvas.str();
  const auto start = svg.find("points=\"");
  ASSERT_NE(start, std::string::npos);
  const std::string points = svg.substr(start + 8, svg.find('"', start + 8) - start - 8);
  EXPECT_EQ(points, "0,10 1.235,10 1,9 0,9 -0.5,9.5");
  EXPECT_EQ(count(points, ","), 5u);
  EXPECT_NE(svg.find("fill=\"#444\""), std::string::npos);
}

TEST(SvgCanvas, ManyPolygonsAndSegmentsShareOnePathElement) {
  SvgCanvas canvas(Box{{0.0, 0.0}, {10.0, 10.0}});
  std::vector<Polygon> polys{{{0, 0}, {1, 0}, {1, 1}}, {{2, 2}, {2, 3}, {3, 3}}};  // CCW and CW
  canvas.polygons(polys, svgFill("#888", 0.4));
  std::vector<std::pair<Vec2, Vec2>> segs;
  for (int k = 0; k < 100; ++k) segs.push_back({{0.1 * k, 0.0}, {0.1 * k, 1.0}});
  canvas.segments(segs, svgStroke("#000", 0.5));
  const std::string svg = canvas.str();
  EXPECT_EQ(count(svg, "<path"), 2u);
  EXPECT_EQ(count(svg, "Z"), 2u);
  EXPECT_EQ(count(svg, "M"), 2u + 100u);
  EXPECT_NE(svg.find("fill-opacity=\"0.4\""), std::string::npos);
}

TEST(SvgCanvas, TextIsEscapedAndNumbersAreCompact) {
  SvgCanvas canvas(Box{{0.0, 0.0}, {1.0, 1.0}});
  canvas.text({0.5, 0.5}, "a<b & \"c\"");
  EXPECT_NE(canvas.str().find("a&lt;b &amp; &quot;c&quot;"), std::string::npos);
  EXPECT_EQ(svgNumber(12.5), "12.5");
  EXPECT_EQ(svgNumber(3.0), "3");
  EXPECT_EQ(svgNumber(-0.0001), "0");
  EXPECT_EQ(svgNumber(1.23456), "1.235");
}

TEST(SvgCanvas, ScaleBarPicksOneOrFiveMetres) {
  SvgCanvasOptions o;
  o.px_per_m = 50.0;
  SvgCanvas big(Box{{0.0, 0.0}, {4.0, 4.0}}, o);
  big.scaleBar();
  EXPECT_NE(big.str().find(">1 m<"), std::string::npos);
  o.px_per_m = 20.0;
  SvgCanvas small(Box{{0.0, 0.0}, {30.0, 30.0}}, o);
  small.scaleBar();
  EXPECT_NE(small.str().find(">5 m<"), std::string::npos);
}

TEST(SvgCanvas, ArrowLegendAndGroupsProduceBalancedElements) {
  SvgCanvas canvas(Box{{0.0, 0.0}, {5.0, 5.0}});
  canvas.beginGroup({}, true);
  canvas.arrow(Pose2{1.0, 1.0, 0.5}, 1.0, svgStroke("#c00", 2.0));
  canvas.endGroup();
  const std::vector<LegendEntry> legend{{"wall", svgFill("#333"), LegendSymbol::kArea},
                                        {"path", svgStroke("#e00", 2.0), LegendSymbol::kLine}};
  canvas.legend(legend);
  const std::string svg = canvas.str();
  EXPECT_EQ(count(svg, "<g"), count(svg, "</g>"));
  EXPECT_NE(svg.find("clipPath id=\"world\""), std::string::npos);
  EXPECT_NE(svg.find(">wall<"), std::string::npos);
  EXPECT_NE(svg.find(">path<"), std::string::npos);
}

TEST(SvgCanvas, SaveToAnUnwritablePathThrowsNamingIt) {
  const SvgCanvas canvas(Box{{0.0, 0.0}, {1.0, 1.0}});
  const fs::path bad = fs::temp_directory_path() / "staa-no-such-dir-4711" / "x.svg";
  try {
    canvas.save(bad);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
}

TEST(MapDrawing, DrawsEveryObstacleAndNumberedGoals) {
  PolygonMap map;
  map.name = "two";
  map.bounds = Box{{0.0, 0.0}, {4.0, 3.0}};
  map.obstacles = {{{1, 1}, {2, 1}, {2, 2}, {1, 2}}, {{3, 0}, {4, 0}, {4, 1}}};
  map.goals = {{0.5, 0.5}, {3.5, 2.5}};
  SvgCanvas canvas = makeMapCanvas(map, 40.0);
  drawMap(canvas, map, nullptr);
  const std::vector<Vec2> path{{0.5, 0.5}, {2.5, 2.5}, {3.5, 2.5}};
  drawPath(canvas, path, path.front(), path.back());
  const std::string svg = canvas.str();
  EXPECT_NE(svg.find(">0</text>"), std::string::npos);
  EXPECT_NE(svg.find(">1</text>"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  EXPECT_NE(svg.find("#3d3d3d"), std::string::npos);  // obstacles dark grey
  EXPECT_NEAR(canvas.toPixel({0.0, 0.0}).y() - canvas.toPixel({0.0, 3.0}).y(), 120.0, 1e-9);
}

}  // namespace
}  // namespace staa
