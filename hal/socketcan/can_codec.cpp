#include "hal/socketcan/can_codec.hpp"

#include <linux/can/error.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa::hal {
namespace {

constexpr std::uint8_t kDlc = 8;
constexpr std::size_t kCounterByte = 6;
constexpr std::size_t kChecksumByte = 7;

// Command flags (byte 4) and status flags (byte 0).
constexpr std::uint8_t kCommandEnable = 0x01;
constexpr std::uint8_t kCommandBrake = 0x02;
constexpr std::uint8_t kCommandReserved = 0xFC;
constexpr std::uint8_t kStatusEnabled = 0x01;
constexpr std::uint8_t kStatusEstop = 0x02;
constexpr std::uint8_t kStatusDriveFault = 0x04;
constexpr std::uint8_t kStatusReserved = 0xF8;

// A physical value as the nearest raw LSB count, saturated to [lo, hi]; NaN is 0.
std::int32_t toRaw(double value, double scale, std::int32_t lo, std::int32_t hi) {
  if (std::isnan(value)) return 0;
  const double raw = std::round(value / scale);  // nearest LSB, halves away from 0
  if (raw <= lo) return lo;
  if (raw >= hi) return hi;
  return static_cast<std::int32_t>(raw);
}

// The largest raw count within `limit` (the limit itself when it is a whole number of LSBs).
std::int32_t limitRaw(double limit, double scale) {
  return static_cast<std::int32_t>(std::min(std::floor(limit / scale + 1e-9), 32767.0));
}

void put16(const CanProfile& p, can_frame& f, std::size_t at, std::uint16_t v) {
  const auto lo = static_cast<std::uint8_t>(v & 0xFF);
  const auto hi = static_cast<std::uint8_t>(v >> 8);
  f.data[at] = p.byte_order == CanByteOrder::kLittle ? lo : hi;
  f.data[at + 1] = p.byte_order == CanByteOrder::kLittle ? hi : lo;
}

std::uint16_t get16(const CanProfile& p, const can_frame& f, std::size_t at) {
  const std::uint8_t first = f.data[at], second = f.data[at + 1];
  return p.byte_order == CanByteOrder::kLittle ? static_cast<std::uint16_t>(first | (second << 8))
                                               : static_cast<std::uint16_t>((first << 8) | second);
}

void putInt16(const CanProfile& p, can_frame& f, std::size_t at, std::int32_t raw) {
  put16(p, f, at, static_cast<std::uint16_t>(static_cast<std::int16_t>(raw)));
}

std::int32_t getInt16(const CanProfile& p, const can_frame& f, std::size_t at) {
  return static_cast<std::int16_t>(get16(p, f, at));
}

// A fresh frame with the ID and DLC; the encoder fills bytes 0-5, seal() the rest.
can_frame blank(std::uint32_t id) {
  can_frame f{};
  f.can_id = id & CAN_SFF_MASK;
  f.len = kDlc;
  return f;
}

can_frame seal(can_frame f, std::uint8_t counter) {
  f.data[kCounterByte] = counter;
  f.data[kChecksumByte] = canChecksum(f);
  return f;
}

// The checks every decoder makes first: exact ID (no flags), DLC, checksum.
CanFrameError checkFrame(const can_frame& f, std::uint32_t id) {
  if (f.can_id != (id & CAN_SFF_MASK)) return CanFrameError::kWrongId;
  if (f.len != kDlc) return CanFrameError::kWrongDlc;
  if (f.data[kChecksumByte] != canChecksum(f)) return CanFrameError::kBadChecksum;
  return CanFrameError::kNone;
}

bool bytesZero(const can_frame& f, std::size_t from, std::size_t to) {
  for (std::size_t k = from; k <= to; ++k) {
    if (f.data[k] != 0) return false;
  }
  return true;
}

template <class T>
CanDecoded<T> failed(CanFrameError e) {
  CanDecoded<T> out;
  out.error = e;
  return out;
}

}  // namespace

const char* toString(CanFrameError error) {
  switch (error) {
    case CanFrameError::kNone: return "none";
    case CanFrameError::kWrongId: return "wrong_id";
    case CanFrameError::kWrongDlc: return "wrong_dlc";
    case CanFrameError::kBadChecksum: return "bad_checksum";
    case CanFrameError::kReservedBits: return "reserved_bits";
    case CanFrameError::kOutOfRange: return "out_of_range";
    case CanFrameError::kWrongSize: return "wrong_size";
  }
  return "unknown";
}

const char* toString(CanCounterVerdict verdict) {
  switch (verdict) {
    case CanCounterVerdict::kFirst: return "first";
    case CanCounterVerdict::kInSequence: return "in_sequence";
    case CanCounterVerdict::kGap: return "gap";
    case CanCounterVerdict::kStale: return "stale";
  }
  return "unknown";
}

