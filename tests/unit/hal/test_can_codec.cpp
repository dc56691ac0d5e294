// The CAN profile's frames byte by byte (config/can/hsr_base.yaml): every expected frame is
// written out literally from the profile's layout, not produced by the code under test.
#include "hal/socketcan/can_codec.hpp"

#include <gtest/gtest.h>

#include <linux/can/error.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace staa::hal {
namespace {

using Bytes = std::array<std::uint8_t, 8>;

Bytes bytesOf(const can_frame& f) {
  Bytes b{};
  for (std::size_t k = 0; k < 8; ++k) b[k] = f.data[k];
  return b;
}

can_frame frameOf(canid_t id, const Bytes& b) {
  can_frame f{};
  f.can_id = id;
  f.len = 8;
  for (std::size_t k = 0; k < 8; ++k) f.data[k] = b[k];
  return f;
}

// Sets a byte and recomputes the checksum: the frame is well-formed but for that byte.
can_frame withByte(can_frame f, std::size_t at, std::uint8_t value) {
  f.data[at] = value;
  f.data[7] = canChecksum(f);
  return f;
}

const CanProfile kProfile{};  // the shipped hsr_base.yaml (test_can_profile keeps them equal)

TEST(CanChecksum, FollowsTheProfileFormula) {
  // id 0x110: 0x10 + 0x01; data F4 01 06 FF 01 00 07: sum 0x213 -> 0x13 -> 0xFF - 0x13 = 0xEC.
  const can_frame f = frameOf(0x110, {0xF4, 0x01, 0x06, 0xFF, 0x01, 0x00, 0x07, 0x00});
  EXPECT_EQ(canChecksum(f), 0xEC);
  // All zero on ID 0: 0xFF. Byte 7 itself is not part of the sum.
  EXPECT_EQ(canChecksum(frameOf(0, {0, 0, 0, 0, 0, 0, 0, 0x55})), 0xFF);
  // Flags above the 11-bit ID are not summed.
  EXPECT_EQ(canChecksum(frameOf(0x110 | CAN_EFF_FLAG, {0xF4, 0x01, 0x06, 0xFF, 0x01, 0x00, 0x07, 0})), 0xEC);
}

TEST(CanCommandFrame, EncodesHalfAMetrePerSecondLittleEndian) {
  // v = 0.5 m/s -> 500 LSB = 0x01F4 -> F4 01; w = -0.25 -> -250 = 0xFF06 -> 06 FF; enable.
  const can_frame f = encodeCommand(kProfile, 0.5, -0.25, true, false, 7);
  EXPECT_EQ(f.can_id, 0x110u);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(bytesOf(f), (Bytes{0xF4, 0x01, 0x06, 0xFF, 0x01, 0x00, 0x07, 0xEC}));
}

TEST(CanCommandFrame, ClampsToTheLimitsAndSetsBrake) {
  // v = 5 -> v_limit 2.0 -> 2000 = 0x07D0; w = -10 -> -3.0 -> -3000 = 0xF448; brake = bit 1.
  const can_frame f = encodeCommand(kProfile, 5.0, -10.0, false, true, 255);
  EXPECT_EQ(bytesOf(f), (Bytes{0xD0, 0x07, 0x48, 0xF4, 0x02, 0x00, 0xFF, 0xDA}));
  // Infinite values clamp too; NaN encodes 0.
  const can_frame inf = encodeCommand(kProfile, std::numeric_limits<double>::infinity(), 0.0, false, true, 0);
  EXPECT_EQ(inf.data[0], 0xD0);
  EXPECT_EQ(inf.data[1], 0x07);
  const can_frame nan = encodeCommand(kProfile, std::numeric_limits<double>::quiet_NaN(), 0.0, false, true, 0);
  EXPECT_EQ(nan.data[0], 0x00);
  EXPECT_EQ(nan.data[1], 0x00);
}

TEST(CanCommandFrame, RoundsToTheNearestLsb) {
  EXPECT_EQ(encodeCommand(kProfile, 0.0004, 0.0, true, false, 0).data[0], 0x00);
  EXPECT_EQ(encodeCommand(kProfile, 0.0006, 0.0, true, false, 0).data[0], 0x01);
  EXPECT_EQ(encodeCommand(kProfile, 0.0014, 0.0, true, false, 0).data[0], 0x01);
  // -0.0016 -> -2 = 0xFFFE.
  const can_frame f = encodeCommand(kProfile, -0.0016, 0.0, true, false, 0);
  EXPECT_EQ(f.data[0], 0xFE);
  EXPECT_EQ(f.data[1], 0xFF);
}

TEST(CanCommandFrame, BigEndianProfileSwapsTheFieldBytesOnly) {
  CanProfile big = kProfile;
  big.byte_order = CanByteOrder::kBig;
  const can_frame f = encodeCommand(big, 0.5, -0.25, true, false, 7);
  EXPECT_EQ(bytesOf(f), (Bytes{0x01, 0xF4, 0xFF, 0x06, 0x01, 0x00, 0x07, 0xEC}));
  const CanDecoded<CanCommand> d = decodeCommand(big, f);
  ASSERT_TRUE(d.ok()) << toString(d.error);
  EXPECT_DOUBLE_EQ(d.value.v, 0.5);
  EXPECT_DOUBLE_EQ(d.value.w, -0.25);
}

TEST(CanCommandFrame, DecodesWhatTheHostSent) {
  const CanDecoded<CanCommand> d = decodeCommand(kProfile, frameOf(0x110, {0xD0, 0x07, 0x48, 0xF4, 0x02, 0x00, 0xFF, 0xDA}));
  ASSERT_TRUE(d.ok()) << toString(d.error);
  EXPECT_DOUBLE_EQ(d.value.v, 2.0);
  EXPECT_DOUBLE_EQ(d.value.w, -3.0);
  EXPECT_FALSE(d.value.enable);
  EXPECT_TRUE(d.value.brake);
  EXPECT_EQ(d.value.counter, 255);
}

TEST(CanHeartbeatFrame, HostHeartbeatBytes) {
  const can_frame f = encodeHostHeartbeat(kProfile, CanHostState::kDriving, 0x2A);
  EXPECT_EQ(f.can_id, 0x100u);
  EXPECT_EQ(bytesOf(f), (Bytes{0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x2A, 0xD3}));
  const CanDecoded<CanHostHeartbeat> d = decodeHostHeartbeat(kProfile, f);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d.value.state, CanHostState::kDriving);
  EXPECT_EQ(d.value.counter, 0x2A);
}

