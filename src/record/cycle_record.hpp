#pragma once
// One control cycle as the flight recorder keeps it: everything the cycle saw (time, robot
// state, moving obstacles as handed to DynamicObstacleSet::set, the goal and what the cycle
// carried from the step before, the budget and where it cut the cycle short) and everything
// that came out of it (the command, the state, the plan). Encoded as the binary message of
// the `.../cycle` channel, `x-staa-cycle` version 1: docs/ARCHITECTURE.md, "Flight recorder",
// documents every byte.
//
// encodeCycle() runs in the control thread: it writes into a buffer sized at start-up
// (maxCycleBytes) and allocates nothing. decodeCycle() is for the readers (allocates).

#include "control/control_cycle.hpp"
#include "record/budget_tap.hpp"

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa::record {

inline constexpr std::uint16_t kCycleEncodingVersion = 1;
inline constexpr const char* kCycleEncoding = "x-staa-cycle";

// What happened to the cycle (staad holds the robot without planning on faults and stops).
enum class StepKind : std::uint8_t {
  kStepped = 0,  // ControlCycle::step ran
  kFault = 1,    // staad braked for a fault: no step
  kStopped = 2,  // staad braked on a stop request: no step
};

// Flags of a cycle record (the byte after `fault`).
enum CycleFlags : std::uint8_t {
  kGoalSet = 1 << 0,      // the goal was set (setGoal(memory.goal)) or cleared (no goal in
                          // the memory) before this cycle
  kPoseCorrected = 1 << 1,  // staad: a pose correction (staactl pose) was handed to the base
                            // before this cycle (the robot state shows its effect)
  kNewCycle = 1 << 2,     // a new ControlCycle (staad: a map swapped in) before this cycle
  kFresh = 1 << 3,        // ControlCycle::searchesFresh() before the step: replays exactly from here
  kInputsCut = 1 << 4,    // inputs beyond the recorder's limits were left out: not replayable
  kHeldPath = 1 << 5,     // the held path is recorded (the step may follow it)
};

// The largest inputs one record holds (the buffer is sized by them at start-up).
struct RecordLimits {
  std::size_t obstacles = 32;
  std::size_t vertices = 32;      // per obstacle
  std::size_t path_points = 512;  // held path and global path, each
  std::size_t trajectory = 64;    // plan states
};
std::size_t maxCycleBytes(const RecordLimits& limits);

struct BudgetRecord {
  bool wall_clock = false;
  std::uint32_t max_pops = 0;  // expansion budget
  std::int64_t limit_ns = 0;   // wall-clock budget
  BudgetCut cut;
};
BudgetRecord budgetRecord(const PlannerBudget& budget, const BudgetCut& cut);

// The command that went to the base (staad), or the cycle's own (simulations).
struct CommandRecord {
  double v = 0.0, w = 0.0;
  bool brake = false;
  double next_v = 0.0, next_w = 0.0;  // staad's fallback for a missed cycle
  bool next_brake = false;
};

// The moving obstacles exactly as handed to DynamicObstacleSet::set.
struct ObstacleInputs {
  std::span<const PolygonView> polygons;
  std::span<const Vec2> velocities;
  std::span<const double> turn_rates;  // may be empty (zeros)
};

// Everything encodeCycle needs, by reference (no copies in the control thread).
struct CycleView {
  std::uint16_t agent = 0;
  std::uint64_t cycle = 0;
  std::int64_t time_ns = 0;
  std::uint32_t map_sequence = 0;
  StepKind step = StepKind::kStepped;
  std::uint8_t fault = 0;
  std::uint8_t flags = 0;  // kGoalSet, kPoseCorrected, kNewCycle; kFresh, kInputsCut, kHeldPath: encodeCycle's
  ControlCycle::Memory memory;  // before the step
  bool fresh = false;           // searchesFresh() before the step
  UnicycleState robot;
  BudgetRecord budget;
  ObstacleInputs obstacles;
  const CycleOutput* out = nullptr;  // null when not stepped
  std::span<const Vec2> route;       // the path the step followed (lastPath())
  Pose2 subgoal;                     // G~
  bool subgoal_final = false;
  CommandRecord command;
};

// Encodes into `buffer`; returns the bytes written, 0 when the buffer is too small (it is
// never, when sized by maxCycleBytes of the limits the inputs keep to: inputs beyond them are
// cut and flagged). No allocation.
std::size_t encodeCycle(const CycleView& view, const RecordLimits& limits, std::span<std::byte> buffer);

// The comparable outputs of a step (everything but the timings), bit for bit.
struct StepOutputs {
  double v_cmd = 0.0, w_cmd = 0.0;
  CycleState state = CycleState::kIdle;
  PathStatus path_status = PathStatus::kNoPath;
  bool path_dynamic = false, path_held = false, planned = false;
  double path_length = 0.0;
  std::uint32_t obstacles_dropped = 0;
  PlanResult::Outcome outcome = PlanResult::Outcome::kBrake;
  Action first_action;
  UnicycleState best;
  double best_h = 0.0;
  std::uint32_t brake_safe_actions = 0;
  std::uint8_t tier = 0;
  std::int32_t depth = 0;
  std::uint32_t pops = 0, expansions = 0, successors = 0, collisions = 0, heuristic_calls = 0;
};
StepOutputs stepOutputs(const CycleOutput& out);
// The first field in which two outputs differ ("v_cmd 0.21340000000000001 vs 0.2101"), or
// empty when they are the same bit for bit.
std::string firstDifference(const StepOutputs& recorded, const StepOutputs& replayed);

struct RecordedObstacle {
  Polygon polygon;
  Vec2 velocity{0.0, 0.0};
  double turn_rate = 0.0;
};

// A decoded record.
struct CycleRecord {
  std::uint16_t agent = 0;
  std::uint64_t cycle = 0;
  std::int64_t time_ns = 0;
  std::uint32_t map_sequence = 0;
  StepKind step = StepKind::kStepped;
  std::uint8_t fault = 0;
  std::uint8_t flags = 0;
  // ControlCycle::Memory before the step.
  bool has_goal = false;
  Pose2 goal;
  CycleState state = CycleState::kIdle;
  bool held_valid = false;
  // The byte after held_valid: bit 0 the held path runs in M'', bit 1 a route was chosen
  // for the goal, bit 2 in M'' (Memory::held_passage, route_chosen, route_in_passage).
  std::uint8_t route_bits = 0;
  std::int32_t path_misses = 0;
  Polygon held_path;  // with kHeldPath
  UnicycleState robot;
  BudgetRecord budget;
  std::vector<RecordedObstacle> obstacles;
  // Outputs (when stepped).
  StepOutputs out;
  std::int64_t path_ns = 0, local_ns = 0, plan_ns = 0;
  CommandRecord command;
  Pose2 subgoal;
  bool subgoal_final = false;
  Polygon route;
  std::vector<UnicycleState> trajectory;  // single precision in the record (plots only)

  bool stepped() const { return step == StepKind::kStepped; }
  ControlCycle::Memory memory() const;  // its held_path views this record
};

class RecordError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws RecordError naming `where` and the problem (a short record, a version this reader
// does not know, a value out of range).
CycleRecord decodeCycle(std::span<const std::byte> data, const std::string& where);

}  // namespace staa::record
