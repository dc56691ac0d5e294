#include "app/staad/control_task.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace staa::staad {

namespace {

rt::Nanos secondsToNanos(double s) { return static_cast<rt::Nanos>(std::llround(s * 1e9)); }

ControlConfig controlConfigOf(const DaemonConfig& config) {
  ControlConfig c = config.control;
  c.rate_hz = config.control_hz;
  c.max_moving_obstacles = hal::ObstacleFrame::kMaxObstacles;
  return c;
}

// The monotonic clock is read through the control thread's stall probe.
bool probedClock(const rt::Clock& clock) { return clock.nowFunction() == &rt::monotonicNow; }

// A wall-clock budget's clock: the monotonic clock through the stall probe, else the clock's
// own function (null with an expansion budget: it reads no clock).
ClockFn budgetClockOf(const DaemonConfig& config, const rt::Clock& clock) {
  if (config.budget.isExpansions()) return nullptr;
  return probedClock(clock) ? &rt::StallProbe::now : clock.nowFunction();
}

PlannerBudget budgetOf(const DaemonConfig& config, const rt::Clock& clock) {
  if (config.budget.isExpansions()) return config.budget.make();  // reads no clock
  const ClockFn now = budgetClockOf(config, clock);
  if (now == nullptr) {
    throw std::invalid_argument(
        "ControlTask: a wall-clock budget (budget.ms) needs a clock the planner can read (the monotonic clock), "
        "not a test's manual clock: use budget.expansions");
  }
  return config.budget.make(now);
}

DaemonState fromCycleState(CycleState s) {
  switch (s) {
    case CycleState::kIdle: return DaemonState::kIdle;
    case CycleState::kDriving: return DaemonState::kDriving;
    case CycleState::kReached: return DaemonState::kReached;
    case CycleState::kUnreachable: return DaemonState::kUnreachable;
  }
  return DaemonState::kIdle;
}

// Log messages are string literals (rt::LogRecord keeps the pointer).
const char* stateMessage(DaemonState s) {
  switch (s) {
    case DaemonState::kIdle: return "state: idle";
    case DaemonState::kDriving: return "state: driving";
    case DaemonState::kReached: return "state: reached the goal at (x, y, theta)";
    case DaemonState::kUnreachable: return "state: goal unreachable from (x, y, theta)";
    case DaemonState::kStopped: return "state: stopped";
    case DaemonState::kFault: return "state: fault";
  }
  return "state: ?";
}

const char* faultMessage(FaultKind f) {
  switch (f) {
    case FaultKind::kNone: return "fault cleared: inputs fresh again";
    case FaultKind::kStaleOdometry: return "fault: stale odometry, braking (age s, limit s)";
    case FaultKind::kStaleObstacles: return "fault: stale obstacle frames, braking (age s, limit s)";
    case FaultKind::kBase: return "fault: the base reports a fault, braking (fault, code)";
  }
  return "fault: ?";
}

// A base fault by name (the log keeps the literal's pointer).
const char* baseFaultMessage(hal::BaseFault f) {
  switch (f) {
    case hal::BaseFault::kNone: break;
    case hal::BaseFault::kEmergencyStop: return "fault: the base reports a fault, braking: emergency stop (code)";
    case hal::BaseFault::kHeartbeatLost: return "fault: the base reports a fault, braking: heartbeat lost (code)";
    case hal::BaseFault::kBusOff: return "fault: the base reports a fault, braking: bus off (code)";
    case hal::BaseFault::kWriteFailed: return "fault: the base reports a fault, braking: write failed (code)";
    case hal::BaseFault::kDriverFault: return "fault: the base reports a fault, braking: driver fault (code)";
    case hal::BaseFault::kOdometryInvalid: return "fault: the base reports a fault, braking: odometry invalid (code)";
    case hal::BaseFault::kOdometryStampBack:
      return "fault: the base reports a fault, braking: odometry stamp went back (code)";
  }
  return "fault: the base reports a fault, braking (code)";
}

double ageSeconds(rt::Nanos now, rt::Nanos stamp) { return stamp < 0 ? -1.0 : static_cast<double>(now - stamp) * 1e-9; }

}  // namespace

hal::VelocityCommand brakeCommand(rt::Nanos stamp) {
  hal::VelocityCommand c;
  c.stamp = stamp;
  c.v = 0.0;
  c.w = 0.0;
  c.brake = true;
  return c;
}

