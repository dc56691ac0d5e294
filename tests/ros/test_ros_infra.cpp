// The ROS test infrastructure on the real ROS 1 from Debian: a master per test, the simulated
// HSR-B base (odometry rate, the motion a twist gives, the stop 0.5 s after the last command,
// the limits, bad parameters, signals) and the map publisher (the depot grid as map_server
// gives it, checked against staa_map's own reading of the PGM, and the swap on SIGUSR1).
// C++20 without ROS headers: the ROS side is staa-test-ros-probe, whose JSON lines are parsed.

#include "map/ros_import.hpp"
#include "ros/support/ros_master.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace staa::test {
namespace {

using Json = nlohmann::json;
using std::chrono::milliseconds;
using std::chrono::seconds;

const std::string kBase = STAA_TEST_HSRB_BASE_EXE;
const std::string kMapPublisher = STAA_TEST_MAP_PUBLISHER_EXE;
const std::string kProbe = STAA_TEST_ROS_PROBE_EXE;

std::string testName() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }

// A process is gone once its pid names no process (or only a zombie someone else reaps).
bool processGone(pid_t pid, milliseconds timeout = milliseconds(2000)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (::kill(pid, 0) != 0 && errno == ESRCH) return true;
    const std::string stat = [&] {
      FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r");
      if (f == nullptr) return std::string();
      char buf[512] = {};
      const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
      std::fclose(f);
      return std::string(buf, n);
    }();
    const std::size_t paren = stat.rfind(')');
    if (paren != std::string::npos && paren + 2 < stat.size() && stat[paren + 2] == 'Z') return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(milliseconds(10));
  }
}

std::vector<Json> jsonLines(const std::vector<std::string>& lines) {
  std::vector<Json> out;
  for (const std::string& line : lines) {
    if (!line.empty() && line.front() == '{') out.push_back(Json::parse(line));
  }
  return out;
}

// ---- the master --------------------------------------------------------------------------

TEST(RosMaster, StartsOnAFreePortAnswersAndLeavesNoProcessOrFileBehind) {
  pid_t pid = -1;
  std::filesystem::path dir;
  {
    const RosMaster master(testName());
    pid = master.pid();
    dir = master.dir();
    ASSERT_GT(pid, 0);
    EXPECT_GT(master.port(), 0);
    EXPECT_EQ(master.uri(), "http://127.0.0.1:" + std::to_string(master.port()));
    EXPECT_TRUE(std::filesystem::is_directory(dir));
    const std::optional<std::string> answer = master.call("getPid", {"/test"});
    ASSERT_TRUE(answer.has_value());
    EXPECT_NE(answer->find("<int>" + std::to_string(pid) + "</int>"), std::string::npos) << *answer;
    EXPECT_LT(master.startupTime(), seconds(10));
    std::printf("rosmaster answered after %lld ms\n", static_cast<long long>(master.startupTime().count()));
  }
  EXPECT_TRUE(processGone(pid)) << "rosmaster pid " << pid << " still runs";
  EXPECT_FALSE(std::filesystem::exists(dir)) << dir;
}

TEST(RosMaster, TwoAtOnceGetDifferentPortsAndEachAnswersWithItsOwnPid) {
  const RosMaster a(testName() + "-a");
  const RosMaster b(testName() + "-b");
  EXPECT_NE(a.port(), b.port());
  EXPECT_NE(a.dir(), b.dir());
  for (const RosMaster* m : {&a, &b}) {
    const std::optional<std::string> answer = m->call("getPid", {"/test"});
    ASSERT_TRUE(answer.has_value());
    EXPECT_NE(answer->find("<int>" + std::to_string(m->pid()) + "</int>"), std::string::npos) << *answer;
  }
}

