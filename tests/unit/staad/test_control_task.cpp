// staad's control, base and perception tasks in lockstep: one test thread plays all three
// threads on a manual time line (base at 100 Hz, perception and control at 30 Hz), with the
// scripted HAL (hal::MockBase integrates the commands as a perfect unicycle) on the office map
// with the paper's agent and an expansion budget, so every run is the same. The requests come
// in through the same ring the service thread fills.
#include "app/staad/channels.hpp"
#include "app/staad/config.hpp"
#include "app/staad/control_task.hpp"
#include "app/staad/io_tasks.hpp"
#include "app/staad/run_picture.hpp"
#include "app/staad/telemetry.hpp"
#include "geometry/polygon.hpp"
#include "hal/mock/mock_hal.hpp"
#include "map/polygon_map.hpp"
#include "record/replay.hpp"
#include "rt/alloc_count.hpp"

#include "shared_dir.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

namespace staa::staad {
namespace {

constexpr rt::Nanos kMs = rt::kNanosPerMilli;

DaemonConfig officeConfig(std::uint32_t expansions = 300) {
  DaemonConfig c;
  c.robot_file = test::sourceDir() / "config/robots/paper-agent.yaml";
  c.robot = loadRobotProfile(c.robot_file);
  c.map_file = test::sourceDir() / "config/maps/office.yaml";
  c.map = loadPolygonMap(c.map_file);
  c.control_hz = 30.0;
  c.base_hz = 100.0;
  c.perception_hz = 30.0;
  c.budget = BudgetSpec::expansionsOf(expansions);  // deterministic
  c.control.rate_hz = 30.0;
  c.odometry_timeout_s = 0.1;
  c.obstacles_timeout_s = 0.2;
  c.telemetry_path = "telemetry.csv";  // on: the task pushes records (the file is the service's)
  return c;
}

// The corridor along the office's south rooms: 3 m wide, straight.
const Pose2 kStart{4.5, 4.5, 0.0};
const Pose2 kGoal{8.5, 4.5, 0.0};
const Pose2 kGoal2{7.0, 4.0, 3.14};

class Lockstep {
 public:
  // recorder_bytes: the flight recorder's ring (0: off).
  explicit Lockstep(const DaemonConfig& c, const Pose2& start = kStart, std::size_t recorder_bytes = 0)
      : config(c),
        ch(1024, recorder_bytes),
        base(c.robot, start),
        task(c, ch, clock),
        base_task(base, ch, task.period()),
        perception(sensor, ch),
        control_period(task.period()) {
    next_control = control_period;
  }

  // One control period: the base and perception ticks up to the next control deadline,
  // then (unless paused) the control cycle. The service's part: the rings are drained.
  void step() {
    const rt::Nanos target = next_control;
    while (next_base <= target || next_perception <= target) {
      if (next_base <= next_perception) {
        now = next_base;
        base_task.step(now);
        next_base += kBasePeriod;
      } else {
        now = next_perception;
        perception.step(now);
        next_perception += control_period;
      }
    }
    now = target;
    if (!control_paused) task.step(now);
    next_control += control_period;
    drain();
  }
  void steps(int n) {
    for (int i = 0; i < n; ++i) step();
  }
  // Steps until `done` or `max` cycles; returns the cycles run.
  template <typename Done>
  int stepUntil(Done done, int max) {
    for (int i = 0; i < max; ++i) {
      if (done()) return i;
      step();
    }
    return max;
  }

  void request(RequestKind kind, const Pose2& pose = {}, std::uint64_t goal_id = 0) {
    Request r;
    r.kind = kind;
    r.pose = pose;
    r.goal_id = goal_id;
    ASSERT_TRUE(ch.requests.push(r));
  }

  void drain() {
    TelemetryRecord t;
    while (ch.telemetry.pop(t)) {
      last_telemetry = t;
      ++telemetry_records;
    }
    rt::LogRecord r;
    for (rt::LogRing* ring : {&ch.control_log, &ch.base_log, &ch.perception_log}) {
      while (ring->pop(r)) {
        ++log_records;
        last_log = r.message;
      }
    }
  }

  Status status() {
    ch.status.update();
    return ch.status.readBuffer();
  }
  double distanceTo(const Pose2& p) const {
    const Pose2 q = base.odometry().pose;
    return std::hypot(q.x - p.x, q.y - p.y);
  }

