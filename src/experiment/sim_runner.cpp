#include "experiment/sim_runner.hpp"

#include "experiment/agent_camera.hpp"
#include "experiment/sight_obstacles.hpp"
#include "record/recorder.hpp"
#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>

namespace staa {

Distribution distributionOf(std::vector<double> values) {
  Distribution d;
  if (values.empty()) return d;
  std::sort(values.begin(), values.end());
  d.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  d.p50 = values[values.size() / 2];
  d.p99 = values[std::min(values.size() - 1, values.size() * 99 / 100)];
  d.max = values.back();
  return d;
}

SimResult runSingleRobot(const Scenario& scenario, const SimOptions& options) {
  World world(scenario);
  ControlCycle cycle(scenario.map, scenario.robot, options.control);
  cycle.setGoal(scenario.goal);
  cycle.setLocalController(options.controller);
  DynamicObstacleSet obstacles(options.control.max_moving_obstacles);
  std::vector<Polygon> mover_polys(world.moverCount());
  std::vector<PolygonView> views(world.moverCount());
  std::vector<Vec2> velocities(world.moverCount());
  // Depth: the robot's camera sees the movers as people 1.7 m tall; perception bounds their
  // speed by the fastest of them.
  constexpr double kPersonHeightM = 1.7;
  std::unique_ptr<AgentCamera> camera;
  std::vector<hal::PrismView> prisms(world.moverCount());
  const std::size_t seen_capacity = std::max(hal::ObstacleFrame::kMaxObstacles, world.moverCount());
  std::vector<PolygonView> seen_views(seen_capacity);
  std::vector<Vec2> seen_velocities(seen_capacity);
  std::vector<double> seen_turn_rates(seen_capacity);
  std::size_t seen = 0;  // obstacles in the seen_ spans this cycle
  if (perceived(options.obstacles)) {
    DepthObstaclesConfig perception =
        agentPerceptionConfig(scenario.robot, options.obstacles == ObstacleSource::kDepthScan);
    double fastest = 0.0;
    for (std::size_t i = 0; i < world.moverCount(); ++i) fastest = std::max(fastest, world.mover(i).speed);
    perception.max_speed_mps = std::max(perception.max_speed_mps, 1.25 * fastest);
    perception.acceleration_mps2 = std::max(perception.acceleration_mps2, 1.0);
    camera = std::make_unique<AgentCamera>(scenario.map, scenario.robot, perception, 1,
                                           options.obstacles == ObstacleSource::kDepthScan);
  }
  // Sight: the movers in the robot's line of sight, exactly.
  const bool by_sight = options.obstacles == ObstacleSource::kSight;
  const LineOfSight line_of_sight(by_sight ? std::span<const Polygon>(scenario.map.obstacles)
                                           : std::span<const Polygon>());
  std::unique_ptr<SightObstacles> sight;
  if (by_sight) {
    std::size_t vertices = 0;
    for (std::size_t i = 0; i < world.moverCount(); ++i) vertices = std::max(vertices, world.moverPolygon(i).size());
    sight = std::make_unique<SightObstacles>(line_of_sight, world.moverCount(), vertices, SightConfig{});
  }
  std::unique_ptr<record::SimRecording> recording;
  if (!options.record_path.empty()) {
    record::Session session = options.record_session;
    session.control = cycle.config();
    session.robot = scenario.robot;
    session.map = scenario.map;
    session.agents = {{0, options.controller != nullptr ? options.controller->name() : "staa"}};
    record::RecordLimits limits;
    // Depth: what perception made of a frame (up to ObstacleFrame's obstacles and vertices).
    limits.obstacles = std::max<std::size_t>(1, world.moverCount());
    if (camera) limits.obstacles = std::max(limits.obstacles, hal::ObstacleFrame::kMaxObstacles);
    if (camera) limits.vertices = std::max(limits.vertices, hal::ObstacleFrame::kMaxVertices);
    for (std::size_t i = 0; i < world.moverCount(); ++i) limits.vertices = std::max(limits.vertices, world.moverPolygon(i).size());
    limits.path_points = 4096;
    limits.trajectory = 256;
    recording = std::make_unique<record::SimRecording>(options.record_path, session, limits);
  }

  SimResult result;
  std::vector<double> pops, succ, depth, plan_us, cycle_us, path_us;
  int early = 0;
  const double period = 1.0 / options.rate_hz;
  const int cycles = static_cast<int>(std::ceil(options.duration_s * options.rate_hz - 1e-9));
  if (!options.svg_dir.empty()) std::filesystem::create_directories(options.svg_dir);
  for (int k = 0; k < cycles; ++k) {
    for (std::size_t i = 0; i < world.moverCount(); ++i) {
      mover_polys[i] = world.moverPolygon(i);
      views[i] = mover_polys[i];
      velocities[i] = world.moverVelocity(i);
    }
    if (camera) {
      for (std::size_t i = 0; i < world.moverCount(); ++i) {
        prisms[i] = hal::PrismView{views[i], Vec2(0.0, 0.0), kPersonHeightM};
      }
      camera->perceive(world.time(), world.robot().pose, prisms);
      seen = 0;
      if (const hal::ObstacleFrame* f = camera->delivered(world.time())) {
        for (; seen < f->count; ++seen) {
          seen_views[seen] = PolygonView(f->obstacles[seen].vertices.data(), f->obstacles[seen].n);
          seen_velocities[seen] = f->obstacles[seen].velocity;
          seen_turn_rates[seen] = f->obstacles[seen].turn_rate;
        }
      }
      obstacles.set(std::span<const PolygonView>(seen_views.data(), seen),
                    std::span<const Vec2>(seen_velocities.data(), seen),
                    std::span<const double>(seen_turn_rates.data(), seen));
    } else if (sight) {
      seen = 0;
      for (std::size_t i = 0; i < world.moverCount(); ++i) {
        if (!sight->observe(world.time(), world.robot().pose.position(), i, views[i], velocities[i], 0.0)) continue;
        seen_views[seen] = sight->footprint(i);
        seen_velocities[seen] = sight->velocity(i);
        seen_turn_rates[seen] = 0.0;
        ++seen;
      }
      obstacles.set(std::span<const PolygonView>(seen_views.data(), seen),
                    std::span<const Vec2>(seen_velocities.data(), seen),
                    std::span<const double>(seen_turn_rates.data(), seen));
    } else {
      obstacles.set(views, velocities);
    }
    const RobotState& rs = world.robot();
    CycleInputs in;
    in.robot = UnicycleState{rs.pose.x, rs.pose.y, rs.pose.theta, rs.v, rs.w};
    in.obstacles = &obstacles;
    PlannerBudget budget = options.budget.make();
    if (recording) {
      recording->agent(0).obstacles(camera || sight ? record::ObstacleInputs{std::span<const PolygonView>(seen_views.data(), seen),
                                                                    std::span<const Vec2>(seen_velocities.data(), seen),
                                                                    std::span<const double>(seen_turn_rates.data(), seen)}
                                           : record::ObstacleInputs{views, velocities, {}});
      budget = recording->agent(0).before(cycle, options.budget, &steadyClockNs);
    }
    const CycleOutput out = cycle.step(in, budget);
    double v_cmd = out.v_cmd;
    if (camera) {
      v_cmd = camera->limitSpeed(world.time(), rs.pose, out.v_cmd, out.w_cmd);
      camera->aimHead(rs.pose, out.v_cmd, out.w_cmd, cycle.lastPath(), period);
    }
    if (recording) {
      // The command to the base is the camera's limited one; the cycle's own is beside it.
      recording->agent(0).after(cycle, record::simNanos(world.time()), in.robot, record::StepKind::kStepped, 0, &out,
                                {v_cmd, out.w_cmd, false, out.v_cmd, out.w_cmd, false});
    }
    result.trace.push_back(rs.pose);
    if (out.planned) {
      ++result.calls;
      pops.push_back(out.plan.stats.pops);
      succ.push_back(out.plan.stats.successors);
      depth.push_back(out.plan.depth);
      early += out.plan.outcome == PlanResult::Outcome::kFinished;
      result.brakes += out.plan.outcome == PlanResult::Outcome::kBrake;
      plan_us.push_back(static_cast<double>(out.plan_ns) * 1e-3);
      cycle_us.push_back(static_cast<double>(out.path_ns + out.local_ns + out.plan_ns) * 1e-3);
      path_us.push_back(static_cast<double>(out.path_ns) * 1e-3);
      if (!options.svg_dir.empty() && options.controller == nullptr && k % std::max(1, options.svg_every) == 0) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.svg", k);
        writeFrame(options.svg_dir / name, world, cycle, out, obstacles);
        ++result.frames_written;
      }
    }
    if (options.on_cycle) options.on_cycle(world, out, k);
    result.final_state = toString(out.state);
    result.reason = out.state == CycleState::kUnreachable ? toString(out.path_status) : "";
    if (out.state == CycleState::kReached) {
      result.reached_goal = true;
      result.goals_reached = 1;
      result.time_to_goal_s = world.time();
      break;
    }
    world.step(period, v_cmd, out.w_cmd);
  }
  if (recording) recording->close();
  result.duration_s = world.time();
  if (!result.reached_goal) result.time_to_goal_s = world.time();
  result.collisions = world.collisionEpisodes();
  result.min_clearance_m = world.minClearance();
  result.final_pose = world.robot().pose;
  if (camera) {
    result.camera_frames = camera->frames();
    result.camera_frames_lost = camera->framesLost();
  }
  result.expansions = distributionOf(pops);
  result.successors = distributionOf(succ);
  result.depth = distributionOf(depth);
  result.plan_us = distributionOf(plan_us);
  result.cycle_us = distributionOf(cycle_us);
  result.path_us = distributionOf(path_us);
  result.finished_early_ratio = result.calls > 0 ? static_cast<double>(early) / result.calls : 0.0;
  return result;
}

