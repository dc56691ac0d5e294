// staa-replay: reruns a flight recording (staad or staa-sim --record) cycle by cycle.
//
//   staa-replay FILE                       what the file holds
//   staa-replay FILE --check               every cycle rerun and compared bit for bit: exit 0 and
//                                          "N cycles, N identical", or 1 naming the first difference
//   staa-replay FILE --cycle K --svg OUT   cycle K drawn like the paper's Fig. 1, with why its
//                                          command is what it is
//   staa-replay FILE --set KEY=VALUE ...   rerun with changed parameters: where and how the
//                                          commands change
//   [--from T] [--to T] [--agent N] [--json OUT] [--salvage]
//
// Exit status: 0 done (and --check found every cycle identical), 1 --check found a difference,
// 2 bad input (a file that is no recording, truncated without --salvage, of another version,
// with a map that does not match; an unknown key; a cycle not in the file).

#include "app/cli_support.hpp"
#include "experiment/sim_runner.hpp"
#include "record/config_keys.hpp"
#include "record/explain.hpp"
#include "record/replay.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using staa::cli::InputError;
using Json = nlohmann::ordered_json;
namespace rec = staa::record;

constexpr int kExitDifferent = 1;

struct Args {
  std::string file;
  std::optional<double> from_s, to_s;
  bool check = false;
  std::optional<std::uint64_t> cycle;
  std::string svg;
  std::vector<std::string> sets;
  std::string json;
  std::optional<int> agent;
  bool salvage = false;
};

std::string fmt(double v, int digits) {
  char s[64];
  std::snprintf(s, sizeof s, "%.*f", digits, v);
  return s;
}

// --set KEY=VALUE: the control configuration's keys, and budget.expansions / budget.ms.
void applySets(const std::vector<std::string>& sets, staa::ControlConfig& control, std::optional<staa::BudgetSpec>& budget) {
  for (const std::string& s : sets) {
    const std::size_t eq = s.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--set '" + s + "': expected KEY=VALUE");
    const std::string key = s.substr(0, eq), value = s.substr(eq + 1);
    if (key == "budget.expansions") {
      const auto n = staa::cli::parseUnsigned(value);
      if (!n || *n < 1 || *n > std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("--set budget.expansions: expected an integer >= 1, got '" + value + "'");
      }
      budget = staa::BudgetSpec::expansionsOf(static_cast<std::uint32_t>(*n));
    } else if (key == "budget.ms") {
      const auto ms = staa::cli::parseDouble(value);
      if (!ms || *ms <= 0.0) throw InputError("--set budget.ms: expected milliseconds > 0, got '" + value + "'");
      budget = staa::BudgetSpec::wallClockMs(*ms);
    } else {
      try {
        rec::setControlKey(control, key, value);
      } catch (const rec::KeyError& e) {
        throw InputError(std::string("--set: ") + e.what() + "; or budget.expansions, budget.ms");
      }
    }
  }
}

std::string describeFile(const rec::Recording& r) {
  const rec::Session& s = r.session;
  std::string out = r.path.string() + ": " + s.source + " recording by " + s.software + " (" + s.build_type + "), " +
                    s.recorded_at + "; budget " + s.budget + "; robot " + s.robot.name + "; map " + s.map.name + " (" +
                    std::to_string(s.map.obstacles.size()) + " polygons); " + std::to_string(r.bytes) + " bytes" +
                    (r.truncated ? " (truncated: salvaged)" : "") + "\n";
  for (const auto& [agent, cycles] : r.agents) {
    const auto controller = std::find_if(s.agents.begin(), s.agents.end(), [&](const rec::AgentInfo& a) { return a.agent == agent; });
    std::optional<std::uint64_t> fresh;
    for (const rec::CycleRecord& c : cycles) {
      if (c.flags & rec::kFresh) {
        fresh = c.cycle;
        break;
      }
    }
    const double t0 = static_cast<double>(cycles.front().time_ns - r.first_time_ns) * 1e-9;
    const double t1 = static_cast<double>(cycles.back().time_ns - r.first_time_ns) * 1e-9;
    out += "  agent " + std::to_string(agent) + " (" + controller->controller + "): cycles " +
           std::to_string(cycles.front().cycle) + ".." + std::to_string(cycles.back().cycle) + " (" +
           std::to_string(cycles.size()) + "), t " + fmt(t0, 2) + ".." + fmt(t1, 2) + " s; " +
           (fresh ? "replays exactly from cycle " + std::to_string(*fresh) : std::string("no fresh cycle: replays best effort")) +
           "\n";
  }
  if (!r.events.empty()) out += "  " + std::to_string(r.events.size()) + " events (" + r.events.front().topic + ", ...)\n";
  std::uint64_t cycles = 0;
  double seconds = 0.0;
  for (const auto& [agent, c] : r.agents) {
    cycles += c.size();
    seconds = std::max(seconds, static_cast<double>(c.back().time_ns - r.first_time_ns) * 1e-9 + 1.0 / s.control.rate_hz);
  }
  if (cycles > 0 && seconds > 0.0) {
    const double n = static_cast<double>(cycles);
    out += "  " + fmt(static_cast<double>(r.bytes) / n, 0) + " bytes per cycle (cycle channel " +
           fmt(static_cast<double>(r.cycle_bytes) / n, 0) + ", JSON channels " + fmt(static_cast<double>(r.json_bytes) / n, 0) +
           "), " + fmt(static_cast<double>(r.bytes) / seconds * 60.0 / 1e6, 2) + " MB per minute\n";
  }
  return out;
}

