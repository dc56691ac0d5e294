#include "app/staad/config.hpp"

#include "read_file.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace staa::staad {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A complete config, one key per line, so that every bad value below has a line of its own.
const std::string kValid = R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
hal: sim
sim:
  start: [1.5, 4.5, 0.0]
  movers: 2
  mover_speed: 0.5
  mover_radius: 0.3
  seed: 7
  sensor_range_m: 6.0
rates:
  control_hz: 30
  base_hz: 100
  perception_hz: 30
budget:
  ms: 19
threads:
  control: {priority: 80, cpu: -1}
  base: {priority: 85, cpu: 0}
  perception: {priority: 0, cpu: -1}
  service: {nice: -5}
socket:
  path: /run/staad/staad.sock
  mode: "0660"
limits:
  odometry_timeout_s: 0.1
  obstacles_timeout_s: 0.2
goal:
  tolerance_m: 0.2
  heading_tolerance: 0.4
blind_corners:
  enabled: true
  reaction_s: 0.25
  min_speed: 0.4
  lateral_m: 0.6
telemetry:
  path: ""
  records: 4096
  svg: ""
memory:
  heap_prefault_mb: 64
  stack_prefault_kb: 256
)";

using staa::test::readFile;

// A temporary folder with the shipped robot profile and map beside the config, as in config/.
class ConfigFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("staad-config-test-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "robots");
    fs::create_directories(dir_ / "maps");
    fs::copy_file(test::sourceDir() / "config/robots/hsr.yaml", dir_ / "robots/hsr.yaml");
    fs::copy_file(test::sourceDir() / "config/maps/office.yaml", dir_ / "maps/office.yaml");
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  std::string loadError(const std::string& text, const std::string& name = "staad.yaml") const {
    const fs::path p = write(name, text);
    try {
      loadDaemonConfig(p);
    } catch (const ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no ConfigError for:\n" << text;
    return "";
  }

  fs::path dir_;
};

// `text` (kValid by default) with `from` replaced by `to` (which must occur).
std::string edited(const std::string& from, const std::string& to, std::string s = kValid) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// The 1-based line on which `what` first occurs in `text`.
int lineOf(const std::string& text, const std::string& what) {
  const auto at = text.find(what);
  if (at == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

TEST(ShippedConfig, LoadsWithTheDocumentedValues) {
  const fs::path file = test::sourceDir() / "config/staad.yaml";
  const DaemonConfig c = loadDaemonConfig(file);
  EXPECT_EQ(c.file, file);
  EXPECT_EQ(c.robot_file, (test::sourceDir() / "config/robots/hsr.yaml").lexically_normal());
  EXPECT_EQ(c.robot.name, "hsr");
  EXPECT_DOUBLE_EQ(c.robot.limits.v_max, 0.22);
  EXPECT_EQ(c.map_file, (test::sourceDir() / "config/maps/office.yaml").lexically_normal());
  EXPECT_EQ(c.map.name, "office");
  EXPECT_FALSE(c.map.obstacles.empty());
  EXPECT_EQ(c.hal, HalBackend::kSim);
  EXPECT_EQ(c.obstacles, ObstacleSource::kSim);
  EXPECT_FALSE(c.debug_faults);
  EXPECT_FALSE(c.sim.movers_only);
  EXPECT_DOUBLE_EQ(c.sim.start.x, 1.5);
  EXPECT_DOUBLE_EQ(c.sim.start.y, 4.5);
  EXPECT_DOUBLE_EQ(c.sim.start.theta, 0.0);
  EXPECT_EQ(c.sim.movers, 3);
  EXPECT_DOUBLE_EQ(c.sim.mover_speed, 0.8);
  EXPECT_DOUBLE_EQ(c.sim.mover_radius, 0.25);
  EXPECT_EQ(c.sim.seed, 1u);
  EXPECT_DOUBLE_EQ(c.sim.sensor_range_m, 8.0);
  EXPECT_DOUBLE_EQ(c.sim.obstacle_rate_hz, 30.0);
  EXPECT_DOUBLE_EQ(c.control_hz, 30.0);
  EXPECT_DOUBLE_EQ(c.base_hz, 100.0);
  EXPECT_DOUBLE_EQ(c.perception_hz, 30.0);
  EXPECT_FALSE(c.budget.isExpansions());
  EXPECT_DOUBLE_EQ(c.budget.ms, 19.0);
  EXPECT_EQ(c.control_thread.priority, 80);
  EXPECT_EQ(c.base_thread.priority, 85);
  EXPECT_EQ(c.perception_thread.priority, 70);
  EXPECT_EQ(c.service_nice, -10);
  EXPECT_EQ(c.control_thread.cpu, -1);
  EXPECT_EQ(c.base_thread.cpu, -1);
  EXPECT_EQ(c.perception_thread.cpu, -1);
  EXPECT_EQ(c.control_thread.name, "staad-control");
  EXPECT_EQ(c.socket_path, "/run/staad/staad.sock");
  EXPECT_EQ(c.socket_mode, 0660u);
  EXPECT_EQ(c.socket_max_clients, 16u);
  EXPECT_DOUBLE_EQ(c.socket_idle_timeout_s, 5.0);
  EXPECT_DOUBLE_EQ(c.odometry_timeout_s, 0.1);
  EXPECT_DOUBLE_EQ(c.obstacles_timeout_s, 0.2);
  EXPECT_TRUE(c.telemetry_path.empty());
  EXPECT_EQ(c.telemetry_records, 4096u);
  EXPECT_TRUE(c.svg_path.empty());
  EXPECT_EQ(c.heap_prefault_bytes, std::size_t{64} << 20);
  EXPECT_EQ(c.stack_prefault_bytes, std::size_t{256} << 10);
  EXPECT_DOUBLE_EQ(c.control.rate_hz, 30.0);
  EXPECT_DOUBLE_EQ(c.control.goal_tolerance_m, 0.2);
  EXPECT_DOUBLE_EQ(c.control.goal_heading_tolerance, 0.4);
  EXPECT_TRUE(c.recorder.enabled);
  EXPECT_DOUBLE_EQ(c.recorder.seconds, 30.0);
  EXPECT_TRUE(c.recorder.path.empty());
  EXPECT_EQ(c.recorder.max_file_mb, 64u);
  EXPECT_EQ(c.recorder.max_files, 8u);
  EXPECT_TRUE(c.recorder.fault_dir.empty());
  EXPECT_DOUBLE_EQ(c.recorder.fault_after_s, 2.0);
  EXPECT_EQ(c.recorder.ring_kb, 4096u);
  EXPECT_NE(c.text.find("format: staad-config/1"), std::string::npos) << "the recordings keep the file's text";
}

TEST_F(ConfigFiles, ReadsEveryKeyOfAValidConfig) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", kValid));
  EXPECT_EQ(c.sim.movers, 2);
  EXPECT_DOUBLE_EQ(c.sim.mover_speed, 0.5);
  EXPECT_DOUBLE_EQ(c.sim.mover_radius, 0.3);
  EXPECT_EQ(c.sim.seed, 7u);
  EXPECT_DOUBLE_EQ(c.sim.sensor_range_m, 6.0);
  EXPECT_EQ(c.base_thread.cpu, 0);
  EXPECT_EQ(c.perception_thread.priority, 0);
  EXPECT_EQ(c.service_nice, -5);
  EXPECT_TRUE(c.svg_path.empty());  // "": off
  EXPECT_TRUE(c.control.blind_corners.enabled);
  EXPECT_DOUBLE_EQ(c.control.blind_corners.reaction_s, 0.25);
  EXPECT_DOUBLE_EQ(c.control.blind_corners.min_speed, 0.4);
  EXPECT_DOUBLE_EQ(c.control.blind_corners.lateral_m, 0.6);
  EXPECT_DOUBLE_EQ(c.control.blind_corners.range_m, BlindCornerConfig{}.range_m);  // not given: the default
}

TEST_F(ConfigFiles, TelemetrySvgIsAPathOrEmptyForOff) {
  const DaemonConfig on = loadDaemonConfig(write("staad.yaml", edited("svg: \"\"", "svg: /var/log/staad/run.svg")));
  EXPECT_EQ(on.svg_path, fs::path("/var/log/staad/run.svg"));
  EXPECT_TRUE(on.telemetry_path.empty());  // independent of the CSV file
  const DaemonConfig null = loadDaemonConfig(write("null.yaml", edited("svg: \"\"", "svg:")));
  EXPECT_TRUE(null.svg_path.empty());
  const DaemonConfig absent = loadDaemonConfig(write("absent.yaml", edited("  svg: \"\"\n", "")));
  EXPECT_TRUE(absent.svg_path.empty());
}

// The bad value, the key that holds it and its line must all be in the message.
struct BadCase {
  std::string from;
  std::string to;
  std::vector<const char*> expected;  // substrings of the message
  bool check_line = true;             // the message names the line of `to`
};

TEST_F(ConfigFiles, EveryBadValueIsNamedWithItsKeyAndLine) {
  const std::vector<BadCase> cases = {
      {"control_hz: 30", "control_hz: -3", {"rates.control_hz", "(0, 1000]", "got -3"}},
      {"control_hz: 30", "control_hz: 1001", {"rates.control_hz", "1001"}},
      {"control_hz: 30", "control_hz: abc", {"rates.control_hz", "expected a number", "'abc'"}},
      {"base_hz: 100", "base_hz: .inf", {"rates.base_hz", "finite", ".inf"}},
      {"perception_hz: 30", "perception_hz: 0", {"rates.perception_hz", "got 0"}},
      {"ms: 19", "ms: 40", {"budget.ms", "control period", "got 40"}},
      {"ms: 19", "ms: 0", {"budget.ms", "got 0"}},
      {"ms: 19", "expansions: 0", {"budget.expansions", "1..4294967295", "got 0"}},
      {"ms: 19", "expansions: 1.5", {"budget.expansions", "integer", "1.5"}},
      {"ms: 19", "{}", {"budget", "got neither"}, false},
      {"control: {priority: 80", "control: {priority: 120", {"threads.control.priority", "0..99", "120"}},
      {"control: {priority: 80", "control: {priority: -1", {"threads.control.priority", "-1"}},
      {"base: {priority: 85, cpu: 0}", "base: {priority: 85, cpu: -2}", {"threads.base.cpu", "-1..1023", "-2"}},
      {"perception: {priority: 0, cpu: -1}", "perception: {priority: 0, cpu: 1024}", {"threads.perception.cpu", "1024"}},
      {"service: {nice: -5}", "service: {nice: -21}", {"threads.service.nice", "-20..19", "-21"}},
      {"service: {nice: -5}", "service: {nice: 3.5}", {"threads.service.nice", "3.5"}},
      {"mode: \"0660\"", "mode: \"0999\"", {"socket.mode", "octal", "0999"}},
      {"mode: \"0660\"", "mode: rw-rw----", {"socket.mode", "rw-rw----"}},
      {"mode: \"0660\"", "mode: 660", {"socket.mode", "660"}},
      {"mode: \"0660\"", "mode: \"01777\"", {"socket.mode", "01777"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  max_clients: 0", {"socket.max_clients", "1..256", "got 0"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  max_clients: 257", {"socket.max_clients", "1..256", "257"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  max_clients: 2.5", {"socket.max_clients", "integer", "2.5"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  idle_timeout_s: 0", {"socket.idle_timeout_s", "[0.1, 3600]", "got 0"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  idle_timeout_s: 0.05", {"socket.idle_timeout_s", "0.05"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  idle_timeout_s: 4000", {"socket.idle_timeout_s", "4000"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  idle_timeout_s: .nan", {"socket.idle_timeout_s", "finite", ".nan"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  idle_timeout_s: soon", {"socket.idle_timeout_s", "'soon'"}},
      {"mode: \"0660\"", "mode: \"0660\"\n  max_client: 4", {"socket.max_client", "unknown key", "path, mode, max_clients, idle_timeout_s"}},
      {"odometry_timeout_s: 0.1", "odometry_timeout_s: 0", {"limits.odometry_timeout_s", "> 0", "got 0"}},
      {"odometry_timeout_s: 0.1", "odometry_timeout_s: 0.005", {"limits.odometry_timeout_s", "base_hz", "0.005"}},
      {"obstacles_timeout_s: 0.2", "obstacles_timeout_s: -1", {"limits.obstacles_timeout_s", "-1"}},
      {"tolerance_m: 0.2", "tolerance_m: 0", {"goal.tolerance_m", "got 0"}},
      {"heading_tolerance: 0.4", "heading_tolerance: nope", {"goal.heading_tolerance", "'nope'"}},
      {"enabled: true", "enabled: often", {"blind_corners.enabled", "'often'"}},
      {"reaction_s: 0.25", "reaction_s: 9", {"blind_corners.reaction_s", "9"}},
      {"min_speed: 0.4", "min_speed: -0.1", {"blind_corners.min_speed", "-0.1"}},
      {"lateral_m: 0.6", "lateral_m: .nan", {"blind_corners.lateral_m", ".nan"}},
      {"lateral_m: 0.6", "lateral: 0.6", {"blind_corners.lateral", "unknown key"}},
      {"records: 4096", "records: 8", {"telemetry.records", "16..", "8"}},
      {"records: 4096", "records: many", {"telemetry.records", "many"}},
      {"path: \"\"", "path: [a, b]", {"telemetry.path", "a list of 2 items"}},
      {"svg: \"\"", "svg: [a, b]", {"telemetry.svg", "a file path", "a list of 2 items"}},
      {"svg: \"\"", "svgg: run.svg", {"telemetry.svgg", "unknown key", "path, records, svg"}},
      {"heap_prefault_mb: 64", "heap_prefault_mb: 5000", {"memory.heap_prefault_mb", "0..4096", "5000"}},
      {"stack_prefault_kb: 256", "stack_prefault_kb: -4", {"memory.stack_prefault_kb", "-4"}},
      {"hal: sim", "hal: can", {"hal", "sim, socketcan or ros", "'can'"}},
      {"hal: sim", "hal: socketcan", {"socketcan: missing", "socketcan.interface", "socketcan.profile"}},
      {"hal: sim", "hal: sim\nobstacles: camera", {"obstacles", "sim", "none", "'camera'"}},
      {"hal: sim", "hal: sim\ndebug: {faults: maybe}", {"debug.faults", "true or false", "'maybe'"}},
      {"hal: sim", "hal: sim\ndebug: {fault: true}", {"debug.fault", "unknown key", "faults"}},
      {"hal: sim", "hal: sim\nsocketcan: {interface: can0, profil: x.yaml}", {"socketcan.profil", "unknown key"}},
      {"start: [1.5, 4.5, 0.0]", "start: [1.5, 4.5]", {"sim.start", "[x, y, theta]", "a list of 2 items"}},
      {"start: [1.5, 4.5, 0.0]", "start: [1.5, .nan, 0.0]", {"sim.start[1]", "finite", ".nan"}},
      {"start: [1.5, 4.5, 0.0]", "start: [1.5, x, 0.0]", {"sim.start[1]", "'x'"}},
      {"start: [1.5, 4.5, 0.0]", "start: [1.5, 1.5, 0.0]", {"sim.start", "overlaps obstacle 0", "office.yaml", "[1.5, 1.5, 0]"}},
      {"start: [1.5, 4.5, 0.0]", "start: [1.5, 3.1, 0.0]", {"sim.start", "overlaps obstacle", "[1.5, 3.1, 0]"}},
      {"start: [1.5, 4.5, 0.0]", "start: [-5, 4.5, 0.0]", {"sim.start", "outside the map's bounds", "[-5, 4.5, 0]"}},
      {"movers: 2", "movers: 40", {"sim.movers", "0..32", "40"}},
      {"movers: 2", "movers: 2.5", {"sim.movers", "2.5"}},
      {"mover_speed: 0.5", "mover_speed: -1", {"sim.mover_speed", ">= 0", "-1"}},
      {"mover_radius: 0.3", "mover_radius: 0", {"sim.mover_radius", "> 0", "got 0"}},
      {"seed: 7", "seed: -1", {"sim.seed", "-1"}},
      {"sensor_range_m: 6.0", "sensor_range_m: -.inf", {"sim.sensor_range_m", "-.inf"}},
      {"format: staad-config/1", "format: staad-config/2", {"format", "staad-config/1", "'staad-config/2'"}},
      {"path: /run/staad/staad.sock", "path: /run/" + std::string(120, 's') + ".sock", {"socket.path", "107 bytes"}},
      // Typos are errors, not silently ignored keys.
      {"control_hz: 30", "control_hzz: 30", {"rates.control_hzz", "unknown key", "control_hz, base_hz, perception_hz"}},
      {"hal: sim", "hal: sim\ncolour: blue", {"colour: unknown key (expected format, robot, map"}},
      {"  movers: 2", "  movers: 2\n  mover: 3", {"sim.mover", "unknown key"}},
      {"control: {priority: 80, cpu: -1}", "control: {priority: 80, cpus: -1}", {"threads.control.cpus", "unknown key"}},
      {"rates:\n  control_hz: 30", "rates:\n  control_hz: 30\n  control_hz: 20", {"rates.control_hz", "given twice", "line 13"}},
      {"rates:\n  control_hz: 30\n  base_hz: 100\n  perception_hz: 30", "rates: 30", {"rates", "expected a mapping", "'30'"}},
  };
  for (const BadCase& c : cases) {
    const std::string text = edited(c.from, c.to);
    const std::string error = loadError(text);
    SCOPED_TRACE(c.to + "  ->  " + error);
    for (const char* e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    EXPECT_THAT(error, HasSubstr((dir_ / "staad.yaml").string()));
    if (c.check_line) {
      // The last line of `to` holds the bad value (multi-line `to`s add the bad key last).
      const int line = lineOf(text, c.to) + static_cast<int>(std::count(c.to.begin(), c.to.end(), '\n'));
      EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(line) + ": "));
    }
  }
}

TEST_F(ConfigFiles, BudgetInMillisecondsAndExpansionsTogetherIsRejected) {
  const std::string error = loadError(edited("ms: 19", "ms: 19\n  expansions: 1000"));
  EXPECT_THAT(error, HasSubstr("budget"));
  EXPECT_THAT(error, HasSubstr("not both"));
  EXPECT_THAT(error, HasSubstr("ms 19 and expansions 1000"));
  EXPECT_THAT(error, HasSubstr("staad.yaml:16: "));  // the budget mapping's line
}

TEST_F(ConfigFiles, SocketClientLimitAndIdleTimeoutAreRead) {
  const DaemonConfig c =
      loadDaemonConfig(write("staad.yaml", edited("mode: \"0660\"", "mode: \"0660\"\n  max_clients: 4\n  idle_timeout_s: 0.3")));
  EXPECT_EQ(c.socket_max_clients, 4u);
  EXPECT_DOUBLE_EQ(c.socket_idle_timeout_s, 0.3);
  const DaemonConfig edges =
      loadDaemonConfig(write("edges.yaml", edited("mode: \"0660\"", "mode: \"0660\"\n  max_clients: 256\n  idle_timeout_s: 3600")));
  EXPECT_EQ(edges.socket_max_clients, 256u);
  EXPECT_DOUBLE_EQ(edges.socket_idle_timeout_s, 3600.0);
}

// The flight recorder's keys: paths relative to the file, every number range-checked with
// the file, the line and the key.
TEST_F(ConfigFiles, RecorderKeysAreReadAndEveryBadOneIsNamedWithItsLine) {
  const std::string section = "recorder: {enabled: true, seconds: 12, path: rec/staad.mcap, max_file_mb: 2, max_files: 3, "
                              "fault_dir: faults, fault_after_s: 0.5, ring_kb: 1024}\n";
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", kValid + section));
  EXPECT_DOUBLE_EQ(c.recorder.seconds, 12.0);
  EXPECT_EQ(c.recorder.path, (dir_ / "rec/staad.mcap").lexically_normal());
  EXPECT_EQ(c.recorder.fault_dir, (dir_ / "faults").lexically_normal());
  EXPECT_EQ(c.recorder.max_file_mb, 2u);
  EXPECT_EQ(c.recorder.max_files, 3u);
  EXPECT_DOUBLE_EQ(c.recorder.fault_after_s, 0.5);
  EXPECT_EQ(c.recorder.ring_kb, 1024u);
  const DaemonConfig off = loadDaemonConfig(write("off.yaml", kValid + "recorder: {enabled: false, path: \"\"}\n"));
  EXPECT_FALSE(off.recorder.enabled);
  EXPECT_TRUE(off.recorder.path.empty());
  const int line = static_cast<int>(std::count(kValid.begin(), kValid.end(), '\n')) + 1;
  for (const auto& [bad, expected] : std::vector<std::pair<std::string, std::string>>{
           {"recorder: {seconds: 0}", "recorder.seconds: must be in [1, 3600] s, got 0"},
           {"recorder: {ring_kb: 64}", "recorder.ring_kb: must be an integer in 256..262144 (the ring between the control and service threads), got 64"},
           {"recorder: {max_files: 0}", "recorder.max_files: must be an integer in 1..10000, got 0"},
           {"recorder: {fault_after_s: -1}", "recorder.fault_after_s: must be in [0, 60] s, got -1"},
           {"recorder: {enabled: sometimes}", "recorder.enabled"},
           {"recorder: {fault_dri: x}", "recorder.fault_dri: unknown key (expected enabled, seconds, path, max_file_mb, max_files, fault_dir, fault_after_s, ring_kb)"}}) {
    const std::string error = loadError(kValid + bad + "\n");
    EXPECT_THAT(error, HasSubstr(expected)) << bad;
    EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(line) + ": ")) << error;
  }
}

TEST_F(ConfigFiles, ExpansionBudgetReplacesTheWallClock) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", edited("ms: 19", "expansions: 1000")));
  ASSERT_TRUE(c.budget.isExpansions());
  EXPECT_EQ(c.budget.expansions, 1000u);
}

TEST_F(ConfigFiles, BudgetMustFitTheControlPeriod) {
  // 19 ms is fine at 30 Hz but not at 100 Hz (a 10 ms period).
  const std::string error = loadError(edited("control_hz: 30", "control_hz: 100"));
  EXPECT_THAT(error, HasSubstr("budget.ms"));
  EXPECT_THAT(error, HasSubstr("10 ms at control_hz 100"));
  EXPECT_THAT(error, HasSubstr("got 19"));
  const DaemonConfig c = loadDaemonConfig(write("fast.yaml", edited("ms: 19", "ms: 6", edited("control_hz: 30", "control_hz: 100"))));
  EXPECT_DOUBLE_EQ(c.budget.ms, 6.0);
  EXPECT_DOUBLE_EQ(c.control.rate_hz, 100.0);
}

TEST_F(ConfigFiles, SocketModeAcceptsOctalTextAndIntegers) {
  auto modeOf = [&](const std::string& mode) {
    return loadDaemonConfig(write("staad.yaml", edited("mode: \"0660\"", "mode: " + mode))).socket_mode;
  };
  EXPECT_EQ(modeOf("\"0640\""), 0640u);
  EXPECT_EQ(modeOf("0600"), 0600u);   // unquoted: the text is still read as octal
  EXPECT_EQ(modeOf("0o660"), 0660u);  // YAML 1.2's octal spelling
  EXPECT_EQ(modeOf("416"), 0640u);    // a plain integer is the number itself
}

TEST_F(ConfigFiles, OnlyFormatRobotMapAndStartAreRequired) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
sim: {start: [1.5, 4.5, 0.0]}
)"));
  const DaemonConfig defaults;
  EXPECT_EQ(c.hal, HalBackend::kSim);
  EXPECT_DOUBLE_EQ(c.control_hz, defaults.control_hz);
  EXPECT_DOUBLE_EQ(c.budget.ms, defaults.budget.ms);
  EXPECT_EQ(c.socket_path, defaults.socket_path);
  EXPECT_EQ(c.socket_mode, defaults.socket_mode);
  EXPECT_EQ(c.socket_max_clients, defaults.socket_max_clients);
  EXPECT_DOUBLE_EQ(c.socket_idle_timeout_s, defaults.socket_idle_timeout_s);
  EXPECT_EQ(c.sim.movers, hal::SimHalConfig{}.movers);
  EXPECT_EQ(c.telemetry_records, defaults.telemetry_records);

  EXPECT_THAT(loadError("format: staad-config/1\nrobot: robots/hsr.yaml\nmap: maps/office.yaml\n"),
              HasSubstr("sim: missing (hal: sim needs at least sim.start"));
  EXPECT_THAT(loadError("format: staad-config/1\nmap: maps/office.yaml\n"), HasSubstr("robot: missing"));
  EXPECT_THAT(loadError("robot: robots/hsr.yaml\n"), HasSubstr("format: missing (expected staad-config/1)"));
  EXPECT_THAT(loadError(""), HasSubstr("expected a mapping"));
  EXPECT_THAT(loadError("rates: {control_hz: 30\n"), HasSubstr("not valid YAML"));
  EXPECT_THAT(loadError("- a\n- b\n"), HasSubstr("got a list of 2 items"));
}

