// The flight recorder end to end with the real programs: staad on the simulated HAL (the HSR
// among three people walking, a wall-clock budget) records continuously, saves on request and
// writes a fault file by itself when the obstacle frames stall; staa-replay --check reruns
// each file bit for bit; staa-sim --record of a multi-agent run does too; the MCAP project's
// own reader (@mcap/core, tests/mcap) lists the channels with their schemas and decodes every
// message; staa-replay draws a cycle and refuses bad files with exit code 2.
//
// Every wait has a timeout, and every process this test starts is killed in teardown.
#include "child_process.hpp"
#include "raw_client.hpp"
#include "read_file.hpp"
#include "shared_dir.hpp"
#include "temp_dir.hpp"

#include "record/replay.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using staa::test::Child;
using staa::test::readFile;

struct ToolRun {
  std::optional<int> code;
  std::string out, err;
};

ToolRun runTool(const std::vector<std::string>& argv, const fs::path& dir, const std::string& tag,
            std::chrono::milliseconds timeout = 240s) {
  Child c(argv, dir / (tag + ".out"), dir / (tag + ".err"));
  ToolRun r;
  r.code = c.wait(timeout);
  r.out = readFile(dir / (tag + ".out"));
  r.err = readFile(dir / (tag + ".err"));
  return r;
}

std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

// "N cycles, N identical" with the same N (and N > min).
void expectAllIdentical(const ToolRun& r, std::uint64_t min_cycles, const std::string& what) {
  ASSERT_EQ(r.code, std::optional<int>(0)) << what << ": " << r.out << r.err;
  unsigned long long n = 0, same = 0;
  ASSERT_EQ(std::sscanf(firstLine(r.out).c_str(), "%llu cycles, %llu identical", &n, &same), 2) << r.out;
  EXPECT_EQ(n, same) << what << ": " << r.out;
  EXPECT_GT(n, min_cycles) << what;
}

std::vector<fs::path> filesIn(const fs::path& dir) {
  std::vector<fs::path> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path());
  return out;
}

// @mcap/core's reading of `file` (tests/mcap/read_recording.mjs), or why it cannot run here.
std::optional<nlohmann::json> readWithMcapCore(const fs::path& file, const fs::path& dir, std::string& skip) {
  const std::string node = NODE_EXE;
  const fs::path script = staa::test::sourceDir() / "tests/mcap/read_recording.mjs";
  if (node.empty()) {
    skip = "node was not found at configure time (toolchain/install-deps.sh installs nodejs and npm)";
    return std::nullopt;
  }
  if (!fs::exists(staa::test::sourceDir() / "tests/mcap/node_modules/@mcap/core")) {
    skip = "@mcap/core is not installed in tests/mcap (toolchain/install-deps.sh runs npm ci there)";
    return std::nullopt;
  }
  const ToolRun r = runTool({node, script.string(), file.string()}, dir, "mcap-core-" + file.stem().string());
  EXPECT_EQ(r.code, std::optional<int>(0)) << r.err;
  if (r.code != 0) return std::nullopt;
  return nlohmann::json::parse(r.out);
}

void expectChannelsWithSchemas(const nlohmann::json& j, const std::string& prefix) {
  std::size_t plotted = 0, cycle = 0;
  for (const auto& c : j.at("channels")) {
    const std::string topic = c.at("topic");
    if (topic.rfind(prefix, 0) != 0) continue;
    if (c.at("message_encoding") == "json") {
      EXPECT_EQ(c.at("schema_encoding"), "jsonschema") << topic;
      EXPECT_GT(c.at("messages").get<int>(), 0) << topic;
      ++plotted;
    } else {
      EXPECT_EQ(c.at("message_encoding"), "x-staa-cycle") << topic;
      ++cycle;
    }
  }
  EXPECT_EQ(plotted, 6u) << prefix << ": pose, command, state, plan, obstacles, timing";
  EXPECT_EQ(cycle, 1u) << prefix;
  EXPECT_EQ(j.at("summary").at("message_count"), j.at("messages"));
  EXPECT_EQ(j.at("metadata"), nlohmann::json::array({"staa.session"}));
}