ControlTask::ControlTask(const DaemonConfig& config, Channels& channels, rt::Clock& clock)
    : ch_(channels),
      clock_(clock),
      period_(secondsToNanos(1.0 / config.control_hz)),
      odometry_timeout_(secondsToNanos(config.odometry_timeout_s)),
      obstacles_timeout_(secondsToNanos(config.obstacles_timeout_s)),
      probed_(probedClock(clock)),
      extra_cycle_(static_cast<rt::Nanos>(config.debug_extra_cycle_us) * 1000),
      budget_(budgetOf(config, clock)),
      budget_spec_(config.budget),
      budget_clock_(budgetClockOf(config, clock)),
      budget_ms_(config.budget.isExpansions() ? 0.0 : config.budget.ms),
      limits_(config.robot.limits),
      own_cycle_(config.map, config.robot, controlConfigOf(config)),
      cycle_(&own_cycle_),
      obstacles_(own_cycle_.obstacleCapacity()) {
  if (ch_.recorder) {
    record::RecordLimits limits;
    limits.obstacles = hal::ObstacleFrame::kMaxObstacles;
    limits.vertices = hal::ObstacleFrame::kMaxVertices;
    limits.path_points = 4096;  // the held path's capacity
    limits.trajectory = 256;
    recorder_sink_ = std::make_unique<RingSink>(*ch_.recorder);
    recorder_ = std::make_unique<record::CycleRecorder>(limits, *recorder_sink_);
  }
}

ControlConfig controlConfigFor(const DaemonConfig& config) { return controlConfigOf(config); }

std::unique_ptr<MapBundle> ControlTask::releaseMap() {
  MapBundle* bundle = map_;
  map_ = nullptr;
  cycle_ = &own_cycle_;
  return std::unique_ptr<MapBundle>(bundle);
}

// 0. A map built on the service side replaces the current one between two cycles: the new
// cycle takes the goal; the replaced bundle goes back to be freed there (never here). Taken
// only when the way back has room, so that nothing is ever freed on this thread.
void ControlTask::takeMap(rt::Nanos now) {
  if (ch_.maps.size() == 0 || ch_.retired_maps.size() >= MapRing::capacity()) return;
  MapBundle* next = nullptr;
  if (!ch_.maps.pop(next) || next == nullptr) return;
  if (map_ != nullptr) ch_.retired_maps.push(map_);
  map_ = next;
  cycle_ = map_->cycle.get();
  if (has_goal_) cycle_->setGoal(goal_);
  if (recorder_) recorder_->newCycle();
  ch_.maps_taken.fetch_add(1, std::memory_order_release);
  log(now, rt::LogLevel::kInfo, "map swapped in (sequence)", static_cast<double>(map_->sequence), 0.0, 0.0, 1);
}

void ControlTask::log(rt::Nanos now, rt::LogLevel level, const char* message, double a, double b, double c,
                      std::uint8_t count) {
  rt::pushLog(ch_.control_log, now, level, message, a, b, c, count);  // a full ring drops (and counts) it
}

// 1. Requests from the service thread.
void ControlTask::takeRequests(rt::Nanos now) {
  if (!shutdown_ && ch_.shutdown.load(std::memory_order_acquire)) {
    shutdown_ = true;
    stopped_ = true;
    has_goal_ = false;
    cycle_->clearGoal();
    log(now, rt::LogLevel::kInfo, "shutting down: braking to standstill");
  }
  Request request;
  while (ch_.requests.pop(request)) {
    if (shutdown_) continue;  // stopping: the robot stays braked
    switch (request.kind) {
      case RequestKind::kGoal:
        cycle_->setGoal(request.pose);
        has_goal_ = true;
        goal_ = request.pose;
        goal_id_ = request.goal_id;
        stopped_ = false;
        log(now, rt::LogLevel::kInfo, "goal accepted (x, y, theta)", request.pose.x, request.pose.y, request.pose.theta,
            3);
        break;
      case RequestKind::kStop:
        cycle_->clearGoal();
        has_goal_ = false;
        stopped_ = true;
        log(now, rt::LogLevel::kInfo, "stop requested: braking, goal dropped");
        break;
      case RequestKind::kPose:
        // Only the base thread may call Base::setPose.
        if (!ch_.poses.push(request.pose)) {
          log(now, rt::LogLevel::kWarning, "pose request dropped: the base thread's ring is full");
        } else if (recorder_) {
          recorder_->poseCorrected();
        }
        break;
      case RequestKind::kStatus:  // answered by the service thread itself
      case RequestKind::kHistograms:
      case RequestKind::kRecord:
      case RequestKind::kDebug: break;  // carried out through Channels' debug atomics
    }
  }
}

