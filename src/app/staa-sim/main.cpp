// staa-sim: the simulator (docs/ARCHITECTURE.md section 6). Runs the real control cycle against a
// simulated world: one robot from a start to a goal in a polygon map (--map/--start/--goal), a
// scenario among scripted movers (--scenario), several agents driving between random goals
// of a map (--agents N > 1 or --mode ghost: the paper's Sec. IV-B, one run), or the whole
// experiment (`staa-sim experiment`).
// Exit status: 0 on a completed run (reached or not), 2 on bad input with one line on stderr
// naming the option or file and the value, 1 on an unexpected failure during the run.

#include "experiment/results_json.hpp"
#include "control/control_cycle.hpp"
#include "robot/robot_profile.hpp"
#include "geometry/polygon.hpp"
#include "map/polygon_map.hpp"
#include "planner/heuristic.hpp"
#include "experiment/experiment.hpp"
#include "world/footprint.hpp"
#include "experiment/multi_sim.hpp"
#include "world/multi_world.hpp"
#include "world/scenario.hpp"
#include "experiment/sim_runner.hpp"
#include "world/world.hpp"
#include "viz/map_drawing.hpp"
#include "viz/svg.hpp"
#include "record/recording.hpp"

#include "app/cli_support.hpp"
#include "app/staa-sim/experiment_command.hpp"
#include "app/staa-sim/sim_options.hpp"
#include "control/dwa_controller.hpp"
#include "control/pd_controller.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iostream>
#include <limits>
#include <optional>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace {

namespace fs = std::filesystem;
using staa::Pose2;
using staa::Vec2;
using Json = nlohmann::ordered_json;
using staa::distributionJson;

using staa::cli::InputError;
using staa::cli::kExitBadInput;
constexpr int kExitRunFailed = 1;

// ---- output helpers ----

std::string fmt(double v, int decimals = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

std::string fmtPose(const Pose2& p) { return "(" + fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.theta) + ")"; }


// ---- the request ----

struct Request {
  staa::Scenario scenario;
  std::string map_label;  // the map file as given (or as the scenario resolved it)
  std::string scenario_file;
  staa::ControllerKind controller = staa::ControllerKind::kStaa;
  staa::SimMode mode = staa::SimMode::kCooperative;
  int agents = 1;
  std::uint64_t seed = 1;
  staa::SimOptions options;
  staa::HeuristicKind heuristic = staa::HeuristicKind::kPathRtr;
  std::string json_file;
  bool quiet = false;
};

// The start must leave the whole footprint free (World::collides: obstacles, movers, bounds);
// the message names what it hits.
void checkStart(const staa::Scenario& sc, const std::string& where) {
  const staa::World world(sc);
  if (!world.collides(sc.start)) return;
  const staa::Polygon body = staa::footprintAt(sc.robot.footprint, sc.start);
  std::string what = "touches a mover";
  for (std::size_t i = 0; i < sc.map.obstacles.size(); ++i) {
    if (staa::polygonDistance(body, sc.map.obstacles[i]) == 0.0) {
      what = "overlaps obstacle " + std::to_string(i) + " of the map";
      break;
    }
  }
  if (sc.map.bounds) {
    for (const Vec2& p : body) {
      if (!(p.x() > sc.map.bounds->min.x() && p.x() < sc.map.bounds->max.x() && p.y() > sc.map.bounds->min.y() &&
            p.y() < sc.map.bounds->max.y())) {
        what = "reaches the map bounds";
      }
    }
  }
  throw InputError(where + " " + fmtPose(sc.start) + ": the robot's footprint (" + sc.robot.name + ") " + what);
}

// A goal inside (or on) an obstacle or outside the bounds is rejected (docs/ARCHITECTURE.md section 6).
void checkGoal(const staa::Scenario& sc, const std::string& where) {
  const Vec2 g = sc.goal.position();
  const auto& b = sc.map.bounds;
  if (b && !(g.x() > b->min.x() && g.x() < b->max.x() && g.y() > b->min.y() && g.y() < b->max.y())) {
    throw InputError(where + " " + fmtPose(sc.goal) + ": outside the map bounds [" + fmt(b->min.x()) + ", " +
                     fmt(b->min.y()) + ", " + fmt(b->max.x()) + ", " + fmt(b->max.y()) + "]");
  }
  for (std::size_t i = 0; i < sc.map.obstacles.size(); ++i) {
    if (staa::locatePoint(g, sc.map.obstacles[i]) != staa::Containment::kOutside) {
      throw InputError(where + " " + fmtPose(sc.goal) + ": inside obstacle " + std::to_string(i) + " of the map");
    }
  }
}

// ---- the run ----

