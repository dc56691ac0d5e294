// The SocketCAN base driver over a socketpair(AF_UNIX, SOCK_SEQPACKET): the test plays the
// base on the other end, with the profile's own encoders, and steps time by hand.
#include "hal/socketcan/socketcan_base.hpp"

#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <linux/can/error.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace staa::hal {
namespace {

constexpr rt::Nanos kMs = rt::kNanosPerMilli;

std::size_t kindIndex(CanFrameError e) { return static_cast<std::size_t>(e); }

// The base's end of the link: sends the profile's base->host frames with rolling counters and
// collects what the host sent.
class FakeBase {
 public:
  FakeBase(int fd, const CanProfile& profile) : fd_(fd), profile_(profile) {}
  ~FakeBase() { close(); }
  FakeBase(const FakeBase&) = delete;
  FakeBase& operator=(const FakeBase&) = delete;

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int fd() const { return fd_; }

  // Sends raw bytes as one record; true when it went out whole.
  bool sendRaw(const void* data, std::size_t size) {
    return ::send(fd_, data, size, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(size);
  }
  bool send(const can_frame& f) { return sendRaw(&f, sizeof f); }
  bool odometry(double v, double w, std::uint16_t dt_us = 10000) {
    return send(encodeOdometry(profile_, v, w, dt_us, odo_counter++));
  }
  bool status(bool enabled = true, bool estop = false, bool fault = false, std::uint16_t code = 0) {
    return send(encodeStatus(profile_, enabled, estop, fault, code, status_counter++));
  }
  bool heartbeat(CanBaseState state = CanBaseState::kOk) {
    return send(encodeBaseHeartbeat(profile_, state, heartbeat_counter++));
  }
  bool healthy() { return status() && heartbeat(); }
  bool errorFrame(canid_t classes) {
    can_frame f{};
    f.can_id = CAN_ERR_FLAG | classes;
    f.len = CAN_ERR_DLC;
    return send(f);
  }

  // Every frame the host sent since the last call.
  std::vector<can_frame> received() {
    std::vector<can_frame> out;
    can_frame f{};
    while (::recv(fd_, &f, sizeof f, MSG_DONTWAIT) == static_cast<ssize_t>(sizeof f)) out.push_back(f);
    return out;
  }

  std::uint8_t odo_counter = 0, status_counter = 0, heartbeat_counter = 0;

 private:
  int fd_;
  CanProfile profile_;
};

std::vector<CanCommand> commandsIn(const CanProfile& p, const std::vector<can_frame>& frames) {
  std::vector<CanCommand> out;
  for (const can_frame& f : frames) {
    if (f.can_id != p.command.id) continue;
    const CanDecoded<CanCommand> d = decodeCommand(p, f);
    EXPECT_TRUE(d.ok()) << toString(d.error);
    out.push_back(d.value);
  }
  return out;
}

std::vector<CanHostHeartbeat> heartbeatsIn(const CanProfile& p, const std::vector<can_frame>& frames) {
  std::vector<CanHostHeartbeat> out;
  for (const can_frame& f : frames) {
    if (f.can_id != p.heartbeat.host_id) continue;
    const CanDecoded<CanHostHeartbeat> d = decodeHostHeartbeat(p, f);
    EXPECT_TRUE(d.ok()) << toString(d.error);
    out.push_back(d.value);
  }
  return out;
}

VelocityCommand drive(double v, double w = 0.0) {
  VelocityCommand c;
  c.v = v;
  c.w = w;
  return c;
}

VelocityCommand brake() {
  VelocityCommand c;
  c.brake = true;
  return c;
}

class SocketCanBaseTest : public ::testing::Test {
 protected:
  void SetUp() override { connect(); }

  // A fresh pair; `fill_host_buffer` fills the host's send buffer first (sends will fail).
  void connect(bool fill_host_buffer = false) {
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv), 0);
    if (fill_host_buffer) {
      const can_frame junk = encodeBaseHeartbeat(profile, CanBaseState::kOk, 0);
      int sent = 0;
      while (::send(sv[0], &junk, sizeof junk, MSG_DONTWAIT) == static_cast<ssize_t>(sizeof junk)) ++sent;
      ASSERT_GT(sent, 0);
    }
    peer = std::make_unique<FakeBase>(sv[1], profile);
    base = std::make_unique<SocketCanBase>(adoptSeqPacket(sv[0]), profile);
  }

  void readAt(rt::Nanos t) {
    now = t;
    base->read(now);
  }

  CanProfile profile;
  std::unique_ptr<FakeBase> peer;
  std::unique_ptr<SocketCanBase> base;
  rt::Nanos now = 0;
};

// ---- odometry ----