void writeFrame(const std::filesystem::path& file, const World& world, ControlCycle& cycle, const CycleOutput& out,
                const DynamicObstacleSet& obstacles) {
  FrameScene scene;
  scene.map = &world.map();
  scene.body = world.footprint();
  scene.robot = world.robot().pose;
  char caption[160];
  std::snprintf(caption, sizeof caption, "t = %.2f s   v = %.2f m/s   pops %u   depth %d   %s", world.time(),
                world.robot().v, out.plan.stats.pops, out.plan.depth, toString(out.plan.outcome));
  scene.caption.push_back(caption);
  drawCycleFrame(file, scene, cycle, out, obstacles);
}

void drawCycleFrame(const std::filesystem::path& file, const FrameScene& scene, ControlCycle& cycle,
                    const CycleOutput& out, const DynamicObstacleSet& obstacles) {
  const LocalMap& local = cycle.localMap();
  // Frame the local box with a margin: the paper's Fig. 1 view.
  Box view{local.boxCorners()[0], local.boxCorners()[0]};
  for (const Vec2& c : local.boxCorners()) {
    view.min = view.min.cwiseMin(c);
    view.max = view.max.cwiseMax(c);
  }
  view.min -= Vec2(1.0, 1.0);
  view.max += Vec2(1.0, 1.0);
  SvgCanvasOptions opt;
  opt.px_per_m = 60.0;
  opt.side_panel_px = 170.0;
  opt.margin_px = std::max(opt.margin_px, 14.0 * static_cast<double>(scene.caption.size()) + 6.0);
  SvgCanvas canvas(view, opt);
  canvas.beginGroup(SvgStyle{}, true);
  // Inflated obstacles M' (light) and real ones (dark).
  canvas.polygons(cycle.pathPlanner().inflatedObstacles(), svgFill("#f4c7a1", 0.6));
  canvas.polygons(scene.map->obstacles, svgFill("#4a4a4a"));
  // Occupied cells of the collision grid C and the costmap C' (blurred halo).
  std::vector<Box> cells;
  const int w = local.width(), h = local.height();
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const float c = local.costmap()[static_cast<std::size_t>(j) * w + i];
      if (c > 0.05f && !local.grid()[static_cast<std::size_t>(j) * w + i]) {
        const Vec2 p = local.cellCenter(i, j);
        cells.push_back(Box{p - Vec2(0.02, 0.02), p + Vec2(0.02, 0.02)});
      }
    }
  }
  canvas.rects(cells, svgFill("#e8867c", 0.35));
  cells.clear();
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      if (local.grid()[static_cast<std::size_t>(j) * w + i]) {
        const Vec2 p = local.cellCenter(i, j);
        cells.push_back(Box{p - Vec2(0.025, 0.025), p + Vec2(0.025, 0.025)});
      }
    }
  }
  canvas.rects(cells, svgFill("#d9822b", 0.9));
  // The local box.
  canvas.polygon(std::span<const Vec2>(local.boxCorners().data(), 4), svgStroke("#1f5fa8", 1.5, "6 3"));
  // The global path.
  canvas.polyline(cycle.lastPath(), svgStroke("#1f9e4a", 2.0));
  // The search tree.
  std::vector<std::pair<Vec2, Vec2>> edges;
  cycle.planner().forEachEdge([&](const UnicycleState& a, const UnicycleState& b) { edges.emplace_back(a.position(), b.position()); });
  canvas.segments(edges, svgStroke("#7a7a7a", 0.6));
  // Movers now, and predicted at 0.3 s steps to depth 3.
  FixedPolygon pred;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    canvas.polygon(obstacles.observed(k).view(), svgFill("#8e44ad", 0.8));
    for (int d = 1; d <= 3; ++d) {
      obstacles.predict(k, d * cycle.planner().config().dt, pred);
      canvas.polygon(pred.view(), svgStroke("#8e44ad", 1.0, "3 2"));
    }
  }
  // The chosen trajectory and the robot.
  std::vector<Vec2> traj;
  for (const UnicycleState& s : out.plan.trajectory) traj.push_back(s.position());
  canvas.polyline(traj, svgStroke("#c0392b", 3.0));
  // The first action (to the plan's first state), in its braking-safety tier's colour.
  static const char* const kTierColours[] = {"#e74c3c", "#f39c12", "#27ae60"};
  const bool tiered = scene.first_action_tier >= 0 && scene.first_action_tier <= 2 && traj.size() >= 2;
  if (tiered) {
    canvas.polyline(std::span<const Vec2>(traj.data(), 2), svgStroke(kTierColours[scene.first_action_tier], 6.0));
  }
  canvas.polygon(scene.body, svgFill("#2c3e50", 0.85));
  canvas.arrow(scene.robot, 0.5, svgStroke("#ffffff", 2.0));
  const IntermediateGoal& g = local.intermediateGoal();
  canvas.marker(g.pose.position(), 6.0, svgFill("#f1c40f"));
  canvas.arrow(g.pose, 0.6, svgStroke("#b7950b", 2.0));
  canvas.endGroup();
  for (std::size_t i = 0; i < scene.caption.size(); ++i) {
    canvas.textPx(Vec2(opt.margin_px, 14.0 + 14.0 * static_cast<double>(i)), scene.caption[i], i == 0 ? 12.0 : 11.0);
  }
  canvas.scaleBar();
  std::vector<LegendEntry> legend{
      {"obstacle", svgFill("#4a4a4a"), LegendSymbol::kArea},
      {"inflated (M')", svgFill("#f4c7a1", 0.6), LegendSymbol::kArea},
      {"collision grid C", svgFill("#d9822b", 0.9), LegendSymbol::kArea},
      {"costmap C'", svgFill("#e8867c", 0.35), LegendSymbol::kArea},
      {"local box", svgStroke("#1f5fa8", 1.5, "6 3"), LegendSymbol::kLine},
      {"global path", svgStroke("#1f9e4a", 2.0), LegendSymbol::kLine},
      {"search tree", svgStroke("#7a7a7a", 0.6), LegendSymbol::kLine},
      {"plan", svgStroke("#c0392b", 3.0), LegendSymbol::kLine},
      {"mover, D(t)", svgFill("#8e44ad", 0.8), LegendSymbol::kArea},
      {"G~", svgFill("#f1c40f"), LegendSymbol::kMarker},
  };
  if (tiered) {
    static const char* const kTierNames[] = {"1st action: no tier", "1st action: braking", "1st action: passive"};
    legend.push_back({kTierNames[scene.first_action_tier], svgStroke(kTierColours[scene.first_action_tier], 6.0),
                      LegendSymbol::kLine});
  }
  canvas.legend(legend);
  canvas.save(file);
}

}  // namespace staa
