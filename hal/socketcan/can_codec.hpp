#pragma once
// The frames of a CAN profile (can_profile.hpp, config/can/hsr_base.yaml) as pure functions
// on `struct can_frame`: no sockets, no clocks, no allocation. Both sides are here, host
// (staad's driver) and base (the simulated base firmware in tests/hil/basesim), so the
// profile has one implementation and the two can only disagree with the file.
//
// Decoders check, in order: ID (exactly the profile's 11-bit ID, no EFF/RTR/ERR flag), DLC
// (8), checksum, reserved bits (0), value ranges. The rolling counter (byte 6) is returned,
// not judged: CounterTracker does that per ID.

#include "hal/socketcan/can_profile.hpp"

#include <linux/can.h>

#include <array>
#include <cstddef>
#include <cstdint>

namespace staa::hal {

// Why a frame was dropped (SocketCanCounters::bad_by_kind is indexed by it).
enum class CanFrameError : std::uint8_t {
  kNone,
  kWrongId,       // not the expected ID (or an ID the profile does not receive)
  kWrongDlc,      // DLC != 8
  kBadChecksum,   // byte 7 does not match canChecksum()
  kReservedBits,  // a reserved bit or byte is not 0
  kOutOfRange,    // a value outside its limit (|v| > v_limit, dt = 0 or > max_dt_s, unknown state)
  kWrongSize,     // a transport record that is not one 16-byte struct can_frame
};
inline constexpr std::size_t kCanFrameErrorCount = 7;
const char* toString(CanFrameError error);

// The heartbeat's byte 0.
enum class CanHostState : std::uint8_t { kIdle = 0, kDriving = 1, kFault = 2 };
enum class CanBaseState : std::uint8_t { kOk = 0, kFault = 1 };

// Decoded frames (physical units; raw * scale).
struct CanCommand {
  double v = 0.0;  // m/s
  double w = 0.0;  // rad/s
  bool enable = false;
  bool brake = false;
  std::uint8_t counter = 0;
};
struct CanOdometry {
  double v = 0.0;
  double w = 0.0;
  std::uint16_t dt_us = 0;  // base's clock, since its previous odometry frame
  std::uint8_t counter = 0;
};
struct CanStatus {
  bool enabled = false;
  bool estop = false;
  bool drive_fault = false;
  std::uint16_t fault_code = 0;
  std::uint8_t counter = 0;
};
struct CanHostHeartbeat {
  CanHostState state = CanHostState::kIdle;
  std::uint8_t counter = 0;
};
struct CanBaseHeartbeat {
  CanBaseState state = CanBaseState::kOk;
  std::uint8_t counter = 0;
};

// A decoder's result: the value when error == kNone.
template <class T>
struct CanDecoded {
  T value{};
  CanFrameError error = CanFrameError::kNone;
  bool ok() const { return error == CanFrameError::kNone; }
};

// checksum = 0xFF - ((id & 0xFF) + (id >> 8) + data[0] + ... + data[6]) mod 256, over the
// 11-bit ID (flags masked off). Encoders write it to data[7].
std::uint8_t canChecksum(const can_frame& frame);

// ---- host -> base (the driver encodes, the base decodes) ----
// v and w are clamped to command.v_limit/w_limit and rounded to the nearest LSB; a
// non-finite v or w encodes 0 (and should come with brake).
can_frame encodeCommand(const CanProfile& profile, double v, double w, bool enable, bool brake, std::uint8_t counter);
can_frame encodeHostHeartbeat(const CanProfile& profile, CanHostState state, std::uint8_t counter);
CanDecoded<CanCommand> decodeCommand(const CanProfile& profile, const can_frame& frame);
CanDecoded<CanHostHeartbeat> decodeHostHeartbeat(const CanProfile& profile, const can_frame& frame);

// ---- base -> host (the base encodes, the driver decodes) ----
// Base-side encoders round to the nearest LSB and saturate to the field's type only: not to
// the limits, so a simulated base can send an out-of-range frame on purpose.
can_frame encodeOdometry(const CanProfile& profile, double v, double w, std::uint16_t dt_us, std::uint8_t counter);
can_frame encodeStatus(const CanProfile& profile, bool enabled, bool estop, bool drive_fault, std::uint16_t fault_code,
                       std::uint8_t counter);
can_frame encodeBaseHeartbeat(const CanProfile& profile, CanBaseState state, std::uint8_t counter);
CanDecoded<CanOdometry> decodeOdometry(const CanProfile& profile, const can_frame& frame);
CanDecoded<CanStatus> decodeStatus(const CanProfile& profile, const can_frame& frame);
CanDecoded<CanBaseHeartbeat> decodeBaseHeartbeat(const CanProfile& profile, const can_frame& frame);

// The IDs each side receives (the driver's kernel filter: baseToHostIds).
std::array<canid_t, 3> baseToHostIds(const CanProfile& profile);  // odometry, status, base heartbeat
std::array<canid_t, 2> hostToBaseIds(const CanProfile& profile);  // command, host heartbeat

// ---- error frames (can_id & CAN_ERR_FLAG), from the kernel or a seqpacket peer ----
struct CanErrorFrame {
  bool bus_off = false;     // CAN_ERR_BUSOFF
  bool restarted = false;   // CAN_ERR_RESTARTED: the controller is back after bus-off
  bool controller = false;  // CAN_ERR_CRTL (data[1] says what: overflow, error passive, ...)
  bool no_ack = false;      // CAN_ERR_ACK: nobody acknowledged (the base is off the bus)
};
bool isErrorFrame(const can_frame& frame);
CanErrorFrame classifyErrorFrame(const can_frame& frame);

// ---- rolling counters (byte 6), one tracker per received ID ----
enum class CanCounterVerdict : std::uint8_t {
  kFirst,       // the first frame (or the first after reset()): accepted
  kInSequence,  // last + 1 (mod 256): accepted
  kGap,         // 2..127 ahead: frames were lost; accepted (the newest state)
  kStale,       // 0..128 behind (a repeat or a reordered frame): dropped
};
const char* toString(CanCounterVerdict verdict);

class CounterTracker {
 public:
  // Classifies `counter` and, when accepted, makes it the last one.
  CanCounterVerdict check(std::uint8_t counter);
  // Frames lost before the last kGap (counter jump - 1); 0 otherwise.
  std::uint8_t lastGap() const { return last_gap_; }
  // The next frame counts as the first (a base that restarted begins its counters anew).
  void reset() { started_ = false; }
  bool started() const { return started_; }
  std::uint8_t last() const { return last_; }

 private:
  bool started_ = false;
  std::uint8_t last_ = 0;
  std::uint8_t last_gap_ = 0;
};

}  // namespace staa::hal