TEST_F(SocketCanBaseTest, DrivingHalfAMetrePerSecondForTwoSecondsReachesOneMetre) {
  for (int k = 1; k <= 200; ++k) {
    ASSERT_TRUE(peer->odometry(0.5, 0.0));
    if (k % 5 == 0) {
      ASSERT_TRUE(peer->healthy());
    }
    readAt(k * 10 * kMs);
  }
  const Odometry o = base->odometry();
  EXPECT_NEAR(o.pose.x, 1.0, 1e-9);
  EXPECT_NEAR(o.pose.y, 0.0, 1e-12);
  EXPECT_NEAR(o.pose.theta, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(o.v, 0.5);
  EXPECT_EQ(o.w, 0.0);
  EXPECT_EQ(o.stamp, 2000 * kMs);  // no kernel stamps on a socketpair: read()'s now
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_TRUE(base->status().enabled);
  EXPECT_EQ(base->counters().frames_rx, 280u);
  EXPECT_EQ(base->counters().badFrames(), 0u);
  EXPECT_EQ(base->counters().counter_gaps, 0u);
}

TEST_F(SocketCanBaseTest, IntegratesAnArcFromTheAnchoredPose) {
  const Pose2 start{2.0, 3.0, kPi / 2};
  ASSERT_TRUE(base->setPose(start));
  // 1 m/s at 1.5 rad/s for 1 s: a circle of radius 2/3 about (2 - 2/3, 3).
  for (int k = 1; k <= 100; ++k) {
    ASSERT_TRUE(peer->odometry(1.0, 1.5));
    readAt(k * 10 * kMs);
  }
  const double r = 1.0 / 1.5, theta = kPi / 2 + 1.5;
  const Pose2 p = base->odometry().pose;
  EXPECT_NEAR(p.x, start.x + r * (std::sin(theta) - std::sin(start.theta)), 1e-9);
  EXPECT_NEAR(p.y, start.y - r * (std::cos(theta) - std::cos(start.theta)), 1e-9);
  EXPECT_NEAR(p.theta, theta, 1e-9);
  // Re-anchoring keeps integrating from the new pose.
  ASSERT_TRUE(base->setPose({0.0, 0.0, 0.0}));
  ASSERT_TRUE(peer->odometry(1.0, 0.0));
  readAt(1010 * kMs);
  EXPECT_NEAR(base->odometry().pose.x, 0.01, 1e-12);
}

TEST_F(SocketCanBaseTest, CorruptedOdometryFramesNeitherMoveThePoseNorAdvanceTheStamp) {
  ASSERT_TRUE(peer->odometry(0.5, 0.0));
  readAt(10 * kMs);
  const Odometry before = base->odometry();
  ASSERT_NEAR(before.pose.x, 0.005, 1e-12);

  can_frame checksum = encodeOdometry(profile, 2.0, 0.0, 10000, 1);
  checksum.data[1] ^= 0x02;  // a bit flipped on the bus
  can_frame dlc = encodeOdometry(profile, 2.0, 0.0, 10000, 1);
  dlc.len = 6;
  can_frame eff = encodeOdometry(profile, 2.0, 0.0, 10000, 1);
  eff.can_id |= CAN_EFF_FLAG;
  const can_frame fast = encodeOdometry(profile, 2.5, 0.0, 10000, 1);  // > v_limit
  const can_frame no_dt = encodeOdometry(profile, 2.0, 0.0, 0, 1);
  const unsigned char short_record[10] = {0x10, 0x02, 0, 0, 8, 0, 0, 0, 0xD0, 0x07};
  unsigned char long_record[24] = {};
  std::memcpy(long_record, &fast, sizeof fast);
  ASSERT_TRUE(peer->send(checksum));
  ASSERT_TRUE(peer->send(dlc));
  ASSERT_TRUE(peer->send(eff));
  ASSERT_TRUE(peer->send(fast));
  ASSERT_TRUE(peer->send(no_dt));
  ASSERT_TRUE(peer->sendRaw(short_record, sizeof short_record));
  ASSERT_TRUE(peer->sendRaw(long_record, sizeof long_record));
  ASSERT_TRUE(peer->sendRaw(long_record, 0));  // an empty record
  readAt(20 * kMs);

  const Odometry after = base->odometry();
  EXPECT_EQ(after.pose.x, before.pose.x);
  EXPECT_EQ(after.v, 0.5);
  EXPECT_EQ(after.stamp, 10 * kMs);
  const SocketCanCounters& c = base->counters();
  EXPECT_EQ(c.bad_by_kind[kindIndex(CanFrameError::kBadChecksum)], 1u);
  EXPECT_EQ(c.bad_by_kind[kindIndex(CanFrameError::kWrongDlc)], 1u);
  EXPECT_EQ(c.bad_by_kind[kindIndex(CanFrameError::kWrongId)], 1u);
  EXPECT_EQ(c.bad_by_kind[kindIndex(CanFrameError::kOutOfRange)], 2u);
  EXPECT_EQ(c.bad_by_kind[kindIndex(CanFrameError::kWrongSize)], 3u);
  EXPECT_EQ(c.badFrames(), 8u);
  EXPECT_EQ(base->status().bad_frames, 8u);
  EXPECT_EQ(c.frames_rx, 9u);
  // The link still works: the next good frame (counter 1) is in sequence.
  ASSERT_TRUE(peer->odometry(0.5, 0.0));
  readAt(30 * kMs);
  EXPECT_NEAR(base->odometry().pose.x, 0.010, 1e-12);
  EXPECT_EQ(base->counters().counter_gaps, 0u);
}

TEST_F(SocketCanBaseTest, DuplicatedAndReorderedOdometryIsDroppedAndAGapIsBridged) {
  const auto odo = [&](std::uint8_t counter) { return peer->send(encodeOdometry(profile, 0.5, 0.0, 10000, counter)); };
  ASSERT_TRUE(odo(0));
  ASSERT_TRUE(odo(1));
  ASSERT_TRUE(odo(1));  // duplicate
  ASSERT_TRUE(odo(3));  // 2 lost... or late
  ASSERT_TRUE(odo(2));  // late: overtaken by 3
  readAt(50 * kMs);
  // Frames 0, 1 and 3; 3 also covers the lost 2's step: 0.5 m/s * 10 ms * (1 + 1 + 2).
  EXPECT_NEAR(base->odometry().pose.x, 0.02, 1e-12);
  EXPECT_EQ(base->counters().stale_frames, 2u);
  EXPECT_EQ(base->counters().counter_gaps, 1u);
  EXPECT_EQ(base->counters().badFrames(), 0u);  // stale frames are well-formed, counted apart
}

TEST_F(SocketCanBaseTest, CounterWrapFrom255To0IsInSequence) {
  peer->odo_counter = 250;
  for (int k = 1; k <= 10; ++k) {
    ASSERT_TRUE(peer->odometry(0.5, 0.0));
    readAt(k * 10 * kMs);
  }
  EXPECT_EQ(peer->odo_counter, 4);
  EXPECT_NEAR(base->odometry().pose.x, 0.05, 1e-12);
  EXPECT_EQ(base->counters().counter_gaps, 0u);
  EXPECT_EQ(base->counters().stale_frames, 0u);
}

TEST_F(SocketCanBaseTest, ARestartedBaseCountsAnewAfterASilence) {
  peer->odo_counter = 100;
  ASSERT_TRUE(peer->odometry(0.5, 0.0));
  readAt(10 * kMs);
  // The base reboots (silent longer than odometry.timeout_s) and starts again at 0, which
  // would otherwise be 100 behind: stale.
  peer->odo_counter = 0;
  ASSERT_TRUE(peer->odometry(0.5, 0.0));
  readAt(500 * kMs);
  EXPECT_EQ(base->odometry().stamp, 500 * kMs);
  EXPECT_EQ(base->counters().stale_frames, 0u);
  // Without the silence, a jump back is stale.
  ASSERT_TRUE(peer->send(encodeOdometry(profile, 0.5, 0.0, 10000, 200)));
  readAt(510 * kMs);
  EXPECT_EQ(base->counters().stale_frames, 1u);
  EXPECT_EQ(base->odometry().stamp, 500 * kMs);
}

// ---- faults ----

TEST_F(SocketCanBaseTest, SilenceRaisesHeartbeatLostAndFramesClearIt) {
  readAt(0);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);  // the timeouts count from the first read
  EXPECT_FALSE(base->status().enabled);               // nothing heard yet
  readAt(250 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kHeartbeatLost);

  ASSERT_TRUE(peer->healthy());
  readAt(260 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_TRUE(base->status().enabled);
  EXPECT_EQ(base->status().stamp, 260 * kMs);

  // Status keeps coming, heartbeats stop (timeout 0.3 s after 260 ms).
  for (rt::Nanos t = 300 * kMs; t <= 550 * kMs; t += 50 * kMs) {
    ASSERT_TRUE(peer->status());
    readAt(t);
    EXPECT_EQ(base->status().fault, BaseFault::kNone) << "at " << t / kMs << " ms";
  }
  ASSERT_TRUE(peer->status());
  readAt(570 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kHeartbeatLost);
  EXPECT_FALSE(base->status().enabled);
  ASSERT_TRUE(peer->heartbeat());
  readAt(580 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);

  // Heartbeats keep coming, status stops (timeout 0.2 s after the 570 ms one).
  ASSERT_TRUE(peer->heartbeat());
  readAt(700 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  ASSERT_TRUE(peer->heartbeat());
  readAt(780 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kHeartbeatLost);
  ASSERT_TRUE(peer->status());
  readAt(790 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
}

TEST_F(SocketCanBaseTest, EmergencyStopRaisesTheFaultAndDisablesTheCommands) {
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  base->write(now, drive(0.4));
  ASSERT_TRUE(commandsIn(profile, peer->received()).at(0).enable);

  ASSERT_TRUE(peer->status(true, true));
  readAt(20 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kEmergencyStop);
  EXPECT_TRUE(base->status().enabled);  // what the base says
  base->write(50 * kMs, drive(0.4));
  const std::vector<can_frame> sent = peer->received();
  const std::vector<CanCommand> cmds = commandsIn(profile, sent);
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_FALSE(cmds[0].enable);
  EXPECT_DOUBLE_EQ(cmds[0].v, 0.4);

  ASSERT_TRUE(peer->status(true, false));
  readAt(60 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  base->write(100 * kMs, drive(0.4));
  EXPECT_TRUE(commandsIn(profile, peer->received()).at(0).enable);
}

TEST_F(SocketCanBaseTest, DriveFaultReportsItsCodeAndYieldsToTheEmergencyStop) {
  ASSERT_TRUE(peer->heartbeat());
  ASSERT_TRUE(peer->status(false, false, true, 0x2310));
  readAt(10 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kDriverFault);
  EXPECT_EQ(base->status().fault_code, 0x2310u);
  EXPECT_FALSE(base->status().enabled);

  ASSERT_TRUE(peer->status(false, true, true, 0x2310));
  readAt(20 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kEmergencyStop);
  EXPECT_EQ(base->status().fault_code, 0u);

  ASSERT_TRUE(peer->status(true, false, false, 0));
  readAt(30 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_EQ(base->status().fault_code, 0u);

  // The base's heartbeat saying "fault" is a drive fault too.
  ASSERT_TRUE(peer->heartbeat(CanBaseState::kFault));
  readAt(40 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kDriverFault);
  ASSERT_TRUE(peer->heartbeat(CanBaseState::kOk));
  readAt(50 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
}

TEST_F(SocketCanBaseTest, BusOffSendsOnlyStopProbesUntilTheControllerRestarts) {
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  ASSERT_TRUE(peer->errorFrame(CAN_ERR_BUSOFF));
  readAt(20 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);
  EXPECT_FALSE(base->status().enabled);
  EXPECT_EQ(base->status().error_frames, 1u);
  EXPECT_EQ(base->counters().bus_off_events, 1u);

  // One stop command per recovery interval (1 s), nothing else (no heartbeat).
  base->write(20 * kMs, drive(0.5));
  std::vector<can_frame> sent = peer->received();
  ASSERT_EQ(sent.size(), 1u);
  std::vector<CanCommand> cmds = commandsIn(profile, sent);
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_TRUE(cmds[0].brake);
  EXPECT_FALSE(cmds[0].enable);
  EXPECT_EQ(cmds[0].v, 0.0);
  EXPECT_EQ(cmds[0].w, 0.0);
  for (rt::Nanos t = 30 * kMs; t < 1020 * kMs; t += 10 * kMs) base->write(t, drive(0.5));
  EXPECT_TRUE(peer->received().empty());
  base->write(1020 * kMs, drive(0.5));
  EXPECT_EQ(commandsIn(profile, peer->received()).size(), 1u);

  ASSERT_TRUE(peer->errorFrame(CAN_ERR_RESTARTED));
  ASSERT_TRUE(peer->healthy());
  readAt(1030 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_EQ(base->counters().recoveries, 1u);
  EXPECT_EQ(base->counters().error_frames, 2u);
  base->write(1030 * kMs, drive(0.5));
  cmds = commandsIn(profile, peer->received());
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_TRUE(cmds[0].enable);
  EXPECT_DOUBLE_EQ(cmds[0].v, 0.5);
}

TEST_F(SocketCanBaseTest, BusOffEndsWhenValidFramesArriveAgain) {
  ASSERT_TRUE(peer->healthy());
  ASSERT_TRUE(peer->errorFrame(CAN_ERR_BUSOFF));
  readAt(10 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);
  // Controller and ACK errors are counted, not faults; a corrupted frame does not end bus-off.
  ASSERT_TRUE(peer->errorFrame(CAN_ERR_CRTL | CAN_ERR_ACK));
  can_frame bad = encodeStatus(profile, true, false, false, 0, peer->status_counter);
  bad.data[7] ^= 0xFF;
  ASSERT_TRUE(peer->send(bad));
  readAt(20 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);
  ASSERT_TRUE(peer->healthy());
  readAt(30 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_EQ(base->counters().bus_off_events, 1u);
  EXPECT_EQ(base->counters().recoveries, 1u);
  EXPECT_EQ(base->counters().error_frames, 2u);
}

TEST_F(SocketCanBaseTest, PeerHangUpIsBusOffForGood) {
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  base->write(now, drive(0.5));
  peer->close();
  readAt(20 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);
  EXPECT_EQ(base->counters().bus_off_events, 1u);
  const std::uint64_t tx = base->counters().frames_tx;
  for (rt::Nanos t = 30 * kMs; t < 3000 * kMs; t += 10 * kMs) {
    base->write(t, drive(0.5));
    readAt(t);
  }
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);  // a socketpair cannot come back
  EXPECT_EQ(base->counters().frames_tx, tx);
  EXPECT_EQ(base->counters().bus_off_events, 1u);
}

TEST_F(SocketCanBaseTest, SendingIntoAClosedPeerIsBusOff) {
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  peer->close();
  base->write(20 * kMs, drive(0.5));  // EPIPE before any read noticed
  EXPECT_EQ(base->status().fault, BaseFault::kBusOff);
  EXPECT_EQ(base->counters().write_failures, 0u);
}

TEST_F(SocketCanBaseTest, AFullSendBufferRaisesWriteFailedUntilASendSucceeds) {
  connect(/*fill_host_buffer=*/true);
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  base->write(now, drive(0.5));
  EXPECT_EQ(base->status().fault, BaseFault::kWriteFailed);
  EXPECT_GE(base->counters().write_failures, 1u);
  EXPECT_EQ(base->counters().frames_tx, 0u);
  // A failed command is retried at the next write, not held back by the rate.
  base->write(now + kMs, drive(0.5));
  EXPECT_GE(base->counters().write_failures, 2u);

  const std::size_t junk = peer->received().size();  // the base drains: room again
  ASSERT_GT(junk, 100u);
  base->write(now + 2 * kMs, drive(0.5));
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  const std::vector<CanCommand> cmds = commandsIn(profile, peer->received());
  ASSERT_EQ(cmds.size(), 1u);
  EXPECT_TRUE(cmds[0].enable);
  EXPECT_EQ(cmds[0].counter, 0);  // the failed attempts used no counter value
}

// ---- commands ----

TEST_F(SocketCanBaseTest, CommandsGoOutAtTheCommandRateAndHeartbeatsAtTheirRate) {
  std::vector<rt::Nanos> command_times;
  std::vector<can_frame> frames;
  for (rt::Nanos t = 0; t < 1000 * kMs; t += kMs) {
    if (t % (20 * kMs) == 0) {
      ASSERT_TRUE(peer->healthy());
      readAt(t);
    }
    base->write(t, drive(0.3, -0.2));
    for (const can_frame& f : peer->received()) {
      if (f.can_id == profile.command.id) command_times.push_back(t);
      frames.push_back(f);
    }
  }
  // 30 Hz on a grid of 1/30 s: 0, 34, 67, 100, ... with 1 ms steps (each send at the first
  // step on or after its slot: gaps of 33 or 34 ms, 30 in the second).
  ASSERT_EQ(command_times.size(), 30u);
  for (std::size_t k = 1; k < command_times.size(); ++k) {
    EXPECT_GE(command_times[k] - command_times[k - 1], 33 * kMs) << k;
    EXPECT_LE(command_times[k] - command_times[k - 1], 34 * kMs) << k;
    EXPECT_GE(command_times[k], static_cast<rt::Nanos>(k) * 33'333'333) << k;  // never ahead of its slot
  }
  const std::vector<CanCommand> cmds = commandsIn(profile, frames);
  for (std::size_t k = 0; k < cmds.size(); ++k) {
    EXPECT_EQ(cmds[k].counter, k);
    EXPECT_DOUBLE_EQ(cmds[k].v, 0.3);
    EXPECT_DOUBLE_EQ(cmds[k].w, -0.2);
    EXPECT_TRUE(cmds[k].enable);
    EXPECT_FALSE(cmds[k].brake);
  }
  const std::vector<CanHostHeartbeat> beats = heartbeatsIn(profile, frames);
  ASSERT_EQ(beats.size(), 10u);  // 10 Hz
  for (std::size_t k = 0; k < beats.size(); ++k) {
    EXPECT_EQ(beats[k].counter, k);
    EXPECT_EQ(beats[k].state, CanHostState::kDriving);
  }
  EXPECT_EQ(base->counters().frames_tx, 40u);
}

TEST_F(SocketCanBaseTest, ABaseLoopOf10MsStillSendsThirtyCommandsASecond) {
  // The base I/O thread's period (100 Hz) does not divide the command period: a grid keeps
  // 30 Hz (a "one period since the last send" rule gives 25 Hz: 40 ms gaps).
  int commands = 0;
  for (rt::Nanos t = 0; t < 3000 * kMs; t += 10 * kMs) {
    if (t % (20 * kMs) == 0) {
      ASSERT_TRUE(peer->healthy());
      readAt(t);
    }
    base->write(t, drive(0.3, -0.2));
    for (const can_frame& f : peer->received()) commands += f.can_id == profile.command.id ? 1 : 0;
  }
  EXPECT_EQ(commands, 90);
}

TEST_F(SocketCanBaseTest, ANewCommandGoesOutAtTheNextWriteNotAtTheNextSendSlot) {
  // The control thread's commands (30 Hz, each with its own stamp) seen by a 100 Hz base
  // loop: each goes on the wire at the first write after it was made, within one base period.
  constexpr rt::Nanos kControl = 33'333'333;
  std::vector<rt::Nanos> delays;
  int current = -1;
  int sent = 0;
  for (rt::Nanos t = 0; t < 3000 * kMs; t += 10 * kMs) {
    if (t % (20 * kMs) == 0) {
      ASSERT_TRUE(peer->healthy());
      readAt(t);
    }
    const int k = static_cast<int>(t / kControl);  // the newest command at t
    VelocityCommand c = drive(0.01 * (k % 50), 0.0);
    c.stamp = k * kControl;
    base->write(t, c);
    for (const can_frame& f : peer->received()) {
      if (f.can_id != profile.command.id) continue;
      ++sent;
      if (k != current) {
        delays.push_back(t - c.stamp);
        current = k;
      }
    }
  }
  ASSERT_EQ(delays.size(), 90u);  // every command of the 3 s went out
  for (const rt::Nanos d : delays) EXPECT_LT(d, 10 * kMs);
  EXPECT_LE(sent, 90 + 3);  // and nothing more than the commands (the odd repeat at most)
}

TEST_F(SocketCanBaseTest, BrakeAndStopGoOutAtOnce) {
  ASSERT_TRUE(peer->healthy());
  readAt(0);
  const auto commandsAt = [&](rt::Nanos t, const VelocityCommand& c) {
    base->write(t, c);
    return commandsIn(profile, peer->received());
  };
  ASSERT_EQ(commandsAt(0, drive(0.5)).size(), 1u);
  // A brake starting 5 ms later does not wait for the rate.
  std::vector<CanCommand> c = commandsAt(5 * kMs, brake());
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(c[0].brake);
  EXPECT_EQ(c[0].v, 0.0);
  EXPECT_TRUE(c[0].enable);
  EXPECT_TRUE(commandsAt(10 * kMs, brake()).empty());  // still braking: at the rate
  EXPECT_EQ(commandsAt(40 * kMs, brake()).size(), 1u);
  EXPECT_TRUE(commandsAt(45 * kMs, drive(0.5)).empty());  // starting to move is not urgent
  ASSERT_EQ(commandsAt(80 * kMs, drive(0.5)).size(), 1u);
  // Motion to zero (no brake) goes at once too.
  c = commandsAt(85 * kMs, drive(0.0, 0.0));
  ASSERT_EQ(c.size(), 1u);
  EXPECT_FALSE(c[0].brake);
  EXPECT_EQ(c[0].v, 0.0);
  EXPECT_TRUE(commandsAt(90 * kMs, drive(0.0, 0.0)).empty());
  // A non-finite command is a brake.
  ASSERT_EQ(commandsAt(130 * kMs, drive(0.5)).size(), 1u);
  c = commandsAt(131 * kMs, drive(std::numeric_limits<double>::quiet_NaN()));
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(c[0].brake);
  EXPECT_EQ(c[0].v, 0.0);
}

TEST_F(SocketCanBaseTest, BadStatusFramesAreCountedAndNotActedOn) {
  ASSERT_TRUE(peer->healthy());
  readAt(10 * kMs);
  // Emergency stop in frames that are not well-formed: ignored.
  can_frame bad_sum = encodeStatus(profile, true, true, false, 0, peer->status_counter);
  bad_sum.data[7] ^= 0x01;
  can_frame reserved = encodeStatus(profile, true, true, false, 0, peer->status_counter);
  reserved.data[3] = 0x01;
  reserved.data[7] = canChecksum(reserved);
  can_frame unknown = encodeStatus(profile, true, true, false, 0, peer->status_counter);
  unknown.can_id = 0x221;
  unknown.data[7] = canChecksum(unknown);
  ASSERT_TRUE(peer->send(bad_sum));
  ASSERT_TRUE(peer->send(reserved));
  ASSERT_TRUE(peer->send(unknown));
  readAt(20 * kMs);
  const BaseStatus s = base->status();
  EXPECT_EQ(s.fault, BaseFault::kNone);
  EXPECT_EQ(s.bad_frames, 3u);
  EXPECT_EQ(base->counters().bad_by_kind[kindIndex(CanFrameError::kBadChecksum)], 1u);
  EXPECT_EQ(base->counters().bad_by_kind[kindIndex(CanFrameError::kReservedBits)], 1u);
  EXPECT_EQ(base->counters().bad_by_kind[kindIndex(CanFrameError::kWrongId)], 1u);
  // A status frame repeated with an old counter is stale: its estop bit is ignored too.
  ASSERT_TRUE(peer->send(encodeStatus(profile, true, true, false, 0, static_cast<std::uint8_t>(peer->status_counter - 1))));
  readAt(30 * kMs);
  EXPECT_EQ(base->status().fault, BaseFault::kNone);
  EXPECT_EQ(base->counters().stale_frames, 1u);
}

// ---- real-time ----

TEST_F(SocketCanBaseTest, ReadAndWriteAllocateNothingOverThousandsOfCycles) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_socketcan_base must link staa_rt_alloc_hook";
  {  // the counter counts (a direct call: a new-expression could be elided)
    rt::AllocationScope probe;
    ::operator delete(::operator new(16));
    ASSERT_EQ(probe.count(), 1u);
  }
  ASSERT_TRUE(peer->healthy());
  readAt(0);
  base->write(0, drive(0.5));
  peer->received();

  can_frame corrupt = encodeOdometry(profile, 0.5, 0.0, 10000, 0);
  corrupt.data[0] ^= 0x40;
  const unsigned char short_record[5] = {1, 2, 3, 4, 5};
  can_frame sink[64];
  std::size_t faults_seen = 0;
  rt::AllocationScope scope;
  for (int k = 1; k <= 5000; ++k) {
    const rt::Nanos t = k * 10 * kMs;
    peer->odometry(0.5, 0.1);
    if (k % 2 == 0) peer->status(true, k % 700 == 0, k % 900 == 0, 42);
    if (k % 10 == 0) peer->heartbeat();
    if (k % 97 == 0) peer->send(corrupt);
    if (k % 101 == 0) peer->sendRaw(short_record, sizeof short_record);
    if (k % 1000 == 0) peer->errorFrame(CAN_ERR_BUSOFF);
    if (k % 1000 == 5) peer->errorFrame(CAN_ERR_RESTARTED);
    base->read(t);
    base->write(t, k % 50 < 3 ? brake() : drive(0.5, 0.1));
    faults_seen += base->status().fault != BaseFault::kNone;
    (void)base->odometry();
    // The base's side drains what the host sent, without allocating either.
    while (::recv(peer->fd(), sink, sizeof sink, MSG_DONTWAIT) > 0) {
    }
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_GT(faults_seen, 0u);
  EXPECT_EQ(base->counters().bus_off_events, 5u);
  EXPECT_GT(base->counters().badFrames(), 90u);
  EXPECT_NEAR(base->odometry().v, 0.5, 1e-12);
}

// ---- transports ----

TEST(CanTransport, SeqpacketRecordsOfTheWrongSizeAreBadAndHangUpIsGone) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sv), 0);
  CanTransport t = adoptSeqPacket(sv[0], "pair");
  EXPECT_EQ(t.kind(), CanTransportKind::kSeqPacket);
  EXPECT_FALSE(t.canReconnect());
  CanRxFrame rx;
  EXPECT_EQ(t.receive(rx), CanIo::kWouldBlock);  // non-blocking though adopted blocking

  const can_frame f = encodeOdometry(CanProfile{}, 0.5, 0.0, 10000, 1);
  ASSERT_EQ(::send(sv[1], &f, sizeof f, 0), 16);
  ASSERT_EQ(t.receive(rx), CanIo::kOk);
  EXPECT_EQ(std::memcmp(&rx.frame, &f, sizeof f), 0);
  EXPECT_EQ(rx.stamp, -1);
  unsigned char big[17] = {};
  ASSERT_EQ(::send(sv[1], big, sizeof big, 0), 17);
  ASSERT_EQ(::send(sv[1], big, 15, 0), 15);
  EXPECT_EQ(t.receive(rx), CanIo::kBadRecord);
  EXPECT_EQ(t.receive(rx), CanIo::kBadRecord);

  ASSERT_EQ(t.send(f), CanIo::kOk);
  can_frame back{};
  ASSERT_EQ(::recv(sv[1], &back, sizeof back, 0), 16);
  EXPECT_EQ(std::memcmp(&back, &f, sizeof f), 0);

  ::close(sv[1]);
  EXPECT_EQ(t.receive(rx), CanIo::kGone);
  EXPECT_EQ(t.send(f), CanIo::kGone);
}

TEST(CanTransport, AdoptingSomethingElseThanASeqpacketSocketThrows) {
  int p[2];
  ASSERT_EQ(::pipe(p), 0);
  ::close(p[1]);
  EXPECT_THROW(adoptSeqPacket(p[0], "a pipe"), CanTransportError);
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
  ::close(sv[1]);
  try {
    adoptSeqPacket(sv[0], "stream");
    FAIL() << "adopted a stream socket";
  } catch (const CanTransportError& e) {
    EXPECT_EQ(std::string(e.what()), "stream: not a SOCK_SEQPACKET socket");
  }
}

TEST(CanTransport, OpeningCan0WithoutCanSupportNamesCan0) {
  try {
    CanTransport t = openCanTransport("can0", CanProfile{});
    GTEST_SKIP() << "can0 opened: this machine has CAN";
  } catch (const CanTransportError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("can0: ", 0), 0u) << msg;
    EXPECT_GT(msg.size(), 20u) << msg;
  }
  // An interface that cannot exist: named, whatever the kernel has.
  try {
    CanTransport t = openCanTransport("nosuchcan7", CanProfile{});
    FAIL() << "opened nosuchcan7";
  } catch (const CanTransportError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("nosuchcan7: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(openCanTransport("an-interface-name-too-long", CanProfile{}), CanTransportError);
}

TEST(CanTransport, AMissingSocketPathIsAClearError) {
  try {
    CanTransport t = openCanTransport("unix:/nonexistent/staa-base.sock", CanProfile{});
    FAIL() << "connected to a missing socket";
  } catch (const CanTransportError& e) {
    EXPECT_EQ(std::string(e.what()),
              "unix:/nonexistent/staa-base.sock: cannot connect: no socket at /nonexistent/staa-base.sock (is the "
              "base simulator running?)");
  }
}

// A listening seqpacket socket in a fresh temporary directory.
class Listener {
 public:
  Listener() {
    char dir[] = "/tmp/staa-can-XXXXXX";
    if (::mkdtemp(dir) == nullptr) return;
    dir_ = dir;
    path_ = dir_ + "/base.sock";
    fd_ = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof addr.sun_path - 1);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd_, 4) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~Listener() {
    if (fd_ >= 0) ::close(fd_);
    if (!path_.empty()) ::unlink(path_.c_str());
    if (!dir_.empty()) ::rmdir(dir_.c_str());
  }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;
  bool ok() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  // The next pending connection, or -1.
  int accept() {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 1000) <= 0) return -1;
    return ::accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  }

 private:
  int fd_ = -1;
  std::string dir_, path_;
};

TEST(SocketCanBaseUnixPath, ReconnectsAfterTheBaseRestarts) {
  Listener listener;
  ASSERT_TRUE(listener.ok());
  const CanProfile profile;
  SocketCanBase base(openCanTransport("unix:" + listener.path(), profile), profile);
  EXPECT_TRUE(base.transport().canReconnect());
  EXPECT_EQ(base.transport().name(), "unix:" + listener.path());
  {
    FakeBase first(listener.accept(), profile);
    ASSERT_GE(first.fd(), 0);
    ASSERT_TRUE(first.healthy());
    base.read(10 * kMs);
    EXPECT_EQ(base.status().fault, BaseFault::kNone);
  }  // the simulated base exits
  base.read(20 * kMs);
  EXPECT_EQ(base.status().fault, BaseFault::kBusOff);
  base.read(30 * kMs);  // reconnects (the first attempt is immediate)
  FakeBase second(listener.accept(), profile);
  ASSERT_GE(second.fd(), 0);
  EXPECT_EQ(base.status().fault, BaseFault::kBusOff);  // until the base speaks
  ASSERT_TRUE(second.healthy());
  base.read(40 * kMs);
  EXPECT_EQ(base.status().fault, BaseFault::kNone);
  EXPECT_EQ(base.counters().recoveries, 1u);
  base.write(40 * kMs, drive(0.2));
  EXPECT_EQ(commandsIn(profile, second.received()).size(), 1u);
}

// ---- vcan (skipped without a vcan0) ----

rt::Nanos monotonicNow() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<rt::Nanos>(ts.tv_sec) * rt::kNanosPerSecond + ts.tv_nsec;
}

TEST(SocketCanVcan, HostAndBaseExchangeFramesOverVcan0) {
  const CanProfile profile;
  std::unique_ptr<CanTransport> base_side;
  std::unique_ptr<SocketCanBase> host;
  try {
    base_side = std::make_unique<CanTransport>(openSocketCan("vcan0", hostToBaseIds(profile)));
    host = std::make_unique<SocketCanBase>(openCanTransport("vcan0", profile), profile);
  } catch (const CanTransportError& e) {
    GTEST_SKIP() << "no vcan0 (kernel without CAN or vcan not set up: ip link add dev vcan0 type vcan): " << e.what();
  }
  const rt::Nanos start = monotonicNow();
  ASSERT_EQ(base_side->send(encodeOdometry(profile, 0.5, 0.0, 10000, 0)), CanIo::kOk);
  ASSERT_EQ(base_side->send(encodeStatus(profile, true, false, false, 0, 0)), CanIo::kOk);
  ASSERT_EQ(base_side->send(encodeBaseHeartbeat(profile, CanBaseState::kOk, 0)), CanIo::kOk);
  for (int k = 0; k < 100 && host->counters().frames_rx < 3; ++k) {
    ::usleep(1000);
    host->read(monotonicNow());
  }
  ASSERT_EQ(host->counters().frames_rx, 3u);
  const Odometry o = host->odometry();
  EXPECT_NEAR(o.pose.x, 0.005, 1e-12);
  // The kernel's receive stamp, on the monotonic clock.
  EXPECT_GE(o.stamp, start - 10 * kMs);
  EXPECT_LE(o.stamp, monotonicNow());
  EXPECT_EQ(host->status().fault, BaseFault::kNone);

  host->write(monotonicNow(), drive(0.3));
  CanRxFrame rx;
  bool got = false;
  for (int k = 0; k < 100 && !got; ++k) {
    while (base_side->receive(rx) == CanIo::kOk) got = got || rx.frame.can_id == profile.command.id;
    if (!got) ::usleep(1000);
  }
  ASSERT_TRUE(got);
  const CanDecoded<CanCommand> cmd = decodeCommand(profile, rx.frame);
  ASSERT_TRUE(cmd.ok());
  EXPECT_DOUBLE_EQ(cmd.value.v, 0.3);
  EXPECT_GE(rx.stamp, start - 10 * kMs);
}

}  // namespace
}  // namespace staa::hal
