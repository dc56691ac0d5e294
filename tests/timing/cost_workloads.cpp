// staa-cost: the fixed workloads of the timing suite's cost tier (docs/ARCHITECTURE.md,
// "The timing suite"). Each workload steps one part of the 30 Hz cycle over fixed inputs;
// run under `valgrind --tool=callgrind --collect-atstart=no --instr-atstart=no`, it collects
// exactly the measured calls, one callgrind dump per cycle, so that tests/timing/cost.py
// reads the executed instructions of every cycle. Natively the client requests are no-ops.
//
//   staa-cost list
//   staa-cost record --scenes DIR [--workload W]     the cycle workloads' scenes -> DIR/W.json
//   staa-cost run W --scenes DIR --cycles N --json OUT
//
// The control cycle's workloads replay recorded scenes (tests/timing/scenes): robot states,
// goals and movers per cycle, recorded once from a closed-loop drive. Replayed open loop,
// their inputs stay the same when the planner's behaviour changes, so a change in cost is a
// change in the work per input, not in the drive.

#include "control/control_cycle.hpp"
#include "hal/socketcan/can_codec.hpp"
#include "map/generate.hpp"
#include "map/goals.hpp"
#include "map/polygon_map.hpp"
#include "map/ros_import.hpp"
#include "perception/depth_obstacles.hpp"
#include "robot/robot_profile.hpp"
#include "world/sim_depth_camera.hpp"
#include "world/world.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <valgrind/callgrind.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr double kDt = 1.0 / 30.0;
constexpr std::uint32_t kExpansions = 1000;

// ---- the measured region ----

// Collects the call between the two toggles and writes one dump per cycle (cost.py sums
// each dump's totals). `what` returns the cycle's algorithm counts, taken outside the region.
template <typename F>
Json measured(F&& what) {
  CALLGRIND_TOGGLE_COLLECT;
  Json counts = what();
  CALLGRIND_TOGGLE_COLLECT;
  CALLGRIND_DUMP_STATS;
  return counts;
}

// ---- inputs ----

