#pragma once
// Deterministic replay: every recorded cycle rerun from its recorded inputs, on a control
// cycle built from the recorded map, robot profile and configuration, and compared with
// what the recorded cycle put out, bit for bit.
//
// Exact from a fresh cycle. A cycle's outputs are a function of its inputs, its memory (the
// goal, the state, the held path: recorded every cycle and restored) and what its searches
// kept from earlier cycles (their trees: not recorded, forgotten by every new goal). From
// the first record flagged fresh (ControlCycle::searchesFresh(): the cycle was made or its
// goal set and no search has run since) the replayer's searches do the same work as the
// original's, so a wall-clock budget's cut, recorded as the index of the clock read that
// passed the deadline (record/budget_tap.hpp), lands in the same place, and every output
// is the same. Before that point (a file that starts in the middle of a drive: a rotated
// file, a fault file) a cycle is rerun with the expansions it reached as its budget and
// fresh searches: usually the same, not guaranteed; such cycles are counted apart.

#include "control/control_cycle.hpp"
#include "control/local_controller.hpp"
#include "record/cycle_record.hpp"
#include "record/recording.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace staa::record {

struct RecordedEvent {
  std::string topic;
  std::int64_t time_ns = 0;
  std::string json;
};

struct Recording {
  std::filesystem::path path;
  Session session;
  std::map<std::uint16_t, std::vector<CycleRecord>> agents;  // each agent's cycles in order
  std::vector<RecordedEvent> events;                         // contacts (multi-agent runs)
  bool truncated = false;
  std::int64_t first_time_ns = 0;  // the earliest cycle of the file (--from and --to count from it)
  std::uint64_t bytes = 0;        // the file
  std::uint64_t cycle_bytes = 0;  // the x-staa-cycle messages' data
  std::uint64_t json_bytes = 0;   // the plotted channels' data
};

// Throws McapError (not MCAP, truncated, another version) or RecordError (no session, a bad
// cycle record, a map that does not match its checksum). `salvage`: a truncated file yields
// its complete cycles.
Recording loadRecording(const std::filesystem::path& path, bool salvage = false);

struct ReplayOptions {
  std::optional<double> from_s, to_s;  // seconds from the file's first cycle
  std::optional<std::uint16_t> agent;  // only this agent
  // The configuration to rerun with: the recorded one, or one changed by --set. Changed, the
  // cycles are rerun with the expansions each one reached (a wall-clock cut means nothing to
  // another planner), unless `budget` says otherwise.
  std::optional<ControlConfig> control;
  std::optional<BudgetSpec> budget;
  // Stop after this cycle of the selected agent (--cycle K): the replay runs up to it.
  std::optional<std::uint64_t> until_cycle;
};

// One rerun cycle, as the callback sees it (valid during the call).
struct ReplayedCycle {
  const CycleRecord& record;
  const CycleOutput* out;               // null: the recorded cycle did not step (fault, stop)
  const ControlCycle& cycle;
  ControlCycle& mutable_cycle;          // for drawing (the planner's tree)
  const DynamicObstacleSet& obstacles;
  bool exact;                           // rerun from a fresh point with the recorded cut
  std::string difference;               // empty: identical bit for bit
};

struct AgentReplay {
  std::uint16_t agent = 0;
  std::uint64_t cycles = 0;      // cycles rerun (stepped or held)
  std::uint64_t exact = 0;       // of them, from a fresh point
  std::uint64_t identical = 0;   // of the exact ones, identical
  std::uint64_t best_effort_identical = 0;  // of the others, identical
  std::uint64_t held = 0;        // not stepped by staad (fault, stop): nothing to rerun
  std::uint64_t other_map = 0;   // on a map swapped in from ROS, which the file does not hold: not rerun
  std::optional<std::uint64_t> exact_from;  // the first fresh cycle
  std::optional<std::uint64_t> first_difference_cycle;
  double first_difference_t = 0.0;
  std::string first_difference;
  std::uint64_t differing = 0;   // cycles that differ (any)
  double max_command_change = 0.0;    // max |dv| + |dw| over differing cycles
  double max_path_distance_m = 0.0;   // max distance between recorded and rerun plans
  double mean_path_distance_m = 0.0;  // over differing cycles
};

struct ReplayResult {
  std::vector<AgentReplay> agents;
  std::uint64_t cycles = 0;
  std::uint64_t identical = 0;  // exact + best effort identical, held included
  double seconds = 0.0;         // wall time of the rerun
};

// Reruns the selected cycles; `each` (may be empty) sees every one (but those on a map the
// file does not hold). Throws std::invalid_argument for a configuration the control cycle
// refuses.
ReplayResult replay(const Recording& recording, const ReplayOptions& options,
                    const std::function<void(const ReplayedCycle&)>& each = {});

// The largest distance from a point of one plan to the other plan's polyline (both ways).
double planDistance(std::span<const UnicycleState> a, std::span<const UnicycleState> b);

}  // namespace staa::record