TEST(RosMaster, ChildrenGetThisGraphsEnvironmentAndNotTheCallers) {
  ::setenv("ROS_HOSTNAME", "elsewhere.invalid", 1);
  ::setenv("ROS_MASTER_URI", "http://elsewhere.invalid:11311", 1);
  const RosMaster master(testName());
  const RosRun r = master.run("env", {"env"}, seconds(5));
  ::unsetenv("ROS_HOSTNAME");
  ::unsetenv("ROS_MASTER_URI");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = r.lines();
  const auto has = [&](const std::string& entry) { return std::find(lines.begin(), lines.end(), entry) != lines.end(); };
  EXPECT_TRUE(has("ROS_MASTER_URI=" + master.uri())) << r.out;
  EXPECT_TRUE(has("ROS_IP=127.0.0.1")) << r.out;
  EXPECT_TRUE(has("ROS_HOME=" + master.dir().string())) << r.out;
  EXPECT_TRUE(has("ROS_LOG_DIR=" + (master.dir() / "log").string())) << r.out;
  EXPECT_EQ(r.out.find("ROS_HOSTNAME="), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("elsewhere"), std::string::npos) << r.out;
}

TEST(RosMaster, AProcessHandleKillsItsWholeGroup) {
  const RosMaster master(testName());
  pid_t grandchild = -1;
  {
    RosProcess p = master.spawn("sh", {"/bin/sh", "-c", "sleep 60 & echo $!; wait"});
    const std::vector<std::string> lines = p.waitForLines(1, seconds(5));
    ASSERT_EQ(lines.size(), 1u);
    grandchild = std::stoi(lines[0]);
    EXPECT_TRUE(p.alive());
  }
  EXPECT_TRUE(processGone(grandchild)) << "the shell's child " << grandchild << " survived";
}

TEST(RosMaster, RunReportsTheExitCodeAndKillsWhatOutlivesItsTimeout) {
  const RosMaster master(testName());
  const RosRun ok = master.run("true", {"/bin/sh", "-c", "echo out; echo err >&2; exit 3"}, seconds(5));
  EXPECT_EQ(ok.exit_code, 3);
  EXPECT_EQ(ok.out, "out\n");
  EXPECT_EQ(ok.err, "err\n");
  const auto start = std::chrono::steady_clock::now();
  const RosRun slow = master.run("sleep", {"/bin/sleep", "30"}, milliseconds(300));
  EXPECT_FALSE(slow.exit_code.has_value());
  EXPECT_LT(std::chrono::steady_clock::now() - start, seconds(3));
}

// ---- the simulated base ------------------------------------------------------------------

class SimBase : public ::testing::Test {
 protected:
  void SetUp() override {
    master_.emplace(testName());
    base_ = master_->spawn("base", {kBase});
    ASSERT_TRUE(master_->waitForPublisher("/hsrb/odom", seconds(10))) << base_.err();
    ASSERT_TRUE(master_->waitForSubscriber("/hsrb/command_velocity", seconds(10))) << base_.err();
  }
  void TearDown() override {
    base_ = RosProcess();
    master_.reset();
  }

  // odom-log for `seconds_` in the background, once its first message is in.
  RosProcess startOdomLog(double seconds_) {
    RosProcess log = master_->spawn("odom-log", {kProbe, "odom-log", std::to_string(seconds_)});
    EXPECT_GE(log.waitForLines(1, seconds(10)).size(), 1u) << log.err();
    return log;
  }
  static std::vector<Json> finish(RosProcess& log) {
    EXPECT_EQ(log.wait(seconds(15)), 0) << log.err();
    return jsonLines(log.waitForLines(0, milliseconds(0)));
  }
  Json pubTwist(const std::vector<std::string>& args) {
    std::vector<std::string> argv{kProbe, "pub-twist"};
    argv.insert(argv.end(), args.begin(), args.end());
    const RosRun r = master_->run("pub-twist", argv, seconds(15));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::vector<Json> lines = jsonLines(r.lines());
    EXPECT_EQ(lines.size(), 1u) << r.out;
    return lines.empty() ? Json::object() : lines.back();
  }

