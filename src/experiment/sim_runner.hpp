#pragma once
// One robot driven by the control cycle through a simulated world (staa-sim without
// --agents): the cycle sees the world's state and its movers (ground truth, or with
// ObstacleSource::kDepth what the robot profile's depth camera sees of them, as people 1.7 m
// tall, through staad's perception: experiment/agent_camera.hpp), its command drives the
// world for one control period, until the goal is reached or the time is up.

#include "control/control_cycle.hpp"
#include "experiment/obstacle_source.hpp"
#include "planner/budget.hpp"
#include "record/recording.hpp"
#include "world/world.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace staa {

struct SimOptions {
  double rate_hz = 30.0;
  double duration_s = 60.0;
  // Budget: a fixed number of queue pops (reproducible) or a wall-clock limit.
  BudgetSpec budget;  // default: 19 ms of wall clock
  ControlConfig control;
  // A baseline local controller in place of STAA* (not owned; null: STAA*).
  LocalController* controller = nullptr;
  ObstacleSource obstacles = ObstacleSource::kTruth;
  std::filesystem::path svg_dir;  // empty: no frames
  int svg_every = 15;             // cycles between frames
  // Called after each cycle (progress, tests); may be empty.
  std::function<void(const World&, const CycleOutput&, int cycle)> on_cycle;
  // Every cycle recorded into this MCAP file (staa-sim --record; empty: off). The runner
  // completes the session (control configuration, robot, map, agents).
  std::filesystem::path record_path;
  record::Session record_session;
};

struct Distribution {
  double mean = 0.0, p50 = 0.0, p99 = 0.0, max = 0.0;
};
Distribution distributionOf(std::vector<double> values);

struct SimResult {
  bool reached_goal = false;
  double time_to_goal_s = 0.0;   // when reached; otherwise the duration
  int goals_reached = 0;
  int collisions = 0;            // collision episodes
  double min_clearance_m = 0.0;
  double duration_s = 0.0;       // simulated time
  std::string final_state;       // the cycle's state at the end
  std::string reason;            // why, when that state is unreachable (the path's status)
  Pose2 final_pose;
  // Planner statistics over the cycles that ran STAA*.
  int calls = 0;
  Distribution expansions;       // queue pops per call
  Distribution successors;
  Distribution depth;
  double finished_early_ratio = 0.0;
  int brakes = 0;
  Distribution plan_us;          // STAA* only
  Distribution cycle_us;         // path + local map + STAA*
  Distribution path_us;
  std::vector<Pose2> trace;      // the robot's pose every cycle
  int frames_written = 0;
  std::uint64_t camera_frames = 0;  // depth: frames perceived (and lost)
  std::uint64_t camera_frames_lost = 0;
};

// Runs the scenario's robot from its start to its goal.
SimResult runSingleRobot(const Scenario& scenario, const SimOptions& options);

// Writes one frame like the paper's Fig. 1 (map, local box, occupied grid cells, inflated
// obstacles, search tree, chosen trajectory, G~, the movers and their predictions).
void writeFrame(const std::filesystem::path& file, const World& world, ControlCycle& cycle, const CycleOutput& out,
                const DynamicObstacleSet& obstacles);

// What a frame shows besides the cycle's own state: the map, the robot (its footprint placed
// at its pose) and the caption's lines (the first one is the title).
struct FrameScene {
  const PolygonMap* map = nullptr;
  Polygon body;  // the footprint in the world
  Pose2 robot;
  std::vector<std::string> caption;
  // The first action of the plan drawn in the colour of its braking-safety tier (2 passive,
  // 1 braking hypothesis, 0 none passed), with its legend entry; -1: not drawn.
  int first_action_tier = -1;
};
// The frame of writeFrame, for any source of cycles (staa-replay draws recorded ones).
void drawCycleFrame(const std::filesystem::path& file, const FrameScene& scene, ControlCycle& cycle,
                    const CycleOutput& out, const DynamicObstacleSet& obstacles);

}  // namespace staa
