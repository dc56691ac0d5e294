#include "record/explain.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace staa::record {

namespace {

std::string format(const char* fmt, ...) {
  char s[320];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(s, sizeof s, fmt, args);
  va_end(args);
  return s;
}

const char* faultWords(std::uint8_t fault) {
  switch (fault) {
    case 1: return "stale input: no fresh odometry within limits.odometry_timeout_s";
    case 2: return "stale input: no fresh obstacle frame within limits.obstacles_timeout_s";
    case 3: return "fault: the base reports a fault";
  }
  return "fault";
}

// What the first action does to the speed.
const char* motion(const StepOutputs& o, const UnicycleState& robot) {
  const double a = o.first_action.a;
  if (std::abs(robot.v) > 1e-3 && a * robot.v < 0.0) return "braking";
  if (std::abs(a) < 1e-9) return "holding its speed";
  return a * (robot.v >= 0.0 ? 1.0 : -1.0) > 0.0 ? "accelerating" : "braking";
}

std::string searchWords(const CycleRecord& c) {
  const StepOutputs& o = c.out;
  switch (o.outcome) {
    case PlanResult::Outcome::kFinished: return format("the search finished (h < finish_h) after %u pops", o.pops);
    case PlanResult::Outcome::kExhausted: return format("the queue ran empty after %u pops", o.pops);
    case PlanResult::Outcome::kBrake: return "no collision-free successor of the start";
    case PlanResult::Outcome::kAborted: break;
  }
  if (c.budget.wall_clock) {
    return format("the %.1f ms budget cut the search after %u pops (clock read %lld of %u)",
                  static_cast<double>(c.budget.limit_ns) * 1e-6, o.pops, static_cast<long long>(c.budget.cut.cut_read),
                  c.budget.cut.reads);
  }
  return format("the budget of %u expansions ran out", c.budget.max_pops);
}

std::string safetyWords(const StepOutputs& o) {
  switch (o.tier) {
    case 2: return "passive safety holds (it can stop before any moving obstacle reaches its path)";
    case 1:
      return format("braking safety, tier 1: no first action keeps passive safety; %u let it stop clear if the "
                    "obstacles brake too",
                    o.brake_safe_actions);
    default:
      return format("braking safety, tier 0: no first action lets it stop clear; the %u least bad allowed (latest contact)",
                    o.brake_safe_actions);
  }
}

}  // namespace

std::vector<std::string> explainCycle(const CycleRecord& c, double file_t_s, const std::string& controller) {
  std::vector<std::string> lines;
  const StepOutputs& o = c.out;
  lines.push_back(format("agent %u, cycle %llu, t = %.2f s in the file: v = %.2f m/s, w = %.2f rad/s -> command v = %.3f, "
                         "w = %.3f%s",
                         c.agent, static_cast<unsigned long long>(c.cycle), file_t_s, c.robot.v, c.robot.w, c.command.v,
                         c.command.w, c.command.brake ? " (brake)" : ""));
  if (c.step == StepKind::kFault) {
    lines.push_back(std::string(faultWords(c.fault)) + ": braking; the planner did not run on inputs it cannot trust");
    return lines;
  }
  if (c.step == StepKind::kStopped) {
    lines.push_back("stopped on request: braking, the goal dropped");
    return lines;
  }
  if (!o.planned) {
    switch (o.state) {
      case CycleState::kIdle: lines.push_back("no goal: braking to standstill"); break;
      case CycleState::kReached: lines.push_back("at the goal: braking to a stop"); break;
      case CycleState::kUnreachable:
        lines.push_back(std::string("no path: ") + toString(o.path_status) + "; the goal counts as unreachable, stopping clear of obstacles");
        break;
      case CycleState::kDriving:
        if (o.path_status == PathStatus::kAborted) {
          lines.push_back("no path yet: the path query ran out of the budget (a cold query); stopping clear for now, the "
                          "search resumes next cycle");
        } else {
          lines.push_back("the " + controller + " controller's command along the " +
                          (o.path_held ? std::string("held path") : std::string("global path")));
        }
        break;
    }
    return lines;
  }
  std::string reason;
  if (o.path_held) {
    reason = format("path held: the path query failed (%s) for %d cycles; following the last path found. ",
                    toString(o.path_status), c.path_misses + 1);
  }
  if (o.outcome == PlanResult::Outcome::kBrake) {
    reason += "no collision-free first action: the brake";
  } else {
    reason += std::string("STAA*'s first action is ") + motion(o, c.robot) + "; " + safetyWords(o);
  }
  lines.push_back(reason);
  lines.push_back(searchWords(c) + format("; depth %d, h %.2f s, first action a = %.2f m/s^2, b = %.2f rad/s^2", o.depth,
                                          o.best_h, o.first_action.a, o.first_action.b));
  return lines;
}

}  // namespace staa::record
