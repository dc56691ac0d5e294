// SAT vs libccd GJK vs libccd MPR on the pairs the cycle tests: the robot footprint at a
// predicted pose against a moving obstacle (a 0.5 m square or a ~0.4 m convex octagon).
// Arg: 0 colliding, 1 near (centres 0.35-0.9 m apart: both outcomes, the hard case), 2 far,
// 3 a shuffled mix of all three.

#include "geometry/clip.hpp"
#include "geometry/convex.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace staa {
namespace {

constexpr std::size_t kMaxVertices = 8;
struct Pair {
  std::array<Vec2, kMaxVertices> robot{}, obstacle{};
  std::size_t robot_size = 0, obstacle_size = 0;
  PolygonView robotView() const { return {robot.data(), robot_size}; }
  PolygonView obstacleView() const { return {obstacle.data(), obstacle_size}; }
};

const Polygon kFootprint{{0.4, 0.2}, {0.4, -0.2}, {-0.4, -0.25}, {-0.4, 0.25}};

Polygon obstacleShape(std::mt19937_64& rng, bool square) {
  if (square) return {{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}};
  // A random convex octagon of ~0.4 m: 8 sorted angles on a radius 0.17-0.23 m.
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::array<double, 8> angles{};
  for (std::size_t i = 0; i < 8; ++i) angles[i] = (static_cast<double>(i) + 0.8 * u(rng)) * 2 * kPi / 8;
  Polygon pts;
  for (double a : angles) pts.push_back((0.17 + 0.06 * u(rng)) * Vec2(std::cos(a), std::sin(a)));
  return convexHull(pts);
}

std::vector<Pair> makePairs(int kind, std::size_t count) {
  std::mt19937_64 rng(42 + static_cast<unsigned>(kind));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Pair> pairs(count);
  for (std::size_t i = 0; i < count; ++i) {
    const int k = kind == 3 ? static_cast<int>(i % 3) : kind;
    const double r = k == 0 ? 0.3 * u(rng) : k == 1 ? 0.35 + 0.55 * u(rng) : 1.5 + 3.5 * u(rng);
    const Pose2 robot_pose{10 * u(rng), 10 * u(rng), 2 * kPi * u(rng)};
    const double bearing = 2 * kPi * u(rng);
    const Pose2 obstacle_pose{robot_pose.x + r * std::cos(bearing), robot_pose.y + r * std::sin(bearing),
                              2 * kPi * u(rng)};
    const Polygon shape = obstacleShape(rng, u(rng) < 0.5);
    Pair& p = pairs[i];
    p.robot_size = transformPolygon(kFootprint, robot_pose, p.robot).size;
    p.obstacle_size = transformPolygon(shape, obstacle_pose, p.obstacle).size;
  }
  if (kind == 3) std::shuffle(pairs.begin(), pairs.end(), rng);
  return pairs;
}

template <bool (*Test)(PolygonView, PolygonView)>
void BM_ConvexIntersect(benchmark::State& state) {
  const std::vector<Pair> pairs = makePairs(static_cast<int>(state.range(0)), 1024);
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    const Pair& p = pairs[i++ & 1023];
    const bool hit = Test(p.robotView(), p.obstacleView());
    benchmark::DoNotOptimize(hit);
    hits += hit;
  }
  state.counters["hit_fraction"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
}

BENCHMARK(BM_ConvexIntersect<convexIntersectSat>)->Name("SAT")->DenseRange(0, 3);
BENCHMARK(BM_ConvexIntersect<convexIntersectGjk>)->Name("GJK")->DenseRange(0, 3);
BENCHMARK(BM_ConvexIntersect<convexIntersectMpr>)->Name("MPR")->DenseRange(0, 3);

}  // namespace
}  // namespace staa
