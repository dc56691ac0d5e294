#pragma once
// What staad's control thread does in one cycle, as a runnable (rt/activity.hpp: *what*
// runs is separate from *when*): the daemon's 30 Hz periodic activity steps it, the tests
// step it in lockstep on a manual time line.
//
// step(now), top to bottom:
//   0. a new map (from ROS) swapped in: the cycle built on it replaces the current one;
//   1. requests from the service thread: goal, stop, pose (forwarded to the base thread);
//      a forced overrun and debug.extra_cycle_us (debug.faults, tests) busy-wait here;
//   2. the latest odometry + base status, and the latest obstacle frame;
//   3. the inputs judged: a base fault, stale odometry, stale obstacles -> brake and report
//      (a base fault first: it explains the silence that follows it, e.g. bus-off);
//      each clears by itself when the input is fresh again;
//   4. ControlCycle::step with the planner budget (wall clock or expansions);
//   5. the command (and the plan's next action, the base thread's fallback) published;
//   6. the status published;
//   6b. with plan_wanted, the plan's snapshot for RViz;
//   7. a telemetry record (always: the service thread writes the CSV file and/or keeps the
//      poses for the run's SVG picture), and log records on state changes and faults;
//   8. with the flight recorder (Channels::recorder), the cycle encoded into its ring: what
//      the cycle saw, carried and put out (record/recorder.hpp).
// No allocation, no lock, no I/O: everything is sized by the constructor.
//
// On the monotonic clock the cycle reads its clock through the thread's stall probe
// (rt/stall_probe.hpp): the planner's budget at every pop, the busy-waits every turn. The
// largest gap between two reads is time the thread did not run (lastStall()).

#include "app/staad/channels.hpp"
#include "app/staad/config.hpp"
#include "control/control_cycle.hpp"
#include "local/dynamic_obstacles.hpp"
#include "planner/budget.hpp"
#include "record/recorder.hpp"
#include "rt/activity.hpp"
#include "rt/clock.hpp"
#include "rt/periodic.hpp"
#include "rt/stall_probe.hpp"

#include <array>
#include <cstdint>

namespace staa::staad {

class ControlTask final : public rt::Runnable {
 public:
  // `clock` is the daemon's: a forced overrun busy-waits on it (through the stall probe when
  // it is the monotonic clock), and a wall-clock budget
  // (config budget.ms) is read from it (its nowFunction(): a test's manual clock has none,
  // so with it the budget must be budget.expansions, else std::invalid_argument). With
  // budget.expansions the run is reproducible and the planner reads no clock.
  ControlTask(const DaemonConfig& config, Channels& channels, rt::Clock& clock);
  ControlTask(const ControlTask&) = delete;
  ControlTask& operator=(const ControlTask&) = delete;

  // The periodic loop that steps this task (same thread): each telemetry record learns
  // whether its cycle overran. Optional (lockstep tests step without one).
  void start(const rt::PeriodicLoop& loop) override { loop_ = &loop; }
  // One control cycle at time `now` (the time this cycle woke).
  void step(rt::Nanos now) override;
  // The last cycle's telemetry record (each cycle pushes its predecessor's).
  void stop(rt::Nanos) override { flushTelemetry(); }
  // The largest gap between two clock reads of the last cycle (0 off the monotonic clock).
  rt::Nanos lastStall() const override { return last_stall_; }

  // Pushes the last cycle's telemetry record.
  void flushTelemetry();

  // What the last cycle decided (control thread, or the test driving it).
  DaemonState state() const { return state_; }
  FaultKind fault() const { return fault_; }
  const CommandSlot& lastCommand() const { return last_command_; }
  const Status& lastStatus() const { return last_status_; }
  const CycleOutput& lastOutput() const { return last_output_; }
  std::uint64_t cycles() const { return cycles_; }
  rt::Nanos period() const { return period_; }
  ControlCycle& controlCycle() { return *cycle_; }
  // The map the cycle plans on: 0 the config's, else the MapBundle's sequence.
  std::uint64_t mapSequence() const { return map_ != nullptr ? map_->sequence : 0; }
  // The bundle swapped in last, handed back to be freed, the config's own cycle restored.
  // Only once the control thread has stopped stepping this task.
  std::unique_ptr<MapBundle> releaseMap();
  // The moving obstacles the last cycle planned against (the latest obstacle frame's).
  const DynamicObstacleSet& obstacles() const { return obstacles_; }

