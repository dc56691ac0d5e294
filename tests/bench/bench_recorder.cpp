// What the flight recorder adds to the control thread per cycle: CycleRecorder::before (the
// memory noted, the budget tapped) and after (the cycle encoded and pushed into the byte
// ring that staad's service thread drains), on a real cycle of the office: empty, and
// crowded (12 people as 16-gons, each moving). And what the tap adds to every read of a
// wall-clock budget's clock. Counters: bytes per record, each record's p50 and p99 (its
// wall time with two clock reads; a shared machine adds its preemptions to the p99).
//
//   build/release/tests/bench/bench_recorder --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include "control/control_cycle.hpp"
#include "map/generate.hpp"
#include "record/budget_tap.hpp"
#include "record/recorder.hpp"
#include "rt/byte_ring.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace staa {
namespace {

// The ring of staad's control task; the benchmark empties it when it fills (not timed).
class RingSink final : public record::CycleSink {
 public:
  explicit RingSink(rt::ByteRing& ring) : ring_(ring) {}
  void take(std::span<const std::byte> r) override { pushed_ = ring_.push(r); }
  bool pushed_ = true;

 private:
  rt::ByteRing& ring_;
};

struct Scene {
  PolygonMap map = generateOfficeMap();
  RobotProfile robot = paperAgentProfile();
  ControlCycle cycle{map, robot, ControlConfig{}};
  std::vector<Polygon> polygons;
  std::vector<PolygonView> views;
  std::vector<Vec2> velocities;
  std::vector<double> turns;
  DynamicObstacleSet obstacles{32};
  UnicycleState robot_state{4.5, 4.5, 0.0, 1.0, 0.0};
  CycleOutput out;

  explicit Scene(int people) {
    for (int i = 0; i < people; ++i) {
      Polygon p;
      const Vec2 c(6.0 + 0.8 * i, i % 2 == 0 ? 3.5 : 5.5);
      for (int k = 0; k < 16; ++k) p.emplace_back(c + 0.25 * Vec2(std::cos(k * kPi / 8), std::sin(k * kPi / 8)));
      polygons.push_back(p);
      velocities.emplace_back(-0.8, 0.1 * i);
      turns.push_back(0.05 * i);
    }
    for (const Polygon& p : polygons) views.emplace_back(p);
    obstacles.set(views, velocities, turns);
    cycle.setGoal(Pose2{25.5, 22.5, 0.0});
    out = cycle.step({robot_state, &obstacles}, PlannerBudget::expansions(1000));
  }
};

void recordCycles(benchmark::State& state, int people) {
  Scene s(people);
  rt::ByteRing ring(4u << 20);
  RingSink sink(ring);
  record::RecordLimits limits;
  limits.path_points = 4096;
  limits.trajectory = 256;
  record::CycleRecorder recorder(limits, sink);
  const BudgetSpec budget = BudgetSpec::wallClockMs(19.0);
  std::vector<std::byte> drained;
  std::vector<std::int64_t> ns;  // each record's own time, for p50 and p99 (clock reads included)
  ns.reserve(1u << 22);
  for (auto _ : state) {
    const std::int64_t t0 = steadyClockNs();
    recorder.obstacles({s.views, s.velocities, s.turns});
    PlannerBudget b = recorder.before(s.cycle, budget, &steadyClockNs);
    benchmark::DoNotOptimize(b);
    recorder.after(s.cycle, 1'000'000'000, s.robot_state, record::StepKind::kStepped, 0, &s.out,
                   {s.out.v_cmd, s.out.w_cmd, false, s.out.v_cmd, s.out.w_cmd, false});
    if (ns.size() < ns.capacity()) ns.push_back(steadyClockNs() - t0);
    if (ring.used() > ring.capacity() / 2) {
      state.PauseTiming();
      while (ring.pop(drained)) {
      }
      state.ResumeTiming();
    }
  }
  std::sort(ns.begin(), ns.end());
  if (!ns.empty()) {
    state.counters["p50_ns"] = static_cast<double>(ns[ns.size() / 2]);
    state.counters["p99_ns"] = static_cast<double>(ns[ns.size() * 99 / 100]);
  }
  state.counters["record_bytes"] = static_cast<double>(recorder.lastRecord().size());
  state.counters["pops_recorded"] = s.out.plan.stats.pops;
}

void BM_RecordEmptyOffice(benchmark::State& state) { recordCycles(state, 0); }
void BM_RecordCrowdedOffice(benchmark::State& state) { recordCycles(state, 12); }
BENCHMARK(BM_RecordEmptyOffice);
BENCHMARK(BM_RecordCrowdedOffice);

// One read of a wall-clock budget's clock, directly and through the tap.
void BM_BudgetClockRead(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(steadyClockNs());
}
void BM_BudgetClockReadTapped(benchmark::State& state) {
  record::BudgetTap::install(&steadyClockNs);
  record::BudgetTap::arm(19'000'000);
  for (auto _ : state) benchmark::DoNotOptimize(record::BudgetTap::now());
}
BENCHMARK(BM_BudgetClockRead);
BENCHMARK(BM_BudgetClockReadTapped);

}  // namespace
}  // namespace staa