// 1b. A test's forced overrun (debug.faults): this cycle publishes its command that much
// later, so the base thread falls back to the plan's next action, then brakes.
void ControlTask::forcedOverrun(rt::Nanos now) {
  const std::uint32_t ms = ch_.debug_overrun_ms.exchange(0, std::memory_order_acq_rel);
  if (ms == 0) return;
  log(now, rt::LogLevel::kWarning, "debug: forced overrun, busy-waiting (ms)", static_cast<double>(ms), 0.0, 0.0, 1);
  busyWait(static_cast<rt::Nanos>(ms) * rt::kNanosPerMilli);
}

// Through the stall probe: a busy-wait's time is the cycle's own work, never a stall.
rt::Nanos ControlTask::readClock() const { return probed_ ? rt::StallProbe::now() : clock_.now(); }

void ControlTask::busyWait(rt::Nanos duration) {
  const rt::Nanos until = readClock() + duration;
  while (readClock() < until) {
  }
}

// 2. The latest inputs.
void ControlTask::takeInputs() {
  if (ch_.base.update()) base_ = ch_.base.readBuffer();
  if (ch_.obstacles.update()) {
    const hal::ObstacleFrame& frame = ch_.obstacles.readBuffer();
    const std::size_t n = std::min(frame.count, hal::ObstacleFrame::kMaxObstacles);
    for (std::size_t i = 0; i < n; ++i) {
      const hal::ObstacleFrame::Obstacle& o = frame.obstacles[i];
      views_[i] = PolygonView(o.vertices.data(), std::min(o.n, hal::ObstacleFrame::kMaxVertices));
      velocities_[i] = o.velocity;
      turn_rates_[i] = o.turn_rate;
    }
    // set() copies (hulls) the polygons: the views may dangle after the next update().
    obstacles_.set(std::span<const PolygonView>(views_.data(), n), std::span<const Vec2>(velocities_.data(), n),
                   std::span<const double>(turn_rates_.data(), n));
    frame_n_ = n;
    obstacles_stamp_ = frame.stamp;
  }
}

// 3. Stale or faulty inputs hold the robot.
FaultKind ControlTask::judgeInputs(rt::Nanos now) const {
  // The base's own fault first: a bus-off or a lost heartbeat silences the odometry too, and
  // the status should name the cause, not the symptom.
  if (base_.status.fault != hal::BaseFault::kNone) return FaultKind::kBase;
  const rt::Nanos odometry_stamp = base_.odometry.stamp;
  if (odometry_stamp < 0 || now - odometry_stamp > odometry_timeout_) return FaultKind::kStaleOdometry;
  if (obstacles_stamp_ < 0 || now - obstacles_stamp_ > obstacles_timeout_) return FaultKind::kStaleObstacles;
  return FaultKind::kNone;
}

void ControlTask::setState(rt::Nanos now, DaemonState state, FaultKind fault) {
  if (fault != fault_) {
    const rt::LogLevel level = fault == FaultKind::kNone ? rt::LogLevel::kInfo : rt::LogLevel::kError;
    switch (fault) {
      case FaultKind::kStaleOdometry:
        log(now, level, faultMessage(fault), ageSeconds(now, base_.odometry.stamp),
            static_cast<double>(odometry_timeout_) * 1e-9, 0.0, 2);
        break;
      case FaultKind::kStaleObstacles:
        log(now, level, faultMessage(fault), ageSeconds(now, obstacles_stamp_),
            static_cast<double>(obstacles_timeout_) * 1e-9, 0.0, 2);
        break;
      case FaultKind::kBase:
        log(now, level, baseFaultMessage(base_.status.fault), static_cast<double>(base_.status.fault_code), 0.0, 0.0, 1);
        break;
      case FaultKind::kNone: log(now, level, faultMessage(fault)); break;
    }
    fault_ = fault;
  }
  if (state != state_) {
    const Pose2& p = base_.odometry.pose;
    if (state == DaemonState::kReached || state == DaemonState::kUnreachable) {
      const rt::LogLevel level = state == DaemonState::kReached ? rt::LogLevel::kInfo : rt::LogLevel::kWarning;
      log(now, level, stateMessage(state), p.x, p.y, p.theta, 3);
    } else if (state != DaemonState::kFault) {  // faults are logged above
      log(now, rt::LogLevel::kInfo, stateMessage(state));
    }
    state_ = state;
  }
}