TEST_F(ConfigFiles, MissingMapFileNamesThePath) {
  const std::string error = loadError(edited("map: maps/office.yaml", "map: maps/nowhere.yaml"));
  EXPECT_THAT(error, HasSubstr("staad.yaml:3: map: file not found: " + (dir_ / "maps/nowhere.yaml").string()));
  EXPECT_THAT(error, HasSubstr("maps/nowhere.yaml relative to the config's directory"));

  const std::string robot = loadError(edited("robot: robots/hsr.yaml", "robot: /nonexistent/hsr.yaml"));
  EXPECT_THAT(robot, HasSubstr("staad.yaml:2: robot: file not found: /nonexistent/hsr.yaml"));

  EXPECT_THAT(loadError(edited("map: maps/office.yaml", "map: maps")), HasSubstr("map: is a directory"));
}

TEST_F(ConfigFiles, ErrorsOfTheRobotAndMapFilesAreRethrownUnderTheirKey) {
  write("maps/broken.yaml", "format: staa-polygon-map/1\nobstacles:\n  - [[0, 0], [1, 0]]\n");
  const std::string map = loadError(edited("map: maps/office.yaml", "map: maps/broken.yaml"));
  EXPECT_THAT(map, HasSubstr("staad.yaml:3: map: " + (dir_ / "maps/broken.yaml").string()));
  EXPECT_THAT(map, HasSubstr("vertices"));

  write("robots/bad.yaml", "format: staa-robot/1\nfootprint: [[0.2, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.2, -0.2]]\n"
                           "limits: {v_max: -1, v_min: -1, w_max: 1, a_max: 1, b_max: 1}\n");
  const std::string robot = loadError(edited("robot: robots/hsr.yaml", "robot: robots/bad.yaml"));
  EXPECT_THAT(robot, HasSubstr("staad.yaml:2: robot: " + (dir_ / "robots/bad.yaml").string()));
  EXPECT_THAT(robot, HasSubstr("limits.v_max"));
}

