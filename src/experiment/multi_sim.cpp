#include "experiment/multi_sim.hpp"

#include "control/dwa_controller.hpp"
#include "experiment/agent_camera.hpp"
#include "experiment/sight_obstacles.hpp"
#include "control/pd_controller.hpp"
#include "geometry/splitmix64.hpp"
#include "record/recorder.hpp"
#include "world/multi_world.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace staa {

const char* toString(SimMode mode) {
  switch (mode) {
    case SimMode::kCooperative: return "cooperative";
    case SimMode::kGhost: return "ghost";
  }
  return "unknown";
}

const char* toString(ControllerKind kind) {
  switch (kind) {
    case ControllerKind::kStaa: return "staa";
    case ControllerKind::kDwa: return "dwa";
    case ControllerKind::kPd: return "pd";
  }
  return "unknown";
}

bool parseSimMode(const std::string& text, SimMode& out) {
  if (text == "cooperative") {
    out = SimMode::kCooperative;
  } else if (text == "ghost") {
    out = SimMode::kGhost;
  } else {
    return false;
  }
  return true;
}

bool parseControllerKind(const std::string& text, ControllerKind& out) {
  if (text == "staa") {
    out = ControllerKind::kStaa;
  } else if (text == "dwa") {
    out = ControllerKind::kDwa;
  } else if (text == "pd") {
    out = ControllerKind::kPd;
  } else {
    return false;
  }
  return true;
}

namespace {
// Independent streams: one for the start poses, one per agent for its goals, so an agent's
// goal sequence does not depend on what the others do (the controllers are compared on the
// same goals for the same seed).
std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) {
  SplitMix64 mix(seed ^ (0xD1B54A32D192ED03ULL * (stream + 1)));
  return mix.next();
}

constexpr std::size_t kStartStream = 0;
// The cameras' noise streams: one per agent, apart from the goal streams (1 + agent).
constexpr std::size_t kCameraStream = 1u << 20;
constexpr int kHeadingTries = 16;

struct SimAgent {
  std::unique_ptr<ControlCycle> cycle;
  std::unique_ptr<LocalController> controller;  // DWA or PD; null for STAA*
  DynamicObstacleSet seen;                      // the other agents as this one perceives them
  bool evaluated = false;                       // runs the evaluated controller
  bool perceives = false;                       // sees the other agents
  SplitMix64 rng{0};
  std::size_t goal_index = 0;                   // into map.goals or the goal sequence
  bool has_goal_index = false;                  // start on a goal location: the index of it
  Vec2 goal{0.0, 0.0};
  bool counting = true;                         // false once no goal is left to drive to
  AgentResult result;
  double last_speed = 0.0;  // |v| when this cycle's command was decided
  int last_tier = -1;       // this cycle's STAA* braking-safety tier (-1: none)
  std::unique_ptr<AgentCamera> camera;          // ObstacleSource::kDepth, perceiving agents
  std::unique_ptr<SightObstacles> sight;        // ObstacleSource::kSight, perceiving agents

  explicit SimAgent(std::size_t capacity) : seen(capacity) {}
};

void validate(const PolygonMap& map, const MultiSimOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("runMultiAgent: " + what); };
  if (o.agents < 1) fail("agents must be >= 1, got " + std::to_string(o.agents));
  if (!(o.duration_s >= 0.0) || !std::isfinite(o.duration_s)) fail("duration_s must be finite and >= 0");
  if (!(o.rate_hz > 0.0) || !std::isfinite(o.rate_hz)) fail("rate_hz must be finite and > 0");
  if (!(o.goal_radius_m > 0.0) || !std::isfinite(o.goal_radius_m)) fail("goal_radius_m must be finite and > 0");
  if (!o.budget.isExpansions() && (!(o.budget.ms > 0.0) || !std::isfinite(o.budget.ms))) fail("budget_ms must be > 0");
  const auto n = static_cast<std::size_t>(o.agents);
  if (!o.starts.empty() && o.starts.size() != n) {
    fail(std::to_string(o.starts.size()) + " start poses for " + std::to_string(n) + " agents");
  }
  if (!o.goal_sequences.empty()) {
    if (o.goal_sequences.size() != n) {
      fail(std::to_string(o.goal_sequences.size()) + " goal sequences for " + std::to_string(n) + " agents");
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (o.goal_sequences[i].empty()) fail("agent " + std::to_string(i) + " has an empty goal sequence");
    }
  } else if (map.goals.size() < 2) {
    fail("map '" + map.name + "' needs at least 2 goals, has " + std::to_string(map.goals.size()));
  }
  if (o.starts.empty() && map.goals.size() < n) {
    fail("map '" + map.name + "' has " + std::to_string(map.goals.size()) + " goals for " + std::to_string(n) +
         " agents (each starts on its own goal location)");
  }
}

