// staa-sim experiment: the matrix maps x controllers x modes x agents x heuristics x runs,
// run in parallel with a progress line on stderr, then DIR/results.json, the figures and a
// summary table on stdout.

#include "app/staa-sim/experiment_command.hpp"

#include "app/cli_support.hpp"
#include "map/polygon_map.hpp"
#include "experiment/experiment.hpp"
#include "experiment/experiment_plots.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace staa {
namespace {

namespace fs = std::filesystem;
using cli::InputError;

constexpr int kExitBadInput = 2;
constexpr int kExitRunFailed = 1;

std::vector<std::string> splitList(const std::string& option, const std::string& text) {
  std::vector<std::string> items;
  std::string_view rest(text);
  for (;;) {
    const std::size_t comma = rest.find(',');
    items.emplace_back(rest.substr(0, comma));
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  for (const std::string& item : items) {
    if (item.empty()) throw InputError(option + ": empty item in the list '" + text + "'");
  }
  return items;
}

template <class T>
void appendUnique(const std::string& option, const std::string& item, std::vector<T>& out, const T& value) {
  if (std::find(out.begin(), out.end(), value) != out.end()) {
    throw InputError(option + ": '" + item + "' is listed twice");
  }
  out.push_back(value);
}

std::uint64_t parseCount(const std::string& option, const std::string& text, std::uint64_t min, std::uint64_t max,
                         std::string_view what) {
  const auto v = cli::parseUnsigned(text);
  if (!v || *v < min || *v > max) {
    throw InputError(option + ": expected " + std::string(what) + " (an integer from " + std::to_string(min) +
                     " to " + std::to_string(max) + "), got '" + text + "'");
  }
  return *v;
}

double parsePositive(const std::string& option, const std::string& text, std::string_view what) {
  const auto v = cli::parseDouble(text);
  if (!v || *v <= 0.0) {
    throw InputError(option + ": expected " + std::string(what) + " (a finite number > 0), got '" + text + "'");
  }
  return *v;
}

std::string fmt(double v, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << v;
  return s.str();
}

// h:mm:ss or m:ss.
std::string clock(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
  }
  return buf;
}

std::string pad(std::string s, std::size_t width, bool right = false) {
  if (s.size() >= width) return s;
  return right ? std::string(width - s.size(), ' ') + s : s + std::string(width - s.size(), ' ');
}

std::string meanStd(const MeanStd& m) { return fmt(m.mean, 1) + " \u00b1 " + fmt(m.stddev, 1); }

void printSummary(std::ostream& out, const std::vector<ExperimentCell>& cells) {
  const std::vector<std::size_t> w{12, 12, 7, 11, 13, 5, 14, 14, 14};
  auto row = [&](const std::vector<std::string>& c) {
    std::string line;
    for (std::size_t i = 0; i < c.size(); ++i) line += pad(c[i], w[i], i >= 5) + (i + 1 < c.size() ? "  " : "");
    out << line << '\n';
  };
  row({"map", "mode", "agents", "controller", "heuristic", "runs", "goals", "collisions", "score"});
  for (const ExperimentCell& c : cells) {
    row({c.map, toString(c.mode), std::to_string(c.agents), toString(c.controller),
         c.heuristic ? toString(*c.heuristic) : "-", std::to_string(c.runs), meanStd(c.goals), meanStd(c.collisions),
         meanStd(c.score)});
  }
}

int runCommand(int argc, char** argv) {
  CLI::App app{"staa-sim experiment: the paper's controller comparison (Sec. IV-B, Fig. 5) and heuristic "
               "comparison (Sec. IV-C, Fig. 6). Runs every map x controller x mode x agent count (x heuristic "
               "for STAA*) x run in parallel; writes OUT/results.json, OUT/scores.svg (and heuristics.svg with "
               "more than one heuristic; PNGs too when rsvg-convert is installed) and prints a summary. Lists "
               "are comma-separated. Exit 0 on success, 2 on bad input, 1 when a run fails.",
               "staa-sim experiment"};
  const unsigned hw = std::thread::hardware_concurrency();
  std::string maps_text = "office,apartment,clutter", controllers_text = "pd,dwa,staa",
              modes_text = "cooperative,ghost", agents_text = "1,3,5", runs_text = "3", duration_text = "60",
              jobs_text = std::to_string(hw == 0 ? 1 : hw), heuristics_text = "path-rtr", budget_ms_text,
              budget_exp_text, rate_text = "30", seed_text = "1", out_dir,
              predict_turning_text = StaaConfig{}.predict_turning ? "on" : "off";
  bool quiet = false;
  app.add_option("--maps", maps_text,
                 "office, apartment, clutter (the paper's maps, generated) or polygon map files (a file without goals "
                 "gets 40 placed, 0.6 m from obstacles, 1.5 m apart)")
      ->capture_default_str();
  app.add_option("--controllers", controllers_text, "pd, dwa, staa")->capture_default_str();
  app.add_option("--modes", modes_text, "cooperative, ghost")->capture_default_str();
  app.add_option("--agents", agents_text, "Agent counts")->capture_default_str();
  app.add_option("--runs", runs_text, "Runs per cell (run r uses seed + r)")->capture_default_str();
  app.add_option("--duration", duration_text, "Simulated seconds per run")->capture_default_str();
  app.add_option("--jobs", jobs_text, "Parallel runs (with --budget-ms keep it at most the number of cores)")
      ->capture_default_str();
  app.add_option("--heuristics", heuristics_text, "STAA* heuristics: path-rtr, path-euclid, dijkstra-rtr")
      ->capture_default_str();
  app.add_option("--budget-ms", budget_ms_text, "Wall-clock STAA* budget per cycle in ms (default 19 ms at 30 Hz, "
                                                "scaled with the rate)");
  app.add_option("--budget-expansions", budget_exp_text,
                 "STAA* budget per cycle in queue pops: a bit-for-bit reproducible experiment");
  app.add_option("--rate", rate_text, "Control rate in Hz")->capture_default_str();
  app.add_option("--predict-turning", predict_turning_text,
                 "on or off: STAA*'s braking checks also predict turning agents on their circle "
                 "(StaaConfig::predict_turning)")
      ->capture_default_str();
  app.add_option("--seed", seed_text, "Base seed of the runs")->capture_default_str();
  app.add_option("--out", out_dir, "Output directory (created)")->required();
  app.add_flag("--quiet", quiet, "No progress line on stderr");

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "staa-sim experiment: " << e.what() << " (see staa-sim experiment --help)\n";
    return kExitBadInput;
  }