Json resultJson(const Request& rq, const staa::SimResult& r) {
  const auto& o = rq.options;
  Json j;
  j["map"] = rq.map_label;
  j["scenario"] = rq.scenario_file.empty() ? Json(nullptr) : Json(rq.scenario_file);
  j["robot"] = rq.scenario.robot.name;
  j["controller"] = staa::toString(rq.controller);
  j["mode"] = staa::toString(rq.mode);
  j["agents"] = rq.agents;
  j["seed"] = rq.seed;
  j["rate_hz"] = o.rate_hz;
  j["duration_s"] = o.duration_s;
  j["budget"] = staa::budgetJson(o.budget);
  j["heuristic"] = staa::toString(rq.heuristic);
  j["obstacles"] = staa::toString(o.obstacles);
  j["blind_corners"] = o.control.blind_corners.enabled;
  if (staa::perceived(o.obstacles)) {
    j["camera_frames"] = r.camera_frames;
    j["camera_frames_lost"] = r.camera_frames_lost;
  }
  const Pose2& s = rq.scenario.start;
  const Pose2& g = rq.scenario.goal;
  j["start"] = Json::array({s.x, s.y, s.theta});
  j["goal"] = Json::array({g.x, g.y, g.theta});
  j["movers"] = rq.scenario.movers.size();

  j["goals_reached"] = r.goals_reached;
  j["collisions"] = r.collisions;
  j["score"] = r.goals_reached - r.collisions;
  j["reached_goal"] = r.reached_goal;
  j["time_to_goal_s"] = r.time_to_goal_s;
  // Infinite only in an unbounded, empty world: JSON has no infinity, so null.
  j["min_clearance_m"] = std::isfinite(r.min_clearance_m) ? Json(r.min_clearance_m) : Json(nullptr);

  j["planner"] = plannerJson(r.calls, r.expansions, r.successors, r.finished_early_ratio, r.depth.mean,
                             r.plan_us);
  j["cycle_us"] = distributionJson(r.cycle_us, false, true);
  j["path_us"] = distributionJson(r.path_us, false, true);
  j["brakes"] = r.brakes;
  j["final_state"] = r.final_state;
  j["reason"] = r.reason.empty() ? Json(nullptr) : Json(r.reason);
  j["final_pose"] = Json::array({r.final_pose.x, r.final_pose.y, r.final_pose.theta});
  j["simulated_s"] = r.duration_s;
  j["frames_written"] = r.frames_written;
  return j;
}

std::string summary(const staa::SimResult& r) {
  std::ostringstream s;
  if (r.reached_goal) {
    s << "reached goal in " << fmt(r.time_to_goal_s) << " s";
  } else {
    s << "goal not reached after " << fmt(r.duration_s) << " s (state " << r.final_state
      << (r.reason.empty() ? std::string() : ": " + r.reason) << ")";
  }
  s << "; collisions " << r.collisions << "; min clearance "
    << (std::isfinite(r.min_clearance_m) ? fmt(r.min_clearance_m, 3) + " m" : std::string("inf")) << "; planner "
    << r.calls << " calls, pops mean " << fmt(r.expansions.mean, 1) << ", plan p50 " << fmt(r.plan_us.p50 * 1e-3, 3)
    << " ms p99 " << fmt(r.plan_us.p99 * 1e-3, 3) << " ms";
  if (r.brakes > 0) s << ", " << r.brakes << " brakes";
  if (r.frames_written > 0) s << "; " << r.frames_written << " frames";
  return s.str();
}

// Opened before the run: a bad --json path fails before a long run, not after it.
void openJsonOutput(const std::string& file, std::ofstream& out) {
  if (file.empty()) return;
  // Create the folder it goes into, as --svg does for its own.
  const std::filesystem::path parent = std::filesystem::path(file).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  out.open(file, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError("--json: cannot write '" + file + "'");
}

void writeJsonOutput(const std::string& file, std::ofstream& out, const Json& j) {
  if (!out.is_open()) return;
  out << j.dump(2) << '\n';
  out.close();
  if (!out) throw InputError("--json: cannot write '" + file + "'");
}

void makeSvgDir(const fs::path& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw InputError("--svg: cannot create the directory '" + dir.string() + "'" +
                     (ec ? " (" + ec.message() + ")" : std::string()));
  }
}

void announce(const Request& rq) {
  const auto& o = rq.options;
  std::cerr << "staa-sim: " << rq.scenario.name << ": " << fmtPose(rq.scenario.start) << " -> "
            << fmtPose(rq.scenario.goal) << ", " << rq.scenario.movers.size()
            << (rq.scenario.movers.size() == 1 ? " mover, " : " movers, ") << staa::toString(rq.controller) << " ("
            << staa::toString(rq.heuristic) << ", " << o.budget.describe() << " per cycle), " << fmt(o.duration_s, 1)
            << " s at " << fmt(o.rate_hz, 1) << " Hz\n";
}

// One line per simulated second; the callback runs outside the timed cycle.
void reportEverySecond(staa::SimOptions& o) {
  const double rate = o.rate_hz;
  o.on_cycle = [rate, last = 0L](const staa::World& world, const staa::CycleOutput& out, int cycle) mutable {
    const long second = static_cast<long>(std::floor(static_cast<double>(cycle) / rate + 1e-9));
    if (second <= last) return;
    last = second;
    const staa::RobotState& rs = world.robot();
    std::fprintf(stderr, "t=%.1fs pos=(%.2f,%.2f) v=%.2f state=%s\n", world.time(), rs.pose.x, rs.pose.y, rs.v,
                 staa::toString(out.state));
  };
}

// The paper's baselines run in the same cycle in place of STAA* (null: STAA*).
std::unique_ptr<staa::LocalController> baselineController(const Request& rq) {
  if (rq.controller == staa::ControllerKind::kPd) return std::make_unique<staa::PdController>(rq.scenario.robot);
  if (rq.controller == staa::ControllerKind::kDwa) {
    return std::make_unique<staa::DwaController>(rq.scenario.robot, rq.options.control.local);
  }
  return nullptr;
}