// Distinct random goal locations with random headings, each footprint free of the map and of
// the agents placed before it.
void placeRandomStarts(const PolygonMap& map, const MultiSimOptions& o, MultiWorld& world,
                       std::vector<std::unique_ptr<SimAgent>>& agents) {
  SplitMix64 rng(streamSeed(o.seed, kStartStream));
  std::vector<std::size_t> unused(map.goals.size());
  for (std::size_t k = 0; k < unused.size(); ++k) unused[k] = k;
  for (std::size_t i = 0; i < agents.size(); ++i) {
    bool placed = false;
    while (!placed && !unused.empty()) {
      const std::size_t pick = rng.below(unused.size());
      const std::size_t g = unused[pick];
      unused.erase(unused.begin() + static_cast<std::ptrdiff_t>(pick));
      for (int t = 0; t < kHeadingTries && !placed; ++t) {
        const Pose2 pose{map.goals[g].x(), map.goals[g].y(), wrapAngle((2.0 * rng.uniform() - 1.0) * kPi)};
        if (world.touchesAnything(pose)) continue;
        const bool ghost = o.mode == SimMode::kGhost && i > 0;
        world.addAgent(pose, ghost ? AgentBody::kGhost : AgentBody::kSolid);
        agents[i]->goal_index = g;
        agents[i]->has_goal_index = true;
        placed = true;
      }
    }
    if (!placed) {
      throw std::invalid_argument("runMultiAgent: map '" + map.name + "': no free start on a goal location for agent " +
                                  std::to_string(i));
    }
  }
}

// The next goal: the next of the agent's sequence, or a random goal location other than the
// current one and farther than the goal radius from where the agent stands.
void assignNextGoal(const PolygonMap& map, const MultiSimOptions& o, std::size_t i, const Vec2& position, SimAgent& a,
                    bool first) {
  if (!o.goal_sequences.empty()) {
    // The next one in turn that lies beyond the radius (the first one to start with).
    const std::vector<Vec2>& seq = o.goal_sequences[i];
    bool found = false;
    for (std::size_t step = 0; step < seq.size() && !found; ++step) {
      const std::size_t k = first ? step : (a.goal_index + 1 + step) % seq.size();
      if ((seq[k] - position).norm() > o.goal_radius_m) {
        a.goal_index = k;
        found = true;
      }
    }
    if (!found) {
      a.counting = false;  // nowhere left to go: stay at the last goal
      return;
    }
    a.goal = seq[a.goal_index];
  } else {
    std::size_t candidates = 0;
    auto eligible = [&](std::size_t k) {
      return !(a.has_goal_index && k == a.goal_index) && (map.goals[k] - position).norm() > o.goal_radius_m;
    };
    for (std::size_t k = 0; k < map.goals.size(); ++k) candidates += eligible(k);
    if (candidates == 0) {
      a.counting = false;  // every goal lies within the radius: nowhere left to go
      return;
    }
    std::size_t chosen = 0;
    std::size_t nth = a.rng.below(candidates);
    for (std::size_t k = 0; k < map.goals.size(); ++k) {
      if (!eligible(k)) continue;
      if (nth == 0) {
        chosen = k;
        break;
      }
      --nth;
    }
    a.goal_index = chosen;
    a.has_goal_index = true;
    a.goal = map.goals[chosen];
  }
  // The goal's heading only shapes the heuristic's last rotation (arrival ignores it): the
  // direction of travel from here, so the final rotation costs nothing on a straight approach.
  const Vec2 d = a.goal - position;
  const double heading = d.squaredNorm() > 0.0 ? std::atan2(d.y(), d.x()) : 0.0;
  a.cycle->setGoal(Pose2{a.goal.x(), a.goal.y(), heading});
}

}  // namespace