TEST(CanHeartbeatFrame, BaseHeartbeatBytes) {
  const can_frame f = encodeBaseHeartbeat(kProfile, CanBaseState::kFault, 0);
  EXPECT_EQ(f.can_id, 0x200u);
  EXPECT_EQ(bytesOf(f), (Bytes{0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xFC}));
  const CanDecoded<CanBaseHeartbeat> d = decodeBaseHeartbeat(kProfile, f);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d.value.state, CanBaseState::kFault);
}

TEST(CanOdometryFrame, EncodesAndDecodesVelocitiesAndDt) {
  // v 0.5 -> F4 01; w 0.1 -> 100 = 64 00; dt 10000 us = 0x2710 -> 10 27; counter 3.
  const can_frame f = encodeOdometry(kProfile, 0.5, 0.1, 10000, 3);
  EXPECT_EQ(f.can_id, 0x210u);
  EXPECT_EQ(bytesOf(f), (Bytes{0xF4, 0x01, 0x64, 0x00, 0x10, 0x27, 0x03, 0x5A}));
  const CanDecoded<CanOdometry> d = decodeOdometry(kProfile, frameOf(0x210, {0xF4, 0x01, 0x64, 0x00, 0x10, 0x27, 0x03, 0x5A}));
  ASSERT_TRUE(d.ok()) << toString(d.error);
  EXPECT_DOUBLE_EQ(d.value.v, 0.5);
  EXPECT_DOUBLE_EQ(d.value.w, 0.1);
  EXPECT_EQ(d.value.dt_us, 10000);
  EXPECT_EQ(d.value.counter, 3);
}