int simulate(Request& rq) {
  std::ofstream json_out;
  openJsonOutput(rq.json_file, json_out);
  makeSvgDir(rq.options.svg_dir);
  if (!rq.quiet) {
    announce(rq);
    reportEverySecond(rq.options);
  }
  const std::unique_ptr<staa::LocalController> baseline = baselineController(rq);  // owned here, for the run
  rq.options.controller = baseline.get();

  staa::SimResult result;
  try {
    result = staa::runSingleRobot(rq.scenario, rq.options);
  } catch (const std::exception& e) {
    std::cerr << "staa-sim: the run failed: " << e.what() << '\n';
    return kExitRunFailed;
  }

  writeJsonOutput(rq.json_file, json_out, resultJson(rq, result));
  std::cout << summary(result) << '\n';
  return 0;
}

// ---- multi-agent runs (--agents N > 1 or --mode ghost) ----

struct MultiRequest {
  staa::PolygonMap map;
  std::string map_label;       // the map file as given
  bool goals_placed = false;   // the file had no goals: placed for the run
  staa::RobotProfile robot;
  staa::HeuristicKind heuristic = staa::HeuristicKind::kPathRtr;
  staa::MultiSimOptions options;
  std::string json_file;
  fs::path svg_dir;
  int svg_every = 15;
  bool quiet = false;
};

// The agents whose results count (the contract's score): all in cooperative mode, the
// observed agent 0 in ghost mode.
bool counted(const MultiRequest& rq, std::size_t agent) {
  return rq.options.mode == staa::SimMode::kCooperative || agent == 0;
}

// min_clearance_m for several agents: the smallest distance between a counted agent's
// footprint and an obstacle, the bounds or another agent (ghosts included: they count as
// contacts of the observed agent), over the states after every step.
class ClearanceTracker {
 public:
  explicit ClearanceTracker(const staa::PolygonMap& map) : map_(map) {
    for (const staa::Polygon& p : map.obstacles) boxes_.push_back(staa::boundingBox(p));
  }

  void update(const staa::MultiWorld& world, const MultiRequest& rq) {
    for (std::size_t i = 0; i < world.size(); ++i) {
      if (counted(rq, i)) best_ = std::min(best_, clearance(world, i));
    }
  }
  double value() const { return best_; }

 private:
  // Only what lies nearer than the best so far can lower it: boxes prune the rest.
  double clearance(const staa::MultiWorld& world, std::size_t i) const {
    const staa::Polygon& body = world.footprint(i);
    double best = best_;
    if (map_.bounds) {
      const staa::Box& b = *map_.bounds;
      for (const Vec2& p : body) {
        best = std::min({best, p.x() - b.min.x(), b.max.x() - p.x(), p.y() - b.min.y(), b.max.y() - p.y()});
      }
      if (best <= 0.0) return 0.0;
    }
    const staa::Box box = staa::boundingBox(body);
    for (std::size_t k = 0; k < boxes_.size(); ++k) {
      if (staa::boxDistance(box, boxes_[k]) >= best) continue;
      best = std::min(best, staa::polygonDistance(body, map_.obstacles[k]));
      if (best <= 0.0) return 0.0;
    }
    for (std::size_t j = 0; j < world.size(); ++j) {
      if (j == i) continue;
      const staa::Polygon& other = world.footprint(j);
      if (staa::boxDistance(box, staa::boundingBox(other)) >= best) continue;
      best = std::min(best, staa::polygonDistance(body, other));
      if (best <= 0.0) return 0.0;
    }
    return best;
  }

  const staa::PolygonMap& map_;
  std::vector<staa::Box> boxes_;
  double best_ = std::numeric_limits<double>::infinity();
};

// Solid agents each in their own colour (goal, trail and body agree); ghosts grey.
constexpr const char* kAgentColours[] = {"#1971c2", "#e8590c", "#2f9e44", "#c2255c", "#0c8599", "#e67700", "#5f3dc4"};
constexpr const char* kGhostColour = "#868e96";
constexpr const char* kContactColour = "#e03131";
constexpr double kTrailSeconds = 10.0;

const char* agentColour(const staa::MultiWorld& world, std::size_t i) {
  return world.body(i) == staa::AgentBody::kGhost ? kGhostColour : kAgentColours[i % std::size(kAgentColours)];
}