TEST_F(ConfigFiles, RelativePathsResolveAgainstTheConfigsDirectory) {
  std::string text = edited("robot: robots/hsr.yaml", "robot: ../robots/hsr.yaml");
  text.replace(text.find("map: maps/office.yaml"), 21, "map: " + (dir_ / "maps/office.yaml").string());
  text.replace(text.find("path: /run/staad/staad.sock"), 27, "path: run/staad.sock");
  text.replace(text.find("path: \"\""), 8, "path: logs/telemetry.bin");
  text.replace(text.find("svg: \"\""), 7, "svg: pictures/run.svg");
  const fs::path file = write("etc/staad.yaml", text);
  // Started from another directory (systemd starts staad in /): the config's own folder counts.
  const fs::path cwd = fs::current_path();
  fs::current_path(fs::temp_directory_path());
  DaemonConfig c;
  EXPECT_NO_THROW(c = loadDaemonConfig(file));
  fs::current_path(cwd);
  EXPECT_EQ(c.robot_file, dir_ / "robots/hsr.yaml");
  EXPECT_EQ(c.map_file, dir_ / "maps/office.yaml");  // absolute: kept
  EXPECT_EQ(c.socket_path, (dir_ / "etc/run/staad.sock").string());
  EXPECT_EQ(c.telemetry_path, dir_ / "etc/logs/telemetry.bin");
  EXPECT_EQ(c.svg_path, dir_ / "etc/pictures/run.svg");
  EXPECT_EQ(c.robot.name, "hsr");
}

