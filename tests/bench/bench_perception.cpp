// What an agent's depth camera costs in the simulator (staa-sim --obstacles depth), per agent
// per frame: rendering the frame (DepthRenderer, the pixels perception samples), perceiving
// it (DepthObstacleDetector: the same code as staad) and both (AgentCamera::perceive). The
// scenes: every agent of a 5-agent cooperative run of the paper's agent (ground truth,
// 10 s, seed 1) in the office and the clutter, and in the imported depot when ../shared has it,
// each frame seen by one agent among the other four.
//
//   build/release/tests/bench/bench_perception --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include "experiment/agent_camera.hpp"
#include "experiment/experiment.hpp"
#include "experiment/multi_sim.hpp"
#include "map/goals.hpp"
#include "map/polygon_map.hpp"
#include "map/ros_import.hpp"
#include "world/multi_world.hpp"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace staa {
namespace {

struct Scene {
  PolygonMap map;
  // Per recorded step: every agent's pose and footprint.
  std::vector<std::vector<Pose2>> poses;
  std::vector<std::vector<Polygon>> bodies;
};

std::unique_ptr<Scene> record(PolygonMap map) {
  auto scene = std::make_unique<Scene>();
  scene->map = std::move(map);
  MultiSimOptions o;
  o.agents = 5;
  o.duration_s = 10.0;
  o.budget = BudgetSpec::expansionsOf(1000);
  o.seed = 1;
  int step = 0;
  o.on_step = [&](const MultiWorld& w) {
    if (step++ % 3 != 0) return;  // every 3rd step: 100 scenes
    std::vector<Pose2> poses;
    std::vector<Polygon> bodies;
    for (std::size_t i = 0; i < w.size(); ++i) {
      poses.push_back(w.agent(i).pose);
      bodies.push_back(w.footprint(i));
    }
    scene->poses.push_back(std::move(poses));
    scene->bodies.push_back(std::move(bodies));
  };
  runMultiAgent(scene->map, paperAgentProfile(), o);
  return scene;
}

const Scene* scene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Scene>> scenes;
  auto it = scenes.find(name);
  if (it != scenes.end()) return it->second.get();
  std::unique_ptr<Scene> s;
  if (name == "depot") {
    const std::filesystem::path yaml = std::filesystem::path(STAA_SHARED_DIR) / "maps/ros/depot.yaml";
    if (std::filesystem::exists(yaml)) {
      PolygonMap map = importRosMap(yaml, ImportOptions{});
      map.goals = placeGoals(map, kExperimentGoalPlacement);  // as staa-map import --goals 40
      s = record(std::move(map));
    }
  } else {
    s = record(loadExperimentMap(name, 1).map);
  }
  return (scenes[name] = std::move(s)).get();
}

// The frame agent `self` sees at scene step k: the others as prisms 1 m tall.
std::vector<hal::PrismView> others(const Scene& s, std::size_t k, std::size_t self) {
  std::vector<hal::PrismView> prisms;
  for (std::size_t j = 0; j < s.bodies[k].size(); ++j) {
    if (j != self) prisms.push_back(hal::PrismView{PolygonView(s.bodies[k][j]), Vec2(0.0, 0.0), 1.0});
  }
  return prisms;
}

void BM_Render(benchmark::State& state, const std::string& name) {
  const Scene* s = scene(name);
  if (s == nullptr) {
    state.SkipWithError("../shared/maps/ros/depot.yaml not found");
    return;
  }
  const RobotProfile robot = paperAgentProfile();
  const DepthObstaclesConfig perception = agentPerceptionConfig(robot);
  hal::SimDepthConfig c;
  c.intrinsics = cameraIntrinsics(robot.camera);
  c.mount = cameraMount(robot.camera);
  c.mover_height_m = robot.height_m;
  c.min_depth_m = robot.camera.min_range_m;
  c.max_depth_m = robot.camera.max_range_m;
  c.noise_mm_per_m2 = robot.camera.noise_mm_per_m2;
  c.dropout = robot.camera.dropout;
  c.grazing_deg = robot.camera.grazing_deg;
  c.pixel_stride = perception.pixel_stride;
  hal::DepthRenderer renderer(s->map, c);
  auto frame = std::make_unique<hal::DepthFrame>();
  std::size_t k = 0;
  for (auto _ : state) {
    const std::size_t step = (k / 5) % s->poses.size(), self = k % 5;
    ++k;
    const auto prisms = others(*s, step, self);
    renderer.render(s->poses[step][self], prisms, *frame);
    benchmark::DoNotOptimize(frame->depth_mm.data());
  }
}

void BM_AgentCamera(benchmark::State& state, const std::string& name) {
  const Scene* s = scene(name);
  if (s == nullptr) {
    state.SkipWithError("../shared/maps/ros/depot.yaml not found");
    return;
  }
  const RobotProfile robot = paperAgentProfile();
  std::vector<std::unique_ptr<AgentCamera>> cameras;
  for (std::size_t i = 0; i < 5; ++i) {
    cameras.push_back(std::make_unique<AgentCamera>(s->map, robot, agentPerceptionConfig(robot), i + 1));
  }
  std::size_t k = 0;
  double t = 0.0;
  for (auto _ : state) {
    const std::size_t step = (k / 5) % s->poses.size(), self = k % 5;
    if (self == 0) t += 0.1;  // the scenes are 0.1 s apart
    ++k;
    const auto prisms = others(*s, step, self);
    cameras[self]->perceive(t, s->poses[step][self], prisms);
    benchmark::DoNotOptimize(cameras[self]->frame().count);
  }
}

BENCHMARK_CAPTURE(BM_Render, office, std::string("office"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Render, clutter, std::string("clutter"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Render, depot, std::string("depot"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_AgentCamera, office, std::string("office"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_AgentCamera, clutter, std::string("clutter"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_AgentCamera, depot, std::string("depot"))->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace staa