// One frame of a multi-agent run: the whole map with its goals, every agent's trail, its
// current goal (ring and dashed line), its footprint (red outline while in contact) and
// heading, and the running score.
void writeMultiFrame(const fs::path& file, const MultiRequest& rq, const staa::MultiWorld& world,
                     std::span<const Vec2> goals, const std::vector<std::deque<Vec2>>& trails, int goals_reached,
                     int collisions) {
  staa::SvgCanvasOptions opt;
  opt.px_per_m = staa::autoScale(staa::mapDrawingBox(rq.map), 800.0);
  opt.margin_px = 16.0;
  opt.header_px = 22.0;
  opt.footer_px = 30.0;
  opt.side_panel_px = 190.0;
  staa::SvgCanvas canvas(staa::mapDrawingBox(rq.map), opt);
  staa::drawMap(canvas, rq.map, nullptr);

  const std::size_t n = world.size();
  canvas.beginGroup(staa::SvgStyle{}, true);
  for (std::size_t i = 0; i < n && i < trails.size(); ++i) {
    const std::vector<Vec2> trail(trails[i].begin(), trails[i].end());
    staa::SvgStyle line = staa::svgStroke(agentColour(world, i), 1.6);
    line.opacity = 0.7;
    line.extra = "stroke-linejoin=\"round\"";
    canvas.polyline(trail, line);
  }
  for (std::size_t i = 0; i < n && i < goals.size(); ++i) {
    const char* colour = agentColour(world, i);
    canvas.line(world.agent(i).pose.position(), goals[i], staa::svgStroke(colour, 1.0, "4 3"));
    canvas.marker(goals[i], 10.0, staa::svgStroke(colour, 2.5));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const bool ghost = world.body(i) == staa::AgentBody::kGhost;
    staa::SvgStyle body = staa::svgFill(agentColour(world, i), ghost ? 0.45 : 0.9);
    body.stroke = world.inContact(i) ? kContactColour : "#212529";
    body.stroke_width_px = world.inContact(i) ? 2.5 : 1.0;
    if (ghost) body.dash = "3 2";
    canvas.polygon(world.footprint(i), body);
    canvas.arrow(world.agent(i).pose, 0.45, staa::svgStroke("#ffffff", 1.5), 5.0);
    staa::SvgStyle label;
    label.fill = "#212529";
    label.extra = "font-weight=\"bold\"";
    canvas.text(world.agent(i).pose.position(), std::to_string(i), 10.0, staa::TextAnchor::kMiddle, label, 0.0, -12.0);
  }
  canvas.endGroup();

  char caption[200];
  std::snprintf(caption, sizeof caption, "%s: t = %.2f s, %zu %s (%s, %s): goals %d, collisions %d",
                rq.map.name.c_str(), world.time(), n, n == 1 ? "agent" : "agents", staa::toString(rq.options.mode),
                staa::toString(rq.options.controller), goals_reached, collisions);
  canvas.title(caption);
  canvas.scaleBar();
  const bool ghost_mode = rq.options.mode == staa::SimMode::kGhost;
  std::vector<staa::LegendEntry> legend = staa::mapLegend(false, true, false);
  legend.push_back({ghost_mode ? "observed agent" : "agent", staa::svgFill(kAgentColours[0], 0.9),
                    staa::LegendSymbol::kArea});
  if (ghost_mode && n > 1) {
    legend.push_back({"ghost agent", staa::svgFill(kGhostColour, 0.45), staa::LegendSymbol::kArea});
  }
  legend.push_back({"current goal", staa::svgStroke(kAgentColours[0], 2.5), staa::LegendSymbol::kMarker});
  legend.push_back({"trail (last 10 s)", staa::svgStroke(kAgentColours[0], 1.6), staa::LegendSymbol::kLine});
  legend.push_back({"in contact", staa::svgStroke(kContactColour, 2.5), staa::LegendSymbol::kLine});
  canvas.legend(legend);
  canvas.save(file);
}

Json multiResultJson(const MultiRequest& rq, const staa::MultiSimResult& r, double min_clearance, int frames) {
  const auto& o = rq.options;
  Json j;
  j["map"] = rq.map_label;
  j["scenario"] = nullptr;
  j["robot"] = rq.robot.name;
  j["controller"] = staa::toString(o.controller);
  j["mode"] = staa::toString(o.mode);
  j["seed"] = o.seed;
  j["rate_hz"] = o.rate_hz;
  j["duration_s"] = o.duration_s;
  j["budget"] = staa::budgetJson(o.budget);
  j["heuristic"] = staa::toString(rq.heuristic);
  j["obstacles"] = staa::toString(o.obstacles);
  j["blind_corners"] = o.control.blind_corners.enabled;
  // The agents start on goal locations and drive to random ones: no single start or goal.
  j["start"] = nullptr;
  j["goal"] = nullptr;
  j["movers"] = 0;
  j["map_goals"] = rq.map.goals.size();
  j["goals_placed"] = rq.goals_placed;

  // Of the observed agent in ghost mode, summed over the agents in cooperative mode.
  j["goals_reached"] = r.goals_reached;
  j["collisions"] = r.collisions;
  j["score"] = r.score;
  // Only defined for one robot driving to one goal (--start/--goal or --scenario).
  j["reached_goal"] = nullptr;
  j["time_to_goal_s"] = nullptr;
  // Infinite only for a lone agent in an unbounded, empty world: JSON has no infinity.
  j["min_clearance_m"] = std::isfinite(min_clearance) ? Json(min_clearance) : Json(nullptr);

  j["planner"] = plannerJson(r.calls, r.expansions, r.successors, r.finished_early_ratio, r.depth_mean,
                             r.plan_us);
  j["simulated_s"] = r.duration_s;
  j["frames_written"] = frames;
  Json agents = Json::array();
  for (std::size_t i = 0; i < r.agents.size(); ++i) {
    const staa::AgentResult& a = r.agents[i];
    agents.push_back(Json{{"goals_reached", a.goals_reached},
                          {"collisions", a.collisions},
                          {"distance_m", a.distance_m},
                          {"ghost", o.mode == staa::SimMode::kGhost && i > 0}});
  }
  j["agents"] = std::move(agents);
  j["contacts"] = staa::contactsJson(r.contacts);
  if (r.perception) j["perception"] = staa::perceptionJson(*r.perception, false);
  return j;
}