  static constexpr rt::Nanos kBasePeriod = 10 * kMs;
  DaemonConfig config;
  rt::ManualClock clock;  // the task's clock: the expansion budget reads none
  Channels ch;
  hal::MockBase base;
  hal::MockObstacles sensor;
  ControlTask task;
  BaseTask base_task;
  PerceptionTask perception;
  rt::Nanos control_period;
  rt::Nanos now = 0;
  rt::Nanos next_base = 0;
  rt::Nanos next_perception = 0;
  rt::Nanos next_control = 0;
  bool control_paused = false;
  TelemetryRecord last_telemetry;
  std::uint64_t telemetry_records = 0;
  std::uint64_t log_records = 0;
  const char* last_log = "";
};

bool isBrake(const hal::VelocityCommand& c) { return c.brake && c.v == 0.0 && c.w == 0.0; }

TEST(ControlTask, IdleUntilAGoalThenDrivesToItAndReportsReached) {
  Lockstep ls(officeConfig());
  ls.steps(5);
  EXPECT_EQ(ls.task.state(), DaemonState::kIdle);
  EXPECT_EQ(ls.task.fault(), FaultKind::kNone);
  EXPECT_FALSE(ls.status().has_goal);

  ls.request(RequestKind::kGoal, kGoal);
  ls.step();
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
  const Status driving = ls.status();
  EXPECT_TRUE(driving.has_goal);
  EXPECT_DOUBLE_EQ(driving.goal.x, kGoal.x);
  EXPECT_DOUBLE_EQ(driving.goal.y, kGoal.y);

  // 4 m at up to 2 m/s: well within 20 s of simulated time.
  const int cycles = ls.stepUntil([&] { return ls.task.state() == DaemonState::kReached; }, 600);
  ASSERT_EQ(ls.task.state(), DaemonState::kReached) << "after " << cycles << " cycles at "
                                                     << ls.base.odometry().pose.x << ", " << ls.base.odometry().pose.y;
  EXPECT_LE(ls.distanceTo(kGoal), ls.config.control.goal_tolerance_m + 1e-9);
  EXPECT_GT(cycles, 60);  // it really drove (3 m/s would be faster than the robot can)
  std::cout << "reached the goal 4 m away after " << cycles << " cycles (" << cycles / 30.0 << " s)\n";
  ls.steps(30);           // and stays there, stopped
  EXPECT_EQ(ls.task.state(), DaemonState::kReached);
  EXPECT_NEAR(ls.base.odometry().v, 0.0, 0.05);
  const Status reached = ls.status();
  EXPECT_EQ(reached.state, DaemonState::kReached);
  EXPECT_NEAR(reached.pose.x, ls.base.odometry().pose.x, 0.1);
  EXPECT_GT(reached.cycles, 60u);
  EXPECT_GE(reached.odometry_age_s, 0.0);
  EXPECT_LT(reached.odometry_age_s, 0.1);
  EXPECT_GE(reached.obstacles_age_s, 0.0);

  // One telemetry record per cycle (each pushed one cycle later), with the cycle's values.
  EXPECT_EQ(ls.telemetry_records + 1, ls.task.cycles());
  EXPECT_GT(ls.last_telemetry.t_s, 0.0);
  EXPECT_NEAR(ls.last_telemetry.x, ls.base.odometry().pose.x, 0.1);
  EXPECT_FALSE(ls.last_telemetry.overrun);
  EXPECT_GT(ls.log_records, 0u);  // goal accepted, reached
}

TEST(ControlTask, PlansWithTheBudgetAndPublishesCommandAndPlanNextAction) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(10);
  const CycleOutput& out = ls.task.lastOutput();
  ASSERT_TRUE(out.planned);
  EXPECT_LE(out.plan.stats.pops, 300u);  // the expansion budget
  const CommandSlot& slot = ls.task.lastCommand();
  EXPECT_EQ(slot.command.stamp, ls.now);
  EXPECT_FALSE(slot.command.brake);
  EXPECT_DOUBLE_EQ(slot.command.v, out.v_cmd);
  EXPECT_DOUBLE_EQ(slot.command.w, out.w_cmd);
  // The next period's fallback continues the plan's first action.
  const double t = 1.0 / 30.0;
  EXPECT_NEAR(slot.next.v, std::clamp(out.v_cmd + out.plan.first_action.a * t, -1.0, 2.0), 1e-6);
  EXPECT_GT(ls.base.odometry().v, 0.1);  // accelerating along the corridor
  EXPECT_EQ(ls.status().expansions, out.plan.stats.pops);
}

TEST(ControlTask, StaleOdometryBrakesWithinTheTimeoutAndRecovers) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(20);
  ASSERT_EQ(ls.task.state(), DaemonState::kDriving);

  ls.base.freezeOdometry(true);
  const rt::Nanos frozen_at = ls.now;
  ls.step();  // 33 ms: still within the 100 ms limit
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
  const int cycles = ls.stepUntil([&] { return ls.task.state() == DaemonState::kFault; }, 30);
  ASSERT_EQ(ls.task.state(), DaemonState::kFault);
  EXPECT_EQ(ls.task.fault(), FaultKind::kStaleOdometry);
  // Detected at the first cycle past the timeout (+ the base period the stamp may lag).
  EXPECT_LE(ls.now - frozen_at, 100 * kMs + Lockstep::kBasePeriod + ls.control_period);
  EXPECT_LE(cycles, 4);
  EXPECT_TRUE(isBrake(ls.task.lastCommand().command));
  EXPECT_TRUE(isBrake(ls.task.lastCommand().next));
  ls.step();
  EXPECT_TRUE(isBrake(ls.base_task.lastCommand()));
  const Status s = ls.status();
  EXPECT_EQ(s.state, DaemonState::kFault);
  EXPECT_EQ(s.fault, FaultKind::kStaleOdometry);
  EXPECT_GT(s.odometry_age_s, 0.1);
  EXPECT_EQ(s.v_cmd, 0.0);
  EXPECT_TRUE(s.has_goal);  // the goal is kept

