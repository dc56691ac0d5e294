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
//   each RT thread --*_log-->  service                              (SPSC rings)
//
// heartbeat counts control cycles (the watchdog pings only while it advances); shutdown
// tells the control thread to brake and hold (the daemon is stopping). The debug_* atomics
// carry the test-only fault injections (debug.faults) from the service thread.

#include "app/staad/status.hpp"
#include "app/staad/telemetry.hpp"
#include "hal/base.hpp"
#include "hal/obstacles.hpp"
#include "rt/log_ring.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/triple_buffer.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>

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

struct Channels {
  explicit Channels(std::size_t telemetry_records) : telemetry(telemetry_records) {}
  Channels(const Channels&) = delete;
  Channels& operator=(const Channels&) = delete;

  RequestRing requests;
  PoseRing poses;
  rt::TripleBuffer<BaseSample> base;
  rt::TripleBuffer<hal::ObstacleFrame> obstacles;
  rt::TripleBuffer<CommandSlot> command;
  rt::TripleBuffer<Status> status;
  TelemetryRing telemetry;
  rt::LogRing control_log;
  rt::LogRing base_log;
  rt::LogRing perception_log;
  std::atomic<std::uint64_t> heartbeat{0};
  std::atomic<bool> shutdown{false};
  // service -> control: the next cycle busy-waits this long (ms; 0: none), then clears it.
  std::atomic<std::uint32_t> debug_overrun_ms{0};
  // service -> perception: obstacle frames are read but not published (a depth stall).
  std::atomic<bool> debug_stall_obstacles{false};
};

}  // namespace staa::staad