class FlightRecorder : public ::testing::Test {
 protected:
  // A short folder name: the control socket's path is at most 107 bytes.
  void SetUp() override {
    static int count = 0;
    dir_ = staa::test::freshDir("fr", std::to_string(++count));
  }
  void TearDown() override {
    if (HasFailure()) std::cerr << "kept " << dir_ << " (staad's stderr: staad.err)\n";
    if (!HasFailure()) fs::remove_all(dir_);
  }
  fs::path dir_;
};

TEST_F(FlightRecorder, StaadOnTheWallClockAmongPeopleRecordsSavesAndWritesAFaultFileThatAllReplayBitForBit) {
  const fs::path src = staa::test::sourceDir();
  const fs::path socket = dir_ / "staad.sock";
  std::ofstream(dir_ / "staad.yaml") << "format: staad-config/1\n"
                                     << "robot: " << (src / "config/robots/hsr.yaml").string() << "\n"
                                     << "map: " << (src / "config/maps/office.yaml").string() << "\n"
                                     << "hal: sim\n"
                                     << "sim: {start: [1.5, 4.5, 0.0], movers: 3, mover_speed: 0.8, seed: 1}\n"
                                     << "budget: {ms: 10}\n"
                                     << "socket: {path: " << socket.string() << "}\n"
                                     << "recorder: {enabled: true, seconds: 30, path: " << (dir_ / "cont/staad.mcap").string()
                                     << ", fault_dir: " << (dir_ / "faults").string() << ", fault_after_s: 1}\n"
                                     << "memory: {heap_prefault_mb: 16, stack_prefault_kb: 256}\n"
                                     << "debug: {faults: true}\n";
  fs::create_directories(dir_ / "cont");
  Child staad({STAAD_EXE, "--config", (dir_ / "staad.yaml").string()}, dir_ / "staad.out", dir_ / "staad.err");
  ASSERT_TRUE(staad.started());
  bool up = false;
  for (int i = 0; i < 500 && !up && staad.alive(); ++i) {
    std::this_thread::sleep_for(20ms);
    up = staa::test::RawClient(socket).connected();
  }
  ASSERT_TRUE(up) << readFile(dir_ / "staad.err");
  auto ask = [&](const std::string& line) {
    staa::test::RawClient c(socket);
    c.send(line + "\n");
    return c.readLine(5000ms).value_or("");
  };
  EXPECT_NE(ask(R"({"cmd": "goal", "x": 13.5, "y": 1.5, "theta": 0})").find("\"ok\":true"), std::string::npos);
  std::this_thread::sleep_for(5s);
  // Obstacle frames stall for 0.6 s: a fault (stale obstacles), then back to driving.
  EXPECT_EQ(ask(R"({"debug": "stall_obstacles", "on": true})"), R"({"ok":true})");
  std::this_thread::sleep_for(600ms);
  EXPECT_EQ(ask(R"({"debug": "stall_obstacles", "on": false})"), R"({"ok":true})");
  std::this_thread::sleep_for(2s);
  const ToolRun saved = runTool({STAACTL_EXE, "--socket", socket.string(), "record", "save", (dir_ / "saved.mcap").string()},
                            dir_, "save", 10s);
  EXPECT_EQ(saved.code, std::optional<int>(0)) << saved.err;
  const nlohmann::json status = nlohmann::json::parse(ask(R"({"cmd": "status"})")).at("status");
  EXPECT_EQ(status.at("rt_allocations"), 0) << "the recorder allocates nothing in the real-time threads";
  EXPECT_GT(status.at("recorder").at("cycles").get<int>(), 150);
  EXPECT_EQ(status.at("recorder").at("dropped"), 0);
  EXPECT_EQ(status.at("recorder").at("write_failures"), 0);
  staad.signal(SIGTERM);
  ASSERT_EQ(staad.wait(10s), std::optional<int>(0)) << readFile(dir_ / "staad.err");
  EXPECT_NE(readFile(dir_ / "staad.err").find("recorder: "), std::string::npos);

  // The fault file came by itself, with the fault in it.
  const std::vector<fs::path> faults = filesIn(dir_ / "faults");
  ASSERT_EQ(faults.size(), 1u) << readFile(dir_ / "staad.err");
  EXPECT_NE(faults[0].filename().string().find("stale-obstacles"), std::string::npos) << faults[0];
  const staa::record::Recording fault = staa::record::loadRecording(faults[0]);
  const auto& fc = fault.agents.at(0);
  EXPECT_TRUE(std::any_of(fc.begin(), fc.end(), [](const auto& c) { return c.step == staa::record::StepKind::kFault; }));
  EXPECT_TRUE(std::any_of(fc.begin(), fc.end(), [](const auto& c) { return c.budget.cut.cut_read >= 0; }))
      << "the wall clock cut some searches short";
  const std::vector<fs::path> continuous = filesIn(dir_ / "cont");
  ASSERT_EQ(continuous.size(), 1u);
  ASSERT_TRUE(fs::exists(dir_ / "saved.mcap"));

  expectAllIdentical(runTool({STAA_REPLAY_EXE, continuous[0].string(), "--check"}, dir_, "check-cont"), 200, "continuous");
  expectAllIdentical(runTool({STAA_REPLAY_EXE, (dir_ / "saved.mcap").string(), "--check"}, dir_, "check-saved"), 200, "saved");
  expectAllIdentical(runTool({STAA_REPLAY_EXE, faults[0].string(), "--check"}, dir_, "check-fault"), 150, "fault");

  std::string skip;
  if (const auto j = readWithMcapCore(continuous[0], dir_, skip)) {
    expectChannelsWithSchemas(*j, "/staa/");
  } else if (!skip.empty()) {
    GTEST_SKIP() << "@mcap/core's check left out: " << skip;
  }
}

