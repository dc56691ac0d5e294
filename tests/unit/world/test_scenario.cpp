#include "world/scenario.hpp"

#include "shared_dir.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace staa {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A 10 x 8 m room with a box in the middle, and a robot profile, in a folder tree that makes
// the scenario's relative paths matter: scenarios/ beside maps/ and robots/.
const std::string kMap = R"(format: staa-polygon-map/1
name: room
bounds: [0, 0, 10, 8]
obstacles:
  - [[4, 3], [6, 3], [6, 5], [4, 5]]
)";

const std::string kValid = R"(format: staa-scenario/1
map: ../maps/room.yaml
robot: {profile: ../robots/agent.yaml, start: [1.5, 1.5, 0.0], goal: [8.0, 6.5, 1.57]}
movers:
  - polygon: [[-0.25, -0.25], [0.25, -0.25], [0.25, 0.25], [-0.25, 0.25]]
    waypoints: [[8.0, 1.0], [8.0, 6.0]]
    speed: 1.2
  - polygon: [[0, 0], [0.5, 0], [0, 0.5]]
    waypoints: [[2.0, 6.0]]
    speed: 0
)";

class ScenarioFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("staa-test-scenario-" + std::to_string(std::random_device{}()) + "-" + info->name());
    fs::create_directories(dir_ / "maps");
    fs::create_directories(dir_ / "robots");
    fs::create_directories(dir_ / "scenarios");
    write("maps/room.yaml", kMap);
    fs::copy_file(test::sourceDir() / "config/robots/paper-agent.yaml", dir_ / "robots/agent.yaml");
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  std::string loadError(const std::string& text) const {
    const fs::path p = write("scenarios/s.yaml", text);
    try {
      loadScenario(p);
    } catch (const ScenarioError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no ScenarioError for:\n" << text;
    return "";
  }

  // kValid with `from` replaced by `to` (which must occur).
  static std::string edited(const std::string& from, const std::string& to) {
    std::string s = kValid;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    return s;
  }

  fs::path dir_;
};

TEST_F(ScenarioFiles, LoadsWithPathsRelativeToTheScenarioFile) {
  const Scenario sc = loadScenario(write("scenarios/s.yaml", kValid));
  EXPECT_EQ(sc.name, "s");
  EXPECT_EQ(fs::weakly_canonical(sc.map_path), fs::weakly_canonical(dir_ / "maps/room.yaml"));
  EXPECT_EQ(fs::weakly_canonical(sc.profile_path), fs::weakly_canonical(dir_ / "robots/agent.yaml"));
  EXPECT_EQ(sc.map.name, "room");
  ASSERT_EQ(sc.map.obstacles.size(), 1u);
  EXPECT_EQ(sc.robot.name, "paper-agent");
  EXPECT_DOUBLE_EQ(sc.start.x, 1.5);
  EXPECT_DOUBLE_EQ(sc.start.y, 1.5);
  EXPECT_DOUBLE_EQ(sc.start.theta, 0.0);
  EXPECT_DOUBLE_EQ(sc.goal.x, 8.0);
  EXPECT_DOUBLE_EQ(sc.goal.y, 6.5);
  EXPECT_DOUBLE_EQ(sc.goal.theta, 1.57);
  ASSERT_EQ(sc.movers.size(), 2u);
  EXPECT_EQ(sc.movers[0].polygon.size(), 4u);
  ASSERT_EQ(sc.movers[0].waypoints.size(), 2u);
  EXPECT_EQ(sc.movers[0].waypoints[1], Vec2(8.0, 6.0));
  EXPECT_DOUBLE_EQ(sc.movers[0].speed, 1.2);
  EXPECT_EQ(sc.movers[1].waypoints.size(), 1u);  // stands still
  EXPECT_DOUBLE_EQ(sc.movers[1].speed, 0.0);
}

TEST_F(ScenarioFiles, MoversAreOptional) {
  const std::string text = kValid.substr(0, kValid.find("movers:"));
  EXPECT_TRUE(loadScenario(write("scenarios/s.yaml", text)).movers.empty());
}

TEST_F(ScenarioFiles, UnknownFormatAndKeysAreRejected) {
  EXPECT_THAT(loadError(edited("staa-scenario/1", "staa-scenario/9")), HasSubstr("s.yaml:1: format: unknown format, expected staa-scenario/1, got 'staa-scenario/9'"));
  EXPECT_THAT(loadError(kValid + "agents: 3\n"), HasSubstr("s.yaml:11: agents: unknown key"));
  EXPECT_THAT(loadError(edited("speed: 1.2", "speed: 1.2\n    rotation: 1")), HasSubstr("movers[0].rotation: unknown key"));
  EXPECT_THAT(loadError(edited("goal:", "radius: 1, goal:")), HasSubstr("robot.radius: unknown key"));
}