std::string multiSummary(const MultiRequest& rq, const staa::MultiSimResult& r, double min_clearance, int frames) {
  std::ostringstream s;
  s << r.agents.size() << (r.agents.size() == 1 ? " agent, " : " agents, ") << staa::toString(rq.options.mode) << ", "
    << staa::toString(rq.options.controller) << ", " << fmt(r.duration_s) << " s: score " << r.score << " (goals " << r.goals_reached << ", collisions "
    << r.collisions << (rq.options.mode == staa::SimMode::kGhost ? ", observed agent 0" : "") << "); per agent goals ";
  for (std::size_t i = 0; i < r.agents.size(); ++i) s << (i ? "/" : "") << r.agents[i].goals_reached;
  s << ", collisions ";
  for (std::size_t i = 0; i < r.agents.size(); ++i) s << (i ? "/" : "") << r.agents[i].collisions;
  s << "; min clearance " << (std::isfinite(min_clearance) ? fmt(min_clearance, 3) + " m" : std::string("inf"));
  if (r.calls > 0) {
    s << "; planner " << r.calls << " calls, pops mean " << fmt(r.expansions.mean, 1) << ", plan p50 "
      << fmt(r.plan_us.p50 * 1e-3, 3) << " ms p99 " << fmt(r.plan_us.p99 * 1e-3, 3) << " ms";
  }
  if (frames > 0) s << "; " << frames << " frames";
  return s.str();
}

void announceMulti(const MultiRequest& rq) {
  const auto& o = rq.options;
  std::cerr << "staa-sim: " << rq.map.name << ": " << o.agents << (o.agents == 1 ? " agent, " : " agents, ")
            << staa::toString(o.mode) << ", " << staa::toString(o.controller) << " (" << staa::toString(rq.heuristic)
            << ", " << o.budget.describe() << " per cycle), " << rq.map.goals.size() << " goal locations, seed "
            << o.seed << ", " << fmt(o.duration_s, 1) << " s at " << fmt(o.rate_hz, 1) << " Hz\n";
}

// Per step of a multi-agent run, outside the simulated cycle: clearance, progress (a goal
// reached shows as a new current goal), trails, frames and a line per simulated second.
class MultiStepWatcher {
 public:
  explicit MultiStepWatcher(const MultiRequest& rq)
      : rq_(rq),
        clearance_(rq.map),
        reached_(static_cast<std::size_t>(rq.options.agents), 0),
        trails_(rq.svg_dir.empty() ? 0 : static_cast<std::size_t>(rq.options.agents)),
        trail_points_(static_cast<std::size_t>(std::ceil(kTrailSeconds * rq.options.rate_hz)) + 1) {}

  void step(const staa::MultiWorld& world, std::span<const Vec2> goals, int cycle) {
    clearance_.update(world, rq_);
    const Score score = countGoals(world, goals);
    extendTrails(world);
    if (!rq_.svg_dir.empty() && cycle % rq_.svg_every == 0) writeFrame(world, goals, cycle, score);
    const long second = static_cast<long>(std::floor(world.time() + 1e-9));
    if (!rq_.quiet && second > last_second_) {
      last_second_ = second;
      std::fprintf(stderr, "t=%.1fs goals=%d collisions=%d agent0=(%.2f,%.2f)\n", world.time(), score.goals,
                   score.collisions, world.agent(0).pose.x, world.agent(0).pose.y);
    }
  }

  double clearance() const { return clearance_.value(); }
  int frames() const { return frames_; }

 private:
  struct Score {
    int goals = 0;
    int collisions = 0;
  };

  // The counted agents' goals reached so far and collision episodes.
  Score countGoals(const staa::MultiWorld& world, std::span<const Vec2> goals) {
    if (last_goals_.empty()) last_goals_.assign(goals.begin(), goals.end());
    Score score;
    for (std::size_t i = 0; i < goals.size(); ++i) {
      if (goals[i] != last_goals_[i]) ++reached_[i];
      last_goals_[i] = goals[i];
      if (counted(rq_, i)) {
        score.goals += reached_[i];
        score.collisions += world.collisionEpisodes(i);
      }
    }
    return score;
  }

  void extendTrails(const staa::MultiWorld& world) {
    for (std::size_t i = 0; i < trails_.size(); ++i) {
      trails_[i].push_back(world.agent(i).pose.position());
      if (trails_[i].size() > trail_points_) trails_[i].pop_front();
    }
  }

  void writeFrame(const staa::MultiWorld& world, std::span<const Vec2> goals, int cycle, const Score& score) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.svg", cycle);
    writeMultiFrame(rq_.svg_dir / name, rq_, world, goals, trails_, score.goals, score.collisions);
    ++frames_;
  }

  const MultiRequest& rq_;
  ClearanceTracker clearance_;
  std::vector<Vec2> last_goals_;
  std::vector<int> reached_;
  std::vector<std::deque<Vec2>> trails_;
  std::size_t trail_points_;
  int frames_ = 0;
  long last_second_ = 0;
};

