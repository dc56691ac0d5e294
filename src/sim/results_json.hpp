#pragma once
// JSON of the simulator's result figures, shared by `staa-sim --json` and the experiment's
// results.json so that both spell the ARCHITECTURE.md section 6 keys the same way.

#include "sim/sim_runner.hpp"

#include <nlohmann/json.hpp>

namespace staa {

// {"mean"?, "p50", "p99", "max"?} of a distribution.
inline nlohmann::ordered_json distributionJson(const Distribution& d, bool with_mean, bool with_max) {
  nlohmann::ordered_json j;
  if (with_mean) j["mean"] = d.mean;
  j["p50"] = d.p50;
  j["p99"] = d.p99;
  if (with_max) j["max"] = d.max;
  return j;
}

}  // namespace staa
