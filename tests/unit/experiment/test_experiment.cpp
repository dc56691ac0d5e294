// The experiment runner (Sec. IV-B/IV-C): a tiny real experiment on the generated clutter map
// (results.json keys, run count, determinism across threads, the figure) and the plots on a
// hand-made result set. `staa-sim experiment` run for real: tests/integration.

#include "map/polygon_map.hpp"
#include "experiment/experiment.hpp"
#include "experiment/agent_camera.hpp"
#include "experiment/experiment_plots.hpp"

#include "read_file.hpp"
#include "temp_dir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace staa {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using ::testing::HasSubstr;

using staa::test::readFile;

fs::path freshDir(const std::string& name) { return staa::test::freshDir("staa-experiment-test", name); }

// One small generated map, PD and STAA*, one mode, one agent, two runs of 3 s with an
// expansion budget (reproducible), two threads.
ExperimentSpec tinySpec() {
  ExperimentSpec spec;
  spec.maps.push_back(loadExperimentMap("clutter", 1));
  spec.controllers = {ControllerKind::kPd, ControllerKind::kStaa};
  spec.modes = {SimMode::kCooperative};
  spec.agents = {1};
  spec.runs = 2;
  spec.duration_s = 3.0;
  spec.budget = BudgetSpec::expansionsOf(200);
  spec.jobs = 2;
  return spec;
}

// Everything but the wall-clock planner times, which differ from run to run.
Json withoutTimes(Json runs) {
  for (Json& r : runs) r["planner"].erase("plan_us");
  return runs;
}

std::vector<double> attributeValues(const std::string& svg, const std::string& css_class, const std::string& attr) {
  std::vector<double> values;
  const std::regex re("class=\"" + css_class + "\"[^>]*? " + attr + "=\"(-?[0-9.]+)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), re); it != std::sregex_iterator(); ++it) {
    values.push_back(std::stod((*it)[1].str()));
  }
  return values;
}