int simulateMulti(MultiRequest& rq) {
  std::ofstream json_out;
  openJsonOutput(rq.json_file, json_out);
  makeSvgDir(rq.svg_dir);
  if (!rq.quiet) announceMulti(rq);

  MultiStepWatcher watcher(rq);
  rq.options.on_step_goals = [&watcher](const staa::MultiWorld& world, std::span<const Vec2> goals, int cycle) {
    watcher.step(world, goals, cycle);
  };
  staa::MultiSimResult result;
  try {
    result = staa::runMultiAgent(rq.map, rq.robot, rq.options);
  } catch (const std::exception& e) {
    std::cerr << "staa-sim: the run failed: " << e.what() << '\n';
    return kExitRunFailed;
  }
  writeJsonOutput(rq.json_file, json_out, multiResultJson(rq, result, watcher.clearance(), watcher.frames()));
  std::cout << multiSummary(rq, result, watcher.clearance(), watcher.frames()) << '\n';
  return 0;
}

// Loads --map for a multi-agent run: the agents start on distinct goal locations and drive
// between them, so a map without goals gets them placed as the experiment places them.
void loadMultiMap(MultiRequest& rq, const std::string& map_file) {
  rq.map = staa::loadPolygonMap(map_file);
  rq.map_label = map_file;
  if (rq.map.name.empty()) rq.map.name = fs::path(map_file).stem().string();
  if (rq.map.goals.empty()) {
    try {
      rq.map.goals = staa::placeGoals(rq.map, staa::kExperimentGoalPlacement);
    } catch (const staa::MapError& e) {
      throw InputError("--map " + map_file + ": the map has no goals and none can be placed: " + e.what());
    }
    rq.goals_placed = true;
    // Said even with --quiet: the agents drive to goals the map file does not have.
    std::cerr << "staa-sim: " << map_file << " has no goals: placed " << rq.map.goals.size() << " (clearance "
              << fmt(staa::kExperimentGoalPlacement.clearance_m, 1) << " m, spacing "
              << fmt(staa::kExperimentGoalPlacement.min_spacing_m, 1) << " m)\n";
  }
  const std::size_t goals = rq.map.goals.size();
  if (goals < 2) {
    throw InputError("--map " + map_file + ": a multi-agent run needs at least 2 goal locations, the map has " +
                     std::to_string(goals));
  }
  if (goals < static_cast<std::size_t>(rq.options.agents)) {
    throw InputError("--agents " + std::to_string(rq.options.agents) + ": the map " + map_file + " has only " +
                     std::to_string(goals) + " goal locations (each agent starts on its own)");
  }
}

// ---- command line: parse, validate, then one run ----

// The command line, typed and checked by CLI11.
struct Args {
  std::string map_file, scenario_file, start_text, goal_text, robot_file, json_file, svg_dir, record_file;
  std::string command_line;  // for the recording's session
  staa::ControllerKind controller = staa::ControllerKind::kStaa;
  staa::SimMode mode = staa::SimMode::kCooperative;
  int agents = 1;
  double duration_s = 60.0;
  double rate_hz = 30.0;
  std::uint64_t seed = 1;
  std::optional<staa::cli::BudgetOptions> budget;
  staa::HeuristicKind heuristic = staa::HeuristicKind::kPathRtr;
  staa::ObstacleSource obstacles = staa::ObstacleSource::kTruth;
  bool blind_corners = false;
  int svg_every = 15;
  bool quiet = false;
  const CLI::Option* duration_option = nullptr;  // for messages naming the values given
  const CLI::Option* rate_option = nullptr;

  bool multi() const { return agents > 1 || mode == staa::SimMode::kGhost; }
};

constexpr const char* kPoseForm = "X,Y,TH (three finite numbers: metres, metres, radians)";

