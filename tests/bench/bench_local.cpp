// LocalMap::update (collision grid C, costmap C', G~) on the generated office map, the robot
// driving along the corridor ring; and D'(t) for a person-sized obstacle.
//
//   build/release/tests/bench/bench_local --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "map/generate.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

namespace staa {
namespace {

// Poses along the bottom corridor (y 3..6), facing along it with some sway.
std::vector<Pose2> corridorPoses() {
  std::vector<Pose2> poses;
  for (int k = 0; k < 500; ++k) {
    poses.push_back({4.5 + 0.036 * k, 4.5 + 0.3 * std::sin(0.05 * k), 0.3 * std::sin(0.02 * k)});
  }
  return poses;
}

void BM_LocalMapUpdateOffice(benchmark::State& state) {
  const PolygonMap office = generateOfficeMap();
  PolygonSet walls;
  walls.assign(std::span<const Polygon>(office.obstacles), PolygonSet::Options{});
  LocalMap map;
  const auto poses = corridorPoses();
  std::vector<Vec2> path(2);
  std::size_t k = 0;
  for (auto _ : state) {
    const Pose2& robot = poses[k++ % poses.size()];
    path[0] = robot.position();
    path[1] = robot.transform({10.0, 0.0});
    map.update(robot, walls, path, 0.0);
    benchmark::DoNotOptimize(map.costmap().data());
  }
}
BENCHMARK(BM_LocalMapUpdateOffice)->Unit(benchmark::kMicrosecond);

void BM_PredictInflated(benchmark::State& state) {
  const Polygon person{{0, 0}, {0.4, 0}, {0.5, 0.3}, {0.2, 0.5}, {-0.1, 0.3}};
  const PolygonView views[1] = {person};
  const Vec2 velocity[1] = {{0.5, -0.2}};
  DynamicObstacleSet set;
  set.set(views, velocity);
  FixedPolygon out;
  double t = 0.0;
  for (auto _ : state) {
    set.predictInflated(0, t, 0.35, static_cast<int>(state.range(0)), out);
    benchmark::DoNotOptimize(out.v.data());
    t = t < 0.9 ? t + 0.3 : 0.0;
  }
}
BENCHMARK(BM_PredictInflated)->Arg(4)->Arg(8);

}  // namespace
}  // namespace staa