TEST(Experiment, TinyExperimentWritesEveryRunWithTheRequiredKeysAndAFigure) {
  const fs::path dir = freshDir("tiny");
  const ExperimentSpec spec = tinySpec();
  int calls = 0, last_done = 0;
  const std::vector<ExperimentRun> runs = runExperiment(spec, [&](const ExperimentProgress& p) {
    ++calls;
    EXPECT_EQ(p.total, 4);
    EXPECT_EQ(p.done, last_done + 1);
    last_done = p.done;
    EXPECT_GE(p.remaining_s, 0.0);
    ASSERT_NE(p.last, nullptr);
  });
  EXPECT_EQ(calls, 4);
  ASSERT_EQ(runs.size(), 4U);

  const fs::path file = writeExperimentResults(dir, spec, runs);
  EXPECT_EQ(file, dir / "results.json");
  const Json doc = Json::parse(readFile(file));
  ASSERT_EQ(doc["runs"].size(), 4U);
  for (const Json& r : doc["runs"]) {
    for (const char* key : {"map", "controller", "mode", "agents", "run", "seed", "duration_s", "goals_reached",
                            "collisions", "score", "planner", "heuristic"}) {
      EXPECT_TRUE(r.contains(key)) << key << " in " << r.dump();
    }
    for (const char* key : {"calls", "expansions", "successors", "finished_early_ratio", "depth_mean", "plan_us"}) {
      EXPECT_TRUE(r["planner"].contains(key)) << key;
    }
    for (const char* key : {"mean", "p50", "p99"}) {
      EXPECT_TRUE(r["planner"]["expansions"].contains(key));
      EXPECT_TRUE(r["planner"]["successors"].contains(key));
    }
    for (const char* key : {"p50", "p99", "max"}) EXPECT_TRUE(r["planner"]["plan_us"].contains(key));
    EXPECT_EQ(r["map"], "clutter");
    EXPECT_EQ(r["score"].get<int>(), r["goals_reached"].get<int>() - r["collisions"].get<int>());
    // One contact record per counted collision.
    ASSERT_TRUE(r["contacts"].is_array()) << r.dump();
    EXPECT_EQ(r["contacts"].size(), r["collisions"].get<std::size_t>());
    EXPECT_EQ(r["seed"].get<int>(), 1 + r["run"].get<int>());
    EXPECT_NEAR(r["duration_s"].get<double>(), 3.0, 0.05);
    if (r["controller"] == "staa") {
      EXPECT_EQ(r["heuristic"], "path-rtr");
      EXPECT_GT(r["planner"]["calls"].get<int>(), 0);
      EXPECT_LE(r["planner"]["expansions"]["p99"].get<double>(), 200.0);
    } else {
      EXPECT_EQ(r["controller"], "pd");
      EXPECT_EQ(r["planner"]["calls"].get<int>(), 0);
    }
  }
  ASSERT_EQ(doc["summary"].size(), 2U);
  for (const Json& c : doc["summary"]) {
    EXPECT_EQ(c["runs"], 2);
    for (const char* key : {"goals_reached", "collisions", "score"}) {
      EXPECT_TRUE(c[key].contains("mean"));
      EXPECT_TRUE(c[key].contains("stddev"));
    }
  }
  EXPECT_EQ(doc["spec"]["budget"]["kind"], "expansions");
  EXPECT_EQ(doc["spec"]["runs"], 2);
  EXPECT_EQ(doc["spec"]["predict_turning"], spec.control.staa.predict_turning);
  ExperimentSpec turning = spec;
  turning.control.staa.predict_turning = !spec.control.staa.predict_turning;
  const Json doc_turning = Json::parse(readFile(writeExperimentResults(dir / "turning", turning, runs)));
  EXPECT_EQ(doc_turning["spec"]["predict_turning"], turning.control.staa.predict_turning);
  ExperimentSpec lazy = spec;
  lazy.control.staa.lazy_heuristic = !spec.control.staa.lazy_heuristic;
  const Json doc_lazy = Json::parse(readFile(writeExperimentResults(dir / "lazy", lazy, runs)));
  EXPECT_EQ(doc_lazy["spec"]["lazy_heuristic"], lazy.control.staa.lazy_heuristic);
  EXPECT_EQ(doc["spec"]["lazy_heuristic"], spec.control.staa.lazy_heuristic);

  const ExperimentPlots plots = writeExperimentPlots(dir, spec, runs);
  const std::string svg = readFile(dir / "scores.svg");
  EXPECT_THAT(svg, HasSubstr("<svg"));
  // One bar per cell (map x mode x agents x controller), drawn even when its score is zero.
  EXPECT_EQ(attributeValues(svg, "bar-score", "height").size(), 2U);
  EXPECT_THAT(svg, HasSubstr("Clutter"));
  EXPECT_THAT(svg, HasSubstr("STAA*"));
  EXPECT_THAT(svg, HasSubstr("PD"));
  EXPECT_FALSE(fs::exists(dir / "heuristics.svg"));  // one heuristic only
  EXPECT_FALSE(plots.files.empty());
  fs::remove_all(dir);
}

