// How loading, validating and planning around one big polygon grow with its vertex count
// (issue 18): a map of one polygon of n vertices, n from 1,000 to 200,000.
// --benchmark_filter='LoadPlan|LoadValidate' gives the table in docs/results.md.
//
//   build/release/tests/bench/bench_big_polygon --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Shapes, all simple, centred in a 20 x 20 m map:
//   ring:   a toothed ring of radius 5 m (vertices alternately at 5.0 and 4.9 m), as a round
//           room's wall comes out of a CAD export: its edges crowd a thin band of its box.
//   spiky:  a star of long spikes (5.0 and 0.5 m): every edge's box covers much of the map.
//   circle: n vertices on a 5 m circle (every corner convex).
//   room:   a round room's wall, an annulus from 5.0 to 5.2 m with a 1 m door facing +x, n / 2
//           vertices along each arc (a convex and a concave arc).
// LoadValidate: parsePolygonMap of the map's text (YAML reading, the coordinate checks and
//               the simplicity check), then unionArea (what `staa-map info` adds).
// PlannerBuild: GlobalPathPlanner's construction (inflation 0.3 m): M' (the outward
//               simplification of a polygon of more than 1,000 vertices, Clipper's
//               inflation), the edge grids of M' and of the real obstacles.
// PathQuery:    one query from (-8, 0) to the far side (8, 0.1) or (8, -0.1) alternately, so
//               that no search tree is reused; the planner built once outside the timed loop.
// LoadPlan:     the three in one, as `staa-map path` runs them (less reading the file).

#include "geometry/clipper_ops.hpp"
#include "map/polygon_map.hpp"
#include "path/global_path.hpp"
#include "tests/support/big_polygons.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

namespace staa {
namespace {

enum class Shape { kRing, kSpiky, kCircle, kRoom };

PolygonMap bigPolygonMap(std::size_t n, Shape shape) {
  PolygonMap map;
  map.name = "big polygon";
  map.bounds = Box{{-10.0, -10.0}, {10.0, 10.0}};
  const double inner = shape == Shape::kRing ? 4.9 : shape == Shape::kSpiky ? 0.5 : 5.0;
  Polygon p = shape == Shape::kRoom ? test::roundRoomWall(n / 2) : test::alternating(n, 5.0, inner);
  map.obstacles.push_back(std::move(p));
  return map;
}

// 1,000 is at the simplification's bound (kept as it is), 2,000 just past it.
#define STAA_BIG_POLYGON_SIZES Arg(1000)->Arg(2000)->Arg(10000)->Arg(50000)->Arg(100000)->Arg(200000)

void BM_LoadValidate(benchmark::State& state, Shape shape) {
  const std::string text = toYaml(bigPolygonMap(static_cast<std::size_t>(state.range(0)), shape));
  for (auto _ : state) {
    const PolygonMap map = parsePolygonMap(text, "big.yaml");
    benchmark::DoNotOptimize(unionArea(map.obstacles));
  }
  state.counters["bytes"] = static_cast<double>(text.size());
}

void BM_PlannerBuild(benchmark::State& state, Shape shape) {
  const PolygonMap map = bigPolygonMap(static_cast<std::size_t>(state.range(0)), shape);
  std::size_t corners = 0;
  for (auto _ : state) {
    const GlobalPathPlanner planner(map, GlobalPathOptions{});
    corners = planner.inflatedObstacles().front().size();
    benchmark::DoNotOptimize(corners);
  }
  state.counters["inflated_vertices"] = static_cast<double>(corners);
}

void BM_PathQuery(benchmark::State& state, Shape shape) {
  const PolygonMap map = bigPolygonMap(static_cast<std::size_t>(state.range(0)), shape);
  GlobalPathPlanner planner(map, GlobalPathOptions{});
  std::size_t i = 0;
  double length = 0.0;
  for (auto _ : state) {
    const GlobalPath path = planner.plan({-8.0, 0.0}, {8.0, i++ % 2 == 0 ? 0.1 : -0.1});
    if (path.status != PathStatus::kFound) state.SkipWithError("no path");
    length = path.length;
    benchmark::DoNotOptimize(path.path.data());
  }
  state.counters["length_m"] = length;
}

// What `staa-map path` does past reading the file: parse and validate, build, one query.
void BM_LoadPlan(benchmark::State& state, Shape shape) {
  const std::string text = toYaml(bigPolygonMap(static_cast<std::size_t>(state.range(0)), shape));
  double length = 0.0;
  for (auto _ : state) {
    const PolygonMap map = parsePolygonMap(text, "big.yaml");
    GlobalPathPlanner planner(map, GlobalPathOptions{});
    const GlobalPath path = planner.plan({-8.0, 0.0}, {8.0, 0.1});
    if (path.status != PathStatus::kFound) state.SkipWithError("no path");
    length = path.length;
    benchmark::DoNotOptimize(path.path.data());
  }
  state.counters["length_m"] = length;
}

BENCHMARK_CAPTURE(BM_LoadValidate, ring, Shape::kRing)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadValidate, spiky, Shape::kSpiky)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadValidate, circle, Shape::kCircle)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadValidate, room, Shape::kRoom)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PlannerBuild, ring, Shape::kRing)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PlannerBuild, spiky, Shape::kSpiky)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PlannerBuild, circle, Shape::kCircle)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PlannerBuild, room, Shape::kRoom)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PathQuery, ring, Shape::kRing)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_PathQuery, spiky, Shape::kSpiky)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_PathQuery, circle, Shape::kCircle)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_PathQuery, room, Shape::kRoom)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoadPlan, ring, Shape::kRing)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadPlan, spiky, Shape::kSpiky)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadPlan, circle, Shape::kCircle)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LoadPlan, room, Shape::kRoom)->STAA_BIG_POLYGON_SIZES->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace staa
