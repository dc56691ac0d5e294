// staa-sim experiment: the matrix maps x controllers x modes x agents x heuristics x runs,
// run in parallel with a progress line on stderr, then DIR/results.json, the figures and a
// summary table on stdout.

#include "app/staa-sim/experiment_command.hpp"

#include "app/cli_support.hpp"
#include "app/staa-sim/sim_options.hpp"
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
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace staa {
namespace {

namespace fs = std::filesystem;
using cli::InputError;

using cli::kExitBadInput;
constexpr int kExitRunFailed = 1;

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
  const std::vector<std::size_t> w{12, 12, 7, 10, 11, 13, 5, 14, 14, 14};
  auto row = [&](const std::vector<std::string>& c) {
    std::string line;
    for (std::size_t i = 0; i < c.size(); ++i) line += pad(c[i], w[i], i >= 6) + (i + 1 < c.size() ? "  " : "");
    out << line << '\n';
  };
  row({"map", "mode", "agents", "obstacles", "controller", "heuristic", "runs", "goals", "collisions", "score"});
  for (const ExperimentCell& c : cells) {
    row({c.map, toString(c.mode), std::to_string(c.agents), toString(c.obstacles), toString(c.controller),
         c.heuristic ? toString(*c.heuristic) : "-", std::to_string(c.runs), meanStd(c.goals), meanStd(c.collisions),
         meanStd(c.score)});
  }
}

// ---- command line: parse, validate, prepare, run, report ----

// The command line, typed and checked by CLI11, straight into the spec where it can.
struct Args {
  ExperimentSpec spec;
  std::vector<std::string> maps{"office", "apartment", "clutter"};
  std::optional<cli::BudgetOptions> budget;
  std::string out_dir;
  bool quiet = false;
  const CLI::Option* duration_option = nullptr;  // for messages naming the values given
  const CLI::Option* rate_option = nullptr;
};

void addListOptions(CLI::App& app, Args& a) {
  ExperimentSpec& s = a.spec;
  app.add_option("--maps", a.maps,
                 "office, apartment, clutter (the paper's maps, generated) or polygon map files (a file without goals "
                 "gets 40 placed, 0.6 m from obstacles, 1.5 m apart)")
      ->delimiter(',')
      ->default_str(cli::joined(a.maps, [](const std::string& m) { return m; }));
  cli::choice(app.add_option("--controllers", s.controllers, "pd, dwa, staa"), cli::kControllerNames, s.controllers);
  cli::choice(app.add_option("--modes", s.modes, "cooperative, ghost"), cli::kModeNames, s.modes);
  cli::choice(app.add_option("--obstacles", s.obstacles,
                             "truth (every other agent's exact polygon and velocity), depth (what each evaluated "
                             "agent's depth camera sees, through staad's perception; the robot profile's camera), "
                             "depth+scan (the camera and the profile's base laser scanner), sight (the exact polygons of those "
                             "in each agent's line of sight, 8 m all round: what occlusion alone costs), or several side "
                             "by side"),
              cli::kObstacleNames, s.obstacles);
  app.add_option("--agents", s.agents, "Agent counts")
      ->delimiter(',')
      ->transform(cli::count("agent counts", 1, 100))
      ->default_str(cli::joined(s.agents, [](int n) { return std::to_string(n); }));
}

void addOptions(cli::CommandLine& cl, Args& a) {
  CLI::App& app = cl.app;
  ExperimentSpec& s = a.spec;
  addListOptions(app, a);
  app.add_option("--runs", s.runs, "Runs per cell (run r uses seed + r)")
      ->transform(cli::count("runs per cell", 1, 100000))
      ->capture_default_str();
  a.duration_option = app.add_option("--duration", s.duration_s, "Simulated seconds per run")
                          ->transform(cli::positive("simulated seconds"))
                          ->capture_default_str();
  const unsigned hw = std::thread::hardware_concurrency();
  s.jobs = hw == 0 ? 1 : static_cast<int>(hw);
  app.add_option("--jobs", s.jobs, "Parallel runs (with --budget-ms keep it at most the number of cores)")
      ->transform(cli::count("parallel runs", 1, 1024))
      ->capture_default_str();
  cli::choice(app.add_option("--heuristics", s.heuristics, "STAA* heuristics: path-rtr, path-euclid, dijkstra-rtr"),
              cli::kHeuristicNames, s.heuristics);
  a.budget.emplace(cl, "experiment");
  a.rate_option = app.add_option("--rate", s.rate_hz, "Control rate in Hz")
                      ->transform(cli::positive("a control rate in Hz"))
                      ->capture_default_str();
  bool& predict_turning = s.control.staa.predict_turning;
  cli::choice(app.add_option("--predict-turning", predict_turning,
                             "on or off: STAA*'s braking checks also predict turning agents on their circle "
                             "(StaaConfig::predict_turning)"),
              std::vector<std::pair<std::string, bool>>{{"on", true}, {"off", false}}, predict_turning);
  bool& lazy_heuristic = s.control.staa.lazy_heuristic;
  cli::choice(app.add_option("--lazy-heuristic", lazy_heuristic,
                             "on or off: STAA* computes h when a state is popped, not when it is generated "
                             "(StaaConfig::lazy_heuristic)"),
              std::vector<std::pair<std::string, bool>>{{"on", true}, {"off", false}}, lazy_heuristic);
  bool& separate_contacts = s.control.staa.separate_contacts;
  cli::choice(app.add_option("--separate-contacts", separate_contacts,
                             "on or off: a standing STAA* robot that finds no free motion plans again without the moving "
                             "obstacles it touches, first moving away from them (StaaConfig::separate_contacts)"),
              std::vector<std::pair<std::string, bool>>{{"on", true}, {"off", false}}, separate_contacts);
  bool& blind_corners = s.control.blind_corners.enabled;
  cli::choice(app.add_option("--blind-corners", blind_corners,
                             "on or off: every agent's control cycle limits its speed at the map's blind corners "
                             "(ControlConfig::blind_corners)"),
              std::vector<std::pair<std::string, bool>>{{"on", true}, {"off", false}}, blind_corners);
  app.add_option("--seed", s.seed, "Base seed of the runs")
      ->transform(cli::count("a seed", 0, std::numeric_limits<std::uint64_t>::max() - 100000))
      ->capture_default_str();
  app.add_option("--out", a.out_dir, "Output directory (created)")->required();
  app.add_flag("--quiet", a.quiet, "No progress line on stderr");
}

// Loading the maps is the slow part of validation: last.
void loadMaps(Args& a) {
  for (const std::string& item : a.maps) {
    ExperimentMap m;
    try {
      m = loadExperimentMap(item, a.spec.map_seed);
    } catch (const MapError& e) {
      throw InputError(std::string("--maps: ") + e.what());
    }
    for (const ExperimentMap& other : a.spec.maps) {
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
    a.spec.maps.push_back(std::move(m));
  }
}

// The whole spec (e.g. enough goals in every map for the most agents) before the runs.
void validate(Args& a) {
  ExperimentSpec& s = a.spec;
  cli::requireDistinct("--controllers", s.controllers, [](ControllerKind k) { return toString(k); });
  cli::requireDistinct("--modes", s.modes, [](SimMode m) { return toString(m); });
  cli::requireDistinct("--agents", s.agents, [](int n) { return std::to_string(n); });
  cli::requireDistinct("--heuristics", s.heuristics, [](HeuristicKind h) { return toString(h); });
  cli::requireDistinct("--obstacles", s.obstacles, [](ObstacleSource o) { return toString(o); });
  cli::checkCycles(a.duration_option, a.rate_option, s.duration_s, s.rate_hz, " per run");
  s.budget = a.budget->spec(s.rate_hz);
  loadMaps(a);
  validateExperimentSpec(s);
}

// The output directory before the runs: a bad --out fails now, not after an hour.
fs::path prepareOutput(const std::string& out_dir) {
  const fs::path dir(out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  const fs::path probe = dir / ".staa-experiment-write-test";
  std::ofstream test(probe, std::ios::binary | std::ios::trunc);
  if (!test) {
    throw InputError("--out: cannot write into '" + out_dir + "'" + (ec ? " (" + ec.message() + ")" : std::string()));
  }
  test.close();
  fs::remove(probe, ec);
  return dir;
}

// One progress line, rewritten in place after every run.
class ProgressLine {
 public:
  ProgressLine(const ExperimentSpec& spec, bool quiet) : spec_(spec), quiet_(quiet) {}

  void announce() const {
    if (quiet_) return;
    const std::size_t total = planExperiment(spec_).size();
    std::cerr << "staa-sim experiment: " << total << " runs of " << fmt(spec_.duration_s, 1) << " s ("
              << spec_.maps.size() << (spec_.maps.size() == 1 ? " map, " : " maps, ") << spec_.runs
              << (spec_.runs == 1 ? " run" : " runs") << " per cell, " << spec_.budget.describe()
              << " per STAA* cycle) on " << spec_.jobs << (spec_.jobs == 1 ? " thread\n" : " threads\n");
  }

  void update(const ExperimentProgress& p) {
    if (quiet_) return;
    const ExperimentRun& r = *p.last;
    std::string line = "[" + std::to_string(p.done) + "/" + std::to_string(p.total) + "] " + clock(p.elapsed_s) +
                       " elapsed, ~" + clock(p.remaining_s) + " left; last: " + r.map + " " + toString(r.controller) +
                       (r.heuristic && spec_.heuristics.size() > 1 ? std::string("/") + toString(*r.heuristic) : "") +
                       " " + toString(r.mode) + " x" + std::to_string(r.agents) +
                       (spec_.obstacles.size() > 1 ? std::string(" ") + toString(r.obstacles) : "") + " run " +
                       std::to_string(r.run) +
                       ": score " + std::to_string(r.result.score);
    const std::size_t width = line.size();
    if (width < last_width_) line += std::string(last_width_ - width, ' ');
    last_width_ = width;
    std::cerr << '\r' << line << std::flush;
  }

  // Ends the line (before anything else is said on stderr).
  void finish() const {
    if (!quiet_ && last_width_ > 0) std::cerr << '\n';
  }

 private:
  const ExperimentSpec& spec_;
  bool quiet_;
  std::size_t last_width_ = 0;
};

// results.json, the figures and the summary table.
int report(const fs::path& dir, const ExperimentSpec& spec, const std::vector<ExperimentRun>& runs) {
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

int runCommand(int argc, char** argv) {
  cli::CommandLine cl("staa-sim experiment",
                      "staa-sim experiment: the paper's controller comparison (Sec. IV-B, Fig. 5) and heuristic "
                      "comparison (Sec. IV-C, Fig. 6). Runs every map x controller x mode x agent count (x heuristic "
                      "for STAA*) x run in parallel; writes OUT/results.json, OUT/scores.svg (and heuristics.svg with "
                      "more than one heuristic; PNGs too when rsvg-convert is installed) and prints a summary. Lists "
                      "are comma-separated. Exit 0 on success, 2 on bad input, 1 when a run fails.");
  Args args;
  addOptions(cl, args);
  if (const auto exit = cl.parse(argc, argv)) return *exit;
  validate(args);
  const fs::path dir = prepareOutput(args.out_dir);

  ProgressLine progress(args.spec, args.quiet);
  progress.announce();
  std::vector<ExperimentRun> runs;
  try {
    runs = runExperiment(args.spec, [&](const ExperimentProgress& p) { progress.update(p); });
  } catch (const std::exception& e) {
    progress.finish();
    std::cerr << "staa-sim experiment: " << e.what() << '\n';
    return kExitRunFailed;
  }
  progress.finish();
  return report(dir, args.spec, runs);
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
