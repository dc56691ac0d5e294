// The base I/O thread's bookkeeping for the status: the command-to-wire latency (a control
// command's stamp to the driver's hand-over of the first frame carrying it). BaseTask runs in
// lockstep on a manual time line, with the SocketCAN driver over a socketpair (the test plays
// the base on the other end) or the scripted MockBase. (Its thread's counters are the
// activity's: tests/unit/rt/test_activity.cpp.)
#include "app/staad/channels.hpp"
#include "app/staad/io_tasks.hpp"
#include "robot/robot_profile.hpp"
#include "hal/mock/mock_hal.hpp"
#include "hal/socketcan/can_codec.hpp"
#include "hal/socketcan/can_profile.hpp"
#include "hal/socketcan/socketcan_base.hpp"
#include "rt/alloc_count.hpp"

#include "shared_dir.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include <sys/socket.h>
#include <unistd.h>

namespace staa::staad {
namespace {

constexpr rt::Nanos kMs = rt::kNanosPerMilli;
constexpr rt::Nanos kUs = 1000;
constexpr rt::Nanos kControlPeriod = 33'333'333;  // 30 Hz
constexpr rt::Nanos kBasePeriod = 10 * kMs;       // 100 Hz

hal::VelocityCommand driveAt(double v, rt::Nanos stamp) {
  hal::VelocityCommand c;
  c.stamp = stamp;
  c.v = v;
  return c;
}

// The control thread's part: a command (and the same as the plan's next action) stamped `stamp`.
void publishCommand(Channels& ch, double v, rt::Nanos stamp) {
  CommandSlot& slot = ch.command.writeBuffer();
  slot.command = driveAt(v, stamp);
  slot.next = driveAt(v, stamp);
  ch.command.publish();
}

// The SocketCAN driver over a socketpair, its send stamps on a manual clock: the test sets
// the moment "sendmsg returns" apart from the cycle's `now`.
class BaseTaskOverSocketCan : public ::testing::Test {
 protected:
  void SetUp() override {
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv), 0);
    peer_fd = sv[1];
    base = std::make_unique<hal::SocketCanBase>(hal::adoptSeqPacket(sv[0]), profile, Pose2{}, &clock);
    task = std::make_unique<BaseTask>(*base, ch, kControlPeriod);
  }
  void TearDown() override { ::close(peer_fd); }

  // One base period at `now`; the driver's sends read `sent_at` off the clock.
  void cycleAt(rt::Nanos now, rt::Nanos sent_at) {
    clock.set(sent_at);
    task->step(now);
  }

  // The command frames the base received since the last call.
  std::vector<hal::CanCommand> commandsReceived() {
    std::vector<hal::CanCommand> out;
    can_frame f{};
    while (::recv(peer_fd, &f, sizeof f, MSG_DONTWAIT) == static_cast<ssize_t>(sizeof f)) {
      if (f.can_id != profile.command.id) continue;
      const hal::CanDecoded<hal::CanCommand> d = hal::decodeCommand(profile, f);
      EXPECT_TRUE(d.ok());
      out.push_back(d.value);
    }
    return out;
  }

  hal::CanProfile profile;
  rt::ManualClock clock;
  Channels ch{64};
  int peer_fd = -1;
  std::unique_ptr<hal::SocketCanBase> base;
  std::unique_ptr<BaseTask> task;
};

TEST_F(BaseTaskOverSocketCan, ACommandStampedAtTAndSentAtTPlus3500UsRecords3500Us) {
  const rt::Nanos t0 = 1000 * kMs;
  publishCommand(ch, 0.3, t0);
  cycleAt(t0 + 2 * kMs, t0 + 3500 * kUs);

  const std::vector<hal::CanCommand> sent = commandsReceived();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_DOUBLE_EQ(sent[0].v, 0.3);
  EXPECT_EQ(base->lastCommandSent().command_stamp, t0);
  EXPECT_EQ(base->lastCommandSent().sent_at, t0 + 3500 * kUs);
  const rt::TimingSummary s = task->commandToWire().summary();
  EXPECT_EQ(s.count, 1u);
  EXPECT_DOUBLE_EQ(s.p50_us, 3500.0);
  EXPECT_DOUBLE_EQ(s.p99_us, 3500.0);
  EXPECT_DOUBLE_EQ(s.max_us, 3500.0);
  EXPECT_EQ(task->commandsUnsent(), 0u);
}

