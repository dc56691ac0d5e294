#include "experiment/results_json.hpp"
#include "experiment/experiment.hpp"

#include "experiment/agent_camera.hpp"
#include "map/generate.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <tuple>

namespace staa {
namespace {

using Json = nlohmann::ordered_json;

// 0.6 -> "0.6", 1.5 -> "1.5": short numbers for messages.
std::string shortNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

bool isPaperMap(const std::string& name) { return name == "office" || name == "apartment" || name == "clutter"; }

std::string describe(const ExperimentRun& r) {
  std::string s = r.map + " " + toString(r.controller);
  if (r.heuristic) s += std::string(" (") + toString(*r.heuristic) + ")";
  s += std::string(" ") + toString(r.mode) + " " + std::to_string(r.agents) + (r.agents == 1 ? " agent" : " agents") +
       (r.obstacles == ObstacleSource::kTruth ? "" : std::string(" ") + toString(r.obstacles)) + " run " +
       std::to_string(r.run) + " (seed " + std::to_string(r.seed) + ")";
  return s;
}

MeanStd meanStd(const std::vector<double>& v) {
  MeanStd m;
  if (v.empty()) return m;
  double sum = 0.0;
  for (const double x : v) sum += x;
  m.mean = sum / static_cast<double>(v.size());
  if (v.size() > 1) {
    double sq = 0.0;
    for (const double x : v) sq += (x - m.mean) * (x - m.mean);
    m.stddev = std::sqrt(sq / static_cast<double>(v.size() - 1));
  }
  return m;
}


Json meanStdJson(const MeanStd& m) { return Json{{"mean", m.mean}, {"stddev", m.stddev}}; }

// The robot profile's camera as the depth runs used it.
Json cameraJson(const RobotProfile& robot) {
  const DepthCameraProfile& c = robot.camera;
  Json j;
  j["body_height_m"] = robot.height_m;
  j["mount"] = Json{{"x", c.x}, {"y", c.y}, {"z", c.z}, {"roll", c.roll}, {"pitch", c.pitch}, {"yaw", c.yaw}};
  j["fov_deg"] = Json::array({c.fov_h_deg, c.fov_v_deg});
  j["range_m"] = Json::array({c.min_range_m, c.max_range_m});
  j["rate_hz"] = c.rate_hz;
  j["noise_mm_per_m2"] = c.noise_mm_per_m2;
  j["dropout"] = c.dropout;
  j["grazing_deg"] = c.grazing_deg;
  j["frame_loss"] = c.frame_loss;
  j["latency_s"] = c.latency_s;
  j["head"] = Json{{"pan_max", c.pan_max}, {"pan_rate", c.pan_rate}, {"look_ahead_m", c.look_ahead_m},
                   {"scan", c.scan}};
  return j;
}

Json scannerJson(const ScannerProfile& c) {
  Json j;
  j["mount"] = Json{{"x", c.x}, {"y", c.y}, {"z", c.z}, {"yaw", c.yaw}};
  j["fov_deg"] = c.fov_deg;
  j["beams"] = c.beams;
  j["range_m"] = Json::array({c.min_range_m, c.max_range_m});
  j["noise_m"] = c.noise_m;
  j["dropout"] = c.dropout;
  return j;
}

Json perceptionConfigJson(const DepthObstaclesConfig& p) {
  Json j;
  j["pixel_stride"] = p.pixel_stride;
  j["min_depth_m"] = p.min_depth_m;
  j["max_range_m"] = p.max_range_m;
  j["min_height_m"] = p.min_height_m;
  j["max_height_m"] = p.max_height_m;
  j["cell_m"] = p.cell_m;
  j["min_points_per_cell"] = p.min_points_per_cell;
  j["min_cluster_points"] = p.min_cluster_points;
  j["cluster_gap_m"] = p.cluster_gap_m;
  j["static_margin_m"] = p.static_margin_m;
  j["max_vertices"] = p.max_vertices;
  j["gate_m"] = p.gate_m;
  j["centroid_noise_m"] = p.centroid_noise_m;
  j["acceleration_mps2"] = p.acceleration_mps2;
  j["max_speed_mps"] = p.max_speed_mps;
  j["turn_rate_time_s"] = p.turn_rate_time_s;
  j["turn_min_speed_mps"] = p.turn_min_speed_mps;
  j["max_turn_rate_rps"] = p.max_turn_rate_rps;
  j["max_missed_frames"] = p.max_missed_frames;
  j["keep_unseen_s"] = p.keep_unseen_s;
  j["confirm_frames"] = p.confirm_frames;
  j["max_growth_m"] = p.max_growth_m;
  j["hidden_depth_m"] = p.hidden_depth_m;
  j["self_clearance_m"] = p.self_clearance_m;
  j["uncertainty_horizon_s"] = p.uncertainty_horizon_s;
  j["truncated_noise_m"] = p.truncated_noise_m;
  j["max_frame_gap_s"] = p.max_frame_gap_s;
  return j;
}

}  // namespace

ExperimentMap loadExperimentMap(const std::string& name_or_path, std::uint64_t seed) {
  ExperimentMap m;
  if (isPaperMap(name_or_path)) {
    m.name = name_or_path;
    m.map = generatePaperMap(name_or_path, seed);
  } else {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(name_or_path, ec)) {
      throw MapError("'" + name_or_path +
                     "' is neither a generated map (office, apartment, clutter) nor a readable map file");
    }
    m.map = loadPolygonMap(name_or_path);  // MapError names the file and the polygon
    m.name = m.map.name.empty() ? std::filesystem::path(name_or_path).stem().string() : m.map.name;
  }
  if (m.map.goals.empty()) {
    // The agents drive between the map's goal locations: a map without them (an imported ROS
    // map) gets well-spread reachable ones rather than being refused.
    try {
      m.map.goals = placeGoals(m.map, kExperimentGoalPlacement);
    } catch (const MapError& e) {
      throw MapError(name_or_path + ": the map has no goals and none can be placed: " + e.what());
    }
    m.goals_placed = true;
    // Refused now rather than when the first run starts, maybe an hour into the experiment.
    if (m.map.goals.size() < 2) {
      throw MapError(name_or_path + ": the map has no goals and room for only " + std::to_string(m.map.goals.size()) +
                     " with " + shortNumber(kExperimentGoalPlacement.clearance_m) + " m clearance, " +
                     shortNumber(kExperimentGoalPlacement.min_spacing_m) +
                     " m apart: the agents drive between at least 2 (add goals to the file)");
    }
  }
  return m;
}