TEST(Experiment, TruthBesideDepthRecordsTheSourceThePerceptionAndDrawsBoth) {
  const fs::path dir = freshDir("depth");
  ExperimentSpec spec = tinySpec();
  spec.controllers = {ControllerKind::kStaa};
  spec.agents = {2};
  spec.runs = 1;
  spec.obstacles = {ObstacleSource::kTruth, ObstacleSource::kDepth};
  const std::vector<ExperimentRun> runs = runExperiment(spec);
  ASSERT_EQ(runs.size(), 2U);
  const Json doc = Json::parse(experimentJson(spec, runs));
  ASSERT_EQ(doc["runs"].size(), 2U);
  EXPECT_EQ(doc["runs"][0]["obstacles"], "truth");
  EXPECT_FALSE(doc["runs"][0].contains("perception"));
  const Json& depth = doc["runs"][1];
  EXPECT_EQ(depth["obstacles"], "depth");
  ASSERT_TRUE(depth.contains("perception")) << depth.dump();
  const Json& p = depth["perception"];
  // Two agents with a camera each at 30 Hz for 3 s: 90 frames each, some lost (1 %).
  EXPECT_EQ(p["frames"].get<int>() + p["frames_lost"].get<int>(), 180);
  for (const char* key : {"position_error_m", "velocity_error_mps", "kept_position_error_m", "kept_velocity_error_mps"}) {
    for (const char* stat : {"n", "mean", "p50", "p95", "max", "bins"}) EXPECT_TRUE(p[key].contains(stat)) << key << stat;
  }
  for (const char* key : {"near_samples", "near_missed", "near_missed_in_view", "obstacles", "kept_obstacles",
                          "false_obstacles", "false_kept", "latency", "render_us_mean", "perception_us_mean"}) {
    EXPECT_TRUE(p.contains(key)) << key;
  }
  EXPECT_LE(p["near_missed"].get<int>(), p["near_samples"].get<int>());
  EXPECT_LE(p["false_obstacles"].get<int>(), p["obstacles"].get<int>());
  ASSERT_EQ(doc["summary"].size(), 2U);
  EXPECT_EQ(doc["summary"][1]["obstacles"], "depth");
  EXPECT_TRUE(doc["summary"][1].contains("perception"));
  EXPECT_FALSE(doc["summary"][1]["perception"]["position_error_m"].contains("bins"));
  EXPECT_EQ(doc["spec"]["obstacles"], Json::array({"truth", "depth"}));
  EXPECT_EQ(doc["spec"]["camera"]["fov_deg"], Json::array({58.0, 45.0}));
  EXPECT_EQ(doc["spec"]["perception"]["keep_unseen_s"], agentPerceptionConfig(spec.robot).keep_unseen_s);

  writeExperimentPlots(dir, spec, runs);
  const std::string both = readFile(dir / "obstacles.svg");
  EXPECT_EQ(attributeValues(both, "bar-score", "height").size(), 2U);
  EXPECT_THAT(both, HasSubstr("STAA* truth"));
  EXPECT_THAT(both, HasSubstr("STAA* depth"));
  // scores.svg shows the first source only.
  EXPECT_EQ(attributeValues(readFile(dir / "scores.svg"), "bar-score", "height").size(), 1U);
  fs::remove_all(dir);

  // The same depth run again gives the same results (the cameras' noise is seeded).
  ExperimentSpec only_depth = spec;
  only_depth.obstacles = {ObstacleSource::kDepth};
  const Json again = Json::parse(experimentJson(only_depth, runExperiment(only_depth)));
  Json a = doc["runs"][1], b = again["runs"][0];
  for (Json* r : {&a, &b}) {
    r->erase("planner");
    (*r)["perception"].erase("render_us_mean");
    (*r)["perception"].erase("perception_us_mean");
  }
  EXPECT_EQ(a, b);
}

TEST(Experiment, IdenticalResultsWhenRunTwiceOnDifferentThreadCounts) {
  ExperimentSpec spec = tinySpec();
  const Json a = Json::parse(experimentJson(spec, runExperiment(spec)));
  spec.jobs = 1;
  const Json b = Json::parse(experimentJson(spec, runExperiment(spec)));
  EXPECT_EQ(withoutTimes(a["runs"]), withoutTimes(b["runs"]));
  EXPECT_EQ(a["summary"], b["summary"]);
}

TEST(Experiment, PlanCoversTheMatrixWithStaaOncePerHeuristic) {
  ExperimentSpec spec;
  spec.maps.push_back({"a", PolygonMap{"a", std::nullopt, {}, {{1.0, 1.0}}}});
  spec.maps.push_back({"b", PolygonMap{"b", std::nullopt, {}, {{1.0, 1.0}}}});
  spec.heuristics = {HeuristicKind::kPathRtr, HeuristicKind::kDijkstraRtr};
  spec.runs = 2;
  spec.seed = 7;
  const std::vector<ExperimentRun> plan = planExperiment(spec);
  // 2 maps x 2 modes x 3 agent counts x (PD + DWA + 2 STAA* heuristics) x 2 runs.
  EXPECT_EQ(plan.size(), 2U * 2U * 3U * 4U * 2U);
  for (const ExperimentRun& r : plan) {
    EXPECT_EQ(r.seed, 7U + static_cast<unsigned>(r.run));
    EXPECT_EQ(r.heuristic.has_value(), r.controller == ControllerKind::kStaa);
    EXPECT_EQ(r.obstacles, ObstacleSource::kTruth);
  }
  // Truth beside depth: every cell twice, the same seeds.
  spec.obstacles = {ObstacleSource::kTruth, ObstacleSource::kDepth};
  const std::vector<ExperimentRun> both = planExperiment(spec);
  ASSERT_EQ(both.size(), 2U * plan.size());
  std::size_t depth = 0;
  for (const ExperimentRun& r : both) depth += r.obstacles == ObstacleSource::kDepth ? 1 : 0;
  EXPECT_EQ(depth, plan.size());
}

