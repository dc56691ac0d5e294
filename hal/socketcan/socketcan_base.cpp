#include "hal/socketcan/socketcan_base.hpp"

#include "hal/socketcan/socketcan.hpp"

#include "geometry/types.hpp"

#include <cmath>
#include <ctime>
#include <memory>
#include <utility>

namespace staa::hal {
namespace {

// Frames taken per read(): bounds the call when a peer floods; the rest waits for the next.
constexpr int kMaxFramesPerRead = 1024;

// CLOCK_MONOTONIC, for a driver built without a clock (hal/ does not link rt/'s clocks).
rt::Nanos monotonicNow() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<rt::Nanos>(ts.tv_sec) * rt::kNanosPerSecond + ts.tv_nsec;
}

rt::Nanos toNanos(double seconds) { return static_cast<rt::Nanos>(std::llround(seconds * 1e9)); }

std::size_t index(CanFrameError kind) { return static_cast<std::size_t>(kind); }

// Moves `from` along the arc of speed v, turn rate w for dt seconds (exact for constant v, w):
// the chord of an arc turning by phi has length v*dt*sin(phi/2)/(phi/2), along the mean heading.
Pose2 advanceArc(const Pose2& from, double v, double w, double dt) {
  const double half = 0.5 * w * dt;
  const double sinc = std::abs(half) < 1e-6 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
  const double chord = v * dt * sinc;
  const double heading = from.theta + half;
  return {from.x + chord * std::cos(heading), from.y + chord * std::sin(heading), wrapAngle(from.theta + w * dt)};
}

// Whether an encoded command moves the base: its raw v or w (bytes 0-3) is not 0.
bool commandMoves(const can_frame& frame) {
  return (frame.data[0] | frame.data[1] | frame.data[2] | frame.data[3]) != 0;
}

}  // namespace

std::uint64_t SocketCanCounters::badFrames() const {
  std::uint64_t sum = 0;
  for (std::uint64_t n : bad_by_kind) sum += n;
  return sum;
}

SocketCanBase::SocketCanBase(CanTransport transport, CanProfile profile, const Pose2& start, const rt::Clock* clock)
    : transport_(std::move(transport)), profile_(std::move(profile)), clock_(clock) {
  command_period_ = toNanos(1.0 / profile_.command.rate_hz);
  heartbeat_period_ = toNanos(1.0 / profile_.heartbeat.rate_hz);
  recovery_interval_ = toNanos(profile_.bus.recovery_interval_s);
  odometry_timeout_ = toNanos(profile_.odometry.timeout_s);
  status_timeout_ = toNanos(profile_.status.timeout_s);
  heartbeat_timeout_ = toNanos(profile_.heartbeat.timeout_s);
  odometry_rx_.timeout = odometry_timeout_;
  status_rx_.timeout = status_timeout_;
  heartbeat_rx_.timeout = heartbeat_timeout_;
  odometry_.pose = start;
}

// ---- read ----

void SocketCanBase::read(rt::Nanos now) {
  if (first_call_ < 0) first_call_ = now;
  if (transport_gone_) tryReconnect(now);
  for (int k = 0; k < kMaxFramesPerRead && !transport_gone_; ++k) {
    CanRxFrame rx;
    const CanIo io = transport_.receive(rx);
    if (io == CanIo::kWouldBlock || io == CanIo::kFailed) break;  // kFailed (ENETDOWN...): nothing to read now
    if (io == CanIo::kGone) {
      transportGone();
      break;
    }
    ++counters_.frames_rx;
    if (io == CanIo::kBadRecord) {
      badFrame(CanFrameError::kWrongSize);
      continue;
    }
    handleFrame(rx, now);
  }
  counters_.rx_overflows = transport_.rxOverflows();
  updateTimeouts(now);
}

void SocketCanBase::handleFrame(const CanRxFrame& rx, rt::Nanos now) {
  const can_frame& f = rx.frame;
  if (isErrorFrame(f)) {
    handleErrorFrame(f);
    return;
  }
  const rt::Nanos stamp = rx.stamp >= 0 ? rx.stamp : now;
  if (f.can_id == profile_.odometry.id) {
    const CanDecoded<CanOdometry> d = decodeOdometry(profile_, f);
    if (!d.ok()) {
      badFrame(d.error);
      return;
    }
    if (!acceptCounter(odometry_rx_, d.value.counter, stamp)) return;
    applyOdometry(d.value, odometry_rx_.counter.lastGap(), stamp);
  } else if (f.can_id == profile_.status.id) {
    const CanDecoded<CanStatus> d = decodeStatus(profile_, f);
    if (!d.ok()) {
      badFrame(d.error);
      return;
    }
    if (!acceptCounter(status_rx_, d.value.counter, stamp)) return;
    base_status_ = d.value;
  } else if (f.can_id == profile_.heartbeat.base_id) {
    const CanDecoded<CanBaseHeartbeat> d = decodeBaseHeartbeat(profile_, f);
    if (!d.ok()) {
      badFrame(d.error);
      return;
    }
    if (!acceptCounter(heartbeat_rx_, d.value.counter, stamp)) return;
    base_state_ = d.value.state;
  } else {
    // Not a frame the base sends (the kernel filters these on a CAN socket; a seqpacket
    // peer can send anything).
    badFrame(CanFrameError::kWrongId);
  }
}