// The checkout and ../shared. cost.py passes both as short names of symbolic links in the
// working folder, with a fixed environment and argv: the sizes of what the program allocates
// before the measured cycles then do not depend on where the checkout is, so the heap's
// layout, and with it the alignment-dependent paths of memcpy and memset, stay the same.
// Empty until given: a default held here would itself be an allocation of the checkout's size.
std::string g_root;
std::string g_shared;
fs::path sourceDir() { return g_root.empty() ? fs::path(STAA_SOURCE_DIR) : fs::path(g_root); }
fs::path sharedDir() {
  if (const char* env = std::getenv("STAA_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return g_shared.empty() ? fs::path(STAA_SHARED_DIR) : fs::path(g_shared);
}

// A workload that cannot run here (its input is absent): reported as skipped, with why.
struct Skipped : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Drive {
  PolygonMap map;
  RobotProfile robot;
  Pose2 start;
  std::vector<Vec2> goals;  // driven to in turn
  std::vector<Mover> movers;
  int stride = 12;  // every stride-th cycle becomes a scene (the HSR: 0.4 s, 9 cm at full speed)
};

Polygon personBody() { return {{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}}; }

// Three people walking in the office's corridors, across the HSR's drive between the rooms.
std::vector<Mover> officePeople() {
  return {Mover{personBody(), {{4.5, 10.0}, {4.5, 20.0}}, 1.2}, Mover{personBody(), {{3.5, 22.5}, {5.5, 14.0}}, 1.0},
          Mover{personBody(), {{5.0, 24.0}, {14.0, 22.5}}, 1.4}};
}

// The office's rooms, as tests/timing/measure-staad.sh drives them.
std::vector<Vec2> officeRooms() {
  return {{4.5, 25.5}, {13.5, 1.5}, {22.5, 1.5}, {25.5, 22.5}, {10.5, 4.5}, {13.5, 25.5}, {1.5, 4.5}};
}

RobotProfile hsr() { return loadRobotProfile(sourceDir() / "config/robots/hsr.yaml"); }

Drive driveFor(const std::string& name) {
  Drive d;
  if (name == "cycle.office_empty" || name == "cycle.office_people") {
    d.map = loadPolygonMap(sourceDir() / "config/maps/office.yaml");
    d.robot = hsr();
    d.start = {1.5, 4.5, 0.0};
    d.goals = officeRooms();
    if (name == "cycle.office_people") d.movers = officePeople();
  } else if (name == "cycle.depot") {
    const fs::path yaml = sharedDir() / "maps/ros/depot.yaml";
    if (!fs::exists(yaml)) throw Skipped("shared input " + yaml.string() + " not found (../shared beside the checkout, or STAA_SHARED_DIR)");
    d.map = importRosMap(yaml, ImportOptions{});
    d.robot = hsr();
    GoalPlacement gp;
    gp.count = 8;
    const std::vector<Vec2> g = placeGoals(d.map, gp);
    if (g.size() < 3) throw std::runtime_error("depot: only " + std::to_string(g.size()) + " goals placed");
    d.start = {g[0].x(), g[0].y(), 0.0};
    d.goals.assign(g.begin() + 1, g.end());
  } else if (name == "cycle.clutter") {
    d.map = generateClutterMap(1);
    d.robot = paperAgentProfile();  // the trapezoid: the footprint checks of a non-round base
    d.stride = 4;                   // at 2 m/s
    if (d.map.goals.size() < 3) throw std::runtime_error("clutter: the generated map has too few goals");
    d.start = {d.map.goals[0].x(), d.map.goals[0].y(), 0.0};
    d.goals.assign(d.map.goals.begin() + 1, d.map.goals.begin() + std::min<std::size_t>(d.map.goals.size(), 8));
  } else {
    throw std::invalid_argument("no drive for workload '" + name + "'");
  }
  return d;
}

// ---- scenes ----

struct SceneMover {
  Polygon polygon;
  Vec2 velocity;
  double turn_rate = 0.0;
};
struct Scene {
  UnicycleState robot;
  Pose2 goal;
  std::vector<SceneMover> movers;
};

Json toJson(const Scene& s) {
  Json movers = Json::array();
  for (const SceneMover& m : s.movers) {
    Json poly = Json::array();
    for (const Vec2& p : m.polygon) poly.push_back(Json::array({p.x(), p.y()}));
    movers.push_back({{"polygon", poly}, {"velocity", Json::array({m.velocity.x(), m.velocity.y()})}, {"turn_rate", m.turn_rate}});
  }
  return {{"robot", {s.robot.x, s.robot.y, s.robot.theta, s.robot.v, s.robot.w}},
          {"goal", {s.goal.x, s.goal.y, s.goal.theta}},
          {"movers", movers}};
}

Scene sceneFromJson(const Json& j) {
  Scene s;
  const Json& r = j.at("robot");
  s.robot = UnicycleState{r.at(0).get<double>(), r.at(1).get<double>(), r.at(2).get<double>(), r.at(3).get<double>(),
                          r.at(4).get<double>()};
  const Json& g = j.at("goal");
  s.goal = Pose2{g.at(0).get<double>(), g.at(1).get<double>(), g.at(2).get<double>()};
  for (const Json& m : j.at("movers")) {
    SceneMover sm;
    for (const Json& p : m.at("polygon")) sm.polygon.push_back(Vec2(p.at(0).get<double>(), p.at(1).get<double>()));
    sm.velocity = Vec2(m.at("velocity").at(0).get<double>(), m.at("velocity").at(1).get<double>());
    sm.turn_rate = m.at("turn_rate").get<double>();
    s.movers.push_back(std::move(sm));
  }
  return s;
}

// A closed-loop drive through the goals in turn (the next one when reached or unreachable);
// every d.stride-th planned cycle becomes a scene, up to `count`.
std::vector<Scene> recordDrive(const Drive& d, std::size_t count) {
  World world(d.map, d.robot, d.start, d.movers);
  ControlCycle cycle(d.map, d.robot, ControlConfig{});
  DynamicObstacleSet obstacles(cycle.obstacleCapacity());
  std::vector<Scene> scenes;
  std::size_t goal = 0;
  cycle.setGoal(Pose2{d.goals[0].x(), d.goals[0].y(), 0.0});
  for (int k = 0; k < 20000 && scenes.size() < count; ++k) {
    Scene s;
    const RobotState& r = world.robot();
    s.robot = UnicycleState{r.pose.x, r.pose.y, r.pose.theta, r.v, r.w};
    s.goal = *cycle.goal();
    std::vector<Polygon> polys;
    std::vector<Vec2> vels;
    for (std::size_t i = 0; i < world.moverCount(); ++i) {
      s.movers.push_back({world.moverPolygon(i), world.moverVelocity(i), 0.0});
      polys.push_back(s.movers.back().polygon);
      vels.push_back(s.movers.back().velocity);
    }
    const std::vector<PolygonView> views(polys.begin(), polys.end());
    obstacles.set(views, vels);
    const CycleOutput out = cycle.step(CycleInputs{s.robot, &obstacles}, PlannerBudget::expansions(kExpansions));
    if (out.planned && k % d.stride == 0) scenes.push_back(std::move(s));
    if (out.state == CycleState::kReached || out.state == CycleState::kUnreachable) {
      goal = (goal + 1) % d.goals.size();
      cycle.setGoal(Pose2{d.goals[goal].x(), d.goals[goal].y(), 0.0});
      continue;
    }
    world.step(kDt, out.v_cmd, out.w_cmd);
  }
  return scenes;
}

std::vector<Scene> loadScenes(const fs::path& dir, const std::string& name) {
  const fs::path file = dir / (name + ".json");
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read the recorded scenes (staa-cost record)");
  Json doc;
  try {
    doc = Json::parse(in);
  } catch (const Json::exception& e) {
    throw std::runtime_error(file.string() + ": " + e.what());
  }
  std::vector<Scene> scenes;
  for (const Json& s : doc.at("scenes")) scenes.push_back(sceneFromJson(s));
  if (scenes.empty()) throw std::runtime_error(file.string() + ": no scenes");
  return scenes;
}

// The movers of a scene as the cycle's obstacle set.
void setObstacles(const Scene& s, DynamicObstacleSet& set) {
  std::vector<PolygonView> views;
  std::vector<Vec2> vels;
  std::vector<double> turns;
  for (const SceneMover& m : s.movers) {
    views.emplace_back(m.polygon);
    vels.push_back(m.velocity);
    turns.push_back(m.turn_rate);
  }
  set.set(views, vels, turns);
}

// A clock that advances 1 us per read: the cycle's phase timings and deadlines stay
// deterministic (the vDSO's clock_gettime would add a varying retry loop to the counts).
std::int64_t g_fake_ns = 0;
std::int64_t fakeClock() { return g_fake_ns += 1000; }

// ---- the workloads ----

struct Run {
  std::size_t cycles;
  std::vector<Json> per_cycle;  // algorithm counts
};

Json planCounts(const CycleOutput& out) {
  const PlanStats& st = out.plan.stats;
  return {{"pops", st.pops},
          {"expansions", st.expansions},
          {"successors", st.successors},
          {"collisions", st.collisions},
          {"heuristic_calls", st.heuristic_calls},
          {"state", toString(out.state)}};
}

void runCycle(const std::string& name, const std::vector<Scene>& scenes, Run& run) {
  const Drive d = driveFor(name);
  ControlCycle cycle(d.map, d.robot, ControlConfig{}, &fakeClock);
  DynamicObstacleSet obstacles(cycle.obstacleCapacity());
  std::optional<Pose2> goal;
  CALLGRIND_START_INSTRUMENTATION;
  for (std::size_t k = 0; k < run.cycles; ++k) {
    const Scene& s = scenes[k % scenes.size()];
    setObstacles(s, obstacles);
    if (!goal || goal->x != s.goal.x || goal->y != s.goal.y || goal->theta != s.goal.theta) {
      goal = s.goal;
      cycle.setGoal(s.goal);
    }
    run.per_cycle.push_back(measured([&] {
      const CycleOutput out = cycle.step(CycleInputs{s.robot, &obstacles}, PlannerBudget::expansions(kExpansions));
      return planCounts(out);
    }));
  }
}

// Minimal Construct in M' ∪ D' along the recorded drive with people (per-cycle, warm: the
// same goal keeps the static tree), and cold (each query to another room than the last).
void runPath(const std::string& name, const std::vector<Scene>& scenes, Run& run) {
  const Drive d = driveFor("cycle.office_people");
  const ControlCycle shape(d.map, d.robot, ControlConfig{});  // the cycle's inflations and options
  GlobalPathPlanner planner(d.map, shape.pathPlanner().options());
  DynamicObstacleSet obstacles(shape.obstacleCapacity());
  std::vector<FixedPolygon> inflated(shape.obstacleCapacity());
  std::vector<PolygonView> views(shape.obstacleCapacity());
  const bool cold = name == "path.mc_cold";
  const std::vector<Vec2> rooms = officeRooms();
  CALLGRIND_START_INSTRUMENTATION;
  for (std::size_t k = 0; k < run.cycles; ++k) {
    const Scene& s = scenes[k % scenes.size()];
    setObstacles(s, obstacles);
    const std::size_t n = obstacles.size();
    for (std::size_t i = 0; i < n; ++i) {
      obstacles.predictInflated(i, 0.0, shape.dynamicInflation(), shape.config().staa.heuristic.arc_steps, inflated[i]);
      views[i] = inflated[i].view();
    }
    const Vec2 goal = cold ? rooms[k % rooms.size()] : s.goal.position();
    run.per_cycle.push_back(measured([&] {
      const GlobalPath p = cold ? planner.plan(s.robot.position(), goal)
                                : planner.plan(s.robot.position(), goal, std::span<const PolygonView>(views.data(), n));
      return Json{{"expansions", p.expansions}, {"edge_checks", p.edge_checks}, {"status", toString(p.status)}};
    }));
  }
}

// The local map (box, G~, collision grid, costmap) along the recorded drive with people; the
// global paths are found first, outside the measured region.
void runLocal(const std::vector<Scene>& scenes, Run& run) {
  const Drive d = driveFor("cycle.office_people");
  const ControlConfig config;
  const ControlCycle shape(d.map, d.robot, config);
  GlobalPathPlanner planner(d.map, shape.pathPlanner().options());
  std::vector<std::vector<Vec2>> paths;
  for (std::size_t k = 0; k < std::min(run.cycles, scenes.size()); ++k) {
    const GlobalPath p = planner.plan(scenes[k].robot.position(), scenes[k].goal.position());
    paths.emplace_back(p.path.begin(), p.path.end());
  }
  LocalMap local(shape.config().local);
  CALLGRIND_START_INSTRUMENTATION;
  for (std::size_t k = 0; k < run.cycles; ++k) {
    const Scene& s = scenes[k % scenes.size()];
    const std::vector<Vec2>& path = paths[k % paths.size()];
    run.per_cycle.push_back(measured([&] {
      local.update(s.robot.pose(), planner.realObstacleSet(), path, s.goal.theta);
      return Json{{"path_vertices", path.size()}};
    }));
  }
}

// Perception on depth frames rendered up front (the office corridor, two walkers, the HSR's
// head camera with Xtion-like noise, the robot driving and turning): deterministic frames,
// no file to commit.
void runPerception(Run& run) {
  const PolygonMap map = loadPolygonMap(sourceDir() / "config/maps/office.yaml");
  const RobotProfile robot = hsr();
  const hal::CameraMount head{0.0, 0.0, 1.0, 0.0, 0.3, 0.0};
  const Polygon box{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}};
  World world(map, robot, Pose2{4.5, 4.5, 0.0},
              {Mover{box, {{6.5, 3.9}, {6.5, 5.1}}, 0.5}, Mover{box, {{8.0, 5.2}, {7.0, 3.8}}, 0.8}});
  hal::SimDepthConfig c;
  c.mount = head;
  c.noise_mm_per_m2 = 1.5;
  hal::SimDepthCamera camera(world, c);
  const std::size_t frames = std::min<std::size_t>(run.cycles, 60);
  std::vector<std::unique_ptr<hal::DepthFrame>> recorded;
  std::vector<Pose2> poses;
  constexpr rt::Nanos kPeriod = 33'333'333;
  for (std::size_t k = 1; k <= frames; ++k) {
    world.step(kDt, 0.2, k < frames / 2 ? 0.3 : -0.3);
    recorded.push_back(std::make_unique<hal::DepthFrame>());
    if (!camera.read(static_cast<rt::Nanos>(k) * kPeriod, *recorded.back())) throw std::runtime_error("perception: the sim camera gave no frame");
    poses.push_back(world.robot().pose);
  }
  DepthObstacleDetector detector(map, hal::CameraIntrinsics{}, head);
  hal::ObstacleFrame out;
  rt::Nanos stamp = 0;
  CALLGRIND_START_INSTRUMENTATION;
  for (std::size_t k = 0; k < run.cycles; ++k) {
    hal::DepthFrame& f = *recorded[k % recorded.size()];
    stamp += kPeriod;
    f.stamp = stamp;
    run.per_cycle.push_back(measured([&] {
      const DepthObstaclesStats st = detector.process(f, poses[k % poses.size()], out);
      return Json{{"points", st.points}, {"clusters", st.clusters}, {"tracks", st.tracks}, {"obstacles", out.count}};
    }));
  }
}

// One round of the CAN profile's frames: the driver's command and heartbeat encoded and
// decoded by the base, the base's odometry, status and heartbeat encoded and decoded by the
// driver.
void runCan(Run& run) {
  const hal::CanProfile profile = hal::loadCanProfile(sourceDir() / "config/can/hsr_base.yaml");
  CALLGRIND_START_INSTRUMENTATION;
  for (std::size_t k = 0; k < run.cycles; ++k) {
    const auto counter = static_cast<std::uint8_t>(k);
    const double v = 0.001 * static_cast<double>(k % 200), w = -0.002 * static_cast<double>(k % 150);
    run.per_cycle.push_back(measured([&] {
      int ok = 0;
      ok += hal::decodeCommand(profile, hal::encodeCommand(profile, v, w, true, false, counter)).ok();
      ok += hal::decodeHostHeartbeat(profile, hal::encodeHostHeartbeat(profile, hal::CanHostState::kDriving, counter)).ok();
      ok += hal::decodeOdometry(profile, hal::encodeOdometry(profile, v, w, 33333, counter)).ok();
      ok += hal::decodeStatus(profile, hal::encodeStatus(profile, true, false, false, 0, counter)).ok();
      ok += hal::decodeBaseHeartbeat(profile, hal::encodeBaseHeartbeat(profile, hal::CanBaseState::kOk, counter)).ok();
      return Json{{"decoded", ok}};
    }));
  }
}

const std::vector<std::string>& workloads() {
  static const std::vector<std::string> names{"cycle.office_empty", "cycle.office_people", "cycle.depot", "cycle.clutter",
                                              "path.mc_cycle",      "path.mc_cold",        "local.update", "perception.depth",
                                              "can.codec_round"};
  return names;
}
bool isCycle(const std::string& name) { return name.rfind("cycle.", 0) == 0; }

// The scenes a workload replays (the path and local workloads reuse the drive with people).
std::string scenesOf(const std::string& name) {
  if (isCycle(name)) return name;
  if (name.rfind("path.", 0) == 0 || name == "local.update") return "cycle.office_people";
  return "";
}

int record(const fs::path& dir, const std::string& only, std::size_t count) {
  fs::create_directories(dir);
  for (const std::string& name : workloads()) {
    if (!isCycle(name) || (!only.empty() && name != only)) continue;
    try {
      const std::vector<Scene> scenes = recordDrive(driveFor(name), count);
      Json doc{{"workload", name}, {"expansions", kExpansions}, {"scenes", Json::array()}};
      for (const Scene& s : scenes) doc["scenes"].push_back(toJson(s));
      std::ofstream(dir / (name + ".json")) << doc.dump() << '\n';
      std::cout << name << ": " << scenes.size() << " scenes\n";
    } catch (const Skipped& e) {
      std::cout << name << ": skipped: " << e.what() << '\n';
    }
  }
  return 0;
}

int runWorkload(const std::string& name, const fs::path& scenes_dir, std::size_t cycles, const fs::path& json_out) {
  Run run{cycles, {}};
  Json doc{{"workload", name}, {"cycles", cycles}};
  try {
    const std::string sc = scenesOf(name);
    const std::vector<Scene> scenes = sc.empty() ? std::vector<Scene>{} : loadScenes(scenes_dir, sc);
    if (isCycle(name)) {
      runCycle(name, scenes, run);
    } else if (name.rfind("path.", 0) == 0) {
      runPath(name, scenes, run);
    } else if (name == "local.update") {
      runLocal(scenes, run);
    } else if (name == "perception.depth") {
      runPerception(run);
    } else if (name == "can.codec_round") {
      runCan(run);
    } else {
      std::cerr << "staa-cost: unknown workload '" << name << "' (staa-cost list)\n";
      return 2;
    }
    doc["per_cycle"] = run.per_cycle;
  } catch (const Skipped& e) {
    doc["skipped"] = e.what();
  }
  std::ofstream out(json_out);
  if (!out) {
    std::cerr << "staa-cost: cannot write " << json_out << '\n';
    return 2;
  }
  out << doc.dump(1) << '\n';
  return 0;
}

}  // namespace
}  // namespace staa