ExperimentCell cell(const char* map, ControllerKind c, SimMode mode, int agents, double goals, double collisions,
                    std::optional<HeuristicKind> h = std::nullopt) {
  ExperimentCell x;
  x.map = map;
  x.controller = c;
  x.mode = mode;
  x.agents = agents;
  x.heuristic = c == ControllerKind::kStaa && !h ? std::optional(HeuristicKind::kPathRtr) : h;
  x.runs = 1;
  x.goals.mean = goals;
  x.collisions.mean = collisions;
  x.score.mean = goals - collisions;
  return x;
}

TEST(ExperimentPlots, BarHeightsAreProportionalToScoreAndCollisions) {
  // One panel: 1 agent, PD 10 goals 4 collisions, DWA 6 goals 1, STAA* 8 goals 0.
  const std::vector<ExperimentCell> cells{
      cell("office", ControllerKind::kPd, SimMode::kCooperative, 1, 10.0, 4.0),
      cell("office", ControllerKind::kDwa, SimMode::kCooperative, 1, 6.0, 1.0),
      cell("office", ControllerKind::kStaa, SimMode::kCooperative, 1, 8.0, 0.0),
      // Another heuristic's STAA* cell is not in Fig. 5.
      cell("office", ControllerKind::kStaa, SimMode::kCooperative, 1, 1.0, 0.0, HeuristicKind::kPathEuclid),
  };
  const std::string svg = controllerScoresSvg(cells, HeuristicKind::kPathRtr);
  const std::vector<double> score = attributeValues(svg, "bar-score", "height");
  const std::vector<double> black = attributeValues(svg, "bar-collisions", "height");
  ASSERT_EQ(score.size(), 3U);  // PD, DWA, STAA*, in that order
  ASSERT_EQ(black.size(), 2U);  // STAA* had none
  const double px = score[0] / 6.0;
  EXPECT_GT(px, 0.0);
  EXPECT_NEAR(score[1], 5.0 * px, 0.01);
  EXPECT_NEAR(score[2], 8.0 * px, 0.01);
  EXPECT_NEAR(black[0], 4.0 * px, 0.01);
  EXPECT_NEAR(black[1], 1.0 * px, 0.01);
  // The colours follow the legend: PD's bar is PD's colour.
  EXPECT_THAT(svg, HasSubstr("data-goals=\"10\" data-collisions=\"4\""));
  EXPECT_THAT(svg, HasSubstr("1 agent"));
  EXPECT_THAT(svg, HasSubstr("Office"));
}

TEST(ExperimentPlots, CooperativeRowIsAboveGhostRowAndHeuristicsFigureShowsStaaOnly) {
  const std::vector<ExperimentCell> cells{
      cell("clutter", ControllerKind::kStaa, SimMode::kGhost, 3, 4.0, 2.0),
      cell("clutter", ControllerKind::kStaa, SimMode::kCooperative, 3, 5.0, 0.0),
      cell("clutter", ControllerKind::kStaa, SimMode::kGhost, 3, 3.0, 1.0, HeuristicKind::kDijkstraRtr),
      cell("clutter", ControllerKind::kStaa, SimMode::kCooperative, 3, 6.0, 0.0, HeuristicKind::kDijkstraRtr),
      cell("clutter", ControllerKind::kDwa, SimMode::kGhost, 3, 9.0, 9.0),
  };
  const std::string svg = heuristicScoresSvg(cells);
  EXPECT_EQ(attributeValues(svg, "bar-score", "height").size(), 4U);  // DWA left out
  EXPECT_THAT(svg, HasSubstr("Path RTR"));
  EXPECT_THAT(svg, HasSubstr("Dijkstra RTR"));
  EXPECT_THAT(svg, ::testing::Not(HasSubstr("DWA")));
  // The cooperative panel's title is drawn higher (smaller y) than the ghost panel's.
  const std::regex title_y("y=\"([0-9.]+)\"[^>]*>Clutter \u2014 (cooperative|ghost)<");
  double coop_y = -1.0, ghost_y = -1.0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), title_y); it != std::sregex_iterator(); ++it) {
    ((*it)[2] == "cooperative" ? coop_y : ghost_y) = std::stod((*it)[1].str());
  }
  ASSERT_GT(coop_y, 0.0);
  ASSERT_GT(ghost_y, 0.0);
  EXPECT_LT(coop_y, ghost_y);
}

