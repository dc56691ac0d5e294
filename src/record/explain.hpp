#pragma once
// Why a recorded cycle's command is what it is, in words: the caption of `staa-replay
// --cycle K` (braking safety, no path, path held, stale input, fault, the budget's cut).

#include "record/cycle_record.hpp"

#include <string>
#include <vector>

namespace staa::record {

// Lines: the cycle and its time, the reason for the command, the numbers behind it.
// `file_t_s`: the cycle's time from the file's first cycle.
std::vector<std::string> explainCycle(const CycleRecord& record, double file_t_s, const std::string& controller);

}  // namespace staa::record