std::uint8_t canChecksum(const can_frame& frame) {
  const std::uint32_t id = frame.can_id & CAN_SFF_MASK;
  std::uint32_t sum = (id & 0xFF) + (id >> 8);
  for (std::size_t k = 0; k < kCounterByte + 1; ++k) sum += frame.data[k];
  return static_cast<std::uint8_t>(0xFF - (sum & 0xFF));
}

// ---- host -> base ----

can_frame encodeCommand(const CanProfile& profile, double v, double w, bool enable, bool brake, std::uint8_t counter) {
  const CanCommandProfile& c = profile.command;
  const std::int32_t v_max = limitRaw(c.v_limit, c.v_scale);
  const std::int32_t w_max = limitRaw(c.w_limit, c.w_scale);
  can_frame f = blank(c.id);
  putInt16(profile, f, 0, toRaw(v, c.v_scale, -v_max, v_max));
  putInt16(profile, f, 2, toRaw(w, c.w_scale, -w_max, w_max));
  f.data[4] = static_cast<std::uint8_t>((enable ? kCommandEnable : 0) | (brake ? kCommandBrake : 0));
  return seal(f, counter);
}

can_frame encodeHostHeartbeat(const CanProfile& profile, CanHostState state, std::uint8_t counter) {
  can_frame f = blank(profile.heartbeat.host_id);
  f.data[0] = static_cast<std::uint8_t>(state);
  return seal(f, counter);
}

CanDecoded<CanCommand> decodeCommand(const CanProfile& profile, const can_frame& frame) {
  const CanCommandProfile& c = profile.command;
  if (const CanFrameError e = checkFrame(frame, c.id); e != CanFrameError::kNone) return failed<CanCommand>(e);
  if ((frame.data[4] & kCommandReserved) != 0 || frame.data[5] != 0) return failed<CanCommand>(CanFrameError::kReservedBits);
  const std::int32_t v = getInt16(profile, frame, 0), w = getInt16(profile, frame, 2);
  if (std::abs(v) > limitRaw(c.v_limit, c.v_scale) || std::abs(w) > limitRaw(c.w_limit, c.w_scale)) {
    return failed<CanCommand>(CanFrameError::kOutOfRange);
  }
  CanDecoded<CanCommand> out;
  out.value.v = v * c.v_scale;
  out.value.w = w * c.w_scale;
  out.value.enable = (frame.data[4] & kCommandEnable) != 0;
  out.value.brake = (frame.data[4] & kCommandBrake) != 0;
  out.value.counter = frame.data[kCounterByte];
  return out;
}

CanDecoded<CanHostHeartbeat> decodeHostHeartbeat(const CanProfile& profile, const can_frame& frame) {
  if (const CanFrameError e = checkFrame(frame, profile.heartbeat.host_id); e != CanFrameError::kNone) {
    return failed<CanHostHeartbeat>(e);
  }
  if (!bytesZero(frame, 1, 5)) return failed<CanHostHeartbeat>(CanFrameError::kReservedBits);
  if (frame.data[0] > static_cast<std::uint8_t>(CanHostState::kFault)) return failed<CanHostHeartbeat>(CanFrameError::kOutOfRange);
  CanDecoded<CanHostHeartbeat> out;
  out.value.state = static_cast<CanHostState>(frame.data[0]);
  out.value.counter = frame.data[kCounterByte];
  return out;
}

// ---- base -> host ----

can_frame encodeOdometry(const CanProfile& profile, double v, double w, std::uint16_t dt_us, std::uint8_t counter) {
  const CanOdometryProfile& o = profile.odometry;
  can_frame f = blank(o.id);
  putInt16(profile, f, 0, toRaw(v, o.v_scale, -32768, 32767));
  putInt16(profile, f, 2, toRaw(w, o.w_scale, -32768, 32767));
  put16(profile, f, 4, dt_us);
  return seal(f, counter);
}

can_frame encodeStatus(const CanProfile& profile, bool enabled, bool estop, bool drive_fault, std::uint16_t fault_code,
                       std::uint8_t counter) {
  can_frame f = blank(profile.status.id);
  f.data[0] = static_cast<std::uint8_t>((enabled ? kStatusEnabled : 0) | (estop ? kStatusEstop : 0) |
                                        (drive_fault ? kStatusDriveFault : 0));
  put16(profile, f, 1, fault_code);
  return seal(f, counter);
}