 private:
  void takeMap(rt::Nanos now);
  void publishPlan(rt::Nanos now, const CycleOutput& out);
  void takeRequests(rt::Nanos now);
  void forcedOverrun(rt::Nanos now);
  void busyWait(rt::Nanos duration);
  rt::Nanos readClock() const;
  void takeInputs();
  FaultKind judgeInputs(rt::Nanos now) const;
  void setState(rt::Nanos now, DaemonState state, FaultKind fault);
  void publishCommand(rt::Nanos now, const CycleOutput* out);
  void publishStatus(rt::Nanos now);
  void log(rt::Nanos now, rt::LogLevel level, const char* message, double a = 0.0, double b = 0.0, double c = 0.0,
           std::uint8_t count = 0);

  // The flight recorder's sink: a push into Channels::recorder (a full ring drops the cycle
  // and counts it; never a wait).
  class RingSink final : public record::CycleSink {
   public:
    explicit RingSink(rt::ByteRing& ring) : ring_(ring) {}
    void take(std::span<const std::byte> record) override { ring_.push(record); }

   private:
    rt::ByteRing& ring_;
  };

  Channels& ch_;
  rt::Clock& clock_;
  rt::Nanos period_;
  rt::Nanos odometry_timeout_;
  rt::Nanos obstacles_timeout_;
  bool probed_;                // the clock is read through the thread's stall probe
  rt::Nanos last_stall_ = 0;
  rt::Nanos extra_cycle_;      // debug.extra_cycle_us: busy-waited every cycle
  PlannerBudget budget_;
  BudgetSpec budget_spec_;
  ClockFn budget_clock_;       // a wall-clock budget's clock (the recorder taps it)
  double budget_ms_;           // the wall-clock budget, 0 with an expansion budget
  rt::Nanos path_max_ = 0;     // the longest path and local-map steps so far
  rt::Nanos local_max_ = 0;
  MotionLimits limits_;

  ControlCycle own_cycle_;      // on the config's map
  ControlCycle* cycle_;         // own_cycle_ or map_->cycle
  MapBundle* map_ = nullptr;    // the ROS map swapped in last (owned by the service side)
  DynamicObstacleSet obstacles_;
  std::array<PolygonView, hal::ObstacleFrame::kMaxObstacles> views_{};
  std::array<Vec2, hal::ObstacleFrame::kMaxObstacles> velocities_{};
  std::array<double, hal::ObstacleFrame::kMaxObstacles> turn_rates_{};
  std::size_t frame_n_ = 0;    // obstacles of the frame taken last (views_ .. turn_rates_)
  std::unique_ptr<RingSink> recorder_sink_;
  std::unique_ptr<record::CycleRecorder> recorder_;

  // Inputs as last taken.
  BaseSample base_;
  rt::Nanos obstacles_stamp_ = -1;

  // What the robot is doing.
  DaemonState state_ = DaemonState::kIdle;
  FaultKind fault_ = FaultKind::kNone;
  bool has_goal_ = false;
  Pose2 goal_;
  std::uint64_t goal_id_ = 0;  // the goal pursued or last pursued (the service's numbering)
  bool stopped_ = false;   // a stop request (or the daemon stopping) holds the robot
  bool shutdown_ = false;  // the daemon is stopping: requests are ignored
  CycleOutput last_output_;
  CommandSlot last_command_;
  Status last_status_;
  std::uint64_t cycles_ = 0;
  std::uint64_t capped_cycles_ = 0;  // cycles whose command the blind-corner limit lowered

  // Telemetry: the record of the last cycle waits one cycle so that its overrun flag (known
  // only after the periodic loop's finish()) is filled in.
  const rt::PeriodicLoop* loop_ = nullptr;
  TelemetryRecord pending_;
  bool has_pending_ = false;
  std::uint64_t overruns_seen_ = 0;
};

// The control cycle's configuration staad runs with (the ROS bridge builds new maps' cycles
// with it).
ControlConfig controlConfigFor(const DaemonConfig& config);

// The command that stops the robot: v = w = 0 with the base's full deceleration.
hal::VelocityCommand brakeCommand(rt::Nanos stamp);

}  // namespace staa::staad