void validateExperimentSpec(const ExperimentSpec& spec) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("experiment: " + what); };
  if (spec.maps.empty()) fail("no maps");
  if (spec.controllers.empty()) fail("no controllers");
  if (spec.modes.empty()) fail("no modes");
  if (spec.agents.empty()) fail("no agent counts");
  if (spec.heuristics.empty()) fail("no heuristics");
  if (spec.obstacles.empty()) fail("no obstacle sources");
  const bool any_perceived = std::any_of(spec.obstacles.begin(), spec.obstacles.end(), perceived);
  if (std::find(spec.obstacles.begin(), spec.obstacles.end(), ObstacleSource::kDepthScan) != spec.obstacles.end() &&
      !spec.robot.has_scanner) {
    fail("obstacles 'depth+scan' needs a robot profile with a scanner ('" + spec.robot.name + "' has none)");
  }
  if (any_perceived) {
    if (!spec.robot.has_camera) {
      fail("obstacles 'depth' and 'depth+scan' need a robot profile with a camera ('" + spec.robot.name + "' has none)");
    }
    try {
      (void)agentPerceptionConfig(spec.robot);
      validateDepthObstaclesConfig(spec.perception.value_or(agentPerceptionConfig(spec.robot, spec.robot.has_scanner)),
                                   std::hypot(spec.robot.camera.x, spec.robot.camera.y));
    } catch (const std::invalid_argument& e) {
      fail(std::string("the depth camera's perception: ") + e.what());
    }
  }
  const int most_agents = spec.agents.empty() ? 1 : *std::max_element(spec.agents.begin(), spec.agents.end());
  for (std::size_t i = 0; i < spec.maps.size(); ++i) {
    if (spec.maps[i].map.goals.empty()) fail("map '" + spec.maps[i].name + "' has no goals");
    // Every agent starts on its own goal location and drives to another one.
    const std::size_t need = static_cast<std::size_t>(std::max(2, most_agents));
    if (spec.maps[i].map.goals.size() < need) {
      fail("map '" + spec.maps[i].name + "' has " + std::to_string(spec.maps[i].map.goals.size()) + " goals, " +
           std::to_string(need) + " needed for " + std::to_string(most_agents) +
           (most_agents == 1 ? " agent" : " agents") + " (each starts on its own goal location)");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (spec.maps[j].name == spec.maps[i].name) fail("map name '" + spec.maps[i].name + "' appears twice");
    }
  }
  for (const int a : spec.agents) {
    if (a < 1) fail("agents must be >= 1, got " + std::to_string(a));
  }
  if (spec.runs < 1) fail("runs must be >= 1, got " + std::to_string(spec.runs));
  if (spec.jobs < 1) fail("jobs must be >= 1, got " + std::to_string(spec.jobs));
  if (!(spec.duration_s > 0.0) || !std::isfinite(spec.duration_s)) fail("duration must be > 0");
  if (!(spec.rate_hz > 0.0) || !std::isfinite(spec.rate_hz)) fail("rate must be > 0");
  if (!spec.budget.isExpansions() && !(spec.budget.ms > 0.0)) fail("budget_ms must be > 0");
  if (spec.budget.isExpansions() && spec.budget.expansions == 0) fail("budget_expansions must be > 0");
}

