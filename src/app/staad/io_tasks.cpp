#include "app/staad/io_tasks.hpp"

#include "app/staad/control_task.hpp"

namespace staa::staad {

const char* toString(CommandSource source) {
  switch (source) {
    case CommandSource::kControl: return "control";
    case CommandSource::kPlanNext: return "plan-next";
    case CommandSource::kBrake: return "brake";
  }
  return "unknown";
}

BaseTask::BaseTask(hal::Base& base, Channels& channels, rt::Nanos control_period)
    : base_(base), ch_(channels), fresh_limit_(control_period * 2), fallback_limit_(control_period * 3) {
  last_ = brakeCommand(-1);
}

void BaseTask::log(rt::Nanos now, rt::LogLevel level, const char* message, double a, double b, double c,
                   std::uint8_t count) {
  rt::pushLog(ch_.base_log, now, level, message, a, b, c, count);  // a full ring drops (and counts) it
}

namespace {

// One writer: a relaxed store is enough (readers need each value untorn, not ordered).
void put(std::atomic<std::uint64_t>& a, std::uint64_t value) { a.store(value, std::memory_order_relaxed); }
std::uint64_t get(const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); }

}  // namespace

void BaseTask::trackCommand(rt::Nanos stamp) {
  if (stamp <= seen_stamp_) return;
  if (seen_stamp_ >= 0 && seen_stamp_ > wire_stamp_) put(unsent_, get(unsent_) + 1);
  seen_stamp_ = stamp;
}

void BaseTask::recordWire(rt::Nanos stamp) {
  const hal::CommandSent sent = base_.lastCommandSent();
  // Only a frame sent by this write() carries this command; a stamp already measured went out
  // before (the driver repeats the latest command at its rate).
  if (stamp < 0 || sent.command_stamp != stamp || stamp <= wire_stamp_ || sent.sent_at < 0) return;
  wire_.record(sent.sent_at - stamp);
  wire_stamp_ = stamp;
}

void BaseTask::step(rt::Nanos now) {
  // Pose corrections first, so that this period's odometry already reflects them.
  Pose2 pose;
  while (ch_.poses.pop(pose)) {
    if (base_.setPose(pose)) {
      log(now, rt::LogLevel::kInfo, "pose set (x, y, theta)", pose.x, pose.y, pose.theta, 3);
    } else {
      ++poses_refused_;
      log(now, rt::LogLevel::kWarning, "pose refused by the base (x, y, theta)", pose.x, pose.y, pose.theta, 3);
    }
  }

  base_.read(now);
  BaseSample& sample = ch_.base.writeBuffer();
  sample.odometry = base_.odometry();
  sample.status = base_.status();
  ch_.base.publish();

  ch_.command.update();
  const CommandSlot& slot = ch_.command.readBuffer();
  const rt::Nanos stamp = slot.command.stamp;
  trackCommand(stamp);
  CommandSource source = CommandSource::kBrake;
  hal::VelocityCommand command = brakeCommand(now);
  if (stamp >= 0 && now - stamp < fresh_limit_) {
    source = CommandSource::kControl;
    command = slot.command;
  } else if (stamp >= 0 && now - stamp < fallback_limit_) {
    source = CommandSource::kPlanNext;
    command = slot.next;
    ++fallbacks_;
  } else if (commanded_) {
    ++brakes_;
  }
  // Transitions are logged once the control thread has spoken at all (not the start-up brake).
  if (source != source_ && commanded_) {
    const double age_ms = stamp >= 0 ? static_cast<double>(now - stamp) * 1e-6 : -1.0;
    switch (source) {
      case CommandSource::kControl: log(now, rt::LogLevel::kInfo, "command: the control thread's again"); break;
      case CommandSource::kPlanNext:
        log(now, rt::LogLevel::kWarning, "command: control missed a cycle, on its plan's next action (age ms)", age_ms,
            0.0, 0.0, 1);
        break;
      case CommandSource::kBrake:
        log(now, rt::LogLevel::kError, "command: no fresh command from the control thread, braking (age ms)", age_ms,
            0.0, 0.0, 1);
        break;
    }
  }
  if (stamp >= 0) commanded_ = true;
  source_ = source;
  last_ = command;
  base_.write(now, command);
  if (source != CommandSource::kBrake) recordWire(command.stamp);
}

void BaseTask::brake(rt::Nanos now) {
  last_ = brakeCommand(now);
  source_ = CommandSource::kBrake;
  base_.write(now, last_);
}

PerceptionTask::PerceptionTask(hal::ObstacleSensor& sensor, Channels& channels) : sensor_(sensor), ch_(channels) {}

void PerceptionTask::step(rt::Nanos now) {
  hal::ObstacleFrame& frame = ch_.obstacles.writeBuffer();
  if (!sensor_.read(now, frame)) return;
  // A test's depth stall: the sensor runs on (the simulated world keeps moving), nothing
  // reaches the control thread.
  const bool stall = ch_.debug_stall_obstacles.load(std::memory_order_acquire);
  if (stall != stalled_) {
    rt::pushLog(ch_.perception_log, now, rt::LogLevel::kWarning,
                stall ? "debug: obstacle frames stalled" : "debug: obstacle frames resumed");
    stalled_ = stall;
  }
  if (stall) return;
  if (frame.dropped > dropped_seen_) {
    rt::LogRecord r;
    r.time = now;
    r.level = rt::LogLevel::kWarning;
    r.message = "obstacle frame: obstacles beyond capacity dropped (count)";
    r.values[0] = static_cast<double>(frame.dropped);
    r.value_count = 1;
    ch_.perception_log.push(r);
  }
  dropped_seen_ = frame.dropped;
  ch_.obstacles.publish();
  ++frames_;
}

bool NoObstacles::read(rt::Nanos now, hal::ObstacleFrame& out) {
  out.stamp = now;
  out.sequence = ++sequence_;
  out.count = 0;
  out.dropped = 0;
  return true;
}

}  // namespace staa::staad