can_frame encodeBaseHeartbeat(const CanProfile& profile, CanBaseState state, std::uint8_t counter) {
  can_frame f = blank(profile.heartbeat.base_id);
  f.data[0] = static_cast<std::uint8_t>(state);
  return seal(f, counter);
}

CanDecoded<CanOdometry> decodeOdometry(const CanProfile& profile, const can_frame& frame) {
  const CanOdometryProfile& o = profile.odometry;
  if (const CanFrameError e = checkFrame(frame, o.id); e != CanFrameError::kNone) return failed<CanOdometry>(e);
  const std::int32_t v = getInt16(profile, frame, 0), w = getInt16(profile, frame, 2);
  const std::uint16_t dt_us = get16(profile, frame, 4);
  if (std::abs(v) > limitRaw(o.v_limit, o.v_scale) || std::abs(w) > limitRaw(o.w_limit, o.w_scale) || dt_us == 0 ||
      dt_us * 1e-6 > o.max_dt_s) {
    return failed<CanOdometry>(CanFrameError::kOutOfRange);
  }
  CanDecoded<CanOdometry> out;
  out.value.v = v * o.v_scale;
  out.value.w = w * o.w_scale;
  out.value.dt_us = dt_us;
  out.value.counter = frame.data[kCounterByte];
  return out;
}

CanDecoded<CanStatus> decodeStatus(const CanProfile& profile, const can_frame& frame) {
  if (const CanFrameError e = checkFrame(frame, profile.status.id); e != CanFrameError::kNone) return failed<CanStatus>(e);
  if ((frame.data[0] & kStatusReserved) != 0 || !bytesZero(frame, 3, 5)) return failed<CanStatus>(CanFrameError::kReservedBits);
  CanDecoded<CanStatus> out;
  out.value.enabled = (frame.data[0] & kStatusEnabled) != 0;
  out.value.estop = (frame.data[0] & kStatusEstop) != 0;
  out.value.drive_fault = (frame.data[0] & kStatusDriveFault) != 0;
  out.value.fault_code = get16(profile, frame, 1);
  out.value.counter = frame.data[kCounterByte];
  return out;
}

CanDecoded<CanBaseHeartbeat> decodeBaseHeartbeat(const CanProfile& profile, const can_frame& frame) {
  if (const CanFrameError e = checkFrame(frame, profile.heartbeat.base_id); e != CanFrameError::kNone) {
    return failed<CanBaseHeartbeat>(e);
  }
  if (!bytesZero(frame, 1, 5)) return failed<CanBaseHeartbeat>(CanFrameError::kReservedBits);
  if (frame.data[0] > static_cast<std::uint8_t>(CanBaseState::kFault)) return failed<CanBaseHeartbeat>(CanFrameError::kOutOfRange);
  CanDecoded<CanBaseHeartbeat> out;
  out.value.state = static_cast<CanBaseState>(frame.data[0]);
  out.value.counter = frame.data[kCounterByte];
  return out;
}

std::array<canid_t, 3> baseToHostIds(const CanProfile& profile) {
  return {profile.odometry.id, profile.status.id, profile.heartbeat.base_id};
}

std::array<canid_t, 2> hostToBaseIds(const CanProfile& profile) {
  return {profile.command.id, profile.heartbeat.host_id};
}

// ---- error frames ----

bool isErrorFrame(const can_frame& frame) { return (frame.can_id & CAN_ERR_FLAG) != 0; }

CanErrorFrame classifyErrorFrame(const can_frame& frame) {
  CanErrorFrame e;
  if (!isErrorFrame(frame)) return e;
  e.bus_off = (frame.can_id & CAN_ERR_BUSOFF) != 0;
  e.restarted = (frame.can_id & CAN_ERR_RESTARTED) != 0;
  e.controller = (frame.can_id & CAN_ERR_CRTL) != 0;
  e.no_ack = (frame.can_id & CAN_ERR_ACK) != 0;
  return e;
}

// ---- counters ----

CanCounterVerdict CounterTracker::check(std::uint8_t counter) {
  last_gap_ = 0;
  if (!started_) {
    started_ = true;
    last_ = counter;
    return CanCounterVerdict::kFirst;
  }
  // Steps ahead of the last accepted counter, mod 256: 1 is the next frame; 2..127 a jump
  // over lost frames; 0 (a repeat) and 128..255 (up to 128 behind) a stale frame.
  const auto ahead = static_cast<std::uint8_t>(counter - last_);
  if (ahead == 0 || ahead >= 128) return CanCounterVerdict::kStale;
  last_ = counter;
  if (ahead == 1) return CanCounterVerdict::kInSequence;
  last_gap_ = static_cast<std::uint8_t>(ahead - 1);
  return CanCounterVerdict::kGap;
}

}  // namespace staa::hal