// hal: socketcan: the interface, the CAN profile (parsed at start-up), the simulated camera.
class SocketCanConfig : public ConfigFiles {
 protected:
  void SetUp() override {
    ConfigFiles::SetUp();
    fs::create_directories(dir_ / "can");
    fs::copy_file(test::sourceDir() / "config/can/hsr_base.yaml", dir_ / "can/hsr_base.yaml");
  }
  // kValid on the SocketCAN base with `socketcan` as its section's value.
  static std::string socketcan(const std::string& section, const std::string& obstacles = "sim") {
    return edited("hal: sim", "hal: socketcan\nsocketcan: " + section + "\nobstacles: " + obstacles);
  }
};

TEST_F(SocketCanConfig, ReadsTheInterfaceAndParsesTheProfile) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", socketcan("{interface: can0, profile: can/hsr_base.yaml}")));
  EXPECT_EQ(c.hal, HalBackend::kSocketCan);
  EXPECT_EQ(c.socketcan.interface, "can0");
  EXPECT_EQ(c.socketcan.profile_file, dir_ / "can/hsr_base.yaml");
  EXPECT_EQ(c.socketcan.profile.name, "hsr-base-bridge");
  EXPECT_DOUBLE_EQ(c.socketcan.profile.odometry.rate_hz, 100.0);
  EXPECT_EQ(c.obstacles, ObstacleSource::kSim);
  EXPECT_TRUE(c.sim.movers_only) << "the simulated camera: nobody drives the sim world's robot";
  EXPECT_EQ(c.sim.movers, 2);
  EXPECT_FALSE(c.debug_faults);

  // A relative unix: path is made absolute against the config's directory.
  const DaemonConfig u = loadDaemonConfig(write("u.yaml", socketcan("{interface: \"unix:run/base.sock\", profile: can/hsr_base.yaml}")));
  EXPECT_EQ(u.socketcan.interface, "unix:" + (dir_ / "run/base.sock").string());
  const DaemonConfig a = loadDaemonConfig(write("a.yaml", socketcan("{interface: \"unix:/tmp/b.sock\", profile: can/hsr_base.yaml}")));
  EXPECT_EQ(a.socketcan.interface, "unix:/tmp/b.sock");
}