TEST(ExperimentPlots, NegativeScoreDrawsItsBarBelowZeroAndTheCollisionsOverIt) {
  const std::vector<ExperimentCell> cells{cell("apartment", ControllerKind::kPd, SimMode::kGhost, 5, 2.0, 5.0)};
  const std::string svg = controllerScoresSvg(cells, HeuristicKind::kPathRtr);
  const std::vector<double> score = attributeValues(svg, "bar-score", "height");
  const std::vector<double> black = attributeValues(svg, "bar-collisions", "height");
  ASSERT_EQ(score.size(), 1U);
  ASSERT_EQ(black.size(), 1U);
  EXPECT_NEAR(black[0] / score[0], 5.0 / 3.0, 0.01);  // collisions 5 over a score of -3
}

// ---- the layout: no text over another, for narrow and wide figures ----

// A text's box estimated from its <text> element as the layout estimates it: 0.6 font sizes
// per character, from 0.75 font sizes above the baseline to 0.25 below; a rotate(-90) about
// the text's own position turns it upright.
struct TextBox {
  std::string text;
  double x0 = 0.0, x1 = 0.0, y0 = 0.0, y1 = 0.0;
};

double attribute(const std::string& attrs, const std::string& name, double fallback) {
  const std::regex re("(^|\\s)" + name + "=\"(-?[0-9.]+)\"");
  std::smatch m;
  return std::regex_search(attrs, m, re) ? std::stod(m[2].str()) : fallback;
}

std::vector<TextBox> textBoxes(const std::string& svg) {
  std::vector<TextBox> boxes;
  const std::regex element("<text([^>]*)>([^<]*)</text>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), element); it != std::sregex_iterator(); ++it) {
    const std::string attrs = (*it)[1].str();
    TextBox b;
    b.text = (*it)[2].str();
    // Characters as drawn: an entity (&amp;) or a UTF-8 sequence (the em dash) is one.
    double chars = 0.0;
    for (std::size_t k = 0; k < b.text.size(); ++k) {
      const auto c = static_cast<unsigned char>(b.text[k]);
      if (c == '&') k = b.text.find(';', k);
      chars += (c & 0xC0) != 0x80 ? 1.0 : 0.0;
    }
    const double x = attribute(attrs, "x", 0.0), y = attribute(attrs, "y", 0.0);
    const double font = attribute(attrs, "font-size", 11.0);
    const double w = 0.6 * font * chars;
    const double along = attrs.find("text-anchor=\"middle\"") != std::string::npos ? 0.5
                         : attrs.find("text-anchor=\"end\"") != std::string::npos ? 1.0
                                                                                   : 0.0;
    if (attrs.find("rotate(-90") != std::string::npos) {
      b.x0 = x - 0.75 * font;
      b.x1 = x + 0.25 * font;
      b.y0 = y - (1.0 - along) * w;
      b.y1 = y + along * w;
    } else {
      b.x0 = x - along * w;
      b.x1 = b.x0 + w;
      b.y0 = y - 0.75 * font;
      b.y1 = y + 0.25 * font;
    }
    boxes.push_back(b);
  }
  return boxes;
}

bool overlap(const TextBox& a, const TextBox& b) { return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1; }

double svgSize(const std::string& svg, const std::string& name) {
  std::smatch m;
  const std::regex re("<svg[^>]* " + name + "=\"([0-9.]+)\"");
  return std::regex_search(svg, m, re) ? std::stod(m[1].str()) : 0.0;
}