  ExperimentSpec spec;
  spec.controllers.clear();
  for (const std::string& item : splitList("--controllers", controllers_text)) {
    ControllerKind k{};
    if (!parseControllerKind(item, k)) {
      throw InputError("--controllers: expected pd, dwa or staa, got '" + item + "'");
    }
    appendUnique("--controllers", item, spec.controllers, k);
  }
  spec.modes.clear();
  for (const std::string& item : splitList("--modes", modes_text)) {
    SimMode m{};
    if (!parseSimMode(item, m)) throw InputError("--modes: expected cooperative or ghost, got '" + item + "'");
    appendUnique("--modes", item, spec.modes, m);
  }
  spec.agents.clear();
  for (const std::string& item : splitList("--agents", agents_text)) {
    appendUnique("--agents", item, spec.agents, static_cast<int>(parseCount("--agents", item, 1, 100, "agent counts")));
  }
  spec.heuristics.clear();
  for (const std::string& item : splitList("--heuristics", heuristics_text)) {
    HeuristicKind h{};
    if (!parseHeuristicKind(item.c_str(), h)) {
      throw InputError("--heuristics: expected path-rtr, path-euclid or dijkstra-rtr, got '" + item + "'");
    }
    appendUnique("--heuristics", item, spec.heuristics, h);
  }
  if (predict_turning_text != "on" && predict_turning_text != "off") {
    throw InputError("--predict-turning: expected on or off, got '" + predict_turning_text + "'");
  }
  spec.control.staa.predict_turning = predict_turning_text == "on";
  spec.runs = static_cast<int>(parseCount("--runs", runs_text, 1, 100000, "runs per cell"));
  spec.jobs = static_cast<int>(parseCount("--jobs", jobs_text, 1, 1024, "parallel runs"));
  spec.duration_s = parsePositive("--duration", duration_text, "simulated seconds");
  spec.rate_hz = parsePositive("--rate", rate_text, "a control rate in Hz");
  if (spec.duration_s * spec.rate_hz > 1e8) {
    throw InputError("--duration " + duration_text + " at --rate " + rate_text + " is more than 1e8 cycles per run");
  }
  spec.seed = parseCount("--seed", seed_text, 0, std::numeric_limits<std::uint64_t>::max() - 100000, "a seed");
  if (!budget_ms_text.empty() && !budget_exp_text.empty()) {
    throw InputError("--budget-ms " + budget_ms_text + " and --budget-expansions " + budget_exp_text +
                     " exclude each other: give a wall-clock budget or an expansion budget, not both");
  }
  if (!budget_exp_text.empty()) {
    spec.budget = staa::BudgetSpec::expansionsOf(static_cast<std::uint32_t>(parseCount(
        "--budget-expansions", budget_exp_text, 1, std::numeric_limits<std::uint32_t>::max(), "queue pops per cycle")));
  } else if (!budget_ms_text.empty()) {
    spec.budget = staa::BudgetSpec::wallClockMs(parsePositive("--budget-ms", budget_ms_text, "milliseconds per cycle"));
  } else {
    spec.budget = staa::BudgetSpec::defaultWallClock(spec.rate_hz);
  }