TEST_F(SocketCanConfig, ObstaclesNoneNeedsNoSimulatedWorld) {
  std::string text = socketcan("{interface: vcan0, profile: can/hsr_base.yaml}", "none");
  text.replace(text.find("  start: [1.5, 4.5, 0.0]\n"), 25, "");
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", text));
  EXPECT_EQ(c.obstacles, ObstacleSource::kNone);
  // With obstacles: sim the start anchors the simulated world: required.
  EXPECT_THAT(loadError(edited("obstacles: none", "obstacles: sim", text)), HasSubstr("sim.start: missing"));
  const std::string no_sim = R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
hal: socketcan
socketcan: {interface: can0, profile: can/hsr_base.yaml}
)";
  EXPECT_THAT(loadError(no_sim), HasSubstr("sim: missing (obstacles: sim needs at least sim.start"));
  EXPECT_EQ(loadDaemonConfig(write("none.yaml", no_sim + "obstacles: none\n")).obstacles, ObstacleSource::kNone);
}

TEST_F(SocketCanConfig, BadValuesAreNamedWithTheirKeyAndLine) {
  struct Case {
    std::string section;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {"{interface: \"can 0\", profile: can/hsr_base.yaml}", {"socketcan.interface", "interface name", "'can 0'"}},
      {"{interface: averyveryverylongname0, profile: can/hsr_base.yaml}", {"socketcan.interface", "1..15"}},
      {"{interface: \"unix:\", profile: can/hsr_base.yaml}", {"socketcan.interface", "socket path", "'unix:'"}},
      {"{interface: \"unix:/" + std::string(120, 's') + "\", profile: can/hsr_base.yaml}", {"socketcan.interface", "107 bytes"}},
      {"{interface: [can0], profile: can/hsr_base.yaml}", {"socketcan.interface", "a list of 1 items"}},
      {"{profile: can/hsr_base.yaml}", {"socketcan.interface: missing"}},
      {"{interface: can0}", {"socketcan.profile: missing"}},
      {"{interface: can0, profile: can/none.yaml}", {"socketcan.profile", "file not found", (dir_ / "can/none.yaml").string()}},
      {"{interface: can0, profile: can/bad.yaml}", {"socketcan.profile", "bad.yaml", "odometry.rate_hz"}},
  };
  std::string bad = readFile(dir_ / "can/hsr_base.yaml");
  bad.replace(bad.find("rate_hz: 100"), 12, "rate_hz: -5");
  write("can/bad.yaml", bad);
  for (const Case& c : cases) {
    const std::string text = socketcan(c.section);
    const std::string error = loadError(text);
    SCOPED_TRACE(c.section + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(text, "socketcan: ")) + ": "));
  }
}