void addOptions(staa::cli::CommandLine& cl, Args& a) {
  namespace cli = staa::cli;
  CLI::App& app = cl.app;
  auto* map = app.add_option("--map", a.map_file, "Polygon map (staa-polygon-map/1 YAML)");
  auto* scenario =
      app.add_option("--scenario", a.scenario_file, "Scenario (staa-scenario/1 YAML): map, robot, start, goal, movers");
  auto* start = app.add_option("--start", a.start_text, "Start pose X,Y,TH (metres, radians)")
                    ->check(cli::point<3>(kPoseForm))
                    ->type_name("X,Y,TH");
  auto* goal = app.add_option("--goal", a.goal_text, "Goal pose X,Y,TH (metres, radians)")
                   ->check(cli::point<3>(kPoseForm))
                   ->type_name("X,Y,TH");
  for (CLI::Option* single : {map, start, goal}) {
    cl.exclude(single, scenario, "the scenario names its map, start and goal");
  }
  app.add_option("--robot", a.robot_file, "Robot profile (staa-robot/1 YAML; default: the paper's agent, or the "
                                          "scenario's profile)");
  cli::choice(app.add_option("--controller", a.controller,
                             "staa, dwa (predictive dynamic window) or pd (carrot + force field)"),
              cli::kControllerNames, a.controller);
  cli::choice(app.add_option("--mode", a.mode,
                             "cooperative (every agent runs --controller and avoids the others) or ghost (agent 0 "
                             "runs --controller, the others drive through everything); ghost, or --agents > 1, "
                             "makes a multi-agent run"),
              cli::kModeNames, a.mode);
  app.add_option("--agents", a.agents, "Number of agents; more than 1 makes a multi-agent run: the agents "
                                       "drive between random goals of --map (no --start/--goal/--scenario)")
      ->transform(cli::count("a number of agents", 1, 1000))
      ->capture_default_str();
  a.duration_option = app.add_option("--duration", a.duration_s, "Simulated seconds")
                          ->transform(cli::positive("simulated seconds"))
                          ->capture_default_str();
  a.rate_option = app.add_option("--rate", a.rate_hz, "Control rate in Hz")
                      ->transform(cli::positive("a control rate in Hz"))
                      ->capture_default_str();
  app.add_option("--seed", a.seed, "Seed of a multi-agent run's starts and goals (recorded in the JSON; "
                                   "single-robot runs are deterministic)")
      ->transform(cli::count("a seed", 0, std::numeric_limits<std::uint64_t>::max()))
      ->capture_default_str();
  a.budget.emplace(cl, "run");
  cli::choice(app.add_option("--heuristic", a.heuristic, "path-rtr, path-euclid or dijkstra-rtr"),
              cli::kHeuristicNames, a.heuristic);
  cli::choice(app.add_option("--blind-corners", a.blind_corners,
                             "on or off: limit the speed at the map's blind corners so that the robot can stop before it "
                             "is level with one (ControlConfig::blind_corners)"),
              std::vector<std::pair<std::string, bool>>{{"on", true}, {"off", false}}, a.blind_corners);
  cli::choice(app.add_option("--obstacles", a.obstacles,
                             "truth (the exact polygons and velocities of the movers or other agents), depth (what "
                             "the robot profile's depth camera sees of them, through staad's perception), depth+scan "
                             "(the camera and the profile's base laser scanner) or sight (the exact polygons of those in "
                             "the robot's line of sight, 8 m all round: what occlusion alone costs)"),
              cli::kObstacleNames, a.obstacles);
  app.add_option("--json", a.json_file, "Write the results as JSON to this file");
  app.add_option("--svg", a.svg_dir, "Write frames (frame_NNNNN.svg) into this directory: like the paper's Fig. 1 "
                                     "for one robot, the whole map with every agent for a multi-agent run");
  app.add_option("--svg-every", a.svg_every, "Cycles between frames")
      ->transform(cli::count("cycles between frames", 1, 1'000'000))
      ->capture_default_str();
  app.add_flag("--quiet", a.quiet, "No progress on stderr (the summary line on stdout remains)");
  app.add_option("--record", a.record_file,
                 "Record every cycle of every agent into this MCAP file (the flight recorder's format: "
                 "staa-replay reruns it, Foxglove plots it)");
}

// What the options mean together, before anything is loaded.
void validate(const Args& a) {
  staa::cli::checkCycles(a.duration_option, a.rate_option, a.duration_s, a.rate_hz);
  if (a.multi()) {
    const std::string why = a.agents > 1 ? "--agents " + std::to_string(a.agents) : "--mode ghost";
    for (const auto& [name, text] : {std::pair<const char*, const std::string&>{"--scenario", a.scenario_file},
                                     {"--start", a.start_text},
                                     {"--goal", a.goal_text}}) {
      if (!text.empty()) {
        throw InputError(std::string(name) + " '" + text + "' cannot be combined with " + why +
                         ": in a multi-agent run every agent drives to random goals of --map (--start, --goal "
                         "and --scenario are for a single robot)");
      }
    }
    if (a.map_file.empty()) throw InputError("--map is required with " + why + " (the agents drive between its goals)");
  } else if (a.scenario_file.empty()) {
    if (a.map_file.empty()) throw InputError("--map or --scenario is required (see staa-sim --help)");
    if (a.start_text.empty() || a.goal_text.empty()) {
      throw InputError(std::string(a.start_text.empty() ? "--start" : "--goal") +
                       " is required with --map (a single robot drives from --start X,Y,TH to --goal X,Y,TH)");
    }
  }
}

// The part of a recording's session the command line knows (the runner adds the rest).
staa::record::Session recordSession(const Args& a, const staa::BudgetSpec& budget) {
  staa::record::Session s;
  s.source = "staa-sim";
  s.software = staa::record::softwareVersion();
  s.build_type = staa::record::buildType();
  s.recorded_at = staa::record::utcNow();
  s.budget = budget.describe();
  s.config_text = a.command_line;
  return s;
}

// --record: a path that cannot be written fails before a long run, not after it.
void checkRecordOutput(const std::string& file) {
  if (file.empty()) return;
  const fs::path parent = fs::path(file).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  std::ofstream probe(file, std::ios::binary | std::ios::trunc);
  if (!probe) throw InputError("--record: cannot write '" + file + "'");
}

staa::SimOptions simOptions(const Args& a) {
  staa::SimOptions o;
  o.duration_s = a.duration_s;
  o.rate_hz = a.rate_hz;
  o.budget = a.budget->spec(a.rate_hz);
  o.svg_every = a.svg_every;
  o.svg_dir = a.svg_dir;
  o.control.rate_hz = a.rate_hz;
  o.control.staa.heuristic.kind = a.heuristic;
  o.control.blind_corners.enabled = a.blind_corners;
  o.obstacles = a.obstacles;
  o.record_path = a.record_file;
  if (!a.record_file.empty()) o.record_session = recordSession(a, o.budget);
  return o;
}