  ls.base.freezeOdometry(false);
  ls.steps(2);
  EXPECT_EQ(ls.task.fault(), FaultKind::kNone);
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
  EXPECT_FALSE(ls.task.lastCommand().command.brake);
  ls.steps(10);
  EXPECT_GT(ls.base.odometry().v, 0.3);  // on its way again
}

TEST(ControlTask, NoOdometryAtAllIsAFaultFromTheStart) {
  Lockstep ls(officeConfig());
  ls.base.freezeOdometry(true);  // never a fresh stamp
  ls.control_paused = true;
  ls.steps(1);
  ls.control_paused = false;
  // MockBase may have stamped its first read; by 200 ms the odometry is stale regardless.
  ls.steps(6);
  EXPECT_EQ(ls.task.state(), DaemonState::kFault);
  EXPECT_EQ(ls.task.fault(), FaultKind::kStaleOdometry);
  EXPECT_TRUE(isBrake(ls.task.lastCommand().command));
}

TEST(ControlTask, StaleObstacleFramesBrakeAndRecover) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(15);
  ASSERT_EQ(ls.task.state(), DaemonState::kDriving);

  ls.sensor.stall(true);
  const rt::Nanos stalled_at = ls.now;
  ls.steps(3);  // 100 ms: within the 200 ms limit
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
  ls.stepUntil([&] { return ls.task.state() == DaemonState::kFault; }, 30);
  ASSERT_EQ(ls.task.state(), DaemonState::kFault);
  EXPECT_EQ(ls.task.fault(), FaultKind::kStaleObstacles);
  EXPECT_LE(ls.now - stalled_at, 200 * kMs + 2 * ls.control_period);
  EXPECT_TRUE(isBrake(ls.task.lastCommand().command));
  EXPECT_GT(ls.status().obstacles_age_s, 0.2);

  ls.sensor.stall(false);
  ls.steps(2);
  EXPECT_EQ(ls.task.fault(), FaultKind::kNone);
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
}

// The obstacle frame's polygons, velocities and turn rates are what the planner gets.
TEST(ControlTask, PlansAgainstTheObstacleFramesPolygonsVelocitiesAndTurnRates) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(3);
  EXPECT_EQ(ls.task.obstacles().size(), 0u);  // the mock camera sees nothing
  hal::ObstacleFrame frame;
  frame.count = 2;
  const Vec2 centres[2] = {{7.5, 4.0}, {6.0, 5.2}};
  for (std::size_t i = 0; i < 2; ++i) {
    hal::ObstacleFrame::Obstacle& o = frame.obstacles[i];
    o.n = 4;
    o.vertices[0] = centres[i] + Vec2(-0.2, -0.2);
    o.vertices[1] = centres[i] + Vec2(0.2, -0.2);
    o.vertices[2] = centres[i] + Vec2(0.2, 0.2);
    o.vertices[3] = centres[i] + Vec2(-0.2, 0.2);
  }
  frame.obstacles[0].velocity = {-0.6, 0.2};
  frame.obstacles[0].turn_rate = 1.2;
  frame.obstacles[1].velocity = {0.3, 0.0};
  frame.obstacles[1].turn_rate = -0.4;
  ls.sensor.push(frame);
  ls.step();
  const DynamicObstacleSet& seen = ls.task.obstacles();
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen.velocity(0), Vec2(-0.6, 0.2));
  EXPECT_EQ(seen.turnRate(0), 1.2);
  EXPECT_EQ(seen.velocity(1), Vec2(0.3, 0.0));
  EXPECT_EQ(seen.turnRate(1), -0.4);
  const Box box = boundingBox(seen.observed(0).view());
  EXPECT_NEAR(box.min.x(), 7.3, 1e-9);
  EXPECT_NEAR(box.max.y(), 4.2, 1e-9);
  ls.step();  // the mock's next frame is empty: nothing left to avoid
  EXPECT_EQ(ls.task.obstacles().size(), 0u);
}