  // Maps last among the checks: loading them is the slow part of validation.
  for (const std::string& item : splitList("--maps", maps_text)) {
    ExperimentMap m;
    try {
      m = loadExperimentMap(item, spec.map_seed);
    } catch (const MapError& e) {
      throw InputError(std::string("--maps: ") + e.what());
    }
    for (const ExperimentMap& other : spec.maps) {
      if (other.name == m.name) {
        throw InputError("--maps: '" + item + "': a map named '" + m.name + "' is already in the list");
      }
    }
    if (m.goals_placed) {
      // Said even with --quiet: the runs drive to goals the map file does not have.
      std::cerr << "staa-sim experiment: " << item << " has no goals: placed " << m.map.goals.size()
                << " (clearance " << fmt(kExperimentGoalPlacement.clearance_m, 1) << " m, spacing "
                << fmt(kExperimentGoalPlacement.min_spacing_m, 1) << " m)\n";
    }
    spec.maps.push_back(std::move(m));
  }

  // The whole spec (e.g. enough goals in every map for the most agents) before the runs.
  validateExperimentSpec(spec);

  // The output directory before the runs: a bad --out fails now, not after an hour.
  const fs::path dir(out_dir);
  {
    std::error_code ec;
    fs::create_directories(dir, ec);
    const fs::path probe = dir / ".staa-experiment-write-test";
    std::ofstream test(probe, std::ios::binary | std::ios::trunc);
    if (!test) {
      throw InputError("--out: cannot write into '" + out_dir + "'" + (ec ? " (" + ec.message() + ")" : std::string()));
    }
    test.close();
    fs::remove(probe, ec);
  }

  const std::size_t total = planExperiment(spec).size();
  if (!quiet) {
    std::cerr << "staa-sim experiment: " << total << " runs of " << fmt(spec.duration_s, 1) << " s ("
              << spec.maps.size() << (spec.maps.size() == 1 ? " map, " : " maps, ") << spec.runs
              << (spec.runs == 1 ? " run" : " runs") << " per cell, "
              << spec.budget.describe()
              << " per STAA* cycle) on " << spec.jobs << (spec.jobs == 1 ? " thread\n" : " threads\n");
  }

  std::size_t last_width = 0;
  auto progress = [&](const ExperimentProgress& p) {
    if (quiet) return;
    const ExperimentRun& r = *p.last;
    std::string line = "[" + std::to_string(p.done) + "/" + std::to_string(p.total) + "] " + clock(p.elapsed_s) +
                       " elapsed, ~" + clock(p.remaining_s) + " left; last: " + r.map + " " + toString(r.controller) +
                       (r.heuristic && spec.heuristics.size() > 1 ? std::string("/") + toString(*r.heuristic) : "") +
                       " " + toString(r.mode) + " x" + std::to_string(r.agents) + " run " + std::to_string(r.run) +
                       ": score " + std::to_string(r.result.score);
    const std::size_t width = line.size();
    if (width < last_width) line += std::string(last_width - width, ' ');
    last_width = width;
    std::cerr << '\r' << line << std::flush;
  };

  std::vector<ExperimentRun> runs;
  try {
    runs = runExperiment(spec, progress);
  } catch (const std::exception& e) {
    if (!quiet && last_width > 0) std::cerr << '\n';
    std::cerr << "staa-sim experiment: " << e.what() << '\n';
    return kExitRunFailed;
  }
  if (!quiet && last_width > 0) std::cerr << '\n';

  std::vector<fs::path> written;
  ExperimentPlots plots;
  try {
    written.push_back(writeExperimentResults(dir, spec, runs));
    plots = writeExperimentPlots(dir, spec, runs);
  } catch (const std::exception& e) {
    std::cerr << "staa-sim experiment: " << e.what() << '\n';
    return kExitRunFailed;
  }
  for (const std::string& note : plots.notes) std::cerr << "staa-sim experiment: note: " << note << '\n';
  written.insert(written.end(), plots.files.begin(), plots.files.end());

  printSummary(std::cout, summarizeExperiment(runs));
  std::cout << "wrote";
  for (const fs::path& f : written) std::cout << ' ' << f.string();
  std::cout << '\n';
  return 0;
}

}  // namespace

int runExperimentCommand(int argc, char** argv) {
  try {
    return runCommand(argc, argv);
  } catch (const InputError& e) {
    std::cerr << "staa-sim experiment: " << e.what() << '\n';
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::cerr << "staa-sim experiment: " << e.what() << '\n';
    return kExitBadInput;
  }
}

}  // namespace staa