Pose2 pose(const std::string& checked_text) {
  const auto p = staa::cli::parsePoint<3>(checked_text).value();
  return Pose2{p[0], p[1], p[2]};
}

// --scenario, with --robot in place of the scenario's profile.
void loadScenarioRun(Request& rq, const Args& a) {
  rq.scenario = staa::loadScenario(a.scenario_file);
  rq.scenario_file = a.scenario_file;
  rq.map_label = rq.scenario.map_path.string();
  if (!a.robot_file.empty()) {
    rq.scenario.robot = staa::loadRobotProfile(a.robot_file);
    rq.scenario.profile_path = a.robot_file;
    checkStart(rq.scenario, "--robot " + a.robot_file + ": the scenario's start");
  }
}

// --map from --start to --goal, the paper's agent unless --robot.
void loadMapRun(Request& rq, const Args& a) {
  staa::Scenario& sc = rq.scenario;
  sc.start = pose(a.start_text);
  sc.goal = pose(a.goal_text);
  sc.map = staa::loadPolygonMap(a.map_file);
  sc.map_path = a.map_file;
  sc.name = sc.map.name.empty() ? fs::path(a.map_file).stem().string() : sc.map.name;
  if (a.robot_file.empty()) {
    sc.robot = staa::paperAgentProfile();
  } else {
    sc.robot = staa::loadRobotProfile(a.robot_file);
    sc.profile_path = a.robot_file;
  }
  rq.map_label = a.map_file;
  checkStart(sc, "--start");
  checkGoal(sc, "--goal");
}

// --obstacles depth renders the frames of the profile's camera (depth+scan its scanner's scans
// too): a profile without one is bad input.
void requireCamera(const Args& a, const staa::RobotProfile& robot) {
  const std::string profile = a.robot_file.empty() ? robot.name : a.robot_file;
  if (staa::perceived(a.obstacles) && !robot.has_camera) {
    throw InputError(std::string("--obstacles ") + staa::toString(a.obstacles) + ": the robot profile '" + profile +
                     "' has no camera section (config/robots/paper-agent.yaml shows one)");
  }
  if (a.obstacles == staa::ObstacleSource::kDepthScan && !robot.has_scanner) {
    throw InputError("--obstacles depth+scan: the robot profile '" + profile +
                     "' has no scanner section (config/robots/paper-agent.yaml shows one)");
  }
}

Request singleRequest(const Args& a) {
  Request rq;
  rq.controller = a.controller;
  rq.mode = a.mode;
  rq.agents = a.agents;
  rq.seed = a.seed;
  rq.heuristic = a.heuristic;
  rq.options = simOptions(a);
  rq.json_file = a.json_file;
  rq.quiet = a.quiet;
  if (a.scenario_file.empty()) {
    loadMapRun(rq, a);
  } else {
    loadScenarioRun(rq, a);
  }
  requireCamera(a, rq.scenario.robot);
  return rq;
}

MultiRequest multiRequest(const Args& a) {
  MultiRequest rq;
  rq.quiet = a.quiet;
  rq.heuristic = a.heuristic;
  rq.json_file = a.json_file;
  rq.svg_dir = a.svg_dir;
  rq.svg_every = a.svg_every;
  staa::MultiSimOptions& m = rq.options;
  m.agents = a.agents;
  m.mode = a.mode;
  m.controller = a.controller;
  m.duration_s = a.duration_s;
  m.rate_hz = a.rate_hz;
  m.budget = a.budget->spec(a.rate_hz);
  m.seed = a.seed;
  const staa::SimOptions single = simOptions(a);
  m.control = single.control;
  m.obstacles = a.obstacles;
  m.record_path = single.record_path;
  m.record_session = single.record_session;
  rq.robot = a.robot_file.empty() ? staa::paperAgentProfile() : staa::loadRobotProfile(a.robot_file);
  requireCamera(a, rq.robot);
  loadMultiMap(rq, a.map_file);
  return rq;
}

int run(int argc, char** argv) {
  if (argc > 1 && std::string_view(argv[1]) == "experiment") {
    return staa::runExperimentCommand(argc - 1, argv + 1);
  }
  staa::cli::CommandLine cl("staa-sim",
                            "staa-sim: run the STAA* control cycle against a simulated world: one robot from --start "
                            "to --goal in a polygon map, or a scenario among scripted movers. Exit 0 on a completed "
                            "run (reached or not), 2 on bad input.");
  Args args;
  addOptions(cl, args);
  if (const auto exit = cl.parse(argc, argv)) return *exit;
  validate(args);
  for (int i = 0; i < argc; ++i) args.command_line += (i > 0 ? " " : "") + std::string(argv[i]);
  checkRecordOutput(args.record_file);
  if (args.multi()) {
    MultiRequest rq = multiRequest(args);
    return simulateMulti(rq);
  }
  Request rq = singleRequest(args);
  return simulate(rq);
}

}  // namespace

int main(int argc, char** argv) {
  // Every failure is one line on stderr and a non-zero exit status, never an uncaught exception.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "staa-sim: " << e.what() << '\n';
  } catch (...) {
    std::cerr << "staa-sim: unexpected error\n";
  }
  return kExitBadInput;
}