TEST(ControlTask, BaseFaultBrakesAndClearsWithTheFault) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(15);
  ASSERT_EQ(ls.task.state(), DaemonState::kDriving);

  ls.base.setFault(hal::BaseFault::kEmergencyStop, 7);
  ls.steps(2);
  EXPECT_EQ(ls.task.state(), DaemonState::kFault);
  EXPECT_EQ(ls.task.fault(), FaultKind::kBase);
  EXPECT_TRUE(isBrake(ls.task.lastCommand().command));
  const Status s = ls.status();
  EXPECT_EQ(s.fault, FaultKind::kBase);
  EXPECT_EQ(s.base.fault, hal::BaseFault::kEmergencyStop);
  EXPECT_EQ(s.base.fault_code, 7u);

  ls.base.setFault(hal::BaseFault::kNone, 0);
  ls.steps(2);
  EXPECT_EQ(ls.task.fault(), FaultKind::kNone);
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
}

TEST(ControlTask, FaultWithoutAGoalRecoversToIdle) {
  Lockstep ls(officeConfig());
  ls.steps(3);
  ls.base.setFault(hal::BaseFault::kDriverFault, 3);
  ls.steps(2);
  EXPECT_EQ(ls.task.state(), DaemonState::kFault);
  ls.base.setFault(hal::BaseFault::kNone, 0);
  ls.steps(2);
  EXPECT_EQ(ls.task.state(), DaemonState::kIdle);
}

TEST(ControlTask, StopRequestBrakesDropsTheGoalAndHoldsUntilANewGoal) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(30);
  ASSERT_GT(ls.base.odometry().v, 0.5);

  ls.request(RequestKind::kStop);
  ls.step();
  EXPECT_EQ(ls.task.state(), DaemonState::kStopped);
  EXPECT_EQ(ls.task.lastCommand().command.v, 0.0);
  EXPECT_EQ(ls.task.lastCommand().command.w, 0.0);
  EXPECT_TRUE(ls.task.lastCommand().command.brake);
  Status s = ls.status();
  EXPECT_EQ(s.state, DaemonState::kStopped);
  EXPECT_FALSE(s.has_goal);
  EXPECT_EQ(s.v_cmd, 0.0);
  ls.steps(45);  // 1.5 s: the robot stands
  EXPECT_NEAR(ls.base.odometry().v, 0.0, 1e-3);
  EXPECT_EQ(ls.task.state(), DaemonState::kStopped);

  ls.request(RequestKind::kGoal, kGoal);
  ls.step();
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving);
}

TEST(ControlTask, ShutdownBrakesAndIgnoresLaterGoals) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(30);
  ls.ch.shutdown.store(true);
  ls.step();
  EXPECT_EQ(ls.task.state(), DaemonState::kStopped);
  EXPECT_TRUE(isBrake(ls.task.lastCommand().command));
  ls.request(RequestKind::kGoal, kGoal2);
  ls.steps(2);
  EXPECT_EQ(ls.task.state(), DaemonState::kStopped);
  EXPECT_FALSE(ls.status().has_goal);
}

TEST(ControlTask, StatusCarriesTheIdOfTheGoalPursuedInTheOrderTheGoalsCame) {
  Lockstep ls(officeConfig());
  ls.steps(2);
  EXPECT_EQ(ls.status().goal_id, 0u);  // no goal yet

  ls.request(RequestKind::kGoal, kGoal, 1);
  ls.step();
  Status s = ls.status();
  EXPECT_EQ(s.goal_id, 1u);
  EXPECT_EQ(s.state, DaemonState::kDriving);
  EXPECT_DOUBLE_EQ(s.goal.x, kGoal.x);

  ls.stepUntil([&] { return ls.task.state() == DaemonState::kReached; }, 600);
  ASSERT_EQ(ls.task.state(), DaemonState::kReached);
  EXPECT_EQ(ls.status().goal_id, 1u);  // reached: about goal 1

  // The next goal: its id with its first cycle, never goal 1's "reached" under id 2.
  ls.request(RequestKind::kGoal, kGoal2, 2);
  ls.step();
  s = ls.status();
  EXPECT_EQ(s.goal_id, 2u);
  EXPECT_EQ(s.state, DaemonState::kDriving);
  EXPECT_DOUBLE_EQ(s.goal.x, kGoal2.x);

  // A stop drops the goal: the id stays the last one pursued.
  ls.request(RequestKind::kStop);
  ls.step();
  s = ls.status();
  EXPECT_EQ(s.state, DaemonState::kStopped);
  EXPECT_FALSE(s.has_goal);
  EXPECT_EQ(s.goal_id, 2u);

  // Two goals within one period: the later one is pursued.
  ls.request(RequestKind::kGoal, kGoal, 3);
  ls.request(RequestKind::kGoal, kGoal2, 4);
  ls.step();
  s = ls.status();
  EXPECT_EQ(s.goal_id, 4u);
  EXPECT_DOUBLE_EQ(s.goal.x, kGoal2.x);
  ls.request(RequestKind::kPose, Pose2{5.0, 4.5, 0.0});  // not a goal: the id stays
  ls.step();
  EXPECT_EQ(ls.status().goal_id, 4u);
  ls.request(RequestKind::kGoal, kGoal, 5);
  ls.step();
  EXPECT_EQ(ls.status().goal_id, 5u);
}