std::vector<ExperimentRun> planExperiment(const ExperimentSpec& spec) {
  std::vector<ExperimentRun> plan;
  for (const ExperimentMap& map : spec.maps) {
    for (const SimMode mode : spec.modes) {
      for (const int agents : spec.agents) {
        for (const ObstacleSource obstacles : spec.obstacles) {
        for (const ControllerKind controller : spec.controllers) {
          std::vector<std::optional<HeuristicKind>> heuristics;
          if (controller == ControllerKind::kStaa) {
            heuristics.assign(spec.heuristics.begin(), spec.heuristics.end());
          } else {
            heuristics.push_back(std::nullopt);
          }
          for (const auto& heuristic : heuristics) {
            for (int r = 0; r < spec.runs; ++r) {
              ExperimentRun run;
              run.map = map.name;
              run.controller = controller;
              run.mode = mode;
              run.agents = agents;
              run.obstacles = obstacles;
              run.heuristic = heuristic;
              run.run = r;
              // The same seed in every cell: run r sees the same starts and goal sequences
              // whichever controller drives (common random numbers).
              run.seed = spec.seed + static_cast<std::uint64_t>(r);
              plan.push_back(std::move(run));
            }
          }
        }
        }
      }
    }
  }
  return plan;
}

std::string heuristicLabel(const ExperimentRun& run) { return run.heuristic ? toString(*run.heuristic) : "none"; }

