#pragma once
// The experiment's pictures, like the paper's Fig. 5 and 6: one panel per map, the
// cooperative row above the ghost row, bars grouped by agent count. A bar's total height is
// the mean number of goals reached; its top part, in black, the mean collisions that the
// score subtracts; the coloured part the mean score. Drawn with our own SvgCanvas; PNGs
// beside them when rsvg-convert is on the PATH. Tools only.

#include "experiment/experiment.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace staa {

// Fig. 5: the controllers (PD, DWA, STAA* in that order) side by side; STAA* with
// `staa_heuristic` (cells of other heuristics are left out), the cells of obstacle source
// `obstacles` only.
std::string controllerScoresSvg(const std::vector<ExperimentCell>& cells, HeuristicKind staa_heuristic,
                                ObstacleSource obstacles = ObstacleSource::kTruth);

// Fig. 5 with ground truth beside depth perception: each controller's bars for both sources
// (truth solid, depth lighter) side by side.
std::string obstacleScoresSvg(const std::vector<ExperimentCell>& cells, HeuristicKind staa_heuristic);

// Fig. 6: STAA* only, its heuristics (path-rtr, path-euclid, dijkstra-rtr) side by side.
std::string heuristicScoresSvg(const std::vector<ExperimentCell>& cells);

struct ExperimentPlots {
  std::vector<std::filesystem::path> files;  // written, SVGs and PNGs
  std::vector<std::string> notes;            // e.g. no converter: no PNGs
};

// Writes DIR/scores.svg (the spec's first obstacle source), DIR/heuristics.svg when the spec
// has more than one heuristic, DIR/obstacles.svg when it has both truth and depth, and a PNG
// beside each when rsvg-convert is on the PATH. Throws std::runtime_error naming a file
// it cannot write or a converter that fails.
ExperimentPlots writeExperimentPlots(const std::filesystem::path& dir, const ExperimentSpec& spec,
                                     const std::vector<ExperimentRun>& runs);

}  // namespace staa
