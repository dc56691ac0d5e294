#pragma once
// JSON of the simulator's result figures, shared by `staa-sim --json` and the experiment's
// results.json so that both spell the docs/ARCHITECTURE.md section 6 keys the same way.

#include "experiment/multi_sim.hpp"
#include "experiment/sim_runner.hpp"

#include <nlohmann/json.hpp>

namespace staa {

// {"kind": "expansions" | "wall_ms", "value": pops or milliseconds}.
inline nlohmann::ordered_json budgetJson(const BudgetSpec& b) {
  nlohmann::ordered_json j;
  j["kind"] = b.kindName();
  if (b.isExpansions()) {
    j["value"] = b.expansions;
  } else {
    j["value"] = b.ms;
  }
  return j;
}

// {"mean"?, "p50", "p99", "max"?} of a distribution.
inline nlohmann::ordered_json distributionJson(const Distribution& d, bool with_mean, bool with_max) {
  nlohmann::ordered_json j;
  if (with_mean) j["mean"] = d.mean;
  j["p50"] = d.p50;
  j["p99"] = d.p99;
  if (with_max) j["max"] = d.max;
  return j;
}

// The "planner" object of docs/ARCHITECTURE.md section 6 (one run, one robot or several agents).
inline nlohmann::ordered_json plannerJson(int calls, const Distribution& expansions, const Distribution& successors,
                                          double finished_early_ratio, double depth_mean, const Distribution& plan_us) {
  nlohmann::ordered_json planner;
  planner["calls"] = calls;
  planner["expansions"] = distributionJson(expansions, true, false);
  planner["successors"] = distributionJson(successors, true, false);
  planner["finished_early_ratio"] = finished_early_ratio;
  planner["depth_mean"] = depth_mean;
  planner["plan_us"] = distributionJson(plan_us, false, true);
  return planner;
}

// The "contacts" list of a multi-agent run (not in docs/ARCHITECTURE.md section 6 yet): one object
// per counted contact episode; "other" and the tiers are null for the map and for no plan.
inline nlohmann::ordered_json contactsJson(const std::vector<ContactRecord>& contacts) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  auto orNull = [](int value) { return value >= 0 ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr); };
  for (const ContactRecord& c : contacts) {
    nlohmann::ordered_json j;
    j["time_s"] = c.time_s;
    j["agent"] = c.agent;
    j["other"] = orNull(c.other);
    j["speed"] = c.speed;
    j["other_speed"] = c.other_speed;
    j["tier"] = orNull(c.tier);
    j["other_tier"] = orNull(c.other_tier);
    list.push_back(std::move(j));
  }
  return list;
}

}  // namespace staa
