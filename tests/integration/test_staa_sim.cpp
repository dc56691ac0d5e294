// staa-sim run for real: the built binary in a temporary directory, on a map and a scenario
// the test writes, its exit status, stdout, stderr and the files it writes.

#include "robot/robot_profile.hpp"
#include "map/generate.hpp"
#include "map/polygon_map.hpp"

#include "read_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace staa {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using ::testing::HasSubstr;

struct SimRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

using staa::test::readFile;

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A 12 x 12 m room with one 2 x 2 m box in the middle of the diagonal from (1, 1) to (9, 9).
const char* const kMap = R"(format: staa-polygon-map/1
name: open12
bounds: [0, 0, 12, 12]
obstacles:
  - [[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]]
)";

const char* const kProfile = R"(format: staa-robot/1
name: paper-agent
footprint: [[0.4, 0.2], [0.4, -0.2], [-0.4, -0.25], [-0.4, 0.25]]
limits: {v_max: 2.0, v_min: -1.0, w_max: 3.0, a_max: 2.0, b_max: 6.0}
)";

// One mover that walks up and down beside the goal, across the robot's last metres.
const char* const kScenario = R"(format: staa-scenario/1
name: crossing
map: map.yaml
robot: {profile: robot.yaml, start: [1.0, 1.0, 0.0], goal: [9.0, 9.0, 1.57]}
movers:
  - polygon: [[-0.25, -0.25], [0.25, -0.25], [0.25, 0.25], [-0.25, 0.25]]
    waypoints: [[8.5, 11.0], [8.5, 3.0]]
    speed: 1.0
)";