std::vector<ExperimentRun> runExperiment(const ExperimentSpec& spec,
                                         const std::function<void(const ExperimentProgress&)>& progress) {
  validateExperimentSpec(spec);
  std::vector<ExperimentRun> runs = planExperiment(spec);
  const int total = static_cast<int>(runs.size());
  const auto t0 = std::chrono::steady_clock::now();

  // Workers take the next index; each run writes only its own slot of `runs`, and reads the
  // spec (maps, robot, control) as const.
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;  // guards done, error and the progress callback
  int done = 0;
  std::exception_ptr error;

  auto worker = [&]() {
    for (;;) {
      if (failed.load()) return;
      const int i = next.fetch_add(1);
      if (i >= total) return;
      ExperimentRun& run = runs[static_cast<std::size_t>(i)];
      const ExperimentMap* map = nullptr;
      for (const ExperimentMap& m : spec.maps) {
        if (m.name == run.map) map = &m;
      }
      MultiSimOptions o;
      o.agents = run.agents;
      o.mode = run.mode;
      o.controller = run.controller;
      o.duration_s = spec.duration_s;
      o.rate_hz = spec.rate_hz;
      o.budget = spec.budget;
      o.seed = run.seed;
      o.control = spec.control;
      o.control.rate_hz = spec.rate_hz;
      o.control.staa.heuristic.kind = run.heuristic.value_or(spec.heuristics.front());
      o.obstacles = run.obstacles;
      o.perception = spec.perception;
      try {
        run.result = runMultiAgent(map->map, spec.robot, o);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::make_exception_ptr(std::runtime_error(describe(run) + " failed: " + e.what()));
        failed.store(true);
        return;
      }
      const std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (progress) {
        ExperimentProgress p;
        p.done = done;
        p.total = total;
        p.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        p.remaining_s = p.elapsed_s / done * (total - done);
        p.last = &run;
        progress(p);
      }
    }
  };

  const int threads = std::min(spec.jobs, total);
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  return runs;
}

std::vector<ExperimentCell> summarizeExperiment(const std::vector<ExperimentRun>& runs) {
  std::vector<ExperimentCell> cells;
  std::vector<std::vector<const ExperimentRun*>> members;
  for (const ExperimentRun& r : runs) {
    std::size_t k = 0;
    for (; k < cells.size(); ++k) {
      const ExperimentCell& c = cells[k];
      if (c.map == r.map && c.controller == r.controller && c.mode == r.mode && c.agents == r.agents &&
          c.obstacles == r.obstacles && c.heuristic == r.heuristic) {
        break;
      }
    }
    if (k == cells.size()) {
      ExperimentCell c;
      c.map = r.map;
      c.controller = r.controller;
      c.mode = r.mode;
      c.agents = r.agents;
      c.obstacles = r.obstacles;
      c.heuristic = r.heuristic;
      cells.push_back(std::move(c));
      members.emplace_back();
    }
    members[k].push_back(&r);
  }
  for (std::size_t k = 0; k < cells.size(); ++k) {
    std::vector<double> goals, collisions, score;
    double pops = 0.0;
    ExperimentCell& c = cells[k];
    for (const ExperimentRun* r : members[k]) {
      goals.push_back(r->result.goals_reached);
      collisions.push_back(r->result.collisions);
      score.push_back(r->result.score);
      pops += r->result.expansions.mean;
      if (r->result.perception) {
        if (!c.perception) c.perception.emplace();
        c.perception->merge(*r->result.perception);
      }
    }
    c.runs = static_cast<int>(members[k].size());
    c.goals = meanStd(goals);
    c.collisions = meanStd(collisions);
    c.score = meanStd(score);
    c.expansions_mean = pops / static_cast<double>(c.runs);
  }
  return cells;
}

