#pragma once
// JSON of the simulator's result figures, shared by `staa-sim --json` and the experiment's
// results.json so that both spell the docs/ARCHITECTURE.md section 6 keys the same way.

#include "experiment/multi_sim.hpp"
#include "experiment/perception_score.hpp"
#include "experiment/sim_runner.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <vector>

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

// The "contacts" list of a multi-agent run (docs/ARCHITECTURE.md, staa-sim JSON): one object
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
    if (c.perceived) {
      // What the agent's camera knew of the other (--obstacles depth); null: never in this sighting.
      const PerceptionScorer::Sighting& s = c.sighting;
      nlohmann::ordered_json p;
      p["seen_before_s"] = s.seen ? nlohmann::ordered_json(s.seen_before_s) : nlohmann::ordered_json(nullptr);
      p["seen_at_m"] = s.seen ? nlohmann::ordered_json(s.seen_at_m) : nlohmann::ordered_json(nullptr);
      p["covered_before_s"] = s.covered ? nlohmann::ordered_json(s.covered_before_s) : nlohmann::ordered_json(nullptr);
      // When the map stopped hiding the other (null: it did not in the last second).
      p["in_sight_before_s"] = s.in_sight ? nlohmann::ordered_json(s.in_sight_before_s) : nlohmann::ordered_json(nullptr);
      p["in_sight_at_m"] = s.in_sight ? nlohmann::ordered_json(s.in_sight_at_m) : nlohmann::ordered_json(nullptr);
      j["perceived"] = std::move(p);
    }
    list.push_back(std::move(j));
  }
  return list;
}

// {"mean", "p50", "p95", "max", "n"} of an error histogram (percentiles to its 2 cm bins),
// with the bins themselves ([[lower edge, count], ...], non-empty ones) when `bins`.
inline nlohmann::ordered_json errorJson(const ErrorHistogram& h, bool bins) {
  nlohmann::ordered_json j;
  j["n"] = h.n;
  j["mean"] = h.mean();
  j["p50"] = h.percentile(0.5);
  j["p95"] = h.percentile(0.95);
  j["max"] = h.max;
  if (bins) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < h.counts.size(); ++k) {
      if (h.counts[k] > 0) list.push_back(nlohmann::ordered_json::array({ErrorHistogram::kBin * static_cast<double>(k), h.counts[k]}));
    }
    j["bins"] = std::move(list);
  }
  return j;
}

// The "perception" object of a depth run (experiment/perception_score.hpp says what each
// figure is); `bins`: the histograms' bins and every latency too (a run's; a summary leaves
// them out).
inline nlohmann::ordered_json perceptionJson(const PerceptionAccuracy& a, bool bins) {
  nlohmann::ordered_json j;
  j["frames"] = a.frames;
  j["frames_lost"] = a.frames_lost;
  j["position_error_m"] = errorJson(a.position_m, bins);
  j["velocity_error_mps"] = errorJson(a.velocity_mps, bins);
  j["kept_position_error_m"] = errorJson(a.kept_position_m, bins);
  j["kept_velocity_error_mps"] = errorJson(a.kept_velocity_mps, bins);
  j["near_samples"] = a.near_samples;
  j["near_missed"] = a.near_missed;
  j["near_missed_in_view"] = a.near_missed_in_view;
  j["obstacles"] = a.obstacles;
  j["kept_obstacles"] = a.kept_obstacles;
  j["false_obstacles"] = a.false_obstacles;
  j["false_kept"] = a.false_kept;
  nlohmann::ordered_json latency;
  latency["entries"] = a.entries;
  latency["settled"] = a.latency_s.size();
  latency["unsettled"] = a.unsettled;
  std::vector<double> sorted = a.latency_s;
  std::sort(sorted.begin(), sorted.end());
  const auto at = [&](double p) {
    return sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(p * static_cast<double>(sorted.size())))];
  };
  latency["p50_s"] = at(0.5);
  latency["p90_s"] = at(0.9);
  latency["max_s"] = sorted.empty() ? 0.0 : sorted.back();
  if (bins) latency["values_s"] = sorted;
  j["latency"] = std::move(latency);
  const double frames = a.frames > 0 ? static_cast<double>(a.frames) : 1.0;
  j["render_us_mean"] = a.render_us_sum / frames;
  j["perception_us_mean"] = a.perception_us_sum / frames;
  return j;
}

}  // namespace staa