TEST(ControlTask, PushesATelemetryRecordEveryCycleEvenWithoutATelemetryFile) {
  DaemonConfig config = officeConfig();
  config.telemetry_path.clear();  // no CSV: the service still keeps the poses for the picture
  Lockstep ls(config);
  ls.request(RequestKind::kGoal, kGoal, 1);
  ls.steps(30);
  EXPECT_EQ(ls.telemetry_records + 1, ls.task.cycles());
  EXPECT_NEAR(ls.last_telemetry.x, ls.base.odometry().pose.x, 0.1);
  EXPECT_GT(ls.last_telemetry.x, kStart.x);  // it drove
}

TEST(ControlTask, PoseRequestReachesTheBaseThroughTheControlThread) {
  Lockstep ls(officeConfig());
  ls.steps(2);
  ls.request(RequestKind::kPose, Pose2{6.0, 4.0, 0.5});
  ls.steps(2);  // control forwards it, the base thread applies it
  EXPECT_NEAR(ls.base.odometry().pose.x, 6.0, 1e-6);
  EXPECT_NEAR(ls.base.odometry().pose.y, 4.0, 1e-6);
  EXPECT_NEAR(ls.status().pose.theta, 0.5, 1e-6);
}

TEST(ControlTask, UnreachableGoalIsReported) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, Pose2{1.5, 1.5, 0.0});  // inside a solid corner block
  ls.stepUntil([&] { return ls.task.state() == DaemonState::kUnreachable; }, 10);
  EXPECT_EQ(ls.task.state(), DaemonState::kUnreachable);
  EXPECT_EQ(ls.status().state, DaemonState::kUnreachable);
}

TEST(BaseTask, FallsBackToThePlansNextActionThenBrakesWhenControlFallsSilent) {
  Lockstep ls(officeConfig());
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(20);
  ASSERT_EQ(ls.base_task.source(), CommandSource::kControl);
  const CommandSlot slot = ls.task.lastCommand();

  ls.control_paused = true;
  // Base ticks after the last command: < 2 periods: the command; < 3: the plan's next
  // action; after that a brake.
  bool saw_next = false;
  for (int i = 0; i < 12; ++i) {
    const rt::Nanos t = ls.next_base;
    ls.base_task.step(t);
    ls.next_base += Lockstep::kBasePeriod;
    const rt::Nanos age = t - slot.command.stamp;
    if (age < ls.control_period * 2) {
      EXPECT_EQ(ls.base_task.source(), CommandSource::kControl) << age;
      EXPECT_DOUBLE_EQ(ls.base_task.lastCommand().v, slot.command.v);
    } else if (age < ls.control_period * 3) {
      EXPECT_EQ(ls.base_task.source(), CommandSource::kPlanNext) << age;
      EXPECT_DOUBLE_EQ(ls.base_task.lastCommand().v, slot.next.v);
      saw_next = true;
    } else {
      EXPECT_EQ(ls.base_task.source(), CommandSource::kBrake) << age;
      EXPECT_TRUE(isBrake(ls.base_task.lastCommand()));
    }
  }
  EXPECT_TRUE(saw_next);
  EXPECT_GT(ls.base_task.fallbacks(), 0u);
  EXPECT_GT(ls.base_task.brakes(), 0u);
  // Control back: its command again.
  ls.control_paused = false;
  ls.next_control = ls.next_base;
  ls.step();
  ls.base_task.step(ls.now + 1);
  EXPECT_EQ(ls.base_task.source(), CommandSource::kControl);
}

TEST(BaseTask, BrakesBeforeTheControlThreadHasSentAnything) {
  Lockstep ls(officeConfig());
  ls.base_task.step(0);
  EXPECT_EQ(ls.base_task.source(), CommandSource::kBrake);
  EXPECT_TRUE(isBrake(ls.base_task.lastCommand()));
}

// The daemon's clock is the planner's: a wall-clock budget reads it as a function; a test's
// manual clock has none, so with it only an expansion budget is taken.
TEST(ControlTask, AWallClockBudgetReadsTheInjectedClockWhichAManualClockCannotBe) {
  DaemonConfig c = officeConfig();
  c.budget = BudgetSpec::wallClockMs(19.0);
  Channels ch(64);
  rt::ManualClock manual;
  EXPECT_THROW({ ControlTask task(c, ch, manual); }, std::invalid_argument);
  rt::MonotonicClock monotonic;
  EXPECT_NO_THROW({ ControlTask task(c, ch, monotonic); });
}