void SocketCanBase::handleErrorFrame(const can_frame& frame) {
  ++counters_.error_frames;
  const CanErrorFrame e = classifyErrorFrame(frame);
  if (e.bus_off) {
    enterBusOff();
  } else if (e.restarted) {
    leaveBusOff();
  }
  // Controller problems and missing ACKs are counted only: the timeouts catch a base that
  // is really gone.
}

bool SocketCanBase::badFrame(CanFrameError kind) {
  ++counters_.bad_by_kind[index(kind)];
  return false;
}

bool SocketCanBase::acceptCounter(RxChannel& channel, std::uint8_t counter, rt::Nanos stamp) {
  // A well-formed frame: the bus works again.
  leaveBusOff();
  if (channel.last_seen >= 0 && stamp - channel.last_seen > channel.timeout) channel.counter.reset();
  channel.last_seen = stamp;
  switch (channel.counter.check(counter)) {
    case CanCounterVerdict::kStale:
      ++counters_.stale_frames;
      return false;
    case CanCounterVerdict::kGap:
      ++counters_.counter_gaps;
      break;
    case CanCounterVerdict::kFirst:
    case CanCounterVerdict::kInSequence:
      break;
  }
  channel.last_valid = stamp;
  return true;
}

void SocketCanBase::applyOdometry(const CanOdometry& odo, std::uint8_t lost_frames, rt::Nanos stamp) {
  // dt is the base's own step since its previous odometry frame. Frames lost on the bus took
  // their steps with them: assume each lost one was as long as this one at these velocities,
  // up to the odometry timeout (beyond that the daemon has braked on staleness anyway).
  double dt = odo.dt_us * 1e-6 * (1.0 + lost_frames);
  if (lost_frames > 0 && dt > profile_.odometry.timeout_s) dt = profile_.odometry.timeout_s;
  odometry_.pose = advanceArc(odometry_.pose, odo.v, odo.w, dt);
  odometry_.v = odo.v;
  odometry_.w = odo.w;
  odometry_.stamp = stamp;
}

void SocketCanBase::enterBusOff() {
  if (bus_off_) return;
  bus_off_ = true;
  ++counters_.bus_off_events;
  last_probe_tx_ = -1;  // the first probe goes out at the next write()
}

void SocketCanBase::leaveBusOff() {
  if (!bus_off_ || transport_gone_) return;
  bus_off_ = false;
  ++counters_.recoveries;
}

void SocketCanBase::transportGone() {
  transport_gone_ = true;
  enterBusOff();
}

void SocketCanBase::tryReconnect(rt::Nanos now) {
  if (!transport_.canReconnect()) return;
  if (last_reconnect_ >= 0 && now - last_reconnect_ < recovery_interval_) return;
  last_reconnect_ = now;
  // Connected again, the bus counts as off until the base's first valid frame.
  if (transport_.reconnect()) transport_gone_ = false;
}

void SocketCanBase::updateTimeouts(rt::Nanos now) {
  // Before the first frame of a kind, its timeout counts from the first read() or write().
  const rt::Nanos heartbeat_ref = heartbeat_rx_.last_valid >= 0 ? heartbeat_rx_.last_valid : first_call_;
  const rt::Nanos status_ref = status_rx_.last_valid >= 0 ? status_rx_.last_valid : first_call_;
  heartbeat_lost_ = now - heartbeat_ref > heartbeat_timeout_ || now - status_ref > status_timeout_;
}

BaseFault SocketCanBase::currentFault() const {
  if (bus_off_ || transport_gone_) return BaseFault::kBusOff;
  if (heartbeat_lost_) return BaseFault::kHeartbeatLost;
  if (base_status_.estop) return BaseFault::kEmergencyStop;
  if (base_status_.drive_fault || base_state_ == CanBaseState::kFault) return BaseFault::kDriverFault;
  if (write_failed_) return BaseFault::kWriteFailed;
  return BaseFault::kNone;
}