// Every text inside the figure and clear of every other one.
void expectNoTextOverlaps(const std::string& svg, const std::string& what) {
  const std::vector<TextBox> boxes = textBoxes(svg);
  const double width = svgSize(svg, "width"), height = svgSize(svg, "height");
  ASSERT_GT(boxes.size(), 5U) << what;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const TextBox& a = boxes[i];
    EXPECT_GE(a.x0, 0.0) << what << ": '" << a.text << "' leaves the figure on the left";
    EXPECT_LE(a.x1, width) << what << ": '" << a.text << "' leaves the figure on the right";
    EXPECT_GE(a.y0, 0.0) << what << ": '" << a.text << "' leaves the figure at the top";
    EXPECT_LE(a.y1, height) << what << ": '" << a.text << "' leaves the figure at the bottom";
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_FALSE(overlap(a, boxes[j])) << what << ": '" << a.text << "' overlaps '" << boxes[j].text << "'";
    }
  }
}

const std::vector<std::string> kSixMaps{"office", "apartment", "clutter", "depot", "warehouse", "tb3_sandbox"};

// Every controller in every mode on the first `maps` maps with these agent counts; varied
// values, some large and some negative, so the tick labels vary in width.
std::vector<ExperimentCell> matrixCells(std::size_t maps, const std::vector<int>& agents) {
  std::vector<ExperimentCell> cells;
  double v = 3.0;
  for (std::size_t m = 0; m < maps; ++m) {
    for (const SimMode mode : {SimMode::kCooperative, SimMode::kGhost}) {
      for (const int a : agents) {
        for (const ControllerKind c : {ControllerKind::kPd, ControllerKind::kDwa, ControllerKind::kStaa}) {
          v = std::fmod(v * 7.3 + 11.0, 180.0);
          cells.push_back(cell(kSixMaps[m].c_str(), c, mode, a, v, std::fmod(v * 3.1, 60.0)));
          cells.push_back(cell(kSixMaps[m].c_str(), ControllerKind::kStaa, mode, a, v / 2.0, 1.0,
                               HeuristicKind::kDijkstraRtr));
        }
      }
    }
  }
  return cells;
}

TEST(ExperimentPlots, PanelTitlesOfFourMapsWithOneAgentCountDoNotOverlap) {
  // The narrowest panels: one group of three bars each.
  const std::string svg = controllerScoresSvg(matrixCells(4, {1}), HeuristicKind::kPathRtr);
  std::vector<TextBox> titles;
  for (const TextBox& b : textBoxes(svg)) {
    if (b.text.find("\u2014") != std::string::npos) titles.push_back(b);
  }
  ASSERT_EQ(titles.size(), 8U);  // 4 maps x 2 modes
  const double width = svgSize(svg, "width");
  for (std::size_t i = 0; i < titles.size(); ++i) {
    EXPECT_GE(titles[i].x0, 0.0) << titles[i].text;
    EXPECT_LE(titles[i].x1, width) << titles[i].text;
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_FALSE(overlap(titles[i], titles[j])) << "'" << titles[i].text << "' [" << titles[i].x0 << ", "
                                                  << titles[i].x1 << "] overlaps '" << titles[j].text << "' ["
                                                  << titles[j].x0 << ", " << titles[j].x1 << "]";
    }
  }
}

TEST(ExperimentPlots, NoTextOverlapsAnotherForOneToSixMapsAndOneToThreeAgentCounts) {
  for (std::size_t maps = 1; maps <= kSixMaps.size(); ++maps) {
    for (const std::vector<int>& agents : {std::vector<int>{1}, std::vector<int>{1, 3}, std::vector<int>{1, 3, 5}}) {
      const std::vector<ExperimentCell> cells = matrixCells(maps, agents);
      const std::string what = std::to_string(maps) + " maps, " + std::to_string(agents.size()) + " agent counts";
      expectNoTextOverlaps(controllerScoresSvg(cells, HeuristicKind::kPathRtr), "controllers, " + what);
      expectNoTextOverlaps(heuristicScoresSvg(cells), "heuristics, " + what);
    }
  }
}

