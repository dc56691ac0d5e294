// How loading, validating and planning around one big polygon grow with its vertex count
// (issue 18): a map of one polygon of n vertices, n from 1,000 to 200,000.
//
//   build/release/tests/bench/bench_big_polygon --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Two shapes, both simple, centred in a 20 x 20 m map:
//   Ring:  a toothed ring of radius 5 m (vertices alternately at 5.0 and 4.9 m), as a round
//          room's wall comes out of a CAD export: its edges crowd a thin band of its box.
//   Spiky: a star of long spikes (5.0 and 0.5 m): every edge's box covers much of the map.
// LoadValidate: parsePolygonMap of the map's text (YAML reading, the coordinate checks and
//               the simplicity check), then unionArea (what `staa-map info` adds).
// PathAround:   one query from (-8, 0) to the far side of the ring (inflation 0.3 m), the
//               planner (inflation, the edge grid) built once outside the timed loop; the
//               goal alternates between two points so that no search tree is reused.

#include "geometry/clipper_ops.hpp"
#include "map/polygon_map.hpp"
#include "path/global_path.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

namespace staa {
namespace {

PolygonMap bigPolygonMap(std::size_t n, double inner) {
  PolygonMap map;
  map.name = "big polygon";
  map.bounds = Box{{-10.0, -10.0}, {10.0, 10.0}};
  Polygon p;
  p.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double a = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(n);
    const double r = k % 2 == 0 ? 5.0 : inner;
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  map.obstacles.push_back(std::move(p));
  return map;
}

void loadValidate(benchmark::State& state, double inner) {
  const std::string text = toYaml(bigPolygonMap(static_cast<std::size_t>(state.range(0)), inner));
  for (auto _ : state) {
    const PolygonMap map = parsePolygonMap(text, "big.yaml");
    benchmark::DoNotOptimize(unionArea(map.obstacles));
  }
  state.counters["bytes"] = static_cast<double>(text.size());
  state.SetComplexityN(state.range(0));
}

void BM_LoadValidateRing(benchmark::State& state) { loadValidate(state, 4.9); }
void BM_LoadValidateSpiky(benchmark::State& state) { loadValidate(state, 0.5); }
BENCHMARK(BM_LoadValidateRing)->Arg(1000)->Arg(4000)->Arg(16000)->Arg(64000)->Arg(200000)->Unit(benchmark::kMillisecond)->Complexity();
BENCHMARK(BM_LoadValidateSpiky)->Arg(1000)->Arg(4000)->Arg(16000)->Arg(64000)->Arg(200000)->Unit(benchmark::kMillisecond)->Complexity();

void BM_PathAroundRing(benchmark::State& state) {
  const PolygonMap map = bigPolygonMap(static_cast<std::size_t>(state.range(0)), 4.9);
  GlobalPathPlanner planner(map, GlobalPathOptions{});
  std::size_t i = 0;
  double length = 0.0;
  for (auto _ : state) {
    const GlobalPath path = planner.plan({-8.0, 0.0}, {8.0, 0.1 * static_cast<double>(i++ % 2)});
    if (path.status != PathStatus::kFound) state.SkipWithError("no path");
    length = path.length;
    benchmark::DoNotOptimize(path.path.data());
  }
  state.counters["length_m"] = length;
  state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_PathAroundRing)->Arg(1000)->Arg(2000)->Arg(4000)->Unit(benchmark::kMillisecond)->Complexity();

}  // namespace
}  // namespace staa
