// `staa-sim experiment` run for real: exit codes, results.json and the figure, goals placed
// in a map file without them, bad input named.

#include "planner/staa_star.hpp"

#include "read_file.hpp"
#include "temp_dir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace staa {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using ::testing::HasSubstr;

using staa::test::readFile;

fs::path freshDir(const std::string& name) { return staa::test::freshDir("staa-sim-experiment-test", name); }

// ---- the binary ----

struct Exit {
  int code = -1;
  std::string out, err;
};

Exit runSim(const std::string& args, const fs::path& dir) {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command =
      std::string(STAA_SIM_EXE) + " " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  Exit e;
  e.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  e.out = readFile(out);
  e.err = readFile(err);
  return e;
}

TEST(StaaSimExperiment, SmallExperimentExitsZeroWithResultsAndFigure) {
  const fs::path dir = freshDir("smoke");
  const Exit e = runSim("experiment --maps clutter --controllers staa,dwa --modes cooperative --agents 1 --runs 1 "
                        "--duration 3 --budget-expansions 200 --jobs 2 --out '" + (dir / "out").string() + "'",
                        dir);
  ASSERT_EQ(e.code, 0) << e.err;
  const Json doc = Json::parse(readFile(dir / "out" / "results.json"));
  EXPECT_EQ(doc["runs"].size(), 2U);
  EXPECT_EQ(doc["spec"]["predict_turning"], StaaConfig{}.predict_turning);  // the default, recorded
  EXPECT_EQ(doc["spec"]["lazy_heuristic"], StaaConfig{}.lazy_heuristic);
  EXPECT_TRUE(fs::exists(dir / "out" / "scores.svg"));
  EXPECT_THAT(e.out, HasSubstr("clutter"));
  EXPECT_THAT(e.out, HasSubstr("score"));
  EXPECT_THAT(e.err, HasSubstr("[2/2]"));
  fs::remove_all(dir);
}

TEST(StaaSimExperiment, MapFileWithoutGoalsGetsGoalsPlacedWithANote) {
  const fs::path dir = freshDir("nogoals");
  std::ofstream(dir / "hall.yaml") << "format: staa-polygon-map/1\nname: hall\nbounds: [0, 0, 16, 10]\n"
                                      "obstacles:\n  - [[7, 4], [9, 4], [9, 6], [7, 6]]\n";
  const Exit e = runSim("experiment --maps '" + (dir / "hall.yaml").string() +
                            "' --controllers pd --modes cooperative --agents 2 --runs 1 --duration 2 --jobs 1 "
                            "--quiet --out '" + (dir / "out").string() + "'",
                        dir);
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_THAT(e.err, HasSubstr("hall.yaml has no goals: placed 40 (clearance 0.6 m, spacing 1.5 m)"));
  const Json doc = Json::parse(readFile(dir / "out" / "results.json"));
  ASSERT_EQ(doc["spec"]["map_goals"].size(), 1U);
  EXPECT_EQ(doc["spec"]["map_goals"][0]["goals_placed"], true);
  EXPECT_EQ(doc["runs"].size(), 1U);
  fs::remove_all(dir);
}

TEST(StaaSimExperiment, BadInputExitsTwoNamingTheOptionAndValue) {
  const fs::path dir = freshDir("bad");
  const std::string out = " --out '" + (dir / "out").string() + "'";
  struct Case {
    std::string args, option, value;
  };
  for (const Case& c : std::vector<Case>{{"--agents 1,0", "--agents", "'0'"},
                                         {"--controllers staa,mpc", "--controllers", "'mpc'"},
                                         {"--modes ghosts", "--modes", "'ghosts'"},
                                         {"--heuristics euclid", "--heuristics", "'euclid'"},
                                         {"--runs -1", "--runs", "'-1'"},
                                         {"--jobs 0", "--jobs", "'0'"},
                                         {"--maps clutter,no-such-map.yaml", "--maps", "no-such-map.yaml"},
                                         {"--budget-ms 5 --budget-expansions 100", "--budget-ms", "exclude"},
                                         {"--predict-turning yes", "--predict-turning", "'yes'"},
                                         {"--lazy-heuristic 1", "--lazy-heuristic", "'1'"}}) {
    const Exit e = runSim("experiment " + c.args + out, dir);
    EXPECT_EQ(e.code, 2) << c.args << ": " << e.err;
    EXPECT_THAT(e.err, HasSubstr(c.option)) << c.args;
    EXPECT_THAT(e.err, HasSubstr(c.value)) << c.args;
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "results.json"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace staa