TEST(ExperimentSummary, MeanAndSampleStddevPerCell) {
  std::vector<ExperimentRun> runs(3);
  const int goals[] = {4, 6, 8};
  for (int i = 0; i < 3; ++i) {
    runs[i].map = "office";
    runs[i].run = i;
    runs[i].result.goals_reached = goals[i];
    runs[i].result.collisions = i == 2 ? 1 : 0;
    runs[i].result.score = runs[i].result.goals_reached - runs[i].result.collisions;
  }
  const std::vector<ExperimentCell> cells = summarizeExperiment(runs);
  ASSERT_EQ(cells.size(), 1U);
  EXPECT_EQ(cells[0].runs, 3);
  EXPECT_DOUBLE_EQ(cells[0].goals.mean, 6.0);
  EXPECT_DOUBLE_EQ(cells[0].goals.stddev, 2.0);
  EXPECT_NEAR(cells[0].collisions.mean, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(cells[0].score.mean, 17.0 / 3.0, 1e-12);
}

TEST(ExperimentMaps, AcceptsAUsersMapFileWithGoalsAndPlacesGoalsInOneWithout) {
  const fs::path dir = freshDir("maps");
  std::ofstream(dir / "depot.yaml") << "format: staa-polygon-map/1\nname: depot\nbounds: [0, 0, 10, 10]\n"
                                       "obstacles:\n  - [[4, 4], [6, 4], [6, 6], [4, 6]]\n"
                                       "goals:\n  - [1, 1]\n  - [9, 9]\n";
  std::ofstream(dir / "nogoals.yaml") << "format: staa-polygon-map/1\nname: empty\nbounds: [0, 0, 10, 10]\n"
                                         "obstacles: []\n";
  // Bounds narrower than twice the goals' clearance: nowhere to place one.
  std::ofstream(dir / "narrow.yaml") << "format: staa-polygon-map/1\nname: narrow\nbounds: [0, 0, 1, 10]\n"
                                        "obstacles: []\n";
  const ExperimentMap m = loadExperimentMap((dir / "depot.yaml").string(), 1);
  EXPECT_EQ(m.name, "depot");
  EXPECT_EQ(m.map.goals.size(), 2U);
  EXPECT_FALSE(m.goals_placed);

  const ExperimentMap placed = loadExperimentMap((dir / "nogoals.yaml").string(), 1);
  EXPECT_TRUE(placed.goals_placed);
  // The free 8.8 x 8.8 m square holds fewer than 40 goals 1.5 m apart: as many as fit.
  EXPECT_GE(placed.map.goals.size(), 20U);
  EXPECT_LE(placed.map.goals.size(), 40U);
  for (const Vec2& g : placed.map.goals) {
    EXPECT_GE(std::min({g.x(), g.y(), 10.0 - g.x(), 10.0 - g.y()}), 0.6 - 1e-9) << g.transpose();
  }
  ExperimentSpec spec;
  spec.maps = {m, placed};
  const Json doc = Json::parse(experimentJson(spec, {}));
  ASSERT_EQ(doc["spec"]["map_goals"].size(), 2U);
  EXPECT_EQ(doc["spec"]["map_goals"][0]["goals_placed"], false);
  EXPECT_EQ(doc["spec"]["map_goals"][1]["map"], "empty");
  EXPECT_EQ(doc["spec"]["map_goals"][1]["goals_placed"], true);
  EXPECT_EQ(doc["spec"]["map_goals"][1]["goals"], placed.map.goals.size());
  EXPECT_EQ(doc["spec"]["maps"], Json::array({"depot", "empty"}));

  try {
    loadExperimentMap((dir / "narrow.yaml").string(), 1);
    ADD_FAILURE() << "no error for a map without room for goals";
  } catch (const MapError& e) {
    EXPECT_THAT(e.what(), HasSubstr("narrow.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("no goals"));
  }
  try {
    loadExperimentMap("offfice", 1);
    ADD_FAILURE() << "no error for an unknown map";
  } catch (const MapError& e) {
    EXPECT_THAT(e.what(), HasSubstr("offfice"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace staa
