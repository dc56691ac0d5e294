#pragma once
// What staad's base I/O and perception threads do in one period, as runnables
// (rt/activity.hpp: the daemon's periodic activities step them; tests step them in lockstep
// with the control task).
//
// BaseTask (base_hz): pose corrections forwarded by the control thread; base.read(now);
// odometry + status published; the command chosen: the control thread's latest while it is
// fresh (younger than 2 control periods), else its plan's next action (younger than 3
// periods), else a brake; base.write(now, command). A command is stamped with its cycle's
// wake-up and published when the cycle ends (up to a period later): while the control thread
// keeps its deadlines, every command is replaced before it is 2 periods old.
//
// Command-to-wire latency: from a control command's stamp (its cycle's wake-up) to the moment
// the base driver handed the first frame carrying it to the kernel (hal::Base::lastCommandSent),
// one sample per command, into a histogram the service thread reads. Its own brakes (no fresh
// command) are the base thread's, not the control thread's: not measured. A control command
// replaced before any frame carried it is counted as unsent. Its thread's timing is the
// activity's (rt::PeriodicActivity::timing()). When the activity stops, the base gets a brake.
//
// PerceptionTask (perception_hz): a new obstacle frame from the sensor is published (not
// while a test stalls it: Channels::debug_stall_obstacles, the frame is read and dropped).
//
// NoObstacles: the sensor of `obstacles: none`, an empty frame every period (no moving
// obstacles are seen: the robot avoids the map's obstacles only).
//
// No allocation, no lock, no I/O beyond the HAL's own non-blocking calls.

#include "app/staad/channels.hpp"
#include "hal/base.hpp"
#include "hal/obstacles.hpp"
#include "rt/activity.hpp"
#include "rt/timing_stats.hpp"

#include <atomic>
#include <cstdint>

namespace staa::staad {

enum class CommandSource : std::uint8_t {
  kControl,   // the control thread's latest command
  kPlanNext,  // the control thread missed a cycle: its plan's next action
  kBrake,     // it missed more (or never sent one): brake
};
const char* toString(CommandSource source);

class BaseTask final : public rt::Runnable {
 public:
  BaseTask(hal::Base& base, Channels& channels, rt::Nanos control_period);
  BaseTask(const BaseTask&) = delete;
  BaseTask& operator=(const BaseTask&) = delete;

  void step(rt::Nanos now) override;
  // The base thread's last words: a brake (the daemon is stopping).
  void stop(rt::Nanos now) override { brake(now); }
  void brake(rt::Nanos now);

  CommandSource source() const { return source_; }
  const hal::VelocityCommand& lastCommand() const { return last_; }
  std::uint64_t fallbacks() const { return fallbacks_; }  // periods on the plan's next action
  std::uint64_t brakes() const { return brakes_; }        // periods braked for lack of commands
  std::uint64_t posesRefused() const { return poses_refused_; }

  // Any thread: the command-to-wire histogram (relaxed atomics) and the control commands
  // never sent.
  const rt::LatencyHistogram& commandToWire() const { return wire_; }
  std::uint64_t commandsUnsent() const { return unsent_.load(std::memory_order_relaxed); }

 private:
  // A control command stamp read from the slot: a newer one retires the previous, counted
  // as unsent when no frame carried it.
  void trackCommand(rt::Nanos stamp);
  // After write() of the control thread's command (or its plan's next action) stamped
  // `stamp`: the first frame that carried it is measured.
  void recordWire(rt::Nanos stamp);

  void log(rt::Nanos now, rt::LogLevel level, const char* message, double a = 0.0, double b = 0.0, double c = 0.0,
           std::uint8_t count = 0);

  hal::Base& base_;
  Channels& ch_;
  rt::Nanos fresh_limit_;     // 2 control periods
  rt::Nanos fallback_limit_;  // 3 control periods
  CommandSource source_ = CommandSource::kBrake;
  hal::VelocityCommand last_;
  bool commanded_ = false;  // a control command has been received at all
  std::uint64_t fallbacks_ = 0;
  std::uint64_t brakes_ = 0;
  std::uint64_t poses_refused_ = 0;
  rt::LatencyHistogram wire_;  // command-to-wire, 1 us bins up to 100 ms (beyond: overflow, exact max)
  rt::Nanos seen_stamp_ = -1;  // the newest control command stamp read
  rt::Nanos wire_stamp_ = -1;  // the newest one measured on the wire
  std::atomic<std::uint64_t> unsent_{0};
};

class PerceptionTask final : public rt::Runnable {
 public:
  PerceptionTask(hal::ObstacleSensor& sensor, Channels& channels);
  // Publishes the sensor's new frame, if it has one.
  void step(rt::Nanos now) override;
  std::uint64_t frames() const { return frames_; }  // frames published

 private:
  hal::ObstacleSensor& sensor_;
  Channels& ch_;
  std::uint64_t frames_ = 0;
  std::uint64_t dropped_seen_ = 0;
  bool stalled_ = false;
};

class NoObstacles final : public hal::ObstacleSensor {
 public:
  bool read(rt::Nanos now, hal::ObstacleFrame& out) override;

 private:
  std::uint64_t sequence_ = 0;
};

}  // namespace staa::staad