MultiSimResult runMultiAgent(const PolygonMap& map, const RobotProfile& robot, const MultiSimOptions& options) {
  validate(map, options);
  const auto n = static_cast<std::size_t>(options.agents);

  // The paper counts a goal passed within goal_radius_m: no heading, no stopping at goals.
  ControlConfig config = options.control;
  config.rate_hz = options.rate_hz;
  config.goal_tolerance_m = options.goal_radius_m;
  config.goal_heading_tolerance = 2.0 * kPi;
  config.staa.heuristic.stop_at_goal = false;

  MultiWorld world(map, robot);
  const bool by_camera = perceived(options.obstacles);
  const DepthObstaclesConfig perception =
      by_camera ? options.perception.value_or(agentPerceptionConfig(robot, options.obstacles == ObstacleSource::kDepthScan))
                : DepthObstaclesConfig{};
  const bool by_sight = options.obstacles == ObstacleSource::kSight;
  // Sight's filter and perception's scorer (when each contact came into the line of sight).
  const LineOfSight line_of_sight(by_sight || by_camera ? std::span<const Polygon>(map.obstacles)
                                                        : std::span<const Polygon>());
  std::vector<std::unique_ptr<SimAgent>> agents;
  agents.reserve(n);
  // Every agent plans against all the others: the capacity is raised to them if it is lower.
  config.max_moving_obstacles = std::max(config.max_moving_obstacles, n > 0 ? n - 1 : 0);
  const std::size_t capacity = config.max_moving_obstacles;
  for (std::size_t i = 0; i < n; ++i) {
    auto a = std::make_unique<SimAgent>(capacity);
    a->evaluated = options.mode == SimMode::kCooperative || i == 0;
    a->perceives = a->evaluated;  // ghosts are oblivious of everyone
    a->rng = SplitMix64(streamSeed(options.seed, 1 + i));
    // Ghosts drive blind on purpose: the blind-corner limit is the evaluated agents' only.
    ControlConfig own = config;
    own.blind_corners.enabled = config.blind_corners.enabled && a->evaluated;
    a->cycle = std::make_unique<ControlCycle>(map, robot, own);
    if (!a->evaluated || options.controller == ControllerKind::kPd) {
      a->controller = std::make_unique<PdController>(robot);
    } else if (options.controller == ControllerKind::kDwa) {
      a->controller = std::make_unique<DwaController>(robot, config.local);
    }
    a->cycle->setLocalController(a->controller.get());
    if (by_camera && a->perceives) {
      a->camera = std::make_unique<AgentCamera>(map, robot, perception, streamSeed(options.seed, kCameraStream + i),
                                                options.obstacles == ObstacleSource::kDepthScan);
    }
    if (by_sight && a->perceives) {
      a->sight = std::make_unique<SightObstacles>(line_of_sight, n, robot.footprint.size(), SightConfig{});
    }
    agents.push_back(std::move(a));
  }
  if (options.starts.empty()) {
    placeRandomStarts(map, options, world, agents);
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      const bool ghost = options.mode == SimMode::kGhost && i > 0;
      world.addAgent(options.starts[i], ghost ? AgentBody::kGhost : AgentBody::kSolid);
    }
  }
  for (std::size_t i = 0; i < n; ++i) assignNextGoal(map, options, i, world.agent(i).pose.position(), *agents[i], true);

  // Scratch for the perception seam and the commands, sized once.
  // (a camera's frame holds up to ObstacleFrame::kMaxObstacles)
  const std::size_t seam = std::max(n, hal::ObstacleFrame::kMaxObstacles);
  std::vector<PolygonView> views(seam);
  std::vector<Vec2> velocities(seam);
  std::vector<double> turn_rates(seam);
  std::vector<AgentCommand> commands(n);
  std::vector<Vec2> current_goals(options.on_step_goals ? n : 0);
  std::vector<int> episodes_before(n, 0);
  // Depth: the other bodies as prisms, their pixels in a frame, the scorer.
  std::vector<hal::PrismView> prisms(n);
  std::vector<std::size_t> others(n);
  std::vector<std::uint32_t> pixels(n);
  PerceptionScorer scorer(by_camera ? n : 0, &line_of_sight, SightConfig{}.range_m);
  std::unique_ptr<record::SimRecording> recording;
  if (!options.record_path.empty()) {
    record::Session session = options.record_session;
    session.control = agents[0]->cycle->config();
    session.robot = robot;
    session.map = map;
    for (std::size_t i = 0; i < n; ++i) {
      session.agents.push_back({static_cast<std::uint16_t>(i), agents[i]->controller ? agents[i]->controller->name() : "staa",
                                !agents[i]->evaluated});
    }
    record::RecordLimits limits;
    // Depth: what perception made of a frame (up to ObstacleFrame's obstacles and vertices).
    limits.obstacles = by_camera ? seam : std::max<std::size_t>(1, n - 1);
    if (by_camera) limits.vertices = std::max(limits.vertices, hal::ObstacleFrame::kMaxVertices);
    limits.vertices = std::max<std::size_t>(limits.vertices, robot.footprint.size());
    limits.path_points = 4096;
    limits.trajectory = 256;
    recording = std::make_unique<record::SimRecording>(options.record_path, session, limits);
  }

  MultiSimResult result;
  const double period = 1.0 / options.rate_hz;
  const int cycles = static_cast<int>(std::ceil(options.duration_s * options.rate_hz - 1e-9));
  std::vector<double> pops, succ, depth, plan_us;
  const std::size_t calls = static_cast<std::size_t>(cycles) * (options.mode == SimMode::kCooperative ? n : 1);
  for (std::vector<double>* values : {&pops, &succ, &depth, &plan_us}) values->reserve(calls);
  int early = 0;
  int last_second = 0;
  for (int k = 0; k < cycles; ++k) {
    // Every agent decides on the same snapshot of the world.
    for (std::size_t i = 0; i < n; ++i) {
      SimAgent& a = *agents[i];
      std::size_t m = 0;  // the others seen: what the planner gets (and the recorder keeps)
      if (a.perceives && a.camera) {
        // What its camera saw: a frame rendered now, its obstacles once they have arrived.
        std::size_t bodies = 0;
        for (std::size_t j = 0; j < n; ++j) {
          if (j == i) continue;
          prisms[bodies] = hal::PrismView{PolygonView(world.footprint(j)), Vec2(0.0, 0.0), robot.height_m};
          others[bodies] = j;
          ++bodies;
        }
        const double now = world.time();
        if (a.camera->perceive(now, world.agent(i).pose, std::span<const hal::PrismView>(prisms.data(), bodies),
                               std::span<std::uint32_t>(pixels.data(), bodies))) {
          scorer.score(world, i, now, a.camera->frame(), std::span<const std::size_t>(others.data(), bodies),
                       std::span<const std::uint32_t>(pixels.data(), bodies));
          scorer.addCost(a.camera->renderUs(), a.camera->perceptionUs());
        }
        if (options.on_perceived) options.on_perceived(i, a.camera->delivered(now), a.camera->pan());
        if (const hal::ObstacleFrame* f = a.camera->delivered(now)) {
          for (std::size_t o = 0; o < f->count; ++o) {
            views[m] = PolygonView(f->obstacles[o].vertices.data(), f->obstacles[o].n);
            velocities[m] = f->obstacles[o].velocity;
            turn_rates[m] = f->obstacles[o].turn_rate;
            ++m;
          }
        }
        a.seen.set(std::span<const PolygonView>(views.data(), m), std::span<const Vec2>(velocities.data(), m),
                   std::span<const double>(turn_rates.data(), m));
      } else if (a.perceives && a.sight) {
        // The ground truth of the others in its line of sight (and of those just out of it).
        const Vec2 eye = world.agent(i).pose.position();
        for (std::size_t j = 0; j < n; ++j) {
          if (j == i) continue;
          if (!a.sight->observe(world.time(), eye, j, world.footprint(j), world.velocity(j), world.agent(j).w)) continue;
          views[m] = a.sight->footprint(j);
          velocities[m] = a.sight->velocity(j);
          turn_rates[m] = a.sight->turnRate(j);
          ++m;
        }
        a.seen.set(std::span<const PolygonView>(views.data(), m), std::span<const Vec2>(velocities.data(), m),
                   std::span<const double>(turn_rates.data(), m));
      } else if (a.perceives) {
        // Ground truth: the others' footprints, velocities and turn rates.
        for (std::size_t j = 0; j < n; ++j) {
          if (j == i) continue;
          views[m] = world.footprint(j);
          velocities[m] = world.velocity(j);
          turn_rates[m] = world.agent(j).w;
          ++m;
        }
        a.seen.set(std::span<const PolygonView>(views.data(), m), std::span<const Vec2>(velocities.data(), m),
                   std::span<const double>(turn_rates.data(), m));
      }
      if (a.perceives && options.on_obstacles) {
        options.on_obstacles(i, std::span<const PolygonView>(views.data(), m), std::span<const Vec2>(velocities.data(), m));
      }
      const RobotState& rs = world.agent(i);
      CycleInputs in;
      in.robot = UnicycleState{rs.pose.x, rs.pose.y, rs.pose.theta, rs.v, rs.w};
      in.obstacles = a.perceives ? &a.seen : nullptr;
      PlannerBudget budget = options.budget.make();
      if (recording) {
        record::CycleRecorder& rec = recording->agent(i);
        rec.obstacles({std::span<const PolygonView>(views.data(), m), std::span<const Vec2>(velocities.data(), m),
                       std::span<const double>(turn_rates.data(), m)});
        budget = rec.before(*a.cycle, options.budget, &steadyClockNs);
      }
      const CycleOutput out = a.cycle->step(in, budget);
      commands[i] = AgentCommand{out.v_cmd, out.w_cmd};
      if (a.camera) {
        // The head turns to where the controller wants to go; the speed goes there once seen.
        commands[i].v = a.camera->limitSpeed(world.time(), rs.pose, out.v_cmd, out.w_cmd);
        a.camera->aimHead(rs.pose, out.v_cmd, out.w_cmd, a.cycle->lastPath(), period);
      }
      if (recording) {
        // The command to the base is the camera's limited one; the cycle's own is beside it.
        recording->agent(i).after(*a.cycle, record::simNanos(world.time()), in.robot, record::StepKind::kStepped, 0, &out,
                                  {commands[i].v, out.w_cmd, false, out.v_cmd, out.w_cmd, false});
      }
      a.last_speed = std::abs(rs.v);
      a.last_tier = out.planned && a.evaluated && !a.controller ? out.plan.brake_safety_tier : -1;
      if (options.on_cycle) options.on_cycle(i, out);
      if (a.evaluated && out.planned) {
        ++result.calls;
        pops.push_back(out.plan.stats.pops);
        succ.push_back(out.plan.stats.successors);
        depth.push_back(out.plan.depth);
        early += out.plan.outcome == PlanResult::Outcome::kFinished;
        plan_us.push_back(static_cast<double>(out.plan_ns) * 1e-3);
      }
    }
    for (std::size_t i = 0; i < n; ++i) episodes_before[i] = world.collisionEpisodes(i);
    world.step(period, commands);
    for (std::size_t i = 0; i < n; ++i) {
      if (world.collisionEpisodes(i) == episodes_before[i]) continue;
      if (options.mode == SimMode::kGhost && i != 0) continue;  // only counted agents
      ContactRecord c;
      c.time_s = world.time();
      c.agent = static_cast<int>(i);
      c.other = world.touchedLastStep(i);
      c.speed = agents[i]->last_speed;
      c.tier = agents[i]->last_tier;
      if (c.other >= 0) {
        c.other_speed = agents[static_cast<std::size_t>(c.other)]->last_speed;
        c.other_tier = agents[static_cast<std::size_t>(c.other)]->last_tier;
        if (agents[i]->perceives && agents[i]->camera) {
          c.perceived = true;
          c.sighting = scorer.sighting(i, static_cast<std::size_t>(c.other), c.time_s);
        }
      }
      result.contacts.push_back(c);
      if (recording) {
        char text[256];
        std::snprintf(text, sizeof text,
                      R"({"t":%.17g,"agent":%d,"other":%d,"speed":%.17g,"other_speed":%.17g,"tier":%d,"other_tier":%d})",
                      c.time_s, c.agent, c.other, c.speed, c.other_speed, c.tier, c.other_tier);
        recording->event("/contacts", record::simNanos(c.time_s), text);
      }
    }

    // Goals passed within the radius count; the agent gets its next one.
    for (std::size_t i = 0; i < n; ++i) {
      SimAgent& a = *agents[i];
      const Vec2 p = world.agent(i).pose.position();
      if (a.counting && (p - a.goal).norm() <= options.goal_radius_m) {
        ++a.result.goals_reached;
        assignNextGoal(map, options, i, p, a, false);
      }
    }
    if (options.on_step) options.on_step(world);
    if (options.on_step_goals) {
      for (std::size_t i = 0; i < n; ++i) current_goals[i] = agents[i]->goal;
      options.on_step_goals(world, current_goals, k);
    }
    const int second = static_cast<int>(std::floor(world.time() + 1e-9));
    if (second > last_second) {
      last_second = second;
      if (options.on_second) options.on_second(world.time());
    }
  }

  if (recording) recording->close();
  result.duration_s = world.time();
  result.agents.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    AgentResult& r = result.agents[i];
    r = agents[i]->result;
    r.collisions = world.collisionEpisodes(i);
    r.distance_m = world.distance(i);
    if (options.mode == SimMode::kCooperative || i == 0) {
      result.goals_reached += r.goals_reached;
      result.collisions += r.collisions;
    }
  }
  result.score = result.goals_reached - result.collisions;
  result.expansions = distributionOf(pops);
  result.successors = distributionOf(succ);
  result.plan_us = distributionOf(plan_us);
  result.depth_mean = distributionOf(depth).mean;
  result.finished_early_ratio = result.calls > 0 ? static_cast<double>(early) / result.calls : 0.0;
  if (by_camera) {
    PerceptionAccuracy accuracy = scorer.accuracy();
    for (const auto& a : agents) {
      if (a->camera) accuracy.frames_lost += a->camera->framesLost();
    }
    result.perception = std::move(accuracy);
  }
  return result;
}

}  // namespace staa