TEST_F(FlightRecorder, AMultiAgentStaaSimRunReplaysBitForBitAndReadsInMcapCore) {
  const fs::path file = dir_ / "multi.mcap";
  const ToolRun sim = runTool({STAA_SIM_EXE, "--map", (staa::test::sourceDir() / "config/maps/office.yaml").string(),
                           "--agents", "3", "--budget-ms", "5", "--duration", "3", "--seed", "5", "--quiet", "--record",
                           file.string()},
                          dir_, "sim");
  ASSERT_EQ(sim.code, std::optional<int>(0)) << sim.err;
  expectAllIdentical(runTool({STAA_REPLAY_EXE, file.string(), "--check"}, dir_, "check"), 269, "multi-agent");
  const ToolRun info = runTool({STAA_REPLAY_EXE, file.string()}, dir_, "info");
  EXPECT_EQ(info.code, std::optional<int>(0));
  EXPECT_NE(info.out.find("agent 2 (staa): cycles 0..89 (90)"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("replays exactly from cycle 0"), std::string::npos) << info.out;

  // Cycle 45 of agent 1 drawn, with why its command is what it is.
  const ToolRun svg = runTool({STAA_REPLAY_EXE, file.string(), "--cycle", "45", "--agent", "1", "--svg",
                           (dir_ / "c45.svg").string()},
                          dir_, "svg");
  ASSERT_EQ(svg.code, std::optional<int>(0)) << svg.err;
  const std::string picture = readFile(dir_ / "c45.svg");
  EXPECT_NE(picture.find("agent 1, cycle 45"), std::string::npos);
  EXPECT_NE(picture.find("search tree"), std::string::npos);
  EXPECT_NE(svg.out.find("agent 1, cycle 45"), std::string::npos) << svg.out;

  std::string skip;
  if (const auto j = readWithMcapCore(file, dir_, skip)) {
    for (const char* agent : {"/agent0/", "/agent1/", "/agent2/"}) expectChannelsWithSchemas(*j, agent);
    EXPECT_EQ(j->at("messages").get<int>(), 3 * 90 * 7);
  } else if (!skip.empty()) {
    GTEST_SKIP() << "@mcap/core's check left out: " << skip;
  }
}

// --obstacles depth: the planners got what their cameras saw, and that is what is recorded:
// no obstacle before the first frame has arrived (a frame's obstacles come one frame after
// its exposure; the truth would be the 2 others from cycle 0), perceived ones after it, and
// the command to the base held by the camera's speed limit where it has not looked. What the
// agents see depends on how far they drive, so this run has an expansion budget (the same on
// every build: under the sanitizers a 5 ms budget leaves STAA* 2-7 pops a cycle, the agents
// hardly move and see nobody). The planners rerun bit for bit from it, and from a run on the
// wall clock.
TEST_F(FlightRecorder, ADepthRunRecordsWhatPerceptionGaveThePlannersAndReplaysBitForBit) {
  const auto depthRun = [&](const std::string& name, const std::vector<std::string>& budget) {
    std::vector<std::string> argv{STAA_SIM_EXE, "--map", (staa::test::sourceDir() / "config/maps/office.yaml").string(),
                                  "--robot", (staa::test::sourceDir() / "config/robots/paper-agent.yaml").string(),
                                  "--obstacles", "depth", "--agents", "3", "--duration", "3", "--quiet", "--record",
                                  (dir_ / (name + ".mcap")).string()};
    argv.insert(argv.end(), budget.begin(), budget.end());
    return runTool(argv, dir_, name);
  };
  const ToolRun clock = depthRun("clock", {"--budget-ms", "5", "--seed", "5"});
  ASSERT_EQ(clock.code, std::optional<int>(0)) << clock.err;
  expectAllIdentical(runTool({STAA_REPLAY_EXE, (dir_ / "clock.mcap").string(), "--check"}, dir_, "check-clock"), 269,
                     "depth, wall clock");

  const ToolRun sim = depthRun("depth", {"--budget-expansions", "300", "--seed", "10"});
  ASSERT_EQ(sim.code, std::optional<int>(0)) << sim.err;
  const fs::path file = dir_ / "depth.mcap";
  expectAllIdentical(runTool({STAA_REPLAY_EXE, file.string(), "--check"}, dir_, "check"), 269, "depth");

  const staa::record::Recording rec = staa::record::loadRecording(file);
  ASSERT_EQ(rec.agents.size(), 3u);
  std::size_t perceived = 0, limited = 0;
  for (const auto& [agent, cycles] : rec.agents) {
    ASSERT_EQ(cycles.size(), 90u);
    EXPECT_TRUE(cycles.front().obstacles.empty()) << "agent " << agent << ": no frame has arrived at cycle 0";
    for (const staa::record::CycleRecord& c : cycles) {
      perceived += c.obstacles.size();
      EXPECT_LE(c.command.v, std::max(c.out.v_cmd, 0.0)) << "agent " << agent << ", cycle " << c.cycle;
      limited += c.command.v != c.out.v_cmd;
    }
  }
  EXPECT_GT(perceived, 0u) << "the cameras saw the other agents";
  EXPECT_GT(limited, 0u) << "the camera's speed limit held some command";
}

// The blind-corner limit in ghost mode: the observed agent's cycle lowers its commands at the
// office's doors, the ghosts' cycles have no limit; the recording says which agents are ghosts,
// so the replay rebuilds each cycle as the simulator built it and reruns it bit for bit.
TEST_F(FlightRecorder, BlindCornerLimitedAgentsAndTheirGhostsReplayBitForBit) {
  const fs::path file = dir_ / "blind.mcap";
  const ToolRun sim = runTool({STAA_SIM_EXE, "--map", (staa::test::sourceDir() / "config/maps/office.yaml").string(),
                           "--agents", "3", "--mode", "ghost", "--blind-corners", "on", "--budget-expansions", "300",
                           "--duration", "4", "--seed", "3", "--quiet", "--record", file.string()},
                          dir_, "sim");
  ASSERT_EQ(sim.code, std::optional<int>(0)) << sim.err;
  expectAllIdentical(runTool({STAA_REPLAY_EXE, file.string(), "--check"}, dir_, "check"), 359, "blind corners");
  const staa::record::Recording rec = staa::record::loadRecording(file);
  EXPECT_TRUE(rec.session.control.blind_corners.enabled);
  ASSERT_EQ(rec.session.agents.size(), 3u);
  EXPECT_FALSE(rec.session.agents[0].ghost);
  EXPECT_TRUE(rec.session.agents[1].ghost);
  EXPECT_TRUE(rec.session.agents[2].ghost);
  // Rerun without the limit: the observed agent's commands change where it was capped, the
  // ghosts' (never capped) do not.
  const ToolRun off = runTool({STAA_REPLAY_EXE, file.string(), "--check", "--set", "blind_corners.enabled=false"}, dir_, "off");
  ASSERT_EQ(off.code, std::optional<int>(1)) << off.err;  // 1: a difference found
  EXPECT_LT(off.out.find("cycles changed"), off.out.find("agent 1:")) << "agent 0's commands changed: " << off.out;
  EXPECT_NE(off.out.find("agent 1: 120 cycles, none changed"), std::string::npos) << off.out;
  EXPECT_NE(off.out.find("agent 2: 120 cycles, none changed"), std::string::npos) << off.out;
}

// Issue 16: a rectangular robot whose route runs in the passage map M'' (the building's doors,
// narrowed by furniture below what M' leaves open) carries the route choice between M' and M''
// from cycle to cycle; the replay compares it with the recorded memory every cycle.
TEST_F(FlightRecorder, ARouteThroughThePassageMapReplaysBitForBit) {
  const fs::path file = dir_ / "passages.mcap";
  const fs::path docs = staa::test::sourceDir() / "docs/results/passages";
  const ToolRun sim = runTool({STAA_SIM_EXE, "--map", (docs / "building.yaml").string(), "--robot", (docs / "amr.yaml").string(),
                           "--start", "1.5,2,0", "--goal", "14.5,2,0", "--budget-ms", "5", "--duration", "6", "--quiet",
                           "--record", file.string()},
                          dir_, "sim");
  ASSERT_EQ(sim.code, std::optional<int>(0)) << sim.err;
  expectAllIdentical(runTool({STAA_REPLAY_EXE, file.string(), "--check"}, dir_, "check"), 170, "passages");
}

TEST_F(FlightRecorder, StaaReplayRefusesTruncatedOtherVersionAlteredAndUnknownInputWithExit2) {
  const fs::path file = dir_ / "run.mcap";
  ASSERT_EQ(runTool({STAA_SIM_EXE, "--map", (staa::test::sourceDir() / "config/maps/office.yaml").string(), "--agents",
                     "2", "--budget-expansions", "100", "--duration", "2", "--quiet", "--record", file.string()},
                    dir_, "sim")
                .code,
            std::optional<int>(0));
  const std::string bytes = readFile(file);
  auto variant = [&](const std::string& name, const std::string& content) {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return (dir_ / name).string();
  };
  // Truncated: exit 2 naming it and --salvage; salvaged, its complete cycles replay.
  const std::string cut = variant("cut.mcap", bytes.substr(0, bytes.size() * 2 / 3));
  ToolRun r = runTool({STAA_REPLAY_EXE, cut, "--check"}, dir_, "cut");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--salvage"), std::string::npos) << r.err;
  r = runTool({STAA_REPLAY_EXE, cut, "--check", "--salvage"}, dir_, "salvage");
  expectAllIdentical(r, 40, "salvaged");
  // Another major version of MCAP.
  std::string v1 = bytes;
  v1[5] = '1';
  r = runTool({STAA_REPLAY_EXE, variant("v1.mcap", v1)}, dir_, "v1");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("major version '1'"), std::string::npos) << r.err;
  // The embedded map altered.
  std::string altered = bytes;
  const std::size_t at = altered.find_first_of("123456789", altered.find("obstacles:"));
  altered[at] = altered[at] == '9' ? '8' : static_cast<char>(altered[at] + 1);
  r = runTool({STAA_REPLAY_EXE, variant("altered.mcap", altered), "--check"}, dir_, "altered");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("does not match its checksum"), std::string::npos) << r.err;
  // Not a recording, a cycle not in the file, an unknown key.
  r = runTool({STAA_REPLAY_EXE, variant("text.mcap", "hello")}, dir_, "text");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("not an MCAP file"), std::string::npos) << r.err;
  r = runTool({STAA_REPLAY_EXE, file.string(), "--cycle", "999"}, dir_, "cycle");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("--cycle 999: agent 0's cycles in the file are 0..59"), std::string::npos) << r.err;
  r = runTool({STAA_REPLAY_EXE, file.string(), "--set", "staa.dtt=1"}, dir_, "set");
  EXPECT_EQ(r.code, std::optional<int>(2));
  EXPECT_NE(r.err.find("unknown key 'staa.dtt'"), std::string::npos) << r.err;
  // A changed parameter is reported where it changes the commands; --check then fails.
  r = runTool({STAA_REPLAY_EXE, file.string(), "--set", "staa.heuristic.kind=path-euclid", "--check"}, dir_, "euclid");
  EXPECT_EQ(r.code, std::optional<int>(1)) << r.out << r.err;
  EXPECT_NE(r.out.find("first change at cycle"), std::string::npos) << r.out;
}

}  // namespace
