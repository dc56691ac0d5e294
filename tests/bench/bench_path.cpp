// Minimal Construct query time on the generated office map and on the imported warehouse map
// (inflation 0.3 m, start and goal far apart). Google Benchmark times the loop; every query
// is also timed on its own, and the median, p99 and maximum are reported as counters
// (p50_us, p99_us, max_us), since a control cycle cares about the tail, not the mean.
//
//   build/release/tests/bench/bench_path --benchmark_repetitions=3
//
// Two kinds of query:
//   Cycle: what the control cycle asks 30 times a second: the same goal while the robot
//          drives 5 cm along the path per query. The search tree for the goal is kept.
//   Cold:  a new far-apart pair every query (nothing reused).
// The warehouse map needs ../shared (the ROS maps); without it that case is skipped.

#include "map/generate.hpp"
#include "map/ros_import.hpp"
#include "path/global_path.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>

namespace staa {
namespace {

std::filesystem::path sharedDir() {
  if (const char* env = std::getenv("STAA_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return STAA_SHARED_DIR;
}

struct Scene {
  PolygonMap map;
  std::vector<Vec2> free_points;  // candidate start/goal locations
  bool ok = false;
};

const Scene& officeScene() {
  static const Scene scene = [] {
    Scene s;
    s.map = generateOfficeMap();
    s.free_points = s.map.goals;
    s.ok = true;
    return s;
  }();
  return scene;
}

const Scene& warehouseScene() {
  static const Scene scene = [] {
    Scene s;
    const auto yaml = sharedDir() / "maps/ros/warehouse.yaml";
    if (!std::filesystem::exists(yaml)) return s;
    s.map = importRosMap(yaml, ImportOptions{});
    // Free points: a lattice over the map, kept where a 0.3 m robot fits.
    GlobalPathPlanner probe(s.map, GlobalPathOptions{});
    const Box b = *s.map.bounds;
    for (double x = b.min.x() + 0.5; x < b.max.x(); x += 1.0) {
      for (double y = b.min.y() + 0.5; y < b.max.y(); y += 1.0) {
        const Vec2 p{x, y};
        if (!probe.insideRealObstacle(p) && probe.plan(p, p).status == PathStatus::kFound && !probe.plan(p, p).start_moved) {
          s.free_points.push_back(p);
        }
      }
    }
    s.ok = !s.free_points.empty();
    return s;
  }();
  return scene;
}

void report(benchmark::State& state, std::vector<double>& us, std::size_t found, std::size_t total) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  state.counters["p50_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  state.counters["max_us"] = us.back();
  state.counters["found"] = static_cast<double>(found) / static_cast<double>(std::max<std::size_t>(total, 1));
}

// Far-apart pairs: at least half the map's diagonal.
std::vector<std::pair<Vec2, Vec2>> farPairs(const Scene& s, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const Box b = s.map.bounds.value_or(Box{{0, 0}, {20, 20}});
  const double min_d = 0.5 * std::hypot(b.width(), b.height());
  std::vector<std::pair<Vec2, Vec2>> out;
  while (out.size() < n) {
    const Vec2 a = s.free_points[rng() % s.free_points.size()];
    const Vec2 c = s.free_points[rng() % s.free_points.size()];
    if ((a - c).norm() >= min_d) out.emplace_back(a, c);
  }
  return out;
}

void BM_Cold(benchmark::State& state, const Scene& (*sceneFn)()) {
  const Scene& s = sceneFn();
  if (!s.ok) {
    state.SkipWithError("../shared/maps/ros not found");
    return;
  }
  GlobalPathPlanner planner(s.map, GlobalPathOptions{});
  const auto pairs = farPairs(s, 256, 1);
  std::vector<double> us;
  std::size_t i = 0, found = 0;
  for (auto _ : state) {
    const auto& [a, c] = pairs[i++ % pairs.size()];
    const auto t0 = std::chrono::steady_clock::now();
    const GlobalPath p = planner.plan(a, c);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(p.length);
    found += p.status == PathStatus::kFound;
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  report(state, us, found, i);
}

void BM_Cycle(benchmark::State& state, const Scene& (*sceneFn)()) {
  const Scene& s = sceneFn();
  if (!s.ok) {
    state.SkipWithError("../shared/maps/ros not found");
    return;
  }
  GlobalPathPlanner planner(s.map, GlobalPathOptions{});
  // Precompute the robot's positions: 5 cm steps along each trip's first path.
  std::vector<std::pair<Vec2, Vec2>> queries;
  for (const auto& [a, goal] : farPairs(s, 16, 2)) {
    const GlobalPath first = planner.plan(a, goal);
    if (first.status != PathStatus::kFound) continue;
    const std::vector<Vec2> path(first.path.begin(), first.path.end());
    for (std::size_t k = 0; k + 1 < path.size(); ++k) {
      const double len = (path[k + 1] - path[k]).norm();
      for (double t = 0.0; t < len; t += 0.05) queries.emplace_back(path[k] + (path[k + 1] - path[k]) * (t / len), goal);
    }
  }
  std::vector<double> us;
  std::size_t i = 0, found = 0;
  for (auto _ : state) {
    const auto& [a, goal] = queries[i++ % queries.size()];
    const auto t0 = std::chrono::steady_clock::now();
    const GlobalPath p = planner.plan(a, goal);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(p.length);
    found += p.status == PathStatus::kFound;
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  report(state, us, found, i);
}

void BM_Build(benchmark::State& state, const Scene& (*sceneFn)()) {
  const Scene& s = sceneFn();
  if (!s.ok) {
    state.SkipWithError("../shared/maps/ros not found");
    return;
  }
  for (auto _ : state) {
    GlobalPathPlanner planner(s.map, GlobalPathOptions{});
    benchmark::DoNotOptimize(planner.inflatedObstacles().size());
  }
}

BENCHMARK_CAPTURE(BM_Cycle, office, &officeScene)->Unit(benchmark::kMicrosecond)->Iterations(20000);
BENCHMARK_CAPTURE(BM_Cold, office, &officeScene)->Unit(benchmark::kMicrosecond)->Iterations(1000);
BENCHMARK_CAPTURE(BM_Cycle, warehouse, &warehouseScene)->Unit(benchmark::kMicrosecond)->Iterations(20000);
BENCHMARK_CAPTURE(BM_Cold, warehouse, &warehouseScene)->Unit(benchmark::kMicrosecond)->Iterations(500);
BENCHMARK_CAPTURE(BM_Build, office, &officeScene)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Build, warehouse, &warehouseScene)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace staa