Json agentJson(const rec::AgentReplay& a) {
  Json j;
  j["agent"] = a.agent;
  j["cycles"] = a.cycles;
  j["exact"] = a.exact;
  j["identical"] = a.identical;
  j["best_effort_identical"] = a.best_effort_identical;
  j["held"] = a.held;
  j["exact_from_cycle"] = a.exact_from ? Json(*a.exact_from) : Json(nullptr);
  j["differing"] = a.differing;
  if (a.first_difference_cycle) {
    j["first_difference"] = {{"cycle", *a.first_difference_cycle}, {"t", a.first_difference_t}, {"what", a.first_difference}};
  } else {
    j["first_difference"] = nullptr;
  }
  j["max_command_change"] = a.max_command_change;
  j["max_plan_distance_m"] = a.max_path_distance_m;
  j["mean_plan_distance_m"] = a.mean_path_distance_m;
  return j;
}

// The robot's footprint placed at its pose.
staa::Polygon placed(const staa::Polygon& footprint, const staa::UnicycleState& s) {
  staa::Polygon out;
  const double c = std::cos(s.theta), sn = std::sin(s.theta);
  for (const staa::Vec2& p : footprint) out.emplace_back(s.x + c * p.x() - sn * p.y(), s.y + sn * p.x() + c * p.y());
  return out;
}