TEST(CanOdometryFrame, BaseEncoderDoesNotClampToTheLimits) {
  // A simulated base may send out-of-range values on purpose: 2.5 m/s = 2500 = 0x09C4.
  const can_frame f = encodeOdometry(kProfile, 2.5, 0.0, 10000, 0);
  EXPECT_EQ(f.data[0], 0xC4);
  EXPECT_EQ(f.data[1], 0x09);
  EXPECT_EQ(decodeOdometry(kProfile, f).error, CanFrameError::kOutOfRange);
  // Saturated to int16 only: 100 m/s -> 32767 = 0x7FFF.
  const can_frame sat = encodeOdometry(kProfile, 100.0, 0.0, 10000, 0);
  EXPECT_EQ(sat.data[0], 0xFF);
  EXPECT_EQ(sat.data[1], 0x7F);
}

TEST(CanStatusFrame, EncodesFlagsAndFaultCode) {
  // enabled (bit 0) + emergency stop (bit 1) = 0x03; code 0x2310 -> 10 23.
  const can_frame f = encodeStatus(kProfile, true, true, false, 0x2310, 9);
  EXPECT_EQ(f.can_id, 0x220u);
  EXPECT_EQ(bytesOf(f), (Bytes{0x03, 0x10, 0x23, 0x00, 0x00, 0x00, 0x09, 0x9E}));
  const CanDecoded<CanStatus> d = decodeStatus(kProfile, f);
  ASSERT_TRUE(d.ok());
  EXPECT_TRUE(d.value.enabled);
  EXPECT_TRUE(d.value.estop);
  EXPECT_FALSE(d.value.drive_fault);
  EXPECT_EQ(d.value.fault_code, 0x2310);
  EXPECT_EQ(d.value.counter, 9);
  const CanDecoded<CanStatus> fault = decodeStatus(kProfile, encodeStatus(kProfile, false, false, true, 7, 0));
  ASSERT_TRUE(fault.ok());
  EXPECT_TRUE(fault.value.drive_fault);
  EXPECT_FALSE(fault.value.enabled);
}

TEST(CanDecode, RejectsTheWrongId) {
  const can_frame odo = encodeOdometry(kProfile, 0.5, 0.0, 10000, 0);
  EXPECT_EQ(decodeStatus(kProfile, odo).error, CanFrameError::kWrongId);
  // The same 11 bits as an extended or a remote frame are not the profile's frame.
  can_frame eff = odo;
  eff.can_id |= CAN_EFF_FLAG;
  EXPECT_EQ(decodeOdometry(kProfile, eff).error, CanFrameError::kWrongId);
  can_frame rtr = odo;
  rtr.can_id |= CAN_RTR_FLAG;
  EXPECT_EQ(decodeOdometry(kProfile, rtr).error, CanFrameError::kWrongId);
  EXPECT_EQ(decodeCommand(kProfile, encodeHostHeartbeat(kProfile, CanHostState::kIdle, 0)).error, CanFrameError::kWrongId);
}

TEST(CanDecode, RejectsAWrongDlc) {
  can_frame f = encodeStatus(kProfile, true, false, false, 0, 0);
  f.len = 7;
  EXPECT_EQ(decodeStatus(kProfile, f).error, CanFrameError::kWrongDlc);
  f.len = 0;
  EXPECT_EQ(decodeStatus(kProfile, f).error, CanFrameError::kWrongDlc);
}

TEST(CanDecode, RejectsABadChecksum) {
  can_frame f = encodeOdometry(kProfile, 0.5, 0.0, 10000, 0);
  f.data[0] ^= 0x01;  // one bit flipped on the way
  EXPECT_EQ(decodeOdometry(kProfile, f).error, CanFrameError::kBadChecksum);
  can_frame g = encodeBaseHeartbeat(kProfile, CanBaseState::kOk, 4);
  g.data[7] = static_cast<std::uint8_t>(g.data[7] + 1);
  EXPECT_EQ(decodeBaseHeartbeat(kProfile, g).error, CanFrameError::kBadChecksum);
}

