#pragma once
// The robot base as the control code sees it (docs/ARCHITECTURE.md section 4), shaped like
// ros2_control's hardware interface: the base I/O thread calls read(now) to take in what the
// hardware sent (odometry, velocities, status, faults) and write(now, command) to send the
// latest velocity command. An implementation is used by that one thread only; the daemon
// passes odometry and commands to the other threads through triple buffers.
//
// Implementations: the simulated base (src/world/sim_hal.hpp), hal/mock (scripted, for
// tests), hal/socketcan (a base driver over a CAN transport opened by file descriptor),
// hal/ros (a base commanded over a ROS transport: the HSR-B).
// read() and write() never allocate, lock or block beyond a non-blocking poll of their
// transport.

#include "geometry/types.hpp"
#include "rt/clock.hpp"

#include <cstdint>

namespace staa::hal {

enum class BaseFault : std::uint8_t {
  kNone,
  kEmergencyStop,   // the base's emergency stop is pressed
  kHeartbeatLost,   // the base stopped sending heartbeats
  kBusOff,          // the bus is gone (CAN bus-off, transport closed)
  kWriteFailed,     // the command could not be sent
  kDriverFault,     // the base reports a drive fault (fault_code says which)
  kOdometryInvalid,    // the newest odometry had a NaN or infinite value (hal/ros)
  kOdometryStampBack,  // the newest odometry's stamp went back in time (hal/ros)
};
const char* toString(BaseFault fault);

// Odometry: the base's pose estimate in the map frame (the sim's ground truth, or odometry
// corrected by localization) and the measured velocities.
struct Odometry {
  rt::Nanos stamp = -1;  // when it was measured; < 0: never
  Pose2 pose;
  double v = 0.0;  // m/s
  double w = 0.0;  // rad/s
};

struct BaseStatus {
  rt::Nanos stamp = -1;
  bool enabled = false;
  BaseFault fault = BaseFault::kNone;
  std::uint32_t fault_code = 0;  // the base's own code, 0 when none
  // Link health totals since start (hal/socketcan; 0 for backends without a bus).
  std::uint64_t bad_frames = 0;    // frames dropped as malformed (ID, DLC, checksum, range, ...)
  std::uint64_t rx_overflows = 0;  // frames the kernel dropped on a full receive queue
  std::uint64_t error_frames = 0;  // CAN error frames received
  // Localization fixes applied to the odometry (hal/ros; 0 for backends without one), and the
  // last one's jump: how far it moved the pose staad plans with.
  std::uint64_t localization_fixes = 0;
  std::uint64_t localization_dropped = 0;  // fixes refused: NaN, or older than the odometry kept
  double last_jump_m = 0.0;
  double last_jump_rad = 0.0;
};

struct VelocityCommand {
  rt::Nanos stamp = -1;  // when the control thread produced it
  double v = 0.0;
  double w = 0.0;
  bool brake = false;    // a stop command: v = w = 0 with the base's full deceleration
  rt::Nanos odometry_stamp = -1;  // the odometry it was computed from (Odometry::stamp)
};

// When the base last handed a command frame over to its transport (hal/socketcan: when
// sendmsg returned), and which command it carried: for the command-to-wire latency.
struct CommandSent {
  rt::Nanos command_stamp = -1;  // the VelocityCommand::stamp it carried; < 0: none sent yet
  rt::Nanos sent_at = -1;        // on the command's clock (CLOCK_MONOTONIC in staad)
};

class Base {
 public:
  virtual ~Base() = default;
  // Takes in what the base sent since the last call.
  virtual void read(rt::Nanos now) = 0;
  // Sends `command` (the latest one; the same one again when nothing new came).
  virtual void write(rt::Nanos now, const VelocityCommand& command) = 0;
  virtual Odometry odometry() const = 0;
  virtual BaseStatus status() const = 0;
  // Sets the pose estimate (staactl pose): the sim moves its robot there only when it is
  // free; a real base re-anchors its odometry. Returns false with no change when refused.
  virtual bool setPose(const Pose2& pose) = 0;
  // The last command frame sent (written by write(); none by default: a backend that does not
  // know reports nothing, and no command-to-wire latency is measured).
  virtual CommandSent lastCommandSent() const { return {}; }
};

}  // namespace staa::hal
