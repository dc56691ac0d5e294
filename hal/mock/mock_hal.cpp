#include "hal/mock/mock_hal.hpp"

#include "robot/unicycle.hpp"

#include <algorithm>
#include <cmath>

namespace staa::hal {
namespace {

// `current` moved towards `target` by at most `max_delta`; lands on the target exactly (a
// brake ends at v = 0, not at a rounding residue of 1e-17).
double approach(double current, double target, double max_delta) {
  if (std::abs(target - current) <= max_delta) return target;
  return current + (target > current ? max_delta : -max_delta);
}

}  // namespace

// ---- MockBase ----

MockBase::MockBase(const RobotProfile& robot, const Pose2& start, std::size_t max_commands)
    : robot_(robot), max_commands_(max_commands) {
  odometry_.pose = start;
  // A working base until the script says otherwise.
  status_.enabled = true;
  log_.reserve(max_commands_);
}

void MockBase::read(rt::Nanos now) {
  std::lock_guard lock(mutex_);
  const bool first = last_read_ < 0;
  const double dt = first || now <= last_read_ ? 0.0 : static_cast<double>(now - last_read_) * 1e-9;
  if (first || now > last_read_) last_read_ = now;
  if (integrate_ && dt > 0.0) {
    // A perfect unicycle: the command (clamped to the limits) is approached by at most
    // a_max*dt and b_max*dt, then driven along the arc at the new velocities. A disabled or
    // faulted base does not follow commands: its drives brake to a stop.
    const MotionLimits& lim = robot_.limits;
    const bool follows = status_.enabled && status_.fault == BaseFault::kNone && !last_command_.brake &&
                         std::isfinite(last_command_.v) && std::isfinite(last_command_.w);
    const double v_target = follows ? std::clamp(last_command_.v, lim.v_min, lim.v_max) : 0.0;
    const double w_target = follows ? std::clamp(last_command_.w, -lim.w_max, lim.w_max) : 0.0;
    odometry_.v = std::clamp(approach(odometry_.v, v_target, lim.a_max * dt), lim.v_min, lim.v_max);
    odometry_.w = std::clamp(approach(odometry_.w, w_target, lim.b_max * dt), -lim.w_max, lim.w_max);
    odometry_.pose = integrateArc(odometry_.pose, odometry_.v, odometry_.w, dt);
  }
  odometry_.stamp = last_read_;
  status_.stamp = last_read_;
}

void MockBase::write(rt::Nanos now, const VelocityCommand& command) {
  std::lock_guard lock(mutex_);
  last_command_ = command;
  if (send_delay_ >= 0) sent_ = {command.stamp, now + send_delay_};
  if (log_.size() < max_commands_) log_.push_back(command);  // reserved: no allocation
}

CommandSent MockBase::lastCommandSent() const {
  std::lock_guard lock(mutex_);
  return sent_;
}

void MockBase::setSendDelay(rt::Nanos delay) {
  std::lock_guard lock(mutex_);
  send_delay_ = delay;
}

Odometry MockBase::odometry() const {
  std::lock_guard lock(mutex_);
  return frozen_ ? reported_ : odometry_;
}

BaseStatus MockBase::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

bool MockBase::setPose(const Pose2& pose) {
  std::lock_guard lock(mutex_);
  // Re-anchoring the odometry: the velocities are the drives', they stay.
  odometry_.pose = pose;
  return true;
}

void MockBase::setIntegrate(bool on) {
  std::lock_guard lock(mutex_);
  integrate_ = on;
}

void MockBase::setOdometry(const Odometry& odometry) {
  std::lock_guard lock(mutex_);
  odometry_ = odometry;
}

void MockBase::freezeOdometry(bool frozen) {
  std::lock_guard lock(mutex_);
  // Frozen, the reports stop (odometry() keeps returning the last one, stamp and all) while
  // the "hardware" goes on moving; unfrozen, the reports show where it got to.
  if (frozen && !frozen_) reported_ = odometry_;
  frozen_ = frozen;
}

void MockBase::setFault(BaseFault fault, std::uint32_t code) {
  std::lock_guard lock(mutex_);
  status_.fault = fault;
  status_.fault_code = fault == BaseFault::kNone ? 0 : code;
}

void MockBase::setEnabled(bool enabled) {
  std::lock_guard lock(mutex_);
  status_.enabled = enabled;
}

std::vector<VelocityCommand> MockBase::commands() const {
  std::lock_guard lock(mutex_);
  return log_;
}

VelocityCommand MockBase::lastCommand() const {
  std::lock_guard lock(mutex_);
  return last_command_;
}

// ---- MockObstacles ----

bool MockObstacles::read(rt::Nanos now, ObstacleFrame& out) {
  std::lock_guard lock(mutex_);
  if (stalled_) return false;
  if (has_pending_) {
    out = pending_;
    has_pending_ = false;
    if (out.stamp < 0) out.stamp = now;
    // A scripted sequence number is kept (a test may repeat one); otherwise count on.
    if (out.sequence == 0) {
      out.sequence = ++sequence_;
    } else {
      sequence_ = std::max(sequence_, out.sequence);
    }
    return true;
  }
  // A camera that sees nothing: an empty frame every call.
  out.stamp = now;
  out.sequence = ++sequence_;
  out.count = 0;
  out.dropped = 0;
  return true;
}

void MockObstacles::push(const ObstacleFrame& frame) {
  std::lock_guard lock(mutex_);
  pending_ = frame;
  has_pending_ = true;
}

void MockObstacles::stall(bool stalled) {
  std::lock_guard lock(mutex_);
  stalled_ = stalled;
}

}  // namespace staa::hal