// hal: ros and the ros section (docs/ros.md): the HSR's ROS 1 names by default.
const std::string kRosConfig = R"(format: staad-config/1
robot: robots/hsr.yaml
map: ros
hal: ros
obstacles: none
)";

TEST_F(ConfigFiles, TheRosLinkDefaultsToTheHsrsRos1Names) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", kRosConfig));
  EXPECT_EQ(c.hal, HalBackend::kRos);
  EXPECT_TRUE(c.map_from_ros);
  EXPECT_TRUE(c.map_file.empty());
  EXPECT_TRUE(c.ros.enabled);
  const ros::TransportConfig& t = c.ros.transport;
  EXPECT_EQ(t.cmd_vel_topic, "/hsrb/command_velocity");
  EXPECT_EQ(t.odom_topic, "/hsrb/odom");
  EXPECT_EQ(t.localization, ros::LocalizationSource::kPoseStamped);
  EXPECT_EQ(t.localization_topic, "/global_pose");
  EXPECT_EQ(t.action_name, "move_base");
  EXPECT_EQ(t.simple_goal_topic, "/move_base_simple/goal");
  EXPECT_EQ(t.map_topic, "/map");
  EXPECT_EQ(t.map_frame, "map");
  EXPECT_EQ(t.base_frame, "base_footprint");
  EXPECT_EQ(t.scan_topic, "/hsrb/base_scan");
  EXPECT_DOUBLE_EQ(c.ros.occupied_thresh, 0.65);
  EXPECT_DOUBLE_EQ(c.ros.free_thresh, 0.196);
  // Without any of it the link is off.
  EXPECT_FALSE(loadDaemonConfig(write("sim.yaml", kValid)).ros.enabled);
}

TEST_F(ConfigFiles, TheRosSectionTakesTopicsFramesAndRates) {
  const DaemonConfig c = loadDaemonConfig(write("staad.yaml", kRosConfig + R"(ros:
  master_uri: http://10.0.0.2:11311
  node_name: staad_test
  frames: {map: world, base: base_link}
  base: {cmd_vel: /omni_base_controller/cmd_vel, odom: /omni_base_controller/wheel_odom, queue_size: 2}
  localization: {source: tf, tf_hz: 20}
  goals: {action: "", simple_goal: /goal}
  map: {topic: /static_map, wait_s: 5, occupied_thresh: 0.7, free_thresh: 0.2, simplify_m: 0}
  scanner: {topic: /base_scan}
  markers: {rate_hz: 0}
)"));
  const ros::TransportConfig& t = c.ros.transport;
  EXPECT_EQ(t.master_uri, "http://10.0.0.2:11311");
  EXPECT_EQ(t.node_name, "staad_test");
  EXPECT_EQ(t.map_frame, "world");
  EXPECT_EQ(t.base_frame, "base_link");
  EXPECT_EQ(t.cmd_vel_topic, "/omni_base_controller/cmd_vel");
  EXPECT_EQ(t.odom_topic, "/omni_base_controller/wheel_odom");
  EXPECT_EQ(t.queue_size, 2);
  EXPECT_EQ(t.localization, ros::LocalizationSource::kTf);
  EXPECT_DOUBLE_EQ(t.tf_localization_hz, 20.0);
  EXPECT_TRUE(t.action_name.empty()) << "\"\" turns the action server off";
  EXPECT_EQ(t.simple_goal_topic, "/goal");
  EXPECT_EQ(t.map_topic, "/static_map");
  EXPECT_DOUBLE_EQ(c.ros.map_wait_s, 5.0);
  EXPECT_DOUBLE_EQ(c.ros.occupied_thresh, 0.7);
  EXPECT_DOUBLE_EQ(c.ros.simplify_m, 0.0);
  EXPECT_DOUBLE_EQ(c.ros.markers_hz, 0.0);
  EXPECT_EQ(t.scan_topic, "/base_scan");
}

TEST_F(ConfigFiles, BadRosValuesAreNamedWithTheirKeyAndLine) {
  struct Case {
    std::string section;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {"{base: {odom: \"odom topic\"}}", {"ros.base.odom", "ROS name", "'odom topic'"}},
      {"{base: {cmd_vel: \"\"}}", {"ros.base.cmd_vel", "ROS name"}},
      {"{base: {queue_size: 0}}", {"ros.base.queue_size", "0"}},
      {"{master_uri: 10.0.0.2:11311}", {"ros.master_uri", "http://host:port"}},
      {"{node_name: a/b}", {"ros.node_name", "no '/'"}},
      {"{localization: {source: amcl}}", {"ros.localization.source", "pose (geometry_msgs/PoseStamped", "tf (tf from frames.map", "'amcl'"}},
      {"{map: {occupied_thresh: 0.1, free_thresh: 0.3}}", {"ros.map", "free_thresh (0.3) must be below occupied_thresh (0.1)"}},
      {"{map: {wait_s: -1}}", {"ros.map.wait_s"}},
      {"{markers: {rate_hz: -2}}", {"ros.markers.rate_hz"}},
      {"{topics: {}}", {"ros.topics", "unknown key"}},
      {"{scanner: {topic: \"\"}}", {"ros.scanner.topic", "ROS name"}},
      {"{scanner: {image: /scan}}", {"ros.scanner.image", "unknown key", "topic"}},
  };
  for (const Case& c : cases) {
    const std::string text = kRosConfig + "ros: " + c.section + "\n";
    const std::string error = loadError(text);
    SCOPED_TRACE(c.section + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(text, "ros: ")) + ": "));
  }
}

