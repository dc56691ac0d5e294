#pragma once
// The paper's statistical experiment (Sec. IV-B and IV-C, Fig. 5 and 6) as one object: the
// matrix maps x controllers x modes x agent counts x heuristics x runs, each run an
// independent multi-agent simulation (runMultiAgent) seeded base seed + run index, run in
// parallel over worker threads, and its results.json (docs/ARCHITECTURE.md section 6).
// Tools only: allocates freely and starts threads.

#include "control/control_cycle.hpp"
#include "planner/budget.hpp"
#include "robot/robot_profile.hpp"
#include "map/goals.hpp"
#include "map/polygon_map.hpp"
#include "planner/heuristic.hpp"
#include "experiment/multi_sim.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace staa {

struct ExperimentMap {
  std::string name;  // "office", "apartment", "clutter" or the map file's name
  PolygonMap map;
  bool goals_placed = false;  // the file had no goals: placeGoals(kExperimentGoalPlacement) made them
};

// How goals are placed in a map file without any (an imported ROS map): 40 goals, 0.6 m
// from every obstacle, 1.5 m apart, seed 1 (the same goals whatever the runs' seed).
inline constexpr GoalPlacement kExperimentGoalPlacement{};

// "office", "apartment" and "clutter" generate the paper's maps (generatePaperMap(name,
// seed)); anything else is the path of a polygon map file (a user's own building). A file
// without goals gets goals placed (kExperimentGoalPlacement; goals_placed says so). Throws
// MapError naming the file and the reason (unreadable, invalid, or no free place for goals).
ExperimentMap loadExperimentMap(const std::string& name_or_path, std::uint64_t seed);

struct ExperimentSpec {
  std::vector<ExperimentMap> maps;
  std::vector<ControllerKind> controllers{ControllerKind::kPd, ControllerKind::kDwa, ControllerKind::kStaa};
  std::vector<SimMode> modes{SimMode::kCooperative, SimMode::kGhost};
  std::vector<int> agents{1, 3, 5};
  // Where the evaluated agents' moving obstacles come from: ground truth, their depth cameras
  // (the robot profile's camera, perception as agentPerceptionConfig), or both side by side.
  std::vector<ObstacleSource> obstacles{ObstacleSource::kTruth};
  int runs = 3;
  double duration_s = 60.0;
  double rate_hz = 30.0;
  // Budget per STAA* call: queue pops (reproducible) or wall-clock milliseconds.
  BudgetSpec budget;  // default: 19 ms of wall clock
  // STAA* runs once per heuristic (Fig. 6); PD and DWA do not use one and run once.
  std::vector<HeuristicKind> heuristics{HeuristicKind::kPathRtr};
  std::uint64_t seed = 1;  // run r of every cell uses seed + r
  // The seed the generated maps were made with (recorded only; 1 is `staa-map generate`'s
  // default, so "clutter" is the same map whatever the runs' seed).
  std::uint64_t map_seed = 1;
  int jobs = 1;            // worker threads
  RobotProfile robot = paperAgentProfile();
  ControlConfig control;   // rate and heuristic are set per run from the fields above
  // Depth runs' perception settings (empty: agentPerceptionConfig(robot)).
  std::optional<DepthObstaclesConfig> perception;
};

// Throws std::invalid_argument naming the field and the value.
void validateExperimentSpec(const ExperimentSpec& spec);

// One cell of the matrix and one repetition of it.
struct ExperimentRun {
  std::string map;
  ControllerKind controller = ControllerKind::kStaa;
  SimMode mode = SimMode::kCooperative;
  int agents = 1;
  ObstacleSource obstacles = ObstacleSource::kTruth;
  std::optional<HeuristicKind> heuristic;  // STAA* only
  int run = 0;
  std::uint64_t seed = 0;
  MultiSimResult result;
};

// Every run of the spec in a fixed order (map, mode, agents, obstacles, controller,
// heuristic, run), results empty: the same spec always gives the same list.
std::vector<ExperimentRun> planExperiment(const ExperimentSpec& spec);

// "pd" / "dwa" / "staa" and the heuristic ("none" for PD and DWA) as written to results.json.
std::string heuristicLabel(const ExperimentRun& run);

struct ExperimentProgress {
  int done = 0;
  int total = 0;
  double elapsed_s = 0.0;
  double remaining_s = 0.0;     // estimate: elapsed / done * (total - done)
  const ExperimentRun* last = nullptr;  // the run that just finished
};

// Runs every planned run over spec.jobs threads; `progress` (may be empty) is called, one
// call at a time, after each run finishes. Each run builds its own simulation from const
// inputs: nothing is shared that a run writes. A failing run stops the experiment: the
// exception is rethrown (std::runtime_error naming the run) after the workers have joined.
std::vector<ExperimentRun> runExperiment(const ExperimentSpec& spec,
                                         const std::function<void(const ExperimentProgress&)>& progress = {});

// Mean and sample standard deviation (0 for one value).
struct MeanStd {
  double mean = 0.0;
  double stddev = 0.0;
};

// One summary row: the runs of one map / controller / mode / agents / obstacles / heuristic.
struct ExperimentCell {
  std::string map;
  ControllerKind controller = ControllerKind::kStaa;
  SimMode mode = SimMode::kCooperative;
  int agents = 1;
  ObstacleSource obstacles = ObstacleSource::kTruth;
  std::optional<HeuristicKind> heuristic;
  int runs = 0;
  MeanStd goals, collisions, score;
  double expansions_mean = 0.0;  // STAA* pops per call, over the runs
  std::optional<PerceptionAccuracy> perception;  // depth: the runs' accuracy added up
};

// In the order of first appearance in `runs`.
std::vector<ExperimentCell> summarizeExperiment(const std::vector<ExperimentRun>& runs);

// The results.json document, indented: {"runs": [...], "summary": [...], "spec": {...}}.
std::string experimentJson(const ExperimentSpec& spec, const std::vector<ExperimentRun>& runs);

// Writes DIR/results.json (creating DIR); throws std::runtime_error naming the file.
std::filesystem::path writeExperimentResults(const std::filesystem::path& dir, const ExperimentSpec& spec,
                                             const std::vector<ExperimentRun>& runs);

}  // namespace staa
