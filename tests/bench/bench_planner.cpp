// STAA* on the generated office map, over fixed scenes: the robot's states along a drive from
// room (0, 1) to room (8, 7), once in the empty office and once with three people walking
// through the corridor ahead of it. Counters (per planner call, medians over the scenes):
//   pops_per_ms, successors_per_ms   queue pops and generated successors per millisecond
//   heuristic_pct, collision_pct     share of the planning time (from a timed second pass)
//   finished_early, depth_mean       with the 19 ms wall-clock budget
//   cycle_p50_us, cycle_p99_us       path + local map + STAA* at 1,000 expansions
//
//   build/release/tests/bench/bench_planner --benchmark_repetitions=3

#include "control/control_cycle.hpp"
#include "map/generate.hpp"
#include "world/world.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <numeric>

namespace staa {
namespace {

struct Scene {
  UnicycleState robot;
  std::vector<Polygon> movers;
  std::vector<Vec2> velocities;
};

struct Setup {
  PolygonMap map;
  RobotProfile robot;
  Pose2 goal{25.5, 22.5, 0.0};
  std::vector<Scene> scenes;
};

std::vector<Mover> people() {
  std::vector<Mover> m;
  const Polygon body{{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}};
  m.push_back(Mover{body, {{4.5, 10.0}, {4.5, 20.0}}, 1.2});
  m.push_back(Mover{body, {{3.5, 22.5}, {5.5, 14.0}}, 1.0});
  m.push_back(Mover{body, {{5.0, 24.0}, {14.0, 22.5}}, 1.4});
  return m;
}

// The scenes: every 10th cycle of one drive with the real controller (expansion budget).
Setup makeSetup(bool with_movers) {
  Setup s;
  s.map = generateOfficeMap();
  s.robot = paperAgentProfile();
  World world(s.map, s.robot, Pose2{1.5, 4.5, 0.0}, with_movers ? people() : std::vector<Mover>{});
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(s.goal);
  DynamicObstacleSet obstacles(32);
  for (int k = 0; k < 900; ++k) {
    Scene scene;
    for (std::size_t i = 0; i < world.moverCount(); ++i) {
      scene.movers.push_back(world.moverPolygon(i));
      scene.velocities.push_back(world.moverVelocity(i));
    }
    std::vector<PolygonView> views(scene.movers.begin(), scene.movers.end());
    obstacles.set(views, scene.velocities);
    const RobotState& r = world.robot();
    scene.robot = UnicycleState{r.pose.x, r.pose.y, r.pose.theta, r.v, r.w};
    CycleInputs in;
    in.robot = scene.robot;
    in.obstacles = &obstacles;
    const CycleOutput out = cycle.step(in, PlannerBudget::expansions(1000));
    if (k % 10 == 0 && out.planned) s.scenes.push_back(scene);
    if (out.state == CycleState::kReached) break;
    world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
  }
  return s;
}

const Setup& setup(bool with_movers) {
  static const Setup empty = makeSetup(false);
  static const Setup busy = makeSetup(true);
  return with_movers ? busy : empty;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

// One pass over the scenes; returns per-call figures.
struct Pass {
  std::vector<double> pops_per_ms, succ_per_ms, heuristic_share, collision_share, cycle_us, depth;
  int calls = 0, early = 0;
};

Pass runPass(const Setup& s, ControlCycle& cycle, const PlannerBudget& budget, bool timing) {
  Pass p;
  cycle.planner().setTiming(timing);
  DynamicObstacleSet obstacles(32);
  for (const Scene& scene : s.scenes) {
    std::vector<PolygonView> views(scene.movers.begin(), scene.movers.end());
    obstacles.set(views, scene.velocities);
    CycleInputs in;
    in.robot = scene.robot;
    in.obstacles = &obstacles;
    cycle.setGoal(s.goal);
    const CycleOutput out = cycle.step(in, budget);
    if (!out.planned) continue;
    const double ms = static_cast<double>(out.plan_ns) * 1e-6;
    ++p.calls;
    p.early += out.plan.outcome == PlanResult::Outcome::kFinished;
    p.depth.push_back(out.plan.depth);
    p.pops_per_ms.push_back(out.plan.stats.pops / ms);
    p.succ_per_ms.push_back(out.plan.stats.successors / ms);
    p.cycle_us.push_back(static_cast<double>(out.path_ns + out.local_ns + out.plan_ns) * 1e-3);
    if (timing && out.plan.stats.total_ns > 0) {
      p.heuristic_share.push_back(100.0 * out.plan.stats.heuristic_ns / out.plan.stats.total_ns);
      p.collision_share.push_back(100.0 * out.plan.stats.collision_ns / out.plan.stats.total_ns);
    }
  }
  return p;
}

void BM_Staa1000(benchmark::State& state, bool with_movers) {
  const Setup& s = setup(with_movers);
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  Pass all;
  for (auto _ : state) {
    Pass p = runPass(s, cycle, PlannerBudget::expansions(1000), false);
    all.pops_per_ms.insert(all.pops_per_ms.end(), p.pops_per_ms.begin(), p.pops_per_ms.end());
    all.succ_per_ms.insert(all.succ_per_ms.end(), p.succ_per_ms.begin(), p.succ_per_ms.end());
    all.cycle_us.insert(all.cycle_us.end(), p.cycle_us.begin(), p.cycle_us.end());
  }
  const Pass timed = runPass(s, cycle, PlannerBudget::expansions(1000), true);
  state.counters["scenes"] = static_cast<double>(s.scenes.size());
  state.counters["pops_per_ms"] = median(all.pops_per_ms);
  state.counters["successors_per_ms"] = median(all.succ_per_ms);
  state.counters["cycle_p50_us"] = median(all.cycle_us);
  state.counters["cycle_p99_us"] = percentile(all.cycle_us, 0.99);
  state.counters["cycle_max_us"] = percentile(all.cycle_us, 1.0);
  state.counters["heuristic_pct"] = median(timed.heuristic_share);
  state.counters["collision_pct"] = median(timed.collision_share);
}

void BM_Staa19ms(benchmark::State& state, bool with_movers) {
  const Setup& s = setup(with_movers);
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  Pass all;
  for (auto _ : state) {
    Pass p = runPass(s, cycle, PlannerBudget::wallClock(19'000'000), false);
    all.calls += p.calls;
    all.early += p.early;
    all.depth.insert(all.depth.end(), p.depth.begin(), p.depth.end());
    all.pops_per_ms.insert(all.pops_per_ms.end(), p.pops_per_ms.begin(), p.pops_per_ms.end());
  }
  state.counters["finished_early"] = all.calls > 0 ? static_cast<double>(all.early) / all.calls : 0.0;
  state.counters["depth_mean"] = all.depth.empty() ? 0.0 : std::accumulate(all.depth.begin(), all.depth.end(), 0.0) / all.depth.size();
  state.counters["pops_per_ms"] = median(all.pops_per_ms);
}

BENCHMARK_CAPTURE(BM_Staa1000, office_empty, false)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, office_three_movers, true)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa19ms, office_empty, false)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Staa19ms, office_three_movers, true)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace staa