int main(int argc, char** argv) {
  using namespace staa;
  CLI::App app{"staa-cost: the timing suite's cost workloads (run under callgrind by tests/timing/cost.py)"};
  app.require_subcommand(1);
  app.add_subcommand("list", "the workloads, one per line")->callback([] {
    for (const std::string& w : workloads()) std::cout << w << '\n';
  });
  std::string scenes_dir, only, json_out, name;
  std::size_t count = 150, cycles = 50;
  int status = 0;
  CLI::App* rec = app.add_subcommand("record", "record the cycle workloads' scenes from closed-loop drives");
  rec->add_option("--scenes", scenes_dir, "folder for W.json");
  rec->add_option("--workload", only, "only this workload");
  rec->add_option("--count", count, "scenes per workload")->check(CLI::Range(1, 10000));

  CLI::App* run = app.add_subcommand("run", "step one workload, one callgrind dump per cycle");
  run->add_option("workload", name, "the workload (staa-cost list)")->required();
  run->add_option("--scenes", scenes_dir, "the recorded scenes' folder");
  run->add_option("--cycles", cycles, "measured cycles")->check(CLI::Range(1, 100000));
  run->add_option("--json", json_out, "the algorithm counts per cycle")->required();
  for (CLI::App* sub : {rec, run}) {
    sub->add_option("--root", g_root, "the checkout (default: the one built from)");
    sub->add_option("--shared", g_shared, "../shared (default: beside the checkout built from)");
  }

  try {
    app.parse(argc, argv);
    if (scenes_dir.empty()) scenes_dir = (sourceDir() / "tests/timing/scenes").string();
    if (rec->parsed()) status = record(scenes_dir, only, count);
    if (run->parsed()) status = runWorkload(name, scenes_dir, cycles, json_out);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "staa-cost: " << e.what() << '\n';
    return 2;
  }
  return status;
}