TEST(CanDecode, RejectsReservedBits) {
  const can_frame status = encodeStatus(kProfile, true, false, false, 0, 0);
  EXPECT_EQ(decodeStatus(kProfile, withByte(status, 0, 0x09)).error, CanFrameError::kReservedBits);  // bit 3
  EXPECT_EQ(decodeStatus(kProfile, withByte(status, 0, 0x81)).error, CanFrameError::kReservedBits);  // bit 7
  EXPECT_EQ(decodeStatus(kProfile, withByte(status, 4, 0x01)).error, CanFrameError::kReservedBits);  // byte 4
  const can_frame cmd = encodeCommand(kProfile, 0.0, 0.0, true, false, 0);
  EXPECT_EQ(decodeCommand(kProfile, withByte(cmd, 4, 0x05)).error, CanFrameError::kReservedBits);  // flags bit 2
  EXPECT_EQ(decodeCommand(kProfile, withByte(cmd, 5, 0x10)).error, CanFrameError::kReservedBits);  // byte 5
  const can_frame hb = encodeBaseHeartbeat(kProfile, CanBaseState::kOk, 0);
  EXPECT_EQ(decodeBaseHeartbeat(kProfile, withByte(hb, 1, 0x01)).error, CanFrameError::kReservedBits);
  EXPECT_EQ(decodeBaseHeartbeat(kProfile, withByte(hb, 5, 0x80)).error, CanFrameError::kReservedBits);
  const can_frame host = encodeHostHeartbeat(kProfile, CanHostState::kIdle, 0);
  EXPECT_EQ(decodeHostHeartbeat(kProfile, withByte(host, 3, 0x01)).error, CanFrameError::kReservedBits);
}

TEST(CanDecode, RejectsValuesOutOfRange) {
  // |v| 2.001 > v_limit 2.0: 2001 = 0x07D1; exactly 2.0 is accepted. The checksum is checked
  // first: unsealed, the frame is a bad checksum, sealed it is out of range.
  EXPECT_EQ(decodeOdometry(kProfile, frameOf(0x210, {0xD1, 0x07, 0, 0, 0x10, 0x27, 0, 0})).error, CanFrameError::kBadChecksum);
  can_frame v_high = frameOf(0x210, {0xD1, 0x07, 0, 0, 0x10, 0x27, 0, 0});
  v_high.data[7] = canChecksum(v_high);
  EXPECT_EQ(decodeOdometry(kProfile, v_high).error, CanFrameError::kOutOfRange);
  EXPECT_TRUE(decodeOdometry(kProfile, encodeOdometry(kProfile, -2.0, 3.0, 10000, 0)).ok());
  // |w| 3.001 > 3.0: -3001.
  EXPECT_EQ(decodeOdometry(kProfile, encodeOdometry(kProfile, 0.0, -3.001, 10000, 0)).error, CanFrameError::kOutOfRange);
  // dt 0 is invalid; dt above max_dt_s too.
  EXPECT_EQ(decodeOdometry(kProfile, encodeOdometry(kProfile, 0.5, 0.0, 0, 0)).error, CanFrameError::kOutOfRange);
  CanProfile short_dt = kProfile;
  short_dt.odometry.max_dt_s = 0.05;
  EXPECT_TRUE(decodeOdometry(short_dt, encodeOdometry(short_dt, 0.5, 0.0, 50000, 0)).ok());
  EXPECT_EQ(decodeOdometry(short_dt, encodeOdometry(short_dt, 0.5, 0.0, 50001, 0)).error, CanFrameError::kOutOfRange);
  // Unknown heartbeat states: base 2, host 3.
  EXPECT_EQ(decodeBaseHeartbeat(kProfile, withByte(encodeBaseHeartbeat(kProfile, CanBaseState::kOk, 0), 0, 2)).error,
            CanFrameError::kOutOfRange);
  EXPECT_EQ(decodeHostHeartbeat(kProfile, withByte(encodeHostHeartbeat(kProfile, CanHostState::kIdle, 0), 0, 3)).error,
            CanFrameError::kOutOfRange);
  // A command beyond the limit cannot come from encodeCommand (it clamps): hand-made 2001.
  EXPECT_EQ(decodeCommand(kProfile, withByte(encodeCommand(kProfile, 2.0, 0.0, true, false, 0), 0, 0xD1)).error,
            CanFrameError::kOutOfRange);
}