  std::optional<RosMaster> master_;
  RosProcess base_;
};

TEST_F(SimBase, PublishesOdometryAtFiftyHertzInTheOdomFrameAtTheStartPose) {
  RosProcess log = startOdomLog(2.0);
  const std::vector<Json> odom = finish(log);
  ASSERT_GE(odom.size(), 50u);
  const double span = odom.back()["t"].get<double>() - odom.front()["t"].get<double>();
  const double rate = static_cast<double>(odom.size() - 1) / span;
  EXPECT_NEAR(rate, 50.0, 5.0) << odom.size() << " messages in " << span << " s";
  for (std::size_t i = 0; i < odom.size(); ++i) {
    EXPECT_EQ(odom[i]["frame"], "odom");
    EXPECT_EQ(odom[i]["child"], "base_footprint");
    EXPECT_EQ(odom[i]["x"].get<double>(), 0.0);
    EXPECT_EQ(odom[i]["v"].get<double>(), 0.0);
    if (i > 0) {
      EXPECT_GT(odom[i]["t"].get<double>(), odom[i - 1]["t"].get<double>()) << "stamp " << i;
    }
  }
  // The stamps are ros::Time::now() (wall clock): each arrives within a few ms of its stamp.
  EXPECT_NEAR(odom.back()["recv"].get<double>(), odom.back()["t"].get<double>(), 0.1);
}

