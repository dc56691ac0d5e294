#pragma once
// The CAN frame profile of a base (`staa-can-profile/1`, config/can/hsr_base.yaml): IDs,
// scaling, limits, rates and timeouts of the frames between staad and the base. The file is
// the contract; the codec (can_codec.hpp) is its one implementation, used by the driver and
// by the simulated base firmware alike.
//
// The defaults below are the shipped config/can/hsr_base.yaml (a test keeps them equal), so
// a test can build frames with `CanProfile{}`.

#include "io/config_rules.hpp"

#include <cstdint>
#include <filesystem>
#include <string>

namespace staa::hal {

enum class CanByteOrder : std::uint8_t { kLittle, kBig };

// host -> base: the velocity command.
struct CanCommandProfile {
  std::uint32_t id = 0x110;
  double rate_hz = 30.0;
  double v_scale = 0.001;  // m/s per LSB
  double w_scale = 0.001;  // rad/s per LSB
  double v_limit = 2.0;    // |v| is clamped to this before encoding
  double w_limit = 3.0;
};

// base -> host: measured velocities and the base's time step.
struct CanOdometryProfile {
  std::uint32_t id = 0x210;
  double rate_hz = 100.0;
  double v_scale = 0.001;
  double w_scale = 0.001;
  double v_limit = 2.0;    // |v| above this: out of range, dropped
  double w_limit = 3.0;
  double max_dt_s = 0.1;   // dt above this: out of range, dropped
  double timeout_s = 0.1;  // no valid odometry for this long: stale
};

// base -> host: enabled, emergency stop, drive fault and code.
struct CanStatusProfile {
  std::uint32_t id = 0x220;
  double rate_hz = 50.0;
  double timeout_s = 0.2;  // no valid status for this long: heartbeat lost
};

struct CanHeartbeatProfile {
  std::uint32_t host_id = 0x100;  // host -> base
  std::uint32_t base_id = 0x200;  // base -> host
  double rate_hz = 10.0;
  double timeout_s = 0.3;  // no base heartbeat for this long: heartbeat lost
};

struct CanBusProfile {
  double recovery_interval_s = 1.0;  // after bus-off: one stop command per interval
};

struct CanProfile {
  std::string name = "hsr-base-bridge";
  CanByteOrder byte_order = CanByteOrder::kLittle;
  CanCommandProfile command;
  CanOdometryProfile odometry;
  CanStatusProfile status;
  CanHeartbeatProfile heartbeat;
  CanBusProfile bus;
};

class CanProfileError : public io::ConfigError {
 public:
  using io::ConfigError::ConfigError;
};

// Strict: a missing or unknown key, an unknown format or byte order, an ID above 0x7FF, two
// frames on one ID, a non-positive scale, limit, rate or timeout, or a limit that does not
// fit its int16 field throws CanProfileError naming the place, key and value, e.g.
// "hsr_base.yaml:31: odometry.rate_hz: must be > 0, got -5".
CanProfile parseCanProfile(const std::string& yaml_text, const std::string& source);
CanProfile loadCanProfile(const std::filesystem::path& path);

}  // namespace staa::hal