TEST(CanErrorFrames, ClassifiesBusOffRestartControllerAndAck) {
  can_frame f{};
  f.len = CAN_ERR_DLC;
  f.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  ASSERT_TRUE(isErrorFrame(f));
  CanErrorFrame e = classifyErrorFrame(f);
  EXPECT_TRUE(e.bus_off);
  EXPECT_FALSE(e.restarted);
  f.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  e = classifyErrorFrame(f);
  EXPECT_TRUE(e.restarted);
  EXPECT_FALSE(e.bus_off);
  f.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_ACK;
  e = classifyErrorFrame(f);
  EXPECT_TRUE(e.controller);
  EXPECT_TRUE(e.no_ack);
  EXPECT_FALSE(e.bus_off);
  // A data frame is not an error frame, even with an ID whose bits look like error classes.
  f.can_id = CAN_ERR_BUSOFF;
  EXPECT_FALSE(isErrorFrame(f));
  EXPECT_FALSE(classifyErrorFrame(f).bus_off);
}

TEST(CanIds, FilterListsFollowTheProfile) {
  EXPECT_EQ(baseToHostIds(kProfile), (std::array<canid_t, 3>{0x210, 0x220, 0x200}));
  EXPECT_EQ(hostToBaseIds(kProfile), (std::array<canid_t, 2>{0x110, 0x100}));
}

TEST(CounterTracker, AcceptsTheFirstFrameWhateverItsCounter) {
  CounterTracker t;
  EXPECT_FALSE(t.started());
  EXPECT_EQ(t.check(200), CanCounterVerdict::kFirst);
  EXPECT_EQ(t.check(201), CanCounterVerdict::kInSequence);
  t.reset();
  EXPECT_EQ(t.check(17), CanCounterVerdict::kFirst);  // a restarted base
  EXPECT_EQ(t.last(), 17);
}

TEST(CounterTracker, WrapsFrom255To0) {
  CounterTracker t;
  t.check(254);
  EXPECT_EQ(t.check(255), CanCounterVerdict::kInSequence);
  EXPECT_EQ(t.check(0), CanCounterVerdict::kInSequence);
  EXPECT_EQ(t.check(1), CanCounterVerdict::kInSequence);
  // A gap across the wrap: 254 -> 2 skips 255, 0, 1.
  CounterTracker u;
  u.check(254);
  EXPECT_EQ(u.check(2), CanCounterVerdict::kGap);
  EXPECT_EQ(u.lastGap(), 3);
}

TEST(CounterTracker, AcceptsAGapAndCountsTheLostFrames) {
  CounterTracker t;
  t.check(5);
  EXPECT_EQ(t.check(8), CanCounterVerdict::kGap);
  EXPECT_EQ(t.lastGap(), 2);
  EXPECT_EQ(t.last(), 8);
  EXPECT_EQ(t.check(9), CanCounterVerdict::kInSequence);
  EXPECT_EQ(t.lastGap(), 0);
  // The largest jump still ahead: 127 (126 lost).
  EXPECT_EQ(t.check(static_cast<std::uint8_t>(9 + 127)), CanCounterVerdict::kGap);
  EXPECT_EQ(t.lastGap(), 126);
}

TEST(CounterTracker, DropsDuplicatesAndReorderedFrames) {
  CounterTracker t;
  t.check(5);
  t.check(6);
  EXPECT_EQ(t.check(6), CanCounterVerdict::kStale);  // duplicate
  EXPECT_EQ(t.last(), 6);
  EXPECT_EQ(t.check(8), CanCounterVerdict::kGap);
  EXPECT_EQ(t.check(7), CanCounterVerdict::kStale);  // 7 overtaken by 8: reordered
  EXPECT_EQ(t.last(), 8);
  // Up to 128 behind is stale: 8 - 128 = 136 (mod 256).
  EXPECT_EQ(t.check(136), CanCounterVerdict::kStale);
  EXPECT_EQ(t.check(9), CanCounterVerdict::kInSequence);
  // Behind across the wrap: last 1, then 250.
  CounterTracker u;
  u.check(0);
  u.check(1);
  EXPECT_EQ(u.check(250), CanCounterVerdict::kStale);
  EXPECT_EQ(u.check(2), CanCounterVerdict::kInSequence);
}

}  // namespace
}  // namespace staa::hal