TEST_F(ScenarioFiles, BadMapOrProfileNamesBothFiles) {
  const std::string e = loadError(edited("../maps/room.yaml", "../maps/nope.yaml"));
  EXPECT_THAT(e, HasSubstr("s.yaml:2: map: "));
  EXPECT_THAT(e, HasSubstr("nope.yaml"));
  write("robots/bad.yaml", "format: staa-robot/1\nfootprint: [[1, 1], [2, 1], [2, 2]]\nlimits: {v_max: 1, v_min: 0, w_max: 1, a_max: 1, b_max: 1}\n");
  const std::string p = loadError(edited("../robots/agent.yaml", "../robots/bad.yaml"));
  EXPECT_THAT(p, HasSubstr("s.yaml:3: robot.profile: "));
  EXPECT_THAT(p, HasSubstr("bad.yaml:2: footprint"));
  EXPECT_THAT(p, HasSubstr("origin"));
}

TEST_F(ScenarioFiles, StartInsideOrTouchingAnObstacleIsRejected) {
  const std::string e = loadError(edited("start: [1.5, 1.5, 0.0]", "start: [5.0, 4.0, 0.0]"));
  EXPECT_THAT(e, HasSubstr("s.yaml:3: robot.start:"));
  EXPECT_THAT(e, HasSubstr("(5, 4)"));
  EXPECT_THAT(e, HasSubstr("overlaps obstacle 0"));
  // Origin free, but the 0.4 m nose reaches into the box at x = 4.
  EXPECT_THAT(loadError(edited("start: [1.5, 1.5, 0.0]", "start: [3.7, 4.0, 0.0]")), HasSubstr("overlaps obstacle 0"));
  // Footprint through the wall of the bounds.
  EXPECT_THAT(loadError(edited("start: [1.5, 1.5, 0.0]", "start: [0.2, 4.0, 0.0]")), HasSubstr("outside the map bounds"));
}

TEST_F(ScenarioFiles, GoalInsideAnObstacleOrOutsideTheBoundsIsRejected) {
  const std::string e = loadError(edited("goal: [8.0, 6.5, 1.57]", "goal: [4.5, 3.5, 0]"));
  EXPECT_THAT(e, HasSubstr("s.yaml:3: robot.goal: (4.5, 3.5) is inside obstacle 0"));
  EXPECT_THAT(loadError(edited("goal: [8.0, 6.5, 1.57]", "goal: [12, 3.5, 0]")), HasSubstr("robot.goal: (12, 3.5) is outside the map bounds"));
}

TEST_F(ScenarioFiles, BadPosesAreRejected) {
  EXPECT_THAT(loadError(edited("start: [1.5, 1.5, 0.0]", "start: [1.5, 1.5]")), HasSubstr("robot.start: expected [x, y, theta], got a list of 2 items"));
  EXPECT_THAT(loadError(edited("start: [1.5, 1.5, 0.0]", "start: [1.5, .nan, 0]")), HasSubstr("robot.start[1]: must be finite, got .nan"));
  EXPECT_THAT(loadError(edited(", goal: [8.0, 6.5, 1.57]", "")), HasSubstr("s.yaml:3: robot.goal: missing"));
}

TEST_F(ScenarioFiles, BadMoversAreRejected) {
  EXPECT_THAT(loadError(edited("speed: 1.2", "speed: -1")), HasSubstr("s.yaml:7: movers[0].speed: must be >= 0, got -1"));
  EXPECT_THAT(loadError(edited("speed: 1.2", "speed: quick")), HasSubstr("movers[0].speed: expected a number, got 'quick'"));
  EXPECT_THAT(loadError(edited("waypoints: [[2.0, 6.0]]", "waypoints: []")), HasSubstr("movers[1].waypoints: expected a list of at least one"));
  EXPECT_THAT(loadError(edited("waypoints: [[2.0, 6.0]]", "waypoints: [[2.0, .inf]]")), HasSubstr("movers[1].waypoints[0][1]: must be finite"));
  EXPECT_THAT(loadError(edited("polygon: [[0, 0], [0.5, 0], [0, 0.5]]", "polygon: [[0, 0], [0.5, 0]]")),
              HasSubstr("movers[1].polygon: has 2 vertices"));
  EXPECT_THAT(loadError(edited("polygon: [[0, 0], [0.5, 0], [0, 0.5]]", "polygon: [[0, 0], [1, 1], [1, 0], [0, 1]]")),
              HasSubstr("movers[1].polygon: self-intersecting"));
  EXPECT_THAT(loadError(edited("    speed: 0\n", "")), HasSubstr("movers[1].speed: missing"));
}

}  // namespace
}  // namespace staa