void ControlTask::step(rt::Nanos now) {
  if (probed_) rt::StallProbe::local().begin(now);
  flushTelemetry();  // the previous cycle's record, now that its overrun is known
  takeMap(now);
  takeRequests(now);
  forcedOverrun(now);
  if (extra_cycle_ > 0) busyWait(extra_cycle_);  // debug.extra_cycle_us: a slower cycle
  takeInputs();
  const FaultKind fault = judgeInputs(now);

  const hal::Odometry& odo = base_.odometry;
  const UnicycleState robot{odo.pose.x, odo.pose.y, odo.pose.theta, odo.v, odo.w};
  CycleOutput& out = last_output_;
  PlannerBudget budget = budget_;
  if (recorder_) {
    // The frame's polygons as handed to obstacles_.set (the views stay valid until the next
    // frame is taken), and the budget with its clock tapped.
    recorder_->obstacles({std::span<const PolygonView>(views_.data(), frame_n_),
                          std::span<const Vec2>(velocities_.data(), frame_n_),
                          std::span<const double>(turn_rates_.data(), frame_n_)});
    budget = recorder_->before(*cycle_, budget_spec_, budget_clock_);
  }
  record::StepKind step_kind = record::StepKind::kStepped;
  if (fault != FaultKind::kNone) {
    // Brake; the planner does not run on inputs it cannot trust.
    out = CycleOutput{};
    setState(now, DaemonState::kFault, fault);
    publishCommand(now, nullptr);
    step_kind = record::StepKind::kFault;
  } else if (stopped_) {
    out = CycleOutput{};
    setState(now, DaemonState::kStopped, fault);
    publishCommand(now, nullptr);
    step_kind = record::StepKind::kStopped;
  } else {
    // 4. One cycle of the paper's Sec. III.
    CycleInputs in;
    in.robot = robot;
    in.obstacles = &obstacles_;
    out = cycle_->step(in, budget);
    path_max_ = std::max<rt::Nanos>(path_max_, out.path_ns);
    local_max_ = std::max<rt::Nanos>(local_max_, out.local_ns);
    capped_cycles_ += out.speed_capped ? 1 : 0;
    setState(now, fromCycleState(out.state), fault);
    publishCommand(now, &out);
  }
  if (recorder_) {
    // 8. The cycle for the flight recorder (after the command went out: it never waits for this).
    const hal::VelocityCommand& c = last_command_.command;
    const hal::VelocityCommand& n = last_command_.next;
    recorder_->after(*cycle_, now, robot, step_kind, static_cast<std::uint8_t>(fault),
                     step_kind == record::StepKind::kStepped ? &out : nullptr, {c.v, c.w, c.brake, n.v, n.w, n.brake},
                     static_cast<std::uint32_t>(mapSequence()));
  }
  ++cycles_;
  publishStatus(now);
  if (ch_.plan_wanted.load(std::memory_order_relaxed)) publishPlan(now, out);

  // 7. This cycle's telemetry record (pushed at the start of the next cycle), whether or not
  // a telemetry file is written: the service thread also keeps the poses for the picture.
  {
    TelemetryRecord& r = pending_;
    r.t_s = static_cast<double>(now) * 1e-9;
    r.x = odo.pose.x;
    r.y = odo.pose.y;
    r.theta = odo.pose.theta;
    r.v = odo.v;
    r.w = odo.w;
    r.v_cmd = last_command_.command.v;
    r.w_cmd = last_command_.command.w;
    r.expansions = out.planned ? out.plan.stats.pops : 0u;
    r.depth = out.planned ? out.plan.depth : 0;
    r.budget_used_ms = static_cast<double>(out.plan_ns) * 1e-6;
    r.overrun = false;
    has_pending_ = true;
  }
  ch_.heartbeat.store(cycles_, std::memory_order_release);
  if (probed_) last_stall_ = rt::StallProbe::local().end(rt::StallProbe::now());
}

// 5. The command for the next period, and the one after it (the base thread's fallback).
void ControlTask::publishCommand(rt::Nanos now, const CycleOutput* out) {
  CommandSlot& slot = ch_.command.writeBuffer();
  if (out == nullptr) {
    slot.command = brakeCommand(now);
    slot.next = brakeCommand(now);
  } else {
    slot.command.stamp = now;
    slot.command.v = out->v_cmd;
    slot.command.w = out->w_cmd;
    slot.command.brake = false;
    if (out->planned) {
      // STAA*'s first action holds for dt (0.3 s), far longer than two control periods: the
      // plan's action for the following period is the same acceleration, carried on from
      // this period's command (never through standstill).
      const double t = static_cast<double>(period_) * 1e-9;
      const Action& a = out->plan.first_action;
      double v = std::clamp(out->v_cmd + a.a * t, limits_.v_min, limits_.v_max);
      double w = std::clamp(out->w_cmd + a.b * t, -limits_.w_max, limits_.w_max);
      if (v * out->v_cmd < 0.0) v = 0.0;
      if (w * out->w_cmd < 0.0) w = 0.0;
      slot.next.stamp = now;
      slot.next.v = v;
      slot.next.w = w;
      slot.next.brake = false;
    } else {
      // Idle, reached, unreachable: the cycle is decelerating to a stop; after it, brake.
      slot.next = brakeCommand(now);
    }
  }
  // The odometry this command was planned on: the ROS link's odometry-to-twist latency.
  slot.command.odometry_stamp = base_.odometry.stamp;
  slot.next.odometry_stamp = base_.odometry.stamp;
  last_command_ = slot;
  ch_.command.publish();
}

