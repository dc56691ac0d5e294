// STAA* on the generated office map, over fixed scenes: the robot's states along a drive from
// room (0, 1) to room (8, 7), once in the empty office and once with three people walking
// through the corridor ahead of it; for the paper's agent and for the HSR
// (config/robots/hsr.yaml), each with the shipped ControlConfig, and for the paper's agent also
// with the heuristic evaluated eagerly and lazily (the `eager`/`lazy` variants override the
// shipped StaaConfig::lazy_heuristic). Counters (per planner call, medians over the scenes and
// iterations):
//   pops_per_ms, successors_per_ms   queue pops and generated successors per millisecond
//   heuristic_pct, collision_pct     share of the planning time (from a timed second pass)
//   path_pct, local_pct              share of the cycle in the global path and the local map
//   finished_early, depth_mean       with the 19 ms budget
//   cycle_p50_us, cycle_p99_us, cycle_max_us   path + local map + STAA* at 1,000 expansions
//   plan_p99_us, path_p99_us         the tails of STAA* and of the global path on their own
//
// Times are the thread's CPU time (CLOCK_THREAD_CPUTIME_ID), for the cycle's phases and the
// 19 ms budget alike: on a shared machine the time the thread waits for a core is not the
// planner's (on the robot the control thread runs under SCHED_FIFO and does not wait).
//
//   build/release/tests/bench/bench_planner --benchmark_repetitions=5
//   STAA_BENCH_SCENES=49-55 STAA_BENCH_PRINT=1 build/release/tests/bench/bench_planner --benchmark_filter=BM_Staa1000/office_empty/

#include "control/control_cycle.hpp"
#include "map/generate.hpp"
#include "world/world.hpp"

#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>