TEST_F(ConfigFiles, AMapFromRosCannotAnchorTheSimulatedWorld) {
  const std::string error = loadError(edited("map: maps/office.yaml", "map: ros"));
  EXPECT_THAT(error, HasSubstr("map: ros needs a real base and real obstacles"));
  EXPECT_THAT(error, HasSubstr("staad.yaml:3: "));
}

TEST(ShippedConfig, TheHsrRosConfigLoads) {
  const DaemonConfig c = loadDaemonConfig(test::sourceDir() / "config/staad-hsr-ros.yaml");
  EXPECT_EQ(c.hal, HalBackend::kRos);
  EXPECT_TRUE(c.map_from_ros);
  EXPECT_EQ(c.obstacles, ObstacleSource::kNone);
  EXPECT_EQ(c.ros.transport.cmd_vel_topic, "/hsrb/command_velocity");
  EXPECT_EQ(c.ros.transport.localization_topic, "/global_pose");
  // Its scanner (the base's, over ROS) is in place for obstacles: depth; unused with none.
  EXPECT_EQ(c.ros.transport.scan_topic, "/hsrb/base_scan");
  EXPECT_EQ(c.scanner.backend, ScannerBackend::kNone);
  std::string text = readFile(test::sourceDir() / "config/staad-hsr-ros.yaml");
  text.replace(text.find("\nobstacles: none"), 16, "\nobstacles: depth\ncamera: {backend: ros}");
  const fs::path dir = fs::temp_directory_path() / ("staad-hsr-ros-" + std::to_string(::getpid()));
  fs::create_directories(dir / "robots");
  fs::copy_file(test::sourceDir() / "config/robots/hsr.yaml", dir / "robots/hsr.yaml", fs::copy_options::overwrite_existing);
  std::ofstream(dir / "staad.yaml") << text;
  const DaemonConfig depth = loadDaemonConfig(dir / "staad.yaml");
  fs::remove_all(dir);
  EXPECT_EQ(depth.scanner.backend, ScannerBackend::kRos);
  EXPECT_DOUBLE_EQ(depth.scanner.mount.x, 0.1675);
  EXPECT_DOUBLE_EQ(depth.scanner.mount.z, 0.1844);
}

TEST_F(SocketCanConfig, HalFromTheCommandLineIsAppliedBeforeItsSectionIsRead) {
  // --hal socketcan on a sim config without a socketcan section: named as missing.
  const fs::path sim = write("staad.yaml", kValid);
  try {
    loadDaemonConfig(sim, HalBackend::kSocketCan);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("socketcan: missing"));
  }
  // --hal sim on a socketcan config: the sim section is read (and the socketcan one only
  // checked for typos).
  const DaemonConfig c = loadDaemonConfig(write("can.yaml", socketcan("{interface: can0, profile: can/hsr_base.yaml}")), HalBackend::kSim);
  EXPECT_EQ(c.hal, HalBackend::kSim);
  EXPECT_FALSE(c.sim.movers_only);
  EXPECT_DOUBLE_EQ(c.sim.start.x, 1.5);
  // --hal takes the config's names, parsed into the enum on the command line: not "warp".
  EXPECT_EQ(io::valueOf<HalBackend>(kHalBackends, "warp"), std::nullopt);
  EXPECT_EQ(io::valueOf<HalBackend>(kHalBackends, "socketcan"), HalBackend::kSocketCan);
  EXPECT_EQ(toString(HalBackend::kSocketCan), "socketcan");
}

TEST_F(ConfigFiles, DebugFaultsAreOffUnlessAsked) {
  EXPECT_FALSE(loadDaemonConfig(write("staad.yaml", kValid)).debug_faults);
  EXPECT_TRUE(loadDaemonConfig(write("on.yaml", edited("hal: sim", "hal: sim\ndebug: {faults: true}"))).debug_faults);
  EXPECT_FALSE(loadDaemonConfig(write("off.yaml", edited("hal: sim", "hal: sim\ndebug: {faults: false}"))).debug_faults);
}

TEST_F(ConfigFiles, ExtraCycleTimeIsAFaultCueTakenOnlyWithDebugFaults) {
  EXPECT_EQ(loadDaemonConfig(write("staad.yaml", kValid)).debug_extra_cycle_us, 0u);
  const DaemonConfig on =
      loadDaemonConfig(write("on.yaml", edited("hal: sim", "hal: sim\ndebug: {faults: true, extra_cycle_us: 20000}")));
  EXPECT_TRUE(on.debug_faults);
  EXPECT_EQ(on.debug_extra_cycle_us, 20000u);
  EXPECT_EQ(loadDaemonConfig(write("max.yaml", edited("hal: sim", "hal: sim\ndebug: {extra_cycle_us: 1000000, faults: true}")))
                .debug_extra_cycle_us,
            1'000'000u);
  // 0 is no fault: taken without debug.faults.
  EXPECT_EQ(loadDaemonConfig(write("zero.yaml", edited("hal: sim", "hal: sim\ndebug: {extra_cycle_us: 0}"))).debug_extra_cycle_us,
            0u);

  const std::string off = loadError(edited("hal: sim", "hal: sim\ndebug: {extra_cycle_us: 20000}"));
  EXPECT_THAT(off, HasSubstr("debug.extra_cycle_us"));
  EXPECT_THAT(off, HasSubstr("debug.faults: true"));
  EXPECT_THAT(off, HasSubstr("got 20000"));
  const std::string off2 = loadError(edited("hal: sim", "hal: sim\ndebug: {faults: false, extra_cycle_us: 5}"));
  EXPECT_THAT(off2, HasSubstr("debug.extra_cycle_us"));
  EXPECT_THAT(off2, HasSubstr("got 5"));
  const std::string big = loadError(edited("hal: sim", "hal: sim\ndebug: {faults: true, extra_cycle_us: 1000001}"));
  EXPECT_THAT(big, HasSubstr("debug.extra_cycle_us"));
  EXPECT_THAT(big, HasSubstr("0..1000000"));
  EXPECT_THAT(big, HasSubstr("1000001"));
  const std::string negative = loadError(edited("hal: sim", "hal: sim\ndebug: {faults: true, extra_cycle_us: -1}"));
  EXPECT_THAT(negative, HasSubstr("debug.extra_cycle_us"));
  EXPECT_THAT(negative, HasSubstr("-1"));
  const std::string fraction = loadError(edited("hal: sim", "hal: sim\ndebug: {faults: true, extra_cycle_us: 2.5}"));
  EXPECT_THAT(fraction, HasSubstr("debug.extra_cycle_us"));
  EXPECT_THAT(fraction, HasSubstr("2.5"));
}

