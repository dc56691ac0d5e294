#pragma once
// What staa-sim and `staa-sim experiment` share on their command lines: the names of the
// controllers, modes and heuristics (the enums' own, through their toString) and the limit
// on the cycles of a run.

#include "app/cli_support.hpp"
#include "experiment/multi_sim.hpp"
#include "planner/heuristic.hpp"

#include <string>
#include <utility>
#include <vector>

namespace staa::cli {

inline const std::vector<std::pair<std::string, ControllerKind>> kControllerNames =
    namesOf({ControllerKind::kStaa, ControllerKind::kDwa, ControllerKind::kPd});
inline const std::vector<std::pair<std::string, SimMode>> kModeNames =
    namesOf({SimMode::kCooperative, SimMode::kGhost});
inline const std::vector<std::pair<std::string, ObstacleSource>> kObstacleNames =
    namesOf({ObstacleSource::kTruth, ObstacleSource::kDepth, ObstacleSource::kDepthScan, ObstacleSource::kSight});
inline const std::vector<std::pair<std::string, HeuristicKind>> kHeuristicNames =
    namesOf({HeuristicKind::kPathRtr, HeuristicKind::kPathEuclid, HeuristicKind::kDijkstraRtr});

// A run of more than 1e8 cycles is a typo, not an experiment. `per` ends the message.
inline void checkCycles(const CLI::Option* duration, const CLI::Option* rate, double duration_s, double rate_hz,
                        const std::string& per = "") {
  if (duration_s * rate_hz > 1e8) {
    throw InputError("--duration " + given(duration) + " at --rate " + given(rate) + " is more than 1e8 cycles" + per);
  }
}

}  // namespace staa::cli