namespace staa {
namespace {

std::int64_t threadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

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

enum class Robot { kPaperAgent, kHsr };

std::vector<Mover> people() {
  std::vector<Mover> m;
  const Polygon body{{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}};
  m.push_back(Mover{body, {{4.5, 10.0}, {4.5, 20.0}}, 1.2});
  m.push_back(Mover{body, {{3.5, 22.5}, {5.5, 14.0}}, 1.0});
  m.push_back(Mover{body, {{5.0, 24.0}, {14.0, 22.5}}, 1.4});
  return m;
}

// The scenes: every stride-th cycle of one drive with the real controller (expansion budget):
// the paper's agent every 10th of up to 900 cycles (30 s), the HSR (at a tenth of its speed)
// every 30th of up to 2,700 (90 s, into the corridor the people walk in).
Setup makeSetup(Robot robot, bool with_movers) {
  Setup s;
  s.map = generateOfficeMap();
  s.robot = robot == Robot::kHsr ? loadRobotProfile(std::filesystem::path(STAA_SOURCE_DIR) / "config/robots/hsr.yaml")
                                 : paperAgentProfile();
  const int cycles = robot == Robot::kHsr ? 2700 : 900;
  const int stride = robot == Robot::kHsr ? 30 : 10;
  World world(s.map, s.robot, Pose2{1.5, 4.5, 0.0}, with_movers ? people() : std::vector<Mover>{});
  ControlCycle cycle(s.map, s.robot, ControlConfig{});
  cycle.setGoal(s.goal);
  DynamicObstacleSet obstacles(32);
  for (int k = 0; k < cycles; ++k) {
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
    if (k % stride == 0 && out.planned) s.scenes.push_back(scene);
    if (out.state == CycleState::kReached) break;
    world.step(1.0 / 30.0, out.v_cmd, out.w_cmd);
  }
  return s;
}

const Setup& setup(Robot robot, bool with_movers) {
  if (robot == Robot::kHsr) {
    if (with_movers) {
      static const Setup s = makeSetup(robot, true);
      return s;
    }
    static const Setup s = makeSetup(robot, false);
    return s;
  }
  if (with_movers) {
    static const Setup s = makeSetup(robot, true);
    return s;
  }
  static const Setup s = makeSetup(robot, false);
  return s;
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

// For profiling the tail: STAA_BENCH_SCENES=FIRST-LAST runs only those scenes (indices into the
// drive's scenes; the counters are then of those alone), STAA_BENCH_PRINT=1 prints every call's
// phases to stderr. Neither is set for the figures.
struct SceneFilter {
  std::size_t first = 0;
  std::size_t last = static_cast<std::size_t>(-1);
  bool print = false;
};
const SceneFilter& sceneFilter() {
  static const SceneFilter f = [] {
    SceneFilter r;
    if (const char* range = std::getenv("STAA_BENCH_SCENES")) {
      unsigned long a = 0, b = 0;
      if (std::sscanf(range, "%lu-%lu", &a, &b) == 2 && a <= b) {
        r.first = a;
        r.last = b;
      } else {
        std::fprintf(stderr, "bench_planner: STAA_BENCH_SCENES: expected FIRST-LAST, got '%s'\n", range);
        std::exit(2);
      }
    }
    r.print = std::getenv("STAA_BENCH_PRINT") != nullptr;
    return r;
  }();
  return f;
}

// Per-call figures of passes over the scenes.
struct Pass {
  std::vector<double> pops_per_ms, succ_per_ms, heuristic_share, collision_share, path_share, local_share, cycle_us,
      plan_us, path_us, depth;
  int calls = 0, early = 0;

  void add(const Pass& p) {
    auto append = [](std::vector<double>& to, const std::vector<double>& from) { to.insert(to.end(), from.begin(), from.end()); };
    append(pops_per_ms, p.pops_per_ms);
    append(succ_per_ms, p.succ_per_ms);
    append(path_share, p.path_share);
    append(local_share, p.local_share);
    append(cycle_us, p.cycle_us);
    append(plan_us, p.plan_us);
    append(path_us, p.path_us);
    append(depth, p.depth);
    calls += p.calls;
    early += p.early;
  }
};

Pass runPass(const Setup& s, ControlCycle& cycle, const PlannerBudget& budget, bool timing) {
  Pass p;
  cycle.planner().setTiming(timing);
  DynamicObstacleSet obstacles(32);
  const SceneFilter& filter = sceneFilter();
  for (std::size_t si = 0; si < s.scenes.size(); ++si) {
    if (si < filter.first || si > filter.last) continue;
    const Scene& scene = s.scenes[si];
    std::vector<PolygonView> views(scene.movers.begin(), scene.movers.end());
    obstacles.set(views, scene.velocities);
    CycleInputs in;
    in.robot = scene.robot;
    in.obstacles = &obstacles;
    cycle.setGoal(s.goal);
    const CycleOutput out = cycle.step(in, budget);
    if (!out.planned) continue;
    const double ms = static_cast<double>(std::max<std::int64_t>(out.plan_ns, 1)) * 1e-6;
    const double cycle_ns = static_cast<double>(std::max<std::int64_t>(out.path_ns + out.local_ns + out.plan_ns, 1));
    ++p.calls;
    p.early += out.plan.outcome == PlanResult::Outcome::kFinished;
    p.depth.push_back(out.plan.depth);
    p.pops_per_ms.push_back(out.plan.stats.pops / ms);
    p.succ_per_ms.push_back(out.plan.stats.successors / ms);
    p.cycle_us.push_back(cycle_ns * 1e-3);
    p.plan_us.push_back(static_cast<double>(out.plan_ns) * 1e-3);
    p.path_us.push_back(static_cast<double>(out.path_ns) * 1e-3);
    if (filter.print) {
      std::fprintf(stderr, "scene %zu path_us %.0f local_us %.0f plan_us %.0f pops %u successors %u\n", si,
                   static_cast<double>(out.path_ns) * 1e-3, static_cast<double>(out.local_ns) * 1e-3,
                   static_cast<double>(out.plan_ns) * 1e-3, static_cast<unsigned>(out.plan.stats.pops),
                   static_cast<unsigned>(out.plan.stats.successors));
    }
    p.path_share.push_back(100.0 * static_cast<double>(out.path_ns) / cycle_ns);
    p.local_share.push_back(100.0 * static_cast<double>(out.local_ns) / cycle_ns);
    if (timing && out.plan.stats.total_ns > 0) {
      p.heuristic_share.push_back(100.0 * out.plan.stats.heuristic_ns / out.plan.stats.total_ns);
      p.collision_share.push_back(100.0 * out.plan.stats.collision_ns / out.plan.stats.total_ns);
    }
  }
  return p;
}

enum class Heuristic { kShipped, kEager, kLazy };

ControlConfig config(Heuristic h) {
  ControlConfig c;
  if (h != Heuristic::kShipped) c.staa.lazy_heuristic = h == Heuristic::kLazy;
  return c;
}

void BM_Staa1000(benchmark::State& state, Robot robot, bool with_movers, Heuristic h) {
  const Setup& s = setup(robot, with_movers);
  ControlCycle cycle(s.map, s.robot, config(h), &threadCpuNs);
  Pass all;
  for (auto _ : state) all.add(runPass(s, cycle, PlannerBudget::expansions(1000), false));
  const Pass timed = runPass(s, cycle, PlannerBudget::expansions(1000), true);
  state.counters["scenes"] = static_cast<double>(s.scenes.size());
  state.counters["pops_per_ms"] = median(all.pops_per_ms);
  state.counters["successors_per_ms"] = median(all.succ_per_ms);
  state.counters["cycle_p50_us"] = median(all.cycle_us);
  state.counters["cycle_p99_us"] = percentile(all.cycle_us, 0.99);
  state.counters["cycle_max_us"] = percentile(all.cycle_us, 1.0);
  state.counters["plan_p99_us"] = percentile(all.plan_us, 0.99);
  state.counters["path_p99_us"] = percentile(all.path_us, 0.99);
  state.counters["path_pct"] = median(all.path_share);
  state.counters["local_pct"] = median(all.local_share);
  state.counters["heuristic_pct"] = median(timed.heuristic_share);
  state.counters["collision_pct"] = median(timed.collision_share);
}

void BM_Staa19ms(benchmark::State& state, Robot robot, bool with_movers, Heuristic h) {
  const Setup& s = setup(robot, with_movers);
  ControlCycle cycle(s.map, s.robot, config(h), &threadCpuNs);
  Pass all;
  for (auto _ : state) all.add(runPass(s, cycle, PlannerBudget::wallClock(19'000'000, &threadCpuNs), false));
  state.counters["finished_early"] = all.calls > 0 ? static_cast<double>(all.early) / all.calls : 0.0;
  state.counters["depth_mean"] = all.depth.empty() ? 0.0 : std::accumulate(all.depth.begin(), all.depth.end(), 0.0) / all.depth.size();
  state.counters["pops_per_ms"] = median(all.pops_per_ms);
  state.counters["successors_per_ms"] = median(all.succ_per_ms);
}

BENCHMARK_CAPTURE(BM_Staa1000, office_empty, Robot::kPaperAgent, false, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, office_three_movers, Robot::kPaperAgent, true, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa19ms, office_empty, Robot::kPaperAgent, false, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Staa19ms, office_three_movers, Robot::kPaperAgent, true, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Staa1000, office_empty_eager, Robot::kPaperAgent, false, Heuristic::kEager)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, office_three_movers_eager, Robot::kPaperAgent, true, Heuristic::kEager)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, office_empty_lazy, Robot::kPaperAgent, false, Heuristic::kLazy)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, office_three_movers_lazy, Robot::kPaperAgent, true, Heuristic::kLazy)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, hsr_office_empty, Robot::kHsr, false, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa1000, hsr_office_three_movers, Robot::kHsr, true, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_Staa19ms, hsr_office_empty, Robot::kHsr, false, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Staa19ms, hsr_office_three_movers, Robot::kHsr, true, Heuristic::kShipped)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace staa