TEST_F(ConfigFiles, MissingConfigFileNamesThePath) {
  try {
    loadDaemonConfig(dir_ / "absent.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr((dir_ / "absent.yaml").string() + ": config file not found"));
  }
  EXPECT_THROW(loadDaemonConfig(dir_), ConfigError);
}

// ---- the systemd unit: `systemd-analyze verify` accepts it, and the check catches a broken one ----

struct CommandRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs argv with a time limit (a hang fails the test instead of blocking CI).
CommandRun runCommand(const std::vector<std::string>& args, const fs::path& output_file) {
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  CommandRun r;
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || ::dup2(fd, 1) < 0 || ::dup2(fd, 2) < 0) ::_exit(127);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  if (pid < 0) return r;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      r.output = "timed out";
      return r;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  r.output = readFile(output_file);
  return r;
}

bool onPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (!dir.empty() && ::access((fs::path(dir) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

class SystemdUnit : public ConfigFiles {
 protected:
  // The shipped unit with ExecStart pointing at a binary that exists here (verify checks it),
  // and `edit` applied, in a folder of its own (with the real-time drop-in when asked).
  CommandRun verify(const std::string& name, const std::string& from = "", const std::string& to = "",
                    const std::string& dropin = "") {
    const fs::path unit_dir = dir_ / name;
    std::string unit = readFile(test::sourceDir() / "systemd/staad.service");
    const auto exec = unit.find("ExecStart=/usr/bin/staad");
    EXPECT_NE(exec, std::string::npos);
    if (exec != std::string::npos) unit.replace(exec, std::string("ExecStart=/usr/bin/staad").size(), "ExecStart=/bin/true");
    if (!from.empty()) {
      const auto at = unit.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) unit.replace(at, from.size(), to);
    }
    write(name + "/staad.service", unit);
    if (!dropin.empty()) {
      std::string text = readFile(test::sourceDir() / "systemd/staad.service.d" / dropin);
      for (auto at = text.find("ExecStart=/usr/bin/staad"); at != std::string::npos; at = text.find("ExecStart=/usr/bin/staad")) {
        text.replace(at, std::string("ExecStart=/usr/bin/staad").size(), "ExecStart=/bin/true");
      }
      write(name + "/staad.service.d/" + fs::path(dropin).stem().string() + ".conf", text);
    }
    return runCommand({"systemd-analyze", "verify", (unit_dir / "staad.service").string()}, dir_ / (name + ".out"));
  }
};

TEST_F(SystemdUnit, VerifyAcceptsTheUnitAndRejectsBrokenCopies) {
  if (!onPath("systemd-analyze")) GTEST_SKIP() << "systemd-analyze not found on PATH: the unit is not verified here";
  // Can verify work at all in this environment (a container without systemd, say)?
  write("probe/probe.service", "[Service]\nType=simple\nExecStart=/bin/true\n");
  const CommandRun probe = runCommand({"systemd-analyze", "verify", (dir_ / "probe/probe.service").string()}, dir_ / "probe.out");
  if (probe.exit_code != 0) GTEST_SKIP() << "systemd-analyze verify does not work here: " << probe.output;

  const CommandRun ours = verify("ours");
  EXPECT_EQ(ours.exit_code, 0) << ours.output;
  // Warnings ("ignoring") do not change verify's exit code: none may name our unit.
  EXPECT_THAT(ours.output, ::testing::Not(HasSubstr("staad.service"))) << ours.output;

  const CommandRun with_dropin = verify("dropin", "", "", "realtime.conf.example");
  EXPECT_EQ(with_dropin.exit_code, 0) << with_dropin.output;
  EXPECT_THAT(with_dropin.output, ::testing::Not(HasSubstr("staad.service"))) << with_dropin.output;
  const CommandRun with_ros = verify("ros", "", "", "ros.conf");
  EXPECT_EQ(with_ros.exit_code, 0) << with_ros.output;
  EXPECT_THAT(with_ros.output, ::testing::Not(HasSubstr("staad.service"))) << with_ros.output;
  EXPECT_THAT(with_ros.output, ::testing::Not(HasSubstr("ros.conf"))) << with_ros.output;

  // A missing executable fails verify outright ...
  const CommandRun missing = verify("missing", "ExecStart=/bin/true", "ExecStart=/nonexistent/staad");
  EXPECT_NE(missing.exit_code, 0) << missing.output;
  EXPECT_THAT(missing.output, HasSubstr("/nonexistent/staad"));
  // ... a bad value is reported (systemd 252 exits 0 for a value it ignores, so the output
  // is what this check reads).
  const CommandRun bogus = verify("bogus", "Type=notify", "Type=bogus");
  EXPECT_TRUE(bogus.exit_code != 0 || bogus.output.find("staad.service:") != std::string::npos) << bogus.output;
  EXPECT_THAT(bogus.output, HasSubstr("bogus"));
}

// The ROS drop-in widens the sandbox by IP and TCP binding only.
TEST(SystemdUnitText, TheRosDropInAddsTheIpFamiliesAndTcpBindsAndNothingElse) {
  const std::string ros = readFile(test::sourceDir() / "systemd/staad.service.d/ros.conf");
  for (const char* line : {"RestrictAddressFamilies=AF_UNIX AF_CAN AF_NETLINK AF_INET AF_INET6", "SocketBindAllow=tcp",
                           "SocketBindDeny=any", "ExecStart=\nExecStart=/usr/bin/staad --config /etc/staad/staad-hsr-ros.yaml"}) {
    EXPECT_THAT(ros, HasSubstr(line));
  }
  for (const char* widened : {"NoNewPrivileges", "ProtectSystem", "DevicePolicy", "AF_PACKET", "User="}) {
    EXPECT_THAT(ros, ::testing::Not(HasSubstr(widened))) << "the ROS drop-in must not touch " << widened;
  }
}

TEST(SystemdUnitText, HasTheSettingsTheDaemonReliesOn) {
  const std::string unit = readFile(test::sourceDir() / "systemd/staad.service");
  for (const char* line : {"Type=notify", "NotifyAccess=main", "ExecStart=/usr/bin/staad --config /etc/staad/staad.yaml",
                           "WatchdogSec=2s", "Restart=on-failure", "RuntimeDirectory=staad", "LimitRTPRIO=95",
                           "LimitMEMLOCK=infinity", "RestrictAddressFamilies=AF_UNIX AF_CAN AF_NETLINK", "RestrictRealtime=no",
                           "User=staad", "DevicePolicy=closed", "DeviceAllow=char-usb_device rw"}) {
    EXPECT_THAT(unit, HasSubstr(std::string("\n") + line + "\n")) << line;
  }
}

}  // namespace
}  // namespace staa::staad
