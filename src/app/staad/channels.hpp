#pragma once
// Everything staad's threads pass to each other, in one place (docs/ARCHITECTURE.md section 3):
// lock-free, allocation-free after construction, one writer and one reader each.
//
//   service    --requests-->   control   --poses-->     base        (SPSC rings)
//   base       --base-->       control                              (triple buffer)
//   perception --obstacles-->  control                              (triple buffer)
//   control    --command-->    base                                 (triple buffer)
//   control    --status-->     service                              (triple buffer)
//   control    --telemetry-->  service                              (SPSC ring)
//   control    --recorder-->   service                              (SPSC byte ring: encoded cycles)
//   service    --maps-->       control   --retired_maps--> service  (SPSC rings, ROS maps)
//   control    --plan-->       service                              (triple buffer, RViz)
//   each RT thread --*_log-->  service                              (SPSC rings)
//
// heartbeat counts control cycles (the watchdog pings only while it advances); shutdown
// tells the control thread to brake and hold (the daemon is stopping). The debug_* atomics
// carry the test-only fault injections (debug.faults) from the service thread.

#include "app/staad/status.hpp"
#include "app/staad/telemetry.hpp"
#include "control/control_cycle.hpp"
#include "map/polygon_map.hpp"
#include "hal/base.hpp"
#include "hal/obstacles.hpp"
#include "rt/byte_ring.hpp"
#include "rt/log_ring.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/triple_buffer.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace staa::staad {

using RequestRing = rt::SpscRing<Request, 64>;
using PoseRing = rt::SpscRing<Pose2, 8>;

// What the base thread read from the base in one period.
struct BaseSample {
  hal::Odometry odometry;
  hal::BaseStatus status;
};

// The control thread's command for the period after command.stamp, and its plan's next
// action for the period after that: the base thread falls back to `next` when the control
// thread misses a cycle, and brakes when it misses two.
struct CommandSlot {
  hal::VelocityCommand command;
  hal::VelocityCommand next;
};

// A map from ROS (map_server's /map) with the control cycle built on it, made outside the
// real-time threads; the control thread swaps it in at a cycle boundary (a pointer), and
// hands the one it replaced back to be freed there.
struct MapBundle {
  std::uint64_t sequence = 0;  // 1, 2, ... in the order they were built
  PolygonMap map;
  std::unique_ptr<ControlCycle> cycle;
};
using MapRing = rt::SpscRing<MapBundle*, 4>;

// What RViz draws of one cycle (the ROS bridge turns it into markers), copied by the control
// thread into fixed arrays when asked for (plan_wanted): no allocation.
struct PlanSnapshot {
  static constexpr std::size_t kMaxPath = 512;
  static constexpr std::size_t kMaxTrajectory = 64;
  static constexpr std::size_t kMaxTreeEdges = 4096;
  rt::Nanos stamp = -1;
  Pose2 robot;
  std::array<Vec2, kMaxPath> path{};
  std::size_t path_n = 0;
  std::array<Pose2, kMaxTrajectory> trajectory{};
  std::size_t trajectory_n = 0;
  bool has_subgoal = false;
  Pose2 subgoal;
  std::array<hal::ObstacleFrame::Obstacle, hal::ObstacleFrame::kMaxObstacles> obstacles{};
  std::size_t obstacles_n = 0;
  double horizon_s = 0.0;  // how far ahead the predicted obstacles are drawn
  std::array<std::array<Vec2, 2>, kMaxTreeEdges> tree{};
  std::size_t tree_n = 0;  // 0: this snapshot carries no tree
};

struct Channels {
  // recorder_bytes: the flight recorder's ring (0: no recorder).
  explicit Channels(std::size_t telemetry_records, std::size_t recorder_bytes = 0)
      : telemetry(telemetry_records),
        recorder(recorder_bytes > 0 ? std::make_unique<rt::ByteRing>(recorder_bytes) : nullptr) {}
  Channels(const Channels&) = delete;
  Channels& operator=(const Channels&) = delete;

  RequestRing requests;
  PoseRing poses;
  rt::TripleBuffer<BaseSample> base;
  rt::TripleBuffer<hal::ObstacleFrame> obstacles;
  rt::TripleBuffer<CommandSlot> command;
  rt::TripleBuffer<Status> status;
  TelemetryRing telemetry;
  std::unique_ptr<rt::ByteRing> recorder;  // the flight recorder's encoded cycles; null: off
  rt::LogRing control_log;
  rt::LogRing base_log;
  rt::LogRing perception_log;
  MapRing maps;
  MapRing retired_maps;
  std::atomic<std::uint64_t> maps_taken{0};
  rt::TripleBuffer<PlanSnapshot> plan;
  std::atomic<bool> plan_wanted{false};
  std::atomic<std::uint32_t> plan_tree_every{0};  // a tree in every n-th snapshot (0: never)
  std::atomic<std::uint64_t> heartbeat{0};
  std::atomic<bool> shutdown{false};
  // service -> control: the next cycle busy-waits this long (ms; 0: none), then clears it.
  std::atomic<std::uint32_t> debug_overrun_ms{0};
  // service -> perception: obstacle frames are read but not published (a depth stall).
  std::atomic<bool> debug_stall_obstacles{false};
};

}  // namespace staa::staad