BaseStatus SocketCanBase::status() const {
  BaseStatus s;
  s.stamp = status_rx_.last_valid;
  s.fault = currentFault();
  // What the base last said, while it is heard.
  s.enabled = status_rx_.last_valid >= 0 && base_status_.enabled && !heartbeat_lost_ && s.fault != BaseFault::kBusOff;
  s.fault_code = s.fault == BaseFault::kDriverFault ? base_status_.fault_code : 0;
  s.bad_frames = counters_.badFrames();
  s.rx_overflows = counters_.rx_overflows;
  s.error_frames = counters_.error_frames;
  return s;
}

bool SocketCanBase::setPose(const Pose2& pose) {
  // Re-anchors the odometry; the velocities are the base's.
  odometry_.pose = pose;
  return true;
}

// ---- write ----

void SocketCanBase::write(rt::Nanos now, const VelocityCommand& command) {
  if (first_call_ < 0) first_call_ = now;
  if (transport_gone_) return;  // nothing to send on until read() reconnects
  if (bus_off_) {
    // Only a stop command, once per recovery interval: it probes the bus without flooding a
    // controller that is trying to recover.
    if (last_probe_tx_ < 0 || now - last_probe_tx_ >= recovery_interval_) {
      last_probe_tx_ = now;
      if (sendFrame(encodeCommand(profile_, 0.0, 0.0, false, true, command_counter_))) ++command_counter_;
    }
    return;
  }

  const BaseFault fault = currentFault();
  // A failed send is ours, not the base's: the next frame that gets through keeps it enabled.
  const bool enable = fault == BaseFault::kNone || fault == BaseFault::kWriteFailed;
  const bool brake = command.brake || !std::isfinite(command.v) || !std::isfinite(command.w);
  const can_frame frame =
      encodeCommand(profile_, brake ? 0.0 : command.v, brake ? 0.0 : command.w, enable, brake, command_counter_);
  const bool moves = commandMoves(frame);
  // At once: a brake that starts, or motion that stops; otherwise at the command rate.
  const bool urgent = (brake && !last_sent_brake_) || (!moves && last_sent_motion_);
  // A new command (a new stamp from the control thread) goes out at once, at most one per
  // 3/4 of a command period: waiting for a send slot of our own added up to a period to every
  // command (measured: command-to-wire p50 45 ms, and commands replaced before they were
  // sent). The same command is repeated on a grid of command periods (not "a period since the
  // last send": the base I/O thread writes every 10 ms, and that would give 25 Hz, not 30).
  const bool fresh = command.stamp != last_sent_stamp_ &&
                     (last_command_tx_ < 0 || now - last_command_tx_ >= command_period_ * 3 / 4);
  if (urgent || fresh || last_command_tx_ < 0 || now >= next_command_tx_) {
    if (sendFrame(frame)) {
      // sendmsg has returned: the frame is the kernel's (on a CAN socket, in its queue).
      last_command_sent_ = {command.stamp, clock_ != nullptr ? clock_->now() : monotonicNow()};
      ++command_counter_;
      last_command_tx_ = now;
      next_command_tx_ += command_period_;
      if (next_command_tx_ <= now || urgent || fresh) next_command_tx_ = now + command_period_;
      last_sent_stamp_ = command.stamp;
      last_sent_brake_ = brake;
      last_sent_motion_ = moves;
    }
  }

  if (last_heartbeat_tx_ < 0 || now - last_heartbeat_tx_ >= heartbeat_period_) {
    const CanHostState state = !enable ? CanHostState::kFault : (last_sent_motion_ ? CanHostState::kDriving : CanHostState::kIdle);
    if (sendFrame(encodeHostHeartbeat(profile_, state, heartbeat_counter_))) {
      ++heartbeat_counter_;
      last_heartbeat_tx_ = now;
    }
  }
}

bool SocketCanBase::sendFrame(const can_frame& frame) {
  const CanIo io = transport_.send(frame);
  if (io == CanIo::kOk) {
    ++counters_.frames_tx;
    write_failed_ = false;
    return true;
  }
  if (io == CanIo::kGone) {
    transportGone();
    return false;
  }
  ++counters_.write_failures;
  write_failed_ = true;
  return false;
}

std::unique_ptr<Base> openSocketCanBase(const std::string& interface, const CanProfile& profile,
                                        const Pose2& start, const rt::Clock* clock) {
  return std::make_unique<SocketCanBase>(openCanTransport(interface, profile), profile, start, clock);
}

}  // namespace staa::hal