TEST(ControlTask, ThousandCyclesWithGoalChangesAndAStopAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_control_task must link staa_rt_alloc_hook";
  // A small budget keeps the sanitizer run short; the allocations do not depend on it.
  Lockstep ls(officeConfig(100));
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(5);  // warm-up, not counted

  // The counter counts (a direct call: a new-expression could be elided).
  rt::resetRealtimeAllocations();
  rt::markRealtimeThread(true);
  ::operator delete(::operator new(16));
  rt::markRealtimeThread(false);
  ASSERT_EQ(rt::realtimeAllocations(), 1u);

  rt::resetRealtimeAllocations();
  rt::markRealtimeThread(true);
  int reached = 0;
  for (int k = 0; k < 1000; ++k) {
    // Goal changes and a stop happen in the real-time thread too.
    if (k == 150) ls.request(RequestKind::kGoal, kGoal2, 2);
    if (k == 400) ls.request(RequestKind::kStop);
    if (k == 450) ls.request(RequestKind::kGoal, kGoal);
    if (k == 700) ls.request(RequestKind::kPose, Pose2{5.0, 4.5, 0.0});
    if (k == 720) ls.request(RequestKind::kGoal, Pose2{12.0, 5.0, 0.0});
    if (k == 940) ls.request(RequestKind::kGoal, Pose2{10.5, 1.5, -1.57});  // into a room: new polygons
    ls.step();
    reached += ls.task.state() == DaemonState::kReached;
  }
  rt::markRealtimeThread(false);
  const std::uint64_t allocations = rt::realtimeAllocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(reached, 0);
  EXPECT_EQ(ls.task.cycles(), 1005u);
}

// With the flight recorder on, the cycles (goal changes, a stop, a pose correction) encode
// into the ring without allocating, and what they recorded replays bit for bit.
TEST(ControlTask, TheFlightRecorderAllocatesNothingAndItsCyclesReplayBitForBit) {
  ASSERT_TRUE(rt::hookInstalled());
  const DaemonConfig config = officeConfig(100);
  Lockstep ls(config, kStart, 16u << 20);
  ASSERT_TRUE(ls.ch.recorder);
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(5);
  rt::resetRealtimeAllocations();
  rt::markRealtimeThread(true);
  for (int k = 0; k < 600; ++k) {
    if (k == 150) ls.request(RequestKind::kGoal, kGoal2, 2);
    if (k == 300) ls.request(RequestKind::kStop);
    if (k == 350) ls.request(RequestKind::kGoal, kGoal, 3);
    if (k == 450) ls.request(RequestKind::kPose, Pose2{5.0, 4.5, 0.0});
    ls.step();
  }
  rt::markRealtimeThread(false);
  EXPECT_EQ(rt::realtimeAllocations(), 0u);
  EXPECT_EQ(ls.ch.recorder->dropped(), 0u);

  // The service's half: the records into a file, read back and rerun.
  record::Session session;
  session.source = "staad";
  session.control = ls.task.controlCycle().config();
  session.robot = config.robot;
  session.map = config.map;
  session.agents = {{0, "staa"}};
  const std::filesystem::path file = test::freshDir("ControlTask", "recorder") / "run.mcap";
  std::uint64_t records = 0;
  {
    record::RecordingFile out(file, session);
    std::vector<std::byte> r;
    while (ls.ch.recorder->pop(r)) {
      out.add(r);
      ++records;
    }
    out.close();
    ASSERT_TRUE(out.ok()) << out.error();
  }
  EXPECT_EQ(records, ls.task.cycles());
  const record::Recording recording = record::loadRecording(file);
  const std::vector<record::CycleRecord>& cycles = recording.agents.at(0);
  const auto stopped = std::count_if(cycles.begin(), cycles.end(),
                                     [](const record::CycleRecord& c) { return c.step == record::StepKind::kStopped; });
  EXPECT_EQ(stopped, 50) << "the stop held the robot for 50 cycles without a step";
  const auto goals = std::count_if(cycles.begin(), cycles.end(),
                                   [](const record::CycleRecord& c) { return (c.flags & record::kGoalSet) != 0; });
  EXPECT_EQ(goals, 4) << "three goals and the stop's clearing";
  const auto corrections = std::count_if(cycles.begin(), cycles.end(), [](const record::CycleRecord& c) {
    return (c.flags & record::kPoseCorrected) != 0;
  });
  EXPECT_EQ(corrections, 1) << "the pose correction is in the cycle after it";
  const record::ReplayResult replayed = record::replay(recording, {});
  EXPECT_EQ(replayed.cycles, records);
  EXPECT_EQ(replayed.identical, records) << replayed.agents[0].first_difference;
}