std::string experimentJson(const ExperimentSpec& spec, const std::vector<ExperimentRun>& runs) {
  Json doc;
  Json& jruns = doc["runs"] = Json::array();
  for (const ExperimentRun& r : runs) {
    const MultiSimResult& m = r.result;
    Json j;
    j["map"] = r.map;
    j["controller"] = toString(r.controller);
    j["mode"] = toString(r.mode);
    j["agents"] = r.agents;
    j["obstacles"] = toString(r.obstacles);
    j["run"] = r.run;
    j["seed"] = r.seed;
    j["duration_s"] = m.duration_s;
    j["goals_reached"] = m.goals_reached;
    j["collisions"] = m.collisions;
    j["score"] = m.score;
    j["planner"] = plannerJson(m.calls, m.expansions, m.successors, m.finished_early_ratio, m.depth_mean,
                               m.plan_us);
    j["heuristic"] = heuristicLabel(r);
    Json agents = Json::array();
    for (const AgentResult& a : m.agents) {
      agents.push_back(Json{{"goals_reached", a.goals_reached}, {"collisions", a.collisions},
                            {"distance_m", a.distance_m}});
    }
    j["agent_results"] = std::move(agents);
    j["contacts"] = contactsJson(m.contacts);
    if (m.perception) j["perception"] = perceptionJson(*m.perception, true);
    jruns.push_back(std::move(j));
  }

  Json& summary = doc["summary"] = Json::array();
  for (const ExperimentCell& c : summarizeExperiment(runs)) {
    Json j;
    j["map"] = c.map;
    j["controller"] = toString(c.controller);
    j["mode"] = toString(c.mode);
    j["agents"] = c.agents;
    j["obstacles"] = toString(c.obstacles);
    j["heuristic"] = c.heuristic ? toString(*c.heuristic) : "none";
    j["runs"] = c.runs;
    j["goals_reached"] = meanStdJson(c.goals);
    j["collisions"] = meanStdJson(c.collisions);
    j["score"] = meanStdJson(c.score);
    j["expansions_mean"] = c.expansions_mean;
    if (c.perception) j["perception"] = perceptionJson(*c.perception, false);
    summary.push_back(std::move(j));
  }

  Json s;
  s["maps"] = Json::array();
  for (const ExperimentMap& m : spec.maps) s["maps"].push_back(m.name);
  // Where the goals came from: the map's own, or placed because it had none.
  s["map_goals"] = Json::array();
  for (const ExperimentMap& m : spec.maps) {
    Json g{{"map", m.name}, {"goals", m.map.goals.size()}, {"goals_placed", m.goals_placed}};
    if (m.goals_placed) {
      g["clearance_m"] = kExperimentGoalPlacement.clearance_m;
      g["spacing_m"] = kExperimentGoalPlacement.min_spacing_m;
    }
    s["map_goals"].push_back(std::move(g));
  }
  s["controllers"] = Json::array();
  for (const ControllerKind c : spec.controllers) s["controllers"].push_back(toString(c));
  s["modes"] = Json::array();
  for (const SimMode m : spec.modes) s["modes"].push_back(toString(m));
  s["agents"] = spec.agents;
  s["obstacles"] = Json::array();
  for (const ObstacleSource o : spec.obstacles) s["obstacles"].push_back(toString(o));
  if (std::any_of(spec.obstacles.begin(), spec.obstacles.end(), perceived)) {
    s["camera"] = cameraJson(spec.robot);
    s["perception"] = perceptionConfigJson(spec.perception.value_or(agentPerceptionConfig(spec.robot)));
  }
  if (std::find(spec.obstacles.begin(), spec.obstacles.end(), ObstacleSource::kDepthScan) != spec.obstacles.end()) {
    s["scanner"] = scannerJson(spec.robot.scanner);
    // What depth+scan runs use beyond the camera's perception (the rest is spec.perception).
    s["scanner"]["scan_range_m"] = spec.perception.value_or(agentPerceptionConfig(spec.robot, true)).scan_range_m;
  }
  s["runs"] = spec.runs;
  s["duration_s"] = spec.duration_s;
  s["rate_hz"] = spec.rate_hz;
  s["budget"] = budgetJson(spec.budget);
  s["heuristics"] = Json::array();
  for (const HeuristicKind h : spec.heuristics) s["heuristics"].push_back(toString(h));
  s["seed"] = spec.seed;
  s["map_seed"] = spec.map_seed;
  s["jobs"] = spec.jobs;
  s["robot"] = spec.robot.name;
  s["predict_turning"] = spec.control.staa.predict_turning;
  s["lazy_heuristic"] = spec.control.staa.lazy_heuristic;
  s["separate_contacts"] = spec.control.staa.separate_contacts;
  s["blind_corners"] = spec.control.blind_corners.enabled;
  doc["spec"] = std::move(s);
  return doc.dump(2) + "\n";
}

std::filesystem::path writeExperimentResults(const std::filesystem::path& dir, const ExperimentSpec& spec,
                                             const std::vector<ExperimentRun>& runs) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::filesystem::path file = dir / "results.json";
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write '" + file.string() + "'");
  out << experimentJson(spec, runs);
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + file.string() + "'");
  return file;
}

}  // namespace staa