int run(int argc, char** argv) {
  staa::cli::CommandLine cl("staa-replay",
                            "staa-replay: rerun a flight recording (staad's recorder, staa-sim --record) cycle by "
                            "cycle from its recorded inputs, map, robot and configuration. Exit 0 done, 1 --check "
                            "found a difference, 2 bad input.");
  CLI::App& app = cl.app;
  Args a;
  app.add_option("FILE", a.file, "The recording (MCAP)")->required();
  app.add_option("--from", a.from_s, "Start at this many seconds from the file's first cycle")
      ->transform(staa::cli::nonNegative("seconds"));
  app.add_option("--to", a.to_s, "End at this many seconds from the file's first cycle")
      ->transform(staa::cli::nonNegative("seconds"));
  app.add_flag("--check", a.check,
               "Rerun every cycle and compare commands and states bit for bit: exit 0 and \"N cycles, N identical\", "
               "or 1 naming the first cycle that differs and how");
  auto* cycle = app.add_option("--cycle", a.cycle, "The cycle to explain (and draw with --svg): its number in the file");
  auto* svg = app.add_option("--svg", a.svg, "Draw --cycle K like the paper's Fig. 1 into this SVG file");
  cl.need(svg, cycle, "--svg draws the cycle --cycle K");
  app.add_option("--set", a.sets, "Rerun with KEY=VALUE changed (a control configuration key, e.g. "
                                  "staa.heuristic.kind=path-euclid, or budget.expansions=N, budget.ms=MS); repeatable");
  app.add_option("--json", a.json, "Write the results as JSON to this file");
  app.add_option("--agent", a.agent, "Only this agent (default: every agent; --cycle: agent 0)")
      ->transform(staa::cli::count("an agent", 0, 65535));
  app.add_flag("--salvage", a.salvage, "Read a truncated file (a recorder stopped while writing) up to its last "
                                       "complete record");
  if (const auto exit = cl.parse(argc, argv)) return *exit;
  if (a.from_s && a.to_s && *a.to_s < *a.from_s) {
    throw InputError("--to " + fmt(*a.to_s, 3) + " is before --from " + fmt(*a.from_s, 3));
  }

  rec::Recording recording;
  try {
    recording = rec::loadRecording(a.file, a.salvage);
  } catch (const rec::McapError& e) {
    throw InputError(std::string(e.what()) + (e.truncated() ? " (--salvage replays its complete cycles)" : ""));
  } catch (const rec::RecordError& e) {
    throw InputError(e.what());
  }
  if (recording.agents.empty()) throw InputError(a.file + ": the recording holds no cycle");
  if (a.agent && !recording.agents.contains(static_cast<std::uint16_t>(*a.agent))) {
    throw InputError("--agent " + std::to_string(*a.agent) + ": the recording has no such agent");
  }

  rec::ReplayOptions options;
  options.from_s = a.from_s;
  options.to_s = a.to_s;
  if (a.agent) options.agent = static_cast<std::uint16_t>(*a.agent);
  if (!a.sets.empty()) {
    staa::ControlConfig control = recording.session.control;
    applySets(a.sets, control, options.budget);
    options.control = control;
  }
  const bool explain = a.cycle.has_value();
  if (explain) {
    options.agent = static_cast<std::uint16_t>(a.agent.value_or(recording.agents.begin()->first));
    const std::vector<rec::CycleRecord>& cycles = recording.agents.at(*options.agent);
    const bool found = std::any_of(cycles.begin(), cycles.end(), [&](const rec::CycleRecord& c) { return c.cycle == *a.cycle; });
    if (!found) {
      throw InputError("--cycle " + std::to_string(*a.cycle) + ": agent " + std::to_string(*options.agent) +
                       "'s cycles in the file are " + std::to_string(cycles.front().cycle) + ".." +
                       std::to_string(cycles.back().cycle));
    }
    options.until_cycle = *a.cycle;
  }
  std::ofstream json_out;
  if (!a.json.empty()) {
    json_out.open(a.json, std::ios::binary | std::ios::trunc);
    if (!json_out) throw InputError("--json: cannot write '" + a.json + "'");
  }

  if (!a.check && a.sets.empty() && !explain) {
    std::cout << describeFile(recording);
    if (json_out.is_open()) {
      Json j;
      j["file"] = a.file;
      j["source"] = recording.session.source;
      j["software"] = recording.session.software;
      j["budget"] = recording.session.budget;
      j["cycles"] = 0;
      for (const auto& [agent, cycles] : recording.agents) j["cycles"] = j["cycles"].get<std::size_t>() + cycles.size();
      json_out << j.dump(2) << '\n';
    }
    return 0;
  }

  std::optional<std::string> svg_error;
  std::vector<std::string> caption;
  const rec::ReplayResult result = rec::replay(recording, options, [&](const rec::ReplayedCycle& c) {
    if (!explain || c.record.cycle != *a.cycle) return;
    const double t = static_cast<double>(c.record.time_ns - recording.first_time_ns) * 1e-9;
    const auto info = std::find_if(recording.session.agents.begin(), recording.session.agents.end(),
                                   [&](const rec::AgentInfo& i) { return i.agent == c.record.agent; });
    caption = rec::explainCycle(c.record, t, info->controller);
    if (!c.difference.empty()) caption.push_back("the rerun differs: " + c.difference);
    if (a.svg.empty()) return;
    if (c.out == nullptr) {
      svg_error = "cycle " + std::to_string(c.record.cycle) + " did not step (" + caption.back() + "): nothing to draw";
      return;
    }
    staa::FrameScene scene;
    scene.map = &recording.session.map;
    scene.body = placed(recording.session.robot.footprint, c.record.robot);
    scene.robot = c.record.robot.pose();
    scene.caption = caption;
    scene.first_action_tier = c.out->planned ? c.out->plan.brake_safety_tier : -1;
    try {
      staa::drawCycleFrame(a.svg, scene, c.mutable_cycle, *c.out, c.obstacles);
    } catch (const std::exception& e) {
      svg_error = std::string("--svg: ") + e.what();
    }
  });
  if (svg_error) throw InputError(*svg_error);

  const double speed = result.seconds > 0.0 ? static_cast<double>(result.cycles) / result.seconds : 0.0;
  bool all_exact_identical = true;
  if (!a.sets.empty()) {
    std::string sets;
    for (const std::string& s : a.sets) sets += (sets.empty() ? "" : ", ") + s;
    std::cout << result.cycles << " cycles rerun with " << sets << ": " << (result.cycles - result.identical)
              << " changed (open loop: the robot moves as recorded, only what the cycles decide changes)\n";
  } else {
    std::cout << result.cycles << " cycles, " << result.identical << " identical\n";
  }
  for (const rec::AgentReplay& ar : result.agents) {
    std::string line = "  agent " + std::to_string(ar.agent) + ": " + std::to_string(ar.cycles) + " cycles";
    if (!a.sets.empty()) {
      if (ar.first_difference_cycle) {
        line += "; first change at cycle " + std::to_string(*ar.first_difference_cycle) + " (t = " +
                fmt(ar.first_difference_t, 2) + " s): " + ar.first_difference + "; " + std::to_string(ar.differing) +
                " cycles changed, commands by up to " + fmt(ar.max_command_change, 3) +
                " (|dv| m/s + |dw| rad/s), plans apart by up to " + fmt(ar.max_path_distance_m, 3) + " m (mean " +
                fmt(ar.mean_path_distance_m, 3) + " m)";
      } else {
        line += ", none changed";
      }
      std::cout << line << '\n';
      continue;
    }
    if (ar.exact_from) line += ", exact from cycle " + std::to_string(*ar.exact_from);
    if (ar.exact < ar.cycles) {
      line += ", " + std::to_string(ar.cycles - ar.exact) + " before it rerun best effort (" +
              std::to_string(ar.best_effort_identical) + " identical)";
    }
    if (ar.held > 0) line += ", " + std::to_string(ar.held) + " held by staad without a step";
    if (ar.other_map > 0) {
      line += ", " + std::to_string(ar.other_map) + " on a map swapped in from ROS that the file does not hold (not rerun)";
    }
    if (ar.first_difference_cycle) {
      line += "; first difference at cycle " + std::to_string(*ar.first_difference_cycle) + " (t = " +
              fmt(ar.first_difference_t, 2) + " s): " + ar.first_difference + "; " + std::to_string(ar.differing) +
              " cycles differ";
    }
    std::cout << line << '\n';
    // --check fails on an exact cycle that differs; best-effort ones only count when nothing is exact.
    if (ar.exact != ar.identical) all_exact_identical = false;
    if (ar.exact == 0 && ar.differing > 0) all_exact_identical = false;
    if (ar.exact == 0 && ar.cycles > ar.held) {
      std::cout << "  (agent " << ar.agent << ": no cycle replays exactly: the cycles rerun start in the middle of a "
                   "drive and hold no new goal)\n";
    }
  }
  std::cerr << "staa-replay: " << result.cycles << " cycles in " << fmt(result.seconds, 2) << " s (" << fmt(speed, 0)
            << " cycles/s)\n";
  for (const std::string& line : caption) std::cout << line << '\n';

  if (json_out.is_open()) {
    Json j;
    j["file"] = a.file;
    j["cycles"] = result.cycles;
    j["identical"] = result.identical;
    j["seconds"] = result.seconds;
    j["cycles_per_s"] = speed;
    j["set"] = a.sets;
    Json agents = Json::array();
    for (const rec::AgentReplay& ar : result.agents) agents.push_back(agentJson(ar));
    j["agents"] = agents;
    if (explain) j["caption"] = caption;
    json_out << j.dump(2) << '\n';
    json_out.close();
    if (!json_out) throw InputError("--json: cannot write '" + a.json + "'");
  }
  if (a.check && (!all_exact_identical || (!a.sets.empty() && result.identical != result.cycles))) return kExitDifferent;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const InputError& e) {
    std::cerr << "staa-replay: " << e.what() << '\n';
  } catch (const std::invalid_argument& e) {
    std::cerr << "staa-replay: " << e.what() << '\n';
  } catch (const std::exception& e) {
    std::cerr << "staa-replay: " << e.what() << '\n';
  } catch (...) {
    std::cerr << "staa-replay: unexpected error\n";
  }
  return staa::cli::kExitBadInput;
}