// A map from ROS swapped in while driving: the control thread takes the bundle at a cycle
// boundary, keeps the goal, plans around what the new map adds, hands the replaced bundle
// back, and neither the swap nor the plan snapshots for RViz allocate there.
TEST(ControlTask, AMapSwappedInWhileDrivingIsPlannedOnAtOnceWithoutAllocating) {
  ASSERT_TRUE(rt::hookInstalled());
  const DaemonConfig config = officeConfig(100);
  Lockstep ls(config);
  ls.ch.plan_wanted.store(true);
  ls.ch.plan_tree_every.store(3);
  // The second map: the office with a pillar in the corridor between start and goal.
  auto bundle = [&](std::uint64_t sequence, bool pillar) {
    auto b = std::make_unique<MapBundle>();
    b->sequence = sequence;
    b->map = config.map;
    if (pillar) b->map.obstacles.push_back({{6.3, 4.2}, {6.7, 4.2}, {6.7, 4.8}, {6.3, 4.8}});
    b->cycle = std::make_unique<ControlCycle>(b->map, config.robot, controlConfigFor(config));
    return b;
  };
  std::unique_ptr<MapBundle> first = bundle(1, true);
  std::unique_ptr<MapBundle> second = bundle(2, false);
  ls.request(RequestKind::kGoal, kGoal);
  ls.steps(5);
  EXPECT_EQ(ls.task.mapSequence(), 0u);

  rt::resetRealtimeAllocations();
  rt::markRealtimeThread(true);
  ASSERT_TRUE(ls.ch.maps.push(first.get()));
  ls.step();
  EXPECT_EQ(ls.task.mapSequence(), 1u);
  EXPECT_EQ(ls.ch.maps_taken.load(), 1u);
  EXPECT_EQ(ls.task.state(), DaemonState::kDriving) << "the goal is kept across the swap";
  MapBundle* retired = nullptr;
  EXPECT_FALSE(ls.ch.retired_maps.pop(retired)) << "the config's own cycle is not handed back";
  // The path now goes around the pillar: no path vertex lies inside it grown by the robot.
  ls.steps(2);
  const std::span<const Vec2> path = ls.task.controlCycle().lastPath();
  ASSERT_GE(path.size(), 3u) << "a detour, not the straight corridor";
  for (const Vec2& v : path) EXPECT_FALSE(v.x() > 6.1 && v.x() < 6.9 && v.y() > 4.0 && v.y() < 5.0) << v.transpose();
  // The snapshot for RViz has the path, the trajectory and, every 3rd cycle, the tree.
  ASSERT_TRUE(ls.ch.plan.update());
  EXPECT_EQ(ls.ch.plan.readBuffer().path_n, path.size());
  EXPECT_GT(ls.ch.plan.readBuffer().trajectory_n, 0u);
  std::size_t trees = 0;
  for (int k = 0; k < 6; ++k) {
    ls.step();
    if (ls.ch.plan.update()) trees += ls.ch.plan.readBuffer().tree_n > 0;
  }
  EXPECT_EQ(trees, 2u);
  ASSERT_TRUE(ls.ch.maps.push(second.get()));
  ls.step();
  EXPECT_EQ(ls.task.mapSequence(), 2u);
  ASSERT_TRUE(ls.ch.retired_maps.pop(retired));
  EXPECT_EQ(retired, first.get()) << "the replaced bundle comes back to be freed outside the thread";
  ls.steps(50);
  rt::markRealtimeThread(false);
  EXPECT_EQ(rt::realtimeAllocations(), 0u);
  const int cycles = ls.stepUntil([&] { return ls.task.state() == DaemonState::kReached; }, 600);
  EXPECT_EQ(ls.task.state(), DaemonState::kReached) << "after " << cycles << " more cycles";
  // Once the thread has stopped, the daemon takes the last bundle back to free it.
  std::unique_ptr<MapBundle> last = ls.task.releaseMap();
  EXPECT_EQ(last.get(), second.get());
  EXPECT_EQ(ls.task.mapSequence(), 0u);
  last.release();  // `second` owns it
}

TEST(Telemetry, RowsFollowTheDocumentedHeader) {
  EXPECT_STREQ(telemetryHeader(), "t_s,x,y,theta,v,w,v_cmd,w_cmd,expansions,depth,budget_used_ms,overrun");
  TelemetryRecord r;
  r.t_s = 12.5;
  r.x = 1.25;
  r.y = -2.0;
  r.theta = 0.5;
  r.v = 1.0;
  r.w = -0.25;
  r.v_cmd = 1.1;
  r.w_cmd = -0.3;
  r.expansions = 812;
  r.depth = 4;
  r.budget_used_ms = 18.75;
  r.overrun = true;
  EXPECT_EQ(formatTelemetryRow(r), "12.500000,1.2500,-2.0000,0.5000,1.0000,-0.2500,1.1000,-0.3000,812,4,18.750,1");
}

TEST(Telemetry, RingRoundsUpDropsWhenFullAndKeepsOrder) {
  TelemetryRing ring(5);
  EXPECT_EQ(ring.capacity(), 8u);
  TelemetryRecord r;
  for (int i = 0; i < 10; ++i) {
    r.expansions = static_cast<std::uint32_t>(i);
    EXPECT_EQ(ring.push(r), i < 8);
  }
  EXPECT_EQ(ring.dropped(), 2u);
  for (std::uint32_t i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.pop(r));
    EXPECT_EQ(r.expansions, i);
  }
  EXPECT_FALSE(ring.pop(r));
}