// 6. The status for the service thread.
void ControlTask::publishStatus(rt::Nanos now) {
  Status& s = ch_.status.writeBuffer();
  s.state = state_;
  s.pose = base_.odometry.pose;
  s.v = base_.odometry.v;
  s.w = base_.odometry.w;
  s.v_cmd = last_command_.command.v;
  s.w_cmd = last_command_.command.w;
  s.has_goal = has_goal_;
  s.goal = goal_;
  s.goal_id = goal_id_;
  s.fault = fault_;
  s.reason = state_ == DaemonState::kUnreachable ? toString(last_output_.path_status) : nullptr;
  s.base = base_.status;
  s.cycles = cycles_;
  // The thread's timing is read by the service thread from the activity (costly here).
  s.odometry_age_s = ageSeconds(now, base_.odometry.stamp);
  s.obstacles_age_s = ageSeconds(now, obstacles_stamp_);
  s.expansions = last_output_.planned ? last_output_.plan.stats.pops : 0u;
  s.depth = last_output_.planned ? static_cast<double>(last_output_.plan.depth) : 0.0;
  s.budget_ms = budget_ms_;
  s.blind_corners = cycle_ != nullptr && cycle_->config().blind_corners.enabled;
  s.speed_cap = last_output_.speed_cap;
  s.capped_cycles = capped_cycles_;
  s.path_max_ns = path_max_;
  s.local_max_ns = local_max_;
  s.time_s = static_cast<double>(now) * 1e-9;
  last_status_ = s;
  ch_.status.publish();
}

// 6b. What RViz draws, copied into the snapshot's fixed arrays (cut at their sizes).
void ControlTask::publishPlan(rt::Nanos now, const CycleOutput& out) {
  PlanSnapshot& p = ch_.plan.writeBuffer();
  p.stamp = now;
  p.robot = base_.odometry.pose;
  const std::span<const Vec2> path = cycle_->lastPath();
  p.path_n = std::min(path.size(), PlanSnapshot::kMaxPath);
  std::copy_n(path.begin(), p.path_n, p.path.begin());
  p.trajectory_n = 0;
  if (out.planned) {
    for (const UnicycleState& s : out.plan.trajectory) {
      if (p.trajectory_n == PlanSnapshot::kMaxTrajectory) break;
      p.trajectory[p.trajectory_n++] = Pose2{s.x, s.y, s.theta};
    }
  }
  p.has_subgoal = out.state == CycleState::kDriving;
  p.subgoal = cycle_->localMap().intermediateGoal().pose;
  p.obstacles_n = 0;
  for (std::size_t i = 0; i < obstacles_.size() && p.obstacles_n < p.obstacles.size(); ++i) {
    hal::ObstacleFrame::Obstacle& o = p.obstacles[p.obstacles_n++];
    const FixedPolygon& poly = obstacles_.observed(i);
    o.n = std::min(poly.n, hal::ObstacleFrame::kMaxVertices);
    std::copy_n(poly.v.begin(), o.n, o.vertices.begin());
    o.velocity = obstacles_.velocity(i);
    o.turn_rate = obstacles_.turnRate(i);
  }
  p.horizon_s = 1.0;
  p.tree_n = 0;
  const std::uint32_t every = ch_.plan_tree_every.load(std::memory_order_relaxed);
  if (every > 0 && out.planned && cycles_ % every == 0) {
    cycle_->planner().forEachEdge([&p](const UnicycleState& a, const UnicycleState& b) {
      if (p.tree_n < PlanSnapshot::kMaxTreeEdges) p.tree[p.tree_n++] = {Vec2{a.x, a.y}, Vec2{b.x, b.y}};
    });
  }
  ch_.plan.publish();
}

void ControlTask::flushTelemetry() {
  if (!has_pending_) return;
  if (loop_ != nullptr) {
    const std::uint64_t overruns = loop_->counters().overruns;
    pending_.overrun = overruns > overruns_seen_;
    overruns_seen_ = overruns;
  }
  ch_.telemetry.push(pending_);  // a full ring drops and counts
  has_pending_ = false;
}

}  // namespace staa::staad
