#include "control/staa_controller.hpp"

namespace staa {

StaaController::StaaController(const StaaConfig& config, const RobotProfile& robot,
                               const std::vector<Polygon>& inflated_static, const LocalMapConfig& local,
                               std::size_t max_obstacles)
    : planner_(config, robot, inflated_static, local, max_obstacles) {}

LocalCommand StaaController::compute(const LocalContext& ctx) {
  plan_ = planner_.plan(ctx.robot, *ctx.map, *ctx.obstacles, ctx.budget);
  // The first action, held for one control period, gives the next velocity command.
  return {ctx.robot.v + plan_.first_action.a * ctx.period_s, ctx.robot.w + plan_.first_action.b * ctx.period_s,
          &plan_};
}

LocalCommand StaaController::safeStop(const LocalContext& ctx) {
  const Action a = planner_.safeStop(ctx.robot, *ctx.map, *ctx.obstacles);
  return {ctx.robot.v + a.a * ctx.period_s, ctx.robot.w + a.b * ctx.period_s, nullptr};
}

}  // namespace staa