// The run's picture (staad --svg): what the service thread keeps of the run, and the drawing.
TEST(RunPicture, KeepsOnePointPer5CmOfTravelAndBreaksThePathAtAPoseCorrection) {
  RunRecord run;
  // 1 m along x in 1 cm steps, 100 Hz: 101 records.
  for (int k = 0; k <= 100; ++k) run.addPose(10.0 + 0.01 * k, Pose2{1.0 + 0.01 * k, 2.0, 0.0});
  ASSERT_EQ(run.path().size(), 1u);
  const std::size_t points = run.path()[0].size();
  EXPECT_GE(points, 20u);
  EXPECT_LE(points, 22u);  // one per 5 cm, plus the start and the end pose
  EXPECT_NEAR(run.distanceM(), 1.0, 1e-9);
  EXPECT_NEAR(run.path()[0].back().x(), 2.0, 1e-12);  // ends at the end pose

  // `staactl pose`: 3 m away within one cycle. A new polyline; no distance for the jump.
  run.addPose(11.033, Pose2{5.0, 2.0, 1.0});
  run.addPose(11.066, Pose2{5.02, 2.0, 1.0});
  const auto path = run.path();
  ASSERT_EQ(path.size(), 2u);
  EXPECT_NEAR(path[0].back().x(), 2.0, 1e-12);
  EXPECT_NEAR(path[1].front().x(), 5.0, 1e-12);
  EXPECT_NEAR(path[1].back().x(), 5.02, 1e-12);
  EXPECT_NEAR(run.distanceM(), 1.02, 1e-9);
  EXPECT_NEAR(run.durationS(), 1.066, 1e-9);
  EXPECT_EQ(run.records(), 103u);
  EXPECT_DOUBLE_EQ(run.endPose().theta, 1.0);

  // A long gap (records dropped when the ring was full) is travel, not a relocation.
  run.addPose(20.0, Pose2{7.0, 2.0, 0.0});
  EXPECT_EQ(run.path().size(), 2u);
  EXPECT_NEAR(run.distanceM(), 3.0, 1e-9);
}

TEST(RunPicture, CountsEachGoalReachedOnceByItsId) {
  RunRecord run;
  run.addGoal(1, Pose2{8.5, 4.5, 0.0});
  run.addGoal(2, Pose2{7.0, 4.0, 3.14});
  Status s;
  s.goal_id = 1;
  s.state = DaemonState::kDriving;
  run.observe(s);
  EXPECT_EQ(run.goalsReached(), 0u);
  s.state = DaemonState::kReached;
  for (int k = 0; k < 3; ++k) run.observe(s);  // every 10 ms while it stays reached
  EXPECT_EQ(run.goalsReached(), 1u);
  s.goal_id = 2;
  s.state = DaemonState::kUnreachable;
  run.observe(s);
  EXPECT_EQ(run.goalsReached(), 1u);
  ASSERT_EQ(run.goals().size(), 2u);
  EXPECT_TRUE(run.goals()[0].reached);
  EXPECT_FALSE(run.goals()[1].reached);
}

TEST(RunPicture, DrawsTheMapThePathTheGoalsAndTheRobotAndWritesAtomically) {
  const DaemonConfig c = officeConfig();
  RunRecord run;
  for (int k = 0; k <= 120; ++k) run.addPose(0.033 * k, Pose2{4.5 + 0.033 * k, 4.5, 0.0});
  run.addGoal(1, Pose2{8.5, 4.5, 0.0});
  run.addGoal(2, Pose2{1.5, 1.5, 0.0});  // in a solid block: never reached
  Status s;
  s.goal_id = 1;
  s.state = DaemonState::kReached;
  run.observe(s);
  const std::string doc = runSvg(run, c.map, c.robot.footprint);
  EXPECT_EQ(doc.rfind("<?xml", 0), 0u);
  EXPECT_NE(doc.find("<svg"), std::string::npos);
  EXPECT_NE(doc.find("</svg>"), std::string::npos);
  EXPECT_NE(doc.find("<polyline fill=\"none\" stroke=\"#e8590c\""), std::string::npos);
  EXPECT_NE(doc.find(">1</text>"), std::string::npos);
  EXPECT_NE(doc.find(">2</text>"), std::string::npos);
  EXPECT_NE(doc.find("staad run on office: 4.0 s, 3.96 m driven, 1 of 2 goals reached"), std::string::npos);
  EXPECT_NE(doc.find("robot at the end"), std::string::npos);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("run-picture-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "run.svg";
  std::ofstream(file) << "old";
  writeFileAtomically(file, doc);
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), doc);
  EXPECT_FALSE(std::filesystem::exists(dir / "run.svg.tmp"));
  EXPECT_NO_THROW(checkWritable(file));
  EXPECT_THROW(checkWritable(dir / "missing" / "run.svg"), std::runtime_error);
  EXPECT_THROW(writeFileAtomically(dir / "missing" / "run.svg", doc), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace staa::staad