TEST_F(BaseTaskOverSocketCan, EachCommandIsMeasuredOnceAtItsFirstFrameAndReplacedOnesCountAsUnsent) {
  const rt::Nanos t0 = 1000 * kMs;
  publishCommand(ch, 0.3, t0);
  cycleAt(t0 + 2 * kMs, t0 + 3500 * kUs);  // the first command frame: at once
  ASSERT_EQ(commandsReceived().size(), 1u);

  // The same command in the next base periods: repeated only on the driver's 30 Hz grid (the
  // next slot at t0 + 35.3 ms), nothing new is measured.
  cycleAt(t0 + 12 * kMs, t0 + 12 * kMs);
  cycleAt(t0 + 22 * kMs, t0 + 22 * kMs);
  EXPECT_TRUE(commandsReceived().empty());
  EXPECT_EQ(task->commandToWire().summary().count, 1u);

  // A new command goes out at the first base period after it was made, before the grid's
  // slot: 34.2 ms - 33.3 ms = 867 us.
  const rt::Nanos t1 = t0 + kControlPeriod;
  publishCommand(ch, 0.4, t1);
  cycleAt(t0 + 34 * kMs, t0 + 34200 * kUs);
  const std::vector<hal::CanCommand> second = commandsReceived();
  ASSERT_EQ(second.size(), 1u);
  EXPECT_DOUBLE_EQ(second[0].v, 0.4);
  rt::TimingSummary s = task->commandToWire().summary();
  EXPECT_EQ(s.count, 2u);
  EXPECT_DOUBLE_EQ(s.max_us, 3500.0);
  EXPECT_NEAR(s.mean_us, (3500.0 + (34200.0 - 33333.333)) / 2.0, 0.01);

  // Two commands within 3/4 of a command period of the last send (t0 + 34 ms): the first is
  // replaced before it may go out, never reaches the wire and counts as unsent; the second
  // goes out once the 25 ms have passed (t0 + 60 ms) and is measured.
  publishCommand(ch, 0.5, t0 + 40 * kMs);
  cycleAt(t0 + 42 * kMs, t0 + 42 * kMs);
  EXPECT_TRUE(commandsReceived().empty());
  publishCommand(ch, 0.6, t0 + 50 * kMs);
  cycleAt(t0 + 52 * kMs, t0 + 52 * kMs);
  EXPECT_TRUE(commandsReceived().empty());
  cycleAt(t0 + 60 * kMs, t0 + 60500 * kUs);
  const std::vector<hal::CanCommand> fourth = commandsReceived();
  ASSERT_EQ(fourth.size(), 1u);
  EXPECT_DOUBLE_EQ(fourth[0].v, 0.6);
  s = task->commandToWire().summary();
  EXPECT_EQ(s.count, 3u);
  EXPECT_EQ(task->commandsUnsent(), 1u);
  const rt::Nanos t3 = t0 + 50 * kMs;

  // The control thread falls silent: the base thread's own brake goes out at once, but it is
  // not a control command: not measured.
  cycleAt(t3 + 3 * kControlPeriod + kMs, t3 + 3 * kControlPeriod + 2 * kMs);
  ASSERT_EQ(task->source(), CommandSource::kBrake);
  const std::vector<hal::CanCommand> brake = commandsReceived();
  ASSERT_EQ(brake.size(), 1u);
  EXPECT_TRUE(brake[0].brake);
  EXPECT_EQ(task->commandToWire().summary().count, 3u);
  EXPECT_DOUBLE_EQ(task->commandToWire().summary().max_us, 10500.0);
}

// With the scripted base: 30 Hz commands, a 100 Hz base thread, a driver that takes 2 ms per
// send. Every command is measured once: the wait for the next base period plus the 2 ms; the
// whole bookkeeping allocates nothing.
TEST(BaseTaskWire, EveryControlCommandIsMeasuredOnceWithTheDriversDelayAndNothingIsAllocated) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_io_tasks must link staa_rt_alloc_hook";
  const RobotProfile robot = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  hal::MockBase base(robot, Pose2{}, 4096);
  base.setSendDelay(2 * kMs);
  Channels ch(64);
  BaseTask task(base, ch, kControlPeriod);

  rt::resetRealtimeAllocations();
  rt::markRealtimeThread(true);
  rt::Nanos next_control = 0;
  int commands = 0;
  for (rt::Nanos now = 5 * kMs; now < 10 * rt::kNanosPerSecond; now += kBasePeriod) {
    if (next_control <= now) {
      publishCommand(ch, 0.2, next_control);  // stamped at its cycle's deadline
      next_control += kControlPeriod;
      ++commands;
    }
    task.step(now);
  }
  rt::markRealtimeThread(false);
  EXPECT_EQ(rt::realtimeAllocations(), 0u);

  const rt::TimingSummary s = task.commandToWire().summary();
  EXPECT_EQ(s.count, static_cast<std::uint64_t>(commands));
  EXPECT_EQ(task.commandsUnsent(), 0u);
  EXPECT_GE(s.p50_us, 2000.0);
  EXPECT_LE(s.max_us, 12000.0);  // < a base period + the driver's 2 ms
  EXPECT_GT(s.max_us, s.p50_us);

  // A driver that never sends: nothing measured, every replaced command unsent.
  base.setSendDelay(-1);
  const std::uint64_t measured = s.count;
  for (int k = 0; k < 30; ++k) {
    publishCommand(ch, 0.2, next_control);
    next_control += kControlPeriod;
    task.step(next_control - kControlPeriod + kMs);
  }
  EXPECT_EQ(task.commandToWire().summary().count, measured);
  EXPECT_EQ(task.commandsUnsent(), 29u);  // the 30th is still the latest
}

}  // namespace
}  // namespace staa::staad