class StaaSim : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("staa-sim-test-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    writeFile(dir_ / "map.yaml", kMap);
    writeFile(dir_ / "robot.yaml", kProfile);
    writeFile(dir_ / "scenario.yaml", kScenario);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // Runs staa-sim in the test's directory with stdout and stderr captured to files.
  SimRun sim(const std::vector<std::string>& args) const {
    const fs::path out_file = dir_ / "stdout.txt", err_file = dir_ / "stderr.txt";
    std::vector<char*> argv;
    std::string exe = STAA_SIM_EXE;
    argv.push_back(exe.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) {
      const int o = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int e = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (o < 0 || e < 0 || ::dup2(o, 1) < 0 || ::dup2(e, 2) < 0 || ::chdir(dir_.c_str()) != 0) ::_exit(127);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    SimRun r;
    int status = 0;
    if (pid > 0 && ::waitpid(pid, &status, 0) == pid && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = readFile(out_file);
    r.err = readFile(err_file);
    return r;
  }

  Json json(const std::string& name) const { return Json::parse(readFile(dir_ / name)); }

  fs::path dir_;
};

const std::vector<std::string> kOpenRun{"--map",    "map.yaml",       "--start",    "1,1,0",
                                        "--goal",   "9,9,1.57",       "--budget-expansions", "300",
                                        "--duration", "20"};

std::vector<std::string> with(std::vector<std::string> base, const std::vector<std::string>& more) {
  base.insert(base.end(), more.begin(), more.end());
  return base;
}

void expectDistribution(const Json& j, const std::string& name, const std::vector<std::string>& keys) {
  ASSERT_TRUE(j.contains(name) && j[name].is_object()) << name;
  for (const auto& k : keys) {
    ASSERT_TRUE(j[name].contains(k)) << name << "." << k;
    EXPECT_TRUE(j[name][k].is_number()) << name << "." << k;
  }
}

TEST_F(StaaSim, ReachesGoalAroundBoxAndWritesEveryJsonKey) {
  const SimRun r = sim(with(kOpenRun, {"--json", "out.json"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = json("out.json");

  for (const char* key : {"goals_reached", "collisions", "score", "agents", "brakes", "frames_written"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_number_integer()) << key;
  }
  for (const char* key : {"time_to_goal_s", "min_clearance_m", "rate_hz", "duration_s"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_number()) << key;
  }
  for (const char* key : {"map", "controller", "mode", "heuristic", "final_state"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_string()) << key;
  }
  ASSERT_TRUE(j.contains("reached_goal") && j["reached_goal"].is_boolean());
  ASSERT_TRUE(j.contains("seed") && j["seed"].is_number_unsigned());
  ASSERT_TRUE(j.contains("final_pose") && j["final_pose"].is_array() && j["final_pose"].size() == 3u);
  ASSERT_TRUE(j.contains("budget") && j["budget"].is_object());
  EXPECT_EQ(j["budget"]["kind"], "expansions");
  EXPECT_EQ(j["budget"]["value"], 300);
  ASSERT_TRUE(j.contains("planner") && j["planner"].is_object());
  const Json& p = j["planner"];
  ASSERT_TRUE(p.contains("calls") && p["calls"].is_number_integer());
  expectDistribution(p, "expansions", {"mean", "p50", "p99"});
  expectDistribution(p, "successors", {"mean", "p50", "p99"});
  expectDistribution(p, "plan_us", {"p50", "p99", "max"});
  ASSERT_TRUE(p.contains("finished_early_ratio") && p["finished_early_ratio"].is_number());
  ASSERT_TRUE(p.contains("depth_mean") && p["depth_mean"].is_number());
  expectDistribution(j, "cycle_us", {"p50", "p99", "max"});
  expectDistribution(j, "path_us", {"p50", "p99", "max"});

  EXPECT_EQ(j["map"], "map.yaml");
  EXPECT_EQ(j["controller"], "staa");
  EXPECT_EQ(j["mode"], "cooperative");
  EXPECT_EQ(j["agents"], 1);
  EXPECT_EQ(j["heuristic"], "path-rtr");
  EXPECT_EQ(j["rate_hz"], 30.0);
  EXPECT_EQ(j["duration_s"], 20.0);
  EXPECT_TRUE(j["reached_goal"].get<bool>());
  EXPECT_EQ(j["goals_reached"], 1);
  EXPECT_EQ(j["collisions"], 0);
  EXPECT_EQ(j["score"], 1);
  EXPECT_EQ(j["final_state"], "reached");
  EXPECT_GT(j["min_clearance_m"].get<double>(), 0.0);
  // No faster than the straight line at full speed, and within the run's duration.
  const double t = j["time_to_goal_s"].get<double>();
  EXPECT_GE(t, std::hypot(8.0, 8.0) / paperAgentProfile().limits.v_max);
  EXPECT_LE(t, 20.0);
  const auto pose = j["final_pose"].get<std::vector<double>>();
  EXPECT_LT(std::hypot(pose[0] - 9.0, pose[1] - 9.0), 0.25);
  EXPECT_GT(p["calls"].get<int>(), 0);
  EXPECT_LE(p["expansions"]["p99"].get<double>(), 300.0);  // the budget holds
  EXPECT_GT(p["successors"]["mean"].get<double>(), p["expansions"]["mean"].get<double>());

  // Progress on stderr every simulated second, the summary on stdout.
  EXPECT_THAT(r.err, HasSubstr("t=1.0s pos=("));
  EXPECT_THAT(r.err, HasSubstr("state=driving"));
  EXPECT_THAT(r.out, HasSubstr("reached goal in "));
  EXPECT_THAT(r.out, HasSubstr("collisions 0"));
}

TEST_F(StaaSim, ExpansionBudgetMakesTwoRunsIdentical) {
  const SimRun a = sim(with(kOpenRun, {"--json", "a.json", "--quiet"}));
  const SimRun b = sim(with(kOpenRun, {"--json", "b.json", "--quiet"}));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(a.err, "");  // --quiet: no progress
  Json ja = json("a.json"), jb = json("b.json");
  EXPECT_EQ(ja["goals_reached"], jb["goals_reached"]);
  EXPECT_EQ(ja["collisions"], jb["collisions"]);
  EXPECT_EQ(ja["time_to_goal_s"].get<double>(), jb["time_to_goal_s"].get<double>());
  EXPECT_EQ(ja["planner"]["expansions"], jb["planner"]["expansions"]);
  EXPECT_EQ(ja["final_pose"].get<std::vector<double>>(), jb["final_pose"].get<std::vector<double>>());
  // Everything but the wall-clock timings, bit for bit.
  for (Json* j : {&ja, &jb}) {
    (*j)["planner"].erase("plan_us");
    j->erase("cycle_us");
    j->erase("path_us");
  }
  EXPECT_EQ(ja.dump(), jb.dump());
}

TEST_F(StaaSim, ScenarioWithOneMoverRunsToTheGoal) {
  const SimRun r = sim({"--scenario", "scenario.yaml", "--budget-expansions", "300", "--duration", "20", "--json",
                     "out.json", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = json("out.json");
  EXPECT_EQ(j["scenario"], "scenario.yaml");
  EXPECT_EQ(j["movers"], 1);
  EXPECT_TRUE(j["reached_goal"].get<bool>());
  EXPECT_EQ(j["collisions"], 0);
  EXPECT_EQ(j["score"], 1);
  EXPECT_GT(j["min_clearance_m"].get<double>(), 0.0);
}

TEST_F(StaaSim, SvgWritesFramesOfTheRun) {
  const SimRun r = sim({"--map", "map.yaml", "--start", "1,1,0", "--goal", "9,9,1.57", "--budget-expansions", "200",
                     "--duration", "1", "--svg", "frames", "--svg-every", "10", "--json", "out.json", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int frames = 0;
  for (const auto& entry : fs::directory_iterator(dir_ / "frames")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("frame_", 0) != 0 || entry.path().extension() != ".svg") continue;
    ++frames;
    EXPECT_THAT(readFile(entry.path()), HasSubstr("<svg")) << name;
  }
  EXPECT_GE(frames, 1);
  EXPECT_EQ(json("out.json")["frames_written"], frames);
}

struct BadInput {
  std::vector<std::string> args;
  std::string expected;  // the offending value (or option) named on stderr
};

TEST_F(StaaSim, BadInputExitsTwoNamingTheValue) {
  writeFile(dir_ / "typo.yaml", std::string(kScenario) + "speeed: 3\n");
  const std::vector<std::string> ok_goal{"--map", "map.yaml", "--start", "1,1,0", "--goal", "9,9,1.57"};
  const std::vector<BadInput> cases{
      {{"--map", "map.yaml", "--start", "1,x,0", "--goal", "9,9,1.57"}, "'1,x,0'"},
      {with(ok_goal, {"--rate", "0"}), "--rate: expected a control rate in Hz (a finite number > 0), got '0'"},
      {with(ok_goal, {"--budget-ms", "5", "--budget-expansions", "10"}), "--budget-ms 5 and --budget-expansions 10"},
      {with(ok_goal, {"--heuristic", "foo"}), "'foo'"},
      {with(ok_goal, {"--controller", "mpc"}), "expected staa, dwa or pd, got 'mpc'"},
      {with(ok_goal, {"--agents", "3"}), "--start '1,1,0' cannot be combined with --agents 3"},
      {{"--map", "map.yaml", "--agents", "0"},
       "--agents: expected a number of agents (an integer from 1 to 1000), got '0'"},
      {{"--scenario", "scenario.yaml", "--agents", "2"},
       "--scenario 'scenario.yaml' cannot be combined with --agents 2"},
      {{"--map", "map.yaml", "--mode", "ghost", "--goal", "9,9,0"},
       "--goal '9,9,0' cannot be combined with --mode ghost"},
      {{"--agents", "3"}, "--map is required with --agents 3"},
      {{"--map", "missing.yaml", "--start", "1,1,0", "--goal", "9,9,1.57"}, "missing.yaml"},
      {{"--map", "map.yaml", "--start", "5,5,0", "--goal", "9,9,1.57"}, "--start (5.00, 5.00, 0.00)"},
      {{"--map", "map.yaml", "--start", "1,1,0", "--goal", "5,5,0"}, "--goal (5.00, 5.00, 0.00)"},
      {{"--scenario", "typo.yaml"}, "speeed"},
      {{"--scenario", "scenario.yaml", "--map", "map.yaml"}, "--map"},
      {with(ok_goal, {"--obstacles", "lidar"}), "--obstacles: expected truth, depth, depth+scan or sight, got 'lidar'"},
      {with(ok_goal, {"--robot", "robot.yaml", "--obstacles", "depth"}),
       "--obstacles depth: the robot profile 'robot.yaml' has no camera section"},
      {with(ok_goal, {"--robot", "robot.yaml", "--obstacles", "depth+scan"}),
       "--obstacles depth+scan: the robot profile 'robot.yaml' has no camera section"},
  };
  for (const BadInput& c : cases) {
    std::string line;
    for (const auto& a : c.args) line += a + " ";
    const SimRun r = sim(c.args);
    EXPECT_EQ(r.exit_code, 2) << line << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.expected)) << line;
    EXPECT_THAT(r.err, HasSubstr("staa-sim: ")) << line;
    EXPECT_EQ(r.out, "") << line;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out.json"));
}

// The paper's agent with a depth camera (config/robots/paper-agent.yaml's).
std::string cameraProfile() {
  return std::string(kProfile) + R"(height: 1.0
camera:
  mount: {x: 0.0, y: 0.0, z: 1.0, pitch: 0.3}
  fov_deg: [58, 45]
  range_m: [0.5, 4.5]
  head: {pan_max: 2.8, pan_rate: 2.0}
)";
}

TEST_F(StaaSim, DepthObstaclesDriveTheScenarioOnWhatTheCameraSees) {
  writeFile(dir_ / "camera.yaml", cameraProfile());
  const SimRun r = sim({"--scenario", "scenario.yaml", "--robot", "camera.yaml", "--obstacles", "depth",
                        "--budget-expansions", "300", "--duration", "20", "--json", "out.json", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = json("out.json");
  EXPECT_EQ(j["obstacles"], "depth");
  EXPECT_TRUE(j["reached_goal"].get<bool>());
  EXPECT_EQ(j["collisions"], 0);
  // A frame every 33 ms until the goal, 1 % of them lost.
  const double frames = j["camera_frames"].get<double>() + j["camera_frames_lost"].get<double>();
  EXPECT_NEAR(frames, j["time_to_goal_s"].get<double>() * 30.0, 2.0);
  EXPECT_GT(j["camera_frames"].get<int>(), 0);
  // The same run with the truth is recorded as such.
  const SimRun t = sim({"--scenario", "scenario.yaml", "--budget-expansions", "300", "--duration", "20", "--json",
                        "truth.json", "--quiet"});
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_EQ(json("truth.json")["obstacles"], "truth");
  EXPECT_FALSE(json("truth.json").contains("camera_frames"));
  // The base scanner needs its section: exit 2 naming the profile; with it, the run is one.
  const SimRun no_scanner = sim({"--scenario", "scenario.yaml", "--robot", "camera.yaml", "--obstacles", "depth+scan",
                                 "--budget-expansions", "300", "--duration", "20", "--quiet"});
  EXPECT_EQ(no_scanner.exit_code, 2);
  EXPECT_THAT(no_scanner.err, HasSubstr("--obstacles depth+scan: the robot profile 'camera.yaml' has no scanner section"));
  writeFile(dir_ / "scanner.yaml", cameraProfile() + "scanner:\n  mount: {z: 0.2}\n");
  const SimRun d = sim({"--scenario", "scenario.yaml", "--robot", "scanner.yaml", "--obstacles", "depth+scan",
                        "--budget-expansions", "300", "--duration", "20", "--json", "scan.json", "--quiet"});
  ASSERT_EQ(d.exit_code, 0) << d.err;
  EXPECT_EQ(json("scan.json")["obstacles"], "depth+scan");
  EXPECT_TRUE(json("scan.json")["reached_goal"].get<bool>());
  EXPECT_EQ(json("scan.json")["collisions"], 0);
  // The truth in the line of sight needs no sensor in the profile.
  const SimRun l = sim({"--scenario", "scenario.yaml", "--obstacles", "sight", "--budget-expansions", "300",
                        "--duration", "20", "--json", "sight.json", "--quiet"});
  ASSERT_EQ(l.exit_code, 0) << l.err;
  EXPECT_EQ(json("sight.json")["obstacles"], "sight");
  EXPECT_TRUE(json("sight.json")["reached_goal"].get<bool>());
  EXPECT_EQ(json("sight.json")["collisions"], 0);
  EXPECT_FALSE(json("sight.json").contains("camera_frames"));
}

// ---- multi-agent runs (--agents N > 1 or --mode ghost) ----

// The generated office (43 goals) as a map file in the test's directory.
void writeOffice(const fs::path& dir) { savePolygonMap(generatePaperMap("office", 1), dir / "office.yaml"); }

const std::vector<std::string> kOfficeRun{"--map", "office.yaml", "--duration", "5", "--budget-expansions", "200",
                                          "--quiet"};

// The contract's keys (docs/ARCHITECTURE.md section 6), present in a multi-agent run too; the
// single-robot ones are null there.
void expectContractKeys(const Json& j) {
  for (const char* key : {"goals_reached", "collisions", "score"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_number_integer()) << key;
  }
  for (const char* key : {"reached_goal", "time_to_goal_s", "min_clearance_m"}) ASSERT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["reached_goal"].is_null());
  EXPECT_TRUE(j["time_to_goal_s"].is_null());
  ASSERT_TRUE(j.contains("planner") && j["planner"].is_object());
  const Json& p = j["planner"];
  ASSERT_TRUE(p.contains("calls") && p["calls"].is_number_integer());
  expectDistribution(p, "expansions", {"mean", "p50", "p99"});
  expectDistribution(p, "successors", {"mean", "p50", "p99"});
  expectDistribution(p, "plan_us", {"p50", "p99", "max"});
  ASSERT_TRUE(p.contains("finished_early_ratio") && p["finished_early_ratio"].is_number());
  ASSERT_TRUE(p.contains("depth_mean") && p["depth_mean"].is_number());
}

TEST_F(StaaSim, CooperativeAgentsOnTheOfficeReportEveryAgentAndTheirSummedScore) {
  writeOffice(dir_);
  const SimRun r = sim(with(kOfficeRun, {"--agents", "3", "--mode", "cooperative", "--json", "out.json"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = json("out.json");
  expectContractKeys(j);
  EXPECT_EQ(j["mode"], "cooperative");
  EXPECT_EQ(j["map_goals"], 43);
  EXPECT_FALSE(j["goals_placed"].get<bool>());
  ASSERT_TRUE(j["agents"].is_array());
  ASSERT_EQ(j["agents"].size(), 3U);
  int goals = 0, collisions = 0;
  for (const Json& a : j["agents"]) {
    for (const char* key : {"goals_reached", "collisions"}) EXPECT_TRUE(a[key].is_number_integer()) << key;
    EXPECT_GT(a["distance_m"].get<double>(), 0.5);  // every agent drove
    EXPECT_FALSE(a["ghost"].get<bool>());
    goals += a["goals_reached"].get<int>();
    collisions += a["collisions"].get<int>();
  }
  // Cooperative: summed over the agents.
  EXPECT_EQ(j["goals_reached"], goals);
  EXPECT_EQ(j["collisions"], collisions);
  EXPECT_EQ(j["score"].get<int>(), j["goals_reached"].get<int>() - j["collisions"].get<int>());
  EXPECT_GE(j["min_clearance_m"].get<double>(), 0.0);
  // STAA* ran for every agent every cycle, within the budget.
  EXPECT_EQ(j["planner"]["calls"], 3 * 150);
  EXPECT_LE(j["planner"]["expansions"]["p99"].get<double>(), 200.0);
  EXPECT_NEAR(j["simulated_s"].get<double>(), 5.0, 1e-6);
  EXPECT_THAT(r.out, HasSubstr("score " + std::to_string(j["score"].get<int>())));
  EXPECT_THAT(r.out, HasSubstr("per agent goals "));
}

TEST_F(StaaSim, GhostModeCountsTheObservedAgentOnlyAndPlacesGoalsInAMapWithout) {
  // map.yaml (12 x 12 m, one box) has no goals: placed as the experiment places them.
  const SimRun r = sim({"--map", "map.yaml", "--agents", "3", "--mode", "ghost", "--duration", "3",
                        "--budget-expansions", "200", "--controller", "dwa", "--json", "out.json", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("map.yaml has no goals: placed "));
  EXPECT_THAT(r.err, HasSubstr("(clearance 0.6 m, spacing 1.5 m)"));
  const Json j = json("out.json");
  expectContractKeys(j);
  EXPECT_TRUE(j["goals_placed"].get<bool>());
  EXPECT_GE(j["map_goals"].get<int>(), 3);
  EXPECT_EQ(j["mode"], "ghost");
  EXPECT_EQ(j["controller"], "dwa");
  ASSERT_EQ(j["agents"].size(), 3U);
  EXPECT_FALSE(j["agents"][0]["ghost"].get<bool>());
  EXPECT_TRUE(j["agents"][1]["ghost"].get<bool>());
  EXPECT_TRUE(j["agents"][2]["ghost"].get<bool>());
  // Ghost: the observed agent's goals and collisions alone.
  EXPECT_EQ(j["goals_reached"], j["agents"][0]["goals_reached"]);
  EXPECT_EQ(j["collisions"], j["agents"][0]["collisions"]);
  EXPECT_EQ(j["score"].get<int>(), j["goals_reached"].get<int>() - j["collisions"].get<int>());
  EXPECT_EQ(j["planner"]["calls"], 0);  // DWA: no STAA* calls
  EXPECT_THAT(r.out, HasSubstr("observed agent 0"));
}

TEST_F(StaaSim, DepthObstaclesForEveryAgentReportPerceptionAgainstTheTruth) {
  writeOffice(dir_);
  writeFile(dir_ / "camera.yaml", cameraProfile());
  const SimRun r = sim(with(kOfficeRun, {"--agents", "3", "--robot", "camera.yaml", "--obstacles", "depth", "--json",
                                         "out.json"}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Json j = json("out.json");
  expectContractKeys(j);
  EXPECT_EQ(j["obstacles"], "depth");
  ASSERT_TRUE(j.contains("perception")) << j.dump();
  // 3 cameras at 30 Hz for 5 s.
  EXPECT_EQ(j["perception"]["frames"].get<int>() + j["perception"]["frames_lost"].get<int>(), 450);
  EXPECT_TRUE(j["perception"]["latency"].contains("p50_s"));
}

TEST_F(StaaSim, SameSeedGivesTheSameMultiAgentRun) {
  writeOffice(dir_);
  auto run = [&](const std::string& seed, const std::string& out) {
    const SimRun r = sim({"--map", "office.yaml", "--agents", "2", "--duration", "2", "--budget-expansions", "200",
                          "--seed", seed, "--json", out, "--quiet"});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    Json j = json(out);
    j["planner"].erase("plan_us");  // wall-clock
    return j;
  };
  const Json a = run("5", "a.json");
  const Json b = run("5", "b.json");
  EXPECT_EQ(a.dump(), b.dump());
  // Another seed starts the agents elsewhere.
  const Json c = run("6", "c.json");
  EXPECT_NE(a["agents"].dump(), c["agents"].dump());
}

TEST_F(StaaSim, MultiAgentSvgWritesFramesOfTheWholeMap) {
  writeOffice(dir_);
  const SimRun r = sim({"--map", "office.yaml", "--agents", "2", "--mode", "ghost", "--duration", "1",
                        "--budget-expansions", "100", "--svg", "frames", "--svg-every", "10", "--json", "out.json",
                        "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir_ / "frames")) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  // 30 cycles, a frame every 10: cycles 0, 10 and 20.
  EXPECT_EQ(names, (std::vector<std::string>{"frame_00000.svg", "frame_00010.svg", "frame_00020.svg"}));
  EXPECT_EQ(json("out.json")["frames_written"], 3);
  const std::string svg = readFile(dir_ / "frames" / "frame_00020.svg");
  EXPECT_THAT(svg, HasSubstr("<svg"));
  EXPECT_THAT(svg, HasSubstr("office: t = 0.70 s, 2 agents (ghost, staa)"));
  EXPECT_THAT(svg, HasSubstr("observed agent"));
  EXPECT_THAT(svg, HasSubstr("ghost agent"));
  EXPECT_THAT(svg, HasSubstr(">42</text>"));  // the map's goals, numbered
}

}  // namespace
}  // namespace staa
