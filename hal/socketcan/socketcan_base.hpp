#pragma once
// The HSR base over CAN (docs/ARCHITECTURE.md section 4): a hal::Base over a CanTransport that
// speaks a CanProfile (config/can/hsr_base.yaml).
//
// read(now) drains the pending frames, drops bad ones (counted by kind), tracks each ID's
// rolling counter, integrates the pose from the odometry's v, w and dt (anchored by
// setPose), and keeps the base's status and the fault. write(now, command) sends the command
// at command.rate_hz (at once when braking starts or motion stops) and the host heartbeat at
// heartbeat.rate_hz. Neither allocates, locks or blocks. lastCommandSent() says when the
// last command frame went to the kernel (the clock read as sendmsg returned) and which
// command it carried: the daemon's command-to-wire latency.
//
// Fault precedence (status().fault shows the first that holds; each clears with its cause):
//   kBusOff         bus-off error frame, or transport gone; until a valid frame arrives or
//                   the controller reports CAN_ERR_RESTARTED (a gone "unix:" transport
//                   reconnects once per bus.recovery_interval_s). Meanwhile the only frame
//                   sent is a stop command (brake, not enabled), once per recovery interval.
//   kHeartbeatLost  no valid base heartbeat for heartbeat.timeout_s, or no valid status for
//                   status.timeout_s (counted from the first read()/write() until the first frame).
//   kEmergencyStop  the status frame's emergency stop bit.
//   kDriverFault    the status frame's drive fault bit (fault_code = its code), or the base
//                   heartbeat's state = fault.
//   kWriteFailed    the last send failed (EAGAIN, ENOBUFS, ...); clears on the next success.
// Stale odometry is not a fault: the daemon judges it from odometry().stamp, which only
// valid odometry frames advance (the receive time, or `now` when the transport has none).

#include "hal/base.hpp"
#include "hal/socketcan/can_codec.hpp"
#include "hal/socketcan/can_profile.hpp"
#include "hal/socketcan/can_transport.hpp"

#include <array>
#include <cstdint>

namespace staa::hal {

struct SocketCanCounters {
  std::uint64_t frames_rx = 0;  // every record received, good or bad (error frames too)
  std::uint64_t frames_tx = 0;  // frames sent
  std::array<std::uint64_t, kCanFrameErrorCount> bad_by_kind{};  // indexed by CanFrameError
  std::uint64_t counter_gaps = 0;    // counter jumps ahead (frames lost on the bus): events
  std::uint64_t stale_frames = 0;    // repeated or reordered counters: dropped
  std::uint64_t error_frames = 0;    // CAN error frames
  std::uint64_t rx_overflows = 0;    // the kernel's receive-queue drops (SO_RXQ_OVFL)
  std::uint64_t bus_off_events = 0;  // entries into bus-off (error frame or transport gone)
  std::uint64_t recoveries = 0;      // exits from bus-off
  std::uint64_t write_failures = 0;  // failed sends
  std::uint64_t badFrames() const;   // sum of bad_by_kind
};

class SocketCanBase final : public Base {
 public:
  // `clock` stamps lastCommandSent() (the daemon's clock; nullptr: CLOCK_MONOTONIC). It
  // must outlive the driver.
  SocketCanBase(CanTransport transport, CanProfile profile, const Pose2& start = {},
                const rt::Clock* clock = nullptr);

  void read(rt::Nanos now) override;
  void write(rt::Nanos now, const VelocityCommand& command) override;
  Odometry odometry() const override { return odometry_; }
  BaseStatus status() const override;
  bool setPose(const Pose2& pose) override;
  CommandSent lastCommandSent() const override { return last_command_sent_; }

  const SocketCanCounters& counters() const { return counters_; }
  const CanProfile& profile() const { return profile_; }
  const CanTransport& transport() const { return transport_; }

 private:
  // One CAN ID the base sends: its counter, when it was last heard at all (a silence of
  // `timeout` restarts the counter: a rebooted base counts anew), and when it was last valid.
  struct RxChannel {
    CounterTracker counter;
    rt::Nanos timeout = 0;
    rt::Nanos last_seen = -1;
    rt::Nanos last_valid = -1;
  };

  void handleFrame(const CanRxFrame& rx, rt::Nanos now);
  void handleErrorFrame(const can_frame& frame);
  // Counts a bad frame of `kind`; returns false (the frame is not used).
  bool badFrame(CanFrameError kind);
  // A decoded frame on `channel` at `stamp`: the counter's verdict, and whether to use it.
  bool acceptCounter(RxChannel& channel, std::uint8_t counter, rt::Nanos stamp);
  void applyOdometry(const CanOdometry& odo, std::uint8_t lost_frames, rt::Nanos stamp);
  void enterBusOff();
  void leaveBusOff();
  void transportGone();
  void tryReconnect(rt::Nanos now);
  void updateTimeouts(rt::Nanos now);
  bool sendFrame(const can_frame& frame);
  BaseFault currentFault() const;

  CanTransport transport_;
  CanProfile profile_;
  const rt::Clock* clock_;  // nullptr: CLOCK_MONOTONIC
  // The profile's periods and timeouts in nanoseconds.
  rt::Nanos command_period_ = 0, heartbeat_period_ = 0, recovery_interval_ = 0;
  rt::Nanos odometry_timeout_ = 0, status_timeout_ = 0, heartbeat_timeout_ = 0;

  SocketCanCounters counters_;
  Odometry odometry_;

  // base -> host
  RxChannel odometry_rx_, status_rx_, heartbeat_rx_;
  rt::Nanos first_call_ = -1;  // the first read() or write(): timeouts count from here until the first frame
  CanStatus base_status_;
  CanBaseState base_state_ = CanBaseState::kOk;
  bool heartbeat_lost_ = false;
  bool bus_off_ = false;
  bool transport_gone_ = false;
  bool write_failed_ = false;
  rt::Nanos last_reconnect_ = -1;

  // host -> base
  std::uint8_t command_counter_ = 0, heartbeat_counter_ = 0;
  rt::Nanos last_command_tx_ = -1, last_heartbeat_tx_ = -1, last_probe_tx_ = -1;
  rt::Nanos next_command_tx_ = 0;  // the command grid's next slot
  rt::Nanos last_sent_stamp_ = -2;  // the stamp of the command last sent (-2: none yet)
  bool last_sent_brake_ = false;
  bool last_sent_motion_ = false;
  CommandSent last_command_sent_;  // the bus-off probe carries no command: not recorded
};

}  // namespace staa::hal