TEST_F(SimBase, ATwistOfPointTwoForOneSecondThenABrakeMovesItPointTwoMetresForward) {
  RosProcess log = startOdomLog(3.0);
  const Json sent = pubTwist({"0.2", "0", "1.0", "--brake"});
  const std::vector<Json> odom = finish(log);
  ASSERT_GE(odom.size(), 100u);
  const double first = sent["first"].get<double>();
  ASSERT_LT(odom.front()["t"].get<double>(), first);
  double x0 = 0.0, top_speed = 0.0;
  for (const Json& o : odom) {
    if (o["t"].get<double>() < first) x0 = o["x"].get<double>();
    top_speed = std::max(top_speed, o["v"].get<double>());
  }
  // Up to speed in 0.2 / 1.67 = 0.12 s and down in as long: the ramps lose and gain the same
  // 0.012 m, so the distance is the command's 0.2 m up to the delivery jitter of its ends.
  const Json& last = odom.back();
  EXPECT_NEAR(last["x"].get<double>() - x0, 0.2, 0.03);
  EXPECT_NEAR(last["y"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(last["theta"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(top_speed, 0.2, 1e-9);
  EXPECT_EQ(last["v"].get<double>(), 0.0);
}

TEST_F(SimBase, StopsByItselfHalfASecondAfterTheLastCommand) {
  RosProcess log = startOdomLog(3.5);
  const Json sent = pubTwist({"0.2", "0", "1.0"});  // no brake: the base's timeout stops it
  const std::vector<Json> odom = finish(log);
  const double last_cmd = sent["last"].get<double>();
  double stopped_at = -1.0, x0 = 0.0;
  bool moved = false;
  for (const Json& o : odom) {
    const double t = o["t"].get<double>(), v = o["v"].get<double>();
    if (t < sent["first"].get<double>()) x0 = o["x"].get<double>();
    moved = moved || v > 0.0;
    // Still at full speed until the timeout nears: it does not stop early.
    if (t > last_cmd + 0.05 && t < last_cmd + 0.45) {
      EXPECT_NEAR(v, 0.2, 1e-9) << "at " << t - last_cmd << " s";
    }
    if (moved && v == 0.0 && stopped_at < 0.0) stopped_at = t;
  }
  ASSERT_GT(stopped_at, 0.0) << "never stopped";
  // 0.5 s of timeout, 0.12 s of deceleration, a cycle (20 ms) of each's detection.
  EXPECT_GT(stopped_at - last_cmd, 0.5);
  EXPECT_LT(stopped_at - last_cmd, 0.5 + 0.2 / 1.67 + 0.1);
  // The command's 1 s and the 0.5 s the base holds it: 0.3 m.
  EXPECT_NEAR(odom.back()["x"].get<double>() - x0, 0.3, 0.04);
}

TEST_F(SimBase, HoldsACommandToTheHsrsSpeedLimits) {
  RosProcess log = startOdomLog(2.0);
  pubTwist({"1.0", "-3.0", "0.8", "--vy", "0.1", "--brake"});
  const std::vector<Json> odom = finish(log);
  double top_v = 0.0, top_w = 0.0;
  for (const Json& o : odom) {
    top_v = std::max(top_v, o["v"].get<double>());
    top_w = std::min(top_w, o["w"].get<double>());
    EXPECT_EQ(o["vy"].get<double>(), 0.0);  // the sideways speed is not driven
  }
  EXPECT_NEAR(top_v, 0.34, 1e-9);
  EXPECT_NEAR(top_w, -1.8, 1e-9);
  EXPECT_LT(odom.back()["theta"].get<double>(), -0.5);  // it turned clockwise
}

TEST_F(SimBase, ExitsZeroOnSigintAndOnSigterm) {
  base_.kill(SIGINT);
  EXPECT_EQ(base_.wait(seconds(5)), 0) << base_.err();
  RosProcess second = master_->spawn("base-2", {kBase, "__name:=base_two"});
  ASSERT_TRUE(master_->waitForPublisher("/hsrb/odom", seconds(10)));
  std::this_thread::sleep_for(milliseconds(300));
  second.kill(SIGTERM);
  EXPECT_EQ(second.wait(seconds(5)), 0) << second.err();
  EXPECT_NE(second.out().find("commands received: 0"), std::string::npos) << second.out();
}

TEST(SimBaseParams, ANegativeRateIsFatalWithExitTwoNamingTheParameter) {
  const RosMaster master(testName());
  const RosRun r = master.run("base", {kBase, "_rate:=-1"}, seconds(10));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rate = -1"), std::string::npos) << r.err;
  // Another node name: private parameters stay on the master's parameter server after a run.
  const RosRun s = master.run("base-2", {kBase, "__name:=base_two", "_max_acc:=0"}, seconds(10));
  EXPECT_EQ(s.exit_code, 2);
  EXPECT_NE(s.err.find("max_acc = 0"), std::string::npos) << s.err;
}

// ---- the map publisher -------------------------------------------------------------------

// What map_server makes of the map (staa_map's reading of the same YAML and PGM).
struct ExpectedGrid {
  OccupancyGrid grid;
  long occupied = 0, free = 0, unknown = 0;
  std::string fnv1a;
};

ExpectedGrid expectedGrid(const std::filesystem::path& yaml) {
  ExpectedGrid e;
  e.grid = loadOccupancyGrid(yaml);
  std::uint64_t h = 14695981039346656037ull;
  for (const std::uint8_t c : e.grid.cells) {
    const std::int8_t value = c == OccupancyGrid::kOccupied ? 100 : c == OccupancyGrid::kFree ? 0 : -1;
    (c == OccupancyGrid::kOccupied ? e.occupied : c == OccupancyGrid::kFree ? e.free : e.unknown) += 1;
    h ^= static_cast<std::uint8_t>(value);
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  e.fnv1a = hex;
  return e;
}

void expectGrid(const Json& m, const ExpectedGrid& e) {
  EXPECT_EQ(m["frame"], "map");
  EXPECT_EQ(m["width"].get<int>(), e.grid.width);
  EXPECT_EQ(m["height"].get<int>(), e.grid.height);
  EXPECT_NEAR(m["resolution"].get<double>(), e.grid.resolution, 1e-7);  // a float in the message
  EXPECT_DOUBLE_EQ(m["origin"][0].get<double>(), e.grid.origin.x);
  EXPECT_DOUBLE_EQ(m["origin"][1].get<double>(), e.grid.origin.y);
  EXPECT_NEAR(m["origin"][2].get<double>(), e.grid.origin.theta, 1e-12);
  EXPECT_EQ(m["occupied"].get<long>(), e.occupied);
  EXPECT_EQ(m["free"].get<long>(), e.free);
  EXPECT_EQ(m["unknown"].get<long>(), e.unknown);
  EXPECT_EQ(m["other"].get<long>(), 0);
  EXPECT_EQ(m["fnv1a"], e.fnv1a) << "the cells differ (row order or classification)";
  EXPECT_GT(m["t"].get<double>(), 0.0);
  EXPECT_GT(m["load_time"].get<double>(), 0.0);
}

std::filesystem::path rosMap(const std::string& name) { return sharedDir() / "maps" / "ros" / (name + ".yaml"); }

TEST(MapPublisher, PublishesTheDepotMapAsMapServerWould) {
  const std::filesystem::path depot = rosMap("depot");
  STAA_REQUIRE_SHARED_FILE(depot);
  const ExpectedGrid e = expectedGrid(depot);
  // The depot as its README describes it: 604 x 307 cells of 0.05 m, walls and shelves.
  ASSERT_EQ(e.grid.width, 604);
  ASSERT_EQ(e.grid.height, 307);
  ASSERT_GT(e.occupied, 1000);
  const RosMaster master(testName());
  RosProcess publisher = master.spawn("map-publisher", {kMapPublisher, depot.string()});
  const RosRun r = master.run("map-watch", {kProbe, "map-watch", "1"}, seconds(15));
  ASSERT_EQ(r.exit_code, 0) << r.err << publisher.err();
  const std::vector<Json> maps = jsonLines(r.lines());
  ASSERT_EQ(maps.size(), 1u) << r.out;
  expectGrid(maps[0], e);
  EXPECT_TRUE(publisher.alive());
}

TEST(MapPublisher, SwapsInTheSecondMapOnSigusr1AndLatchesIt) {
  const std::filesystem::path depot = rosMap("depot"), sandbox = rosMap("tb3_sandbox");
  STAA_REQUIRE_SHARED_FILE(depot);
  STAA_REQUIRE_SHARED_FILE(sandbox);
  const RosMaster master(testName());
  RosProcess publisher = master.spawn("map-publisher", {kMapPublisher, depot.string(), sandbox.string()});
  RosProcess watch = master.spawn("map-watch", {kProbe, "map-watch", "2", "--timeout", "15"});
  ASSERT_GE(watch.waitForLines(1, seconds(15)).size(), 1u) << watch.err() << publisher.err();
  publisher.kill(SIGUSR1);
  const std::vector<Json> maps = jsonLines(watch.waitForLines(2, seconds(10)));
  ASSERT_EQ(maps.size(), 2u) << watch.err();
  expectGrid(maps[0], expectedGrid(depot));
  const ExpectedGrid e = expectedGrid(sandbox);
  expectGrid(maps[1], e);
  EXPECT_GT(maps[1]["t"].get<double>(), maps[0]["t"].get<double>());
  EXPECT_EQ(watch.wait(seconds(5)), 0);
  // A subscriber that comes later gets the map now latched: the second.
  const RosRun late = master.run("map-watch-late", {kProbe, "map-watch", "1"}, seconds(15));
  ASSERT_EQ(late.exit_code, 0) << late.err;
  const std::vector<Json> latched = jsonLines(late.lines());
  ASSERT_EQ(latched.size(), 1u);
  EXPECT_EQ(latched[0]["fnv1a"], e.fnv1a);
}

TEST(MapPublisher, AMapThatCannotBeReadIsFatalWithExitTwoNamingTheFile) {
  const RosMaster master(testName());
  const std::filesystem::path missing = master.dir() / "no-such-map.yaml";
  const RosRun r = master.run("map-publisher", {kMapPublisher, missing.string()}, seconds(10));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;
}

}  // namespace
}  // namespace staa::test
