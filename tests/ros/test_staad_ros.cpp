// staad over the real ROS 1 from Debian (issue 17): each test starts its own master on a free
// port, the simulated HSR-B base (staa-test-hsrb-base), map_server's stand-in with the real
// depot map (staa-test-map-publisher) and staad with hal: ros and map: ros, then acts as a ROS
// navigation user would (staa-test-nav-client: the move_base action, RViz's goal topic,
// localization fixes, bad odometry, markers, diagnostics) and reads staad's status on its
// control socket. No ROS header here: the ROS side is in the programs.
#include "map/ros_import.hpp"
#include "read_file.hpp"
#include "ros/support/ros_master.hpp"
#include "rt/unix_socket.hpp"
#include "shared_dir.hpp"
#include "visibility_reference.hpp"
#include "blocked_cycles.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>
#include <nlohmann/json.hpp>

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace staa::test {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using ::testing::HasSubstr;
using std::chrono::milliseconds;
using std::chrono::seconds;

const std::string kStaad = STAA_STAAD_EXE;
const std::string kBase = STAA_TEST_HSRB_BASE_EXE;
const std::string kMapPublisher = STAA_TEST_MAP_PUBLISHER_EXE;
const std::string kNav = STAA_TEST_NAV_CLIENT_EXE;

std::string testName() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }

// A free spot of the depot (0.5 m from every wall) and goals a short drive from it.
constexpr double kStartX = 10.0, kStartY = 2.25;

fs::path depotYaml() { return sharedDir() / "maps/ros/depot.yaml"; }

// The depot with a block of occupied pixels over [x0, x1] x [y0, y1] (map metres): a second
// map to swap in. Written beside the test's other files.
fs::path depotWithBlock(const fs::path& dir, double x0, double y0, double x1, double y1) {
  const RosMapInfo info = loadRosMapInfo(depotYaml());
  PgmImage image = loadPgm(info.image);
  const double res = info.resolution;
  for (int row = 0; row < image.height; ++row) {
    const double y = info.origin.y + (image.height - 1 - row + 0.5) * res;
    for (int col = 0; col < image.width; ++col) {
      const double x = info.origin.x + (col + 0.5) * res;
      if (x >= x0 && x <= x1 && y >= y0 && y <= y1) image.pixels[static_cast<std::size_t>(row) * image.width + col] = 0;
    }
  }
  const fs::path pgm = dir / "depot-block.pgm";
  {
    std::ofstream out(pgm, std::ios::binary);
    out << "P5\n" << image.width << " " << image.height << "\n255\n";
    for (std::uint16_t p : image.pixels) out.put(static_cast<char>(p));
  }
  std::string yaml = readFile(depotYaml());
  yaml.replace(yaml.find("depot.pgm"), 9, pgm.string());
  const fs::path y = dir / "depot-block.yaml";
  std::ofstream(y) << yaml;
  return y;
}

class StaadOverRos : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(depotYaml())) {
      GTEST_SKIP() << "shared input " << depotYaml() << " not found (run from a checkout with ../shared beside it)";
    }
    master_.emplace(testName());
    dir_ = master_->dir();
    socket_ = (dir_ / "staad.sock").string();
  }

  // The config: hal ros, map ros, no camera; `extra` appended (a ros section, say).
  fs::path writeConfig(const std::string& ros_section = "", const std::string& budget = "{ms: 19}") {
    const fs::path p = dir_ / "staad.yaml";
    std::ofstream(p) << "format: staad-config/1\n"
                     << "robot: " << (sourceDir() / "config/robots/hsr.yaml").string() << "\n"
                     << "map: ros\nhal: ros\nobstacles: none\n"
                     << "budget: " << budget << "\n"
                     << "threads: {control: {priority: 0}, base: {priority: 0}, perception: {priority: 0}}\n"
                     << "socket: {path: " << socket_ << "}\n"
                     << "memory: {heap_prefault_mb: 16}\n"
                     << "ros:\n  master_wait_s: 5\n  map: {wait_s: 20}\n"
                     << ros_section;
    return p;
  }

  void startBase(double x = kStartX, double y = kStartY, double theta = 0.0) {
    base_.emplace(master_->spawn("base", {kBase, "_x:=" + std::to_string(x), "_y:=" + std::to_string(y),
                                          "_theta:=" + std::to_string(theta)}));
    ASSERT_TRUE(master_->waitForPublisher("/hsrb/odom", seconds(10))) << base_->err();
  }
  void startMap(const std::vector<std::string>& maps) {
    std::vector<std::string> argv{kMapPublisher};
    argv.insert(argv.end(), maps.begin(), maps.end());
    map_.emplace(master_->spawn("map", argv));
    ASSERT_TRUE(master_->waitForPublisher("/map", seconds(10))) << map_->err();
  }
  // staad, up once its control socket answers a status request.
  void startStaad(const fs::path& config, const std::vector<std::string>& extra_args = {}) {
    std::vector<std::string> argv{kStaad, "--config", config.string()};
    argv.insert(argv.end(), extra_args.begin(), extra_args.end());
    staad_.emplace(master_->spawn("staad", argv));
    const auto deadline = std::chrono::steady_clock::now() + seconds(30);
    while (!status()) {
      ASSERT_TRUE(staad_->alive()) << "staad exited: " << staad_->err();
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "staad did not come up: " << staad_->err();
      std::this_thread::sleep_for(milliseconds(50));
    }
  }

  std::optional<Json> status() {
    try {
      rt::UnixLineClient client(socket_, 2 * rt::kNanosPerSecond);
      client.send("{\"cmd\":\"status\"}\n");
      const Json j = Json::parse(client.receiveLine(1 << 20), nullptr, false);
      if (j.is_discarded() || !j.contains("status")) return std::nullopt;
      return j["status"];
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  template <typename Done>
  std::optional<Json> pollStatus(Done done, milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::optional<Json> last;
    while (std::chrono::steady_clock::now() < deadline) {
      last = status();
      if (last && done(*last)) return last;
      std::this_thread::sleep_for(milliseconds(30));
    }
    ADD_FAILURE() << "status never matched; last: " << (last ? last->dump() : "none") << "\nstaad: "
                  << (staad_ ? staad_->err() : "");
    return std::nullopt;
  }

  // staa-test-nav-client's result line.
  Json nav(const std::vector<std::string>& args, milliseconds timeout = milliseconds(90'000)) {
    std::vector<std::string> argv{kNav};
    argv.insert(argv.end(), args.begin(), args.end());
    const RosRun r = master_->run("nav", argv, timeout);
    EXPECT_EQ(r.exit_code, 0) << args[0] << ": " << r.err << "\nstaad: " << (staad_ ? staad_->err() : "");
    const auto lines = r.lines();
    if (lines.empty()) return Json();
    return Json::parse(lines.back(), nullptr, false);
  }

  static double distance(const Json& s, double x, double y) {
    return std::hypot(s["pose"][0].get<double>() - x, s["pose"][1].get<double>() - y);
  }

  std::optional<RosMaster> master_;
  fs::path dir_;
  std::string socket_;
  std::optional<RosProcess> base_, map_, staad_;
};

TEST_F(StaadOverRos, AMoveBaseGoalSucceedsAndOneFromTheGoalTopicIsReached) {
  startMap({depotYaml().string()});
  startBase();
  startStaad(writeConfig());
  const Json idle = *status();
  EXPECT_EQ(idle["state"], "idle");
  EXPECT_NEAR(idle["pose"][0].get<double>(), kStartX, 0.05) << "the pose is the base's odometry";
  EXPECT_TRUE(idle["ros"]["master"].get<bool>());

  const Json done = nav({"move-base", "12.0", "2.0", "0", "--timeout", "60"});
  EXPECT_EQ(done["state"], "SUCCEEDED") << done.dump();
  EXPECT_THAT(done["text"].get<std::string>(), HasSubstr("reached"));
  EXPECT_GT(done["feedbacks"].get<int>(), 10) << "feedback with the pose while driving";
  EXPECT_NEAR(done["last_feedback"][0].get<double>(), 12.0, 0.3);
  const Json at = *status();
  EXPECT_EQ(at["state"], "reached");
  EXPECT_LE(distance(at, 12.0, 2.0), 0.2 + 1e-6);

  // RViz's 2D Nav Goal (like `rostopic pub /move_base_simple/goal`).
  nav({"simple-goal", "10.5", "2.5", "3.14159"});
  const auto back = pollStatus(
      [](const Json& s) { return s["goal_id"] == 2 && s["state"] == "reached"; }, milliseconds(60'000));
  ASSERT_TRUE(back);
  EXPECT_LE(distance(*back, 10.5, 2.5), 0.2 + 1e-6);
  EXPECT_EQ((*back)["ros"]["goals_in"], 2);
  EXPECT_EQ((*back)["rt_allocations"], 0);
  // The twists went out at the control rate, each traced to the odometry it was planned on.
  EXPECT_GT((*back)["ros"]["twists_out"].get<int>(), 300);
  EXPECT_GT((*back)["ros"]["odometry_to_twist"]["count"].get<int>(), 300);
  // Planned on odometry younger than staad's own staleness limit (limits.odometry_timeout_s,
  // 0.1 s by default): a contract, not a timing target (the machine may be shared: the p50
  // was 74 ms with a two-core experiment beside the test).
  const double age_p50 = (*back)["ros"]["odometry_to_twist"]["p50_us"].get<double>();
  EXPECT_GT(age_p50, 0.0);
  constexpr double kOdometryTimeoutUs = 100'000.0;  // the default; writeConfig leaves it
  EXPECT_LT(age_p50, kOdometryTimeoutUs);
}

TEST_F(StaadOverRos, ACancelStopsTheRobotAndAnUnreachableGoalAbortsWithItsReason) {
  startMap({depotYaml().string()});
  startBase();
  startStaad(writeConfig());
  const Json cancelled = nav({"move-base", "12.0", "2.0", "0", "--cancel-after", "3"});
  EXPECT_EQ(cancelled["state"], "PREEMPTED") << cancelled.dump();
  EXPECT_THAT(cancelled["text"].get<std::string>(), HasSubstr("cancelled"));
  const auto stopped = pollStatus(
      [](const Json& s) { return s["state"] == "stopped" && std::abs(s["velocity"][0].get<double>()) < 0.01; },
      milliseconds(3000));
  ASSERT_TRUE(stopped);
  EXPECT_GT((*stopped)["pose"][0].get<double>(), kStartX + 0.1) << "it had driven before the cancel";

  // A goal inside one of the depot's walls: unreachable in the map from /map (on an empty map
  // it would be reached), aborted with the reason.
  const PolygonMap depot = importRosMap(depotYaml(), ImportOptions{});
  std::optional<Vec2> in_wall;
  for (double r = 0.5; r < 8.0 && !in_wall; r += 0.01) {  // walls are a few cells thick
    for (int k = 0; k < 16 && !in_wall; ++k) {
      const Vec2 p{kStartX + r * std::cos(k * M_PI / 8), kStartY + r * std::sin(k * M_PI / 8)};
      if (p.x() > 0.5 && p.y() > 0.5 && !referencePointFree(p, depot.obstacles)) in_wall = p;
    }
  }
  ASSERT_TRUE(in_wall);
  const Json aborted = nav({"move-base", std::to_string(in_wall->x()), std::to_string(in_wall->y()), "0"});
  EXPECT_EQ(aborted["state"], "ABORTED") << aborted.dump();
  EXPECT_THAT(aborted["text"].get<std::string>(), HasSubstr("unreachable"));
  // A goal in a frame tf does not know: refused with the reason.
  const Json refused = nav({"move-base", "1", "1", "0", "--frame", "no_such_frame"});
  EXPECT_EQ(refused["state"], "ABORTED");
  EXPECT_THAT(refused["text"].get<std::string>(), HasSubstr("no transform from the goal's frame 'no_such_frame'"));
}

TEST_F(StaadOverRos, TheMapFromTheTopicIsPlannedOnAndASecondMapSwapsInWhileDriving) {
  // The second map blocks a square at (11.5, 2.25) in the way of the first goal.
  const fs::path second = depotWithBlock(dir_, 11.25, 2.0, 11.75, 2.5);
  startMap({depotYaml().string(), second.string()});
  startBase();
  startStaad(writeConfig());
  const PolygonMap depot = importRosMap(depotYaml(), ImportOptions{});
  // Drive, swap the map in on the way, and log every pose: none inside the depot's walls.
  nav({"simple-goal", "13.0", "2.25", "0"});
  ASSERT_TRUE(pollStatus([](const Json& s) { return s["state"] == "driving"; }, milliseconds(5000)));
  std::this_thread::sleep_for(milliseconds(1500));
  map_->kill(SIGUSR1);
  const auto swapped = pollStatus([](const Json& s) { return s["ros"]["maps"]["applied"] == 1; }, milliseconds(20'000));
  ASSERT_TRUE(swapped);
  EXPECT_EQ((*swapped)["ros"]["maps"]["in"], 2);
  EXPECT_EQ((*swapped)["state"], "driving") << "the goal is kept across the swap";
  std::vector<Vec2> driven;
  const auto reached = pollStatus(
      [&](const Json& s) {
        driven.push_back({s["pose"][0].get<double>(), s["pose"][1].get<double>()});
        return s["state"] == "reached";
      },
      milliseconds(60'000));
  ASSERT_TRUE(reached);
  ASSERT_GT(driven.size(), 20u);
  for (const Vec2& p : driven) {
    EXPECT_TRUE(referencePointFree(p, depot.obstacles)) << "in a wall at " << p.transpose();
    // Around the block of the second map, by the robot's radius (0.215 m): the distance from
    // the block, rounded at its corners as the round base's clearance is.
    const double dx = std::max({11.25 - p.x(), 0.0, p.x() - 11.75}), dy = std::max({2.0 - p.y(), 0.0, p.y() - 2.5});
    EXPECT_GT(std::hypot(dx, dy), 0.2) << "through the second map's block at " << p.transpose();
  }
  EXPECT_THAT(staad_->err(), HasSubstr("map swapped in (sequence): 2"));
}

TEST_F(StaadOverRos, TheBaseKilledIsAStaleOdometryFaultThatClearsWhenItComesBack) {
  startMap({depotYaml().string()});
  startBase();
  startStaad(writeConfig("  diagnostics: {rate_hz: 5}\n"));
  base_->kill(SIGKILL);
  base_->wait(milliseconds(2000));
  const auto fault = pollStatus([](const Json& s) { return s["state"] == "fault"; }, milliseconds(2000));
  ASSERT_TRUE(fault);
  EXPECT_EQ((*fault)["fault"], "stale_odometry");
  EXPECT_EQ((*fault)["command"][0], 0.0) << "braking";
  const Json diag = nav({"diagnostics", "--until", "fault=stale_odometry"});
  EXPECT_EQ(diag["level"], 2);
  EXPECT_THAT(diag["message"].get<std::string>(), HasSubstr("stale_odometry"));
  EXPECT_EQ(diag["values"]["rt_allocations"], "0");

  startBase(kStartX, kStartY);
  const auto clear = pollStatus([](const Json& s) { return s["state"] == "idle" && s["fault"].is_null(); },
                                milliseconds(5000));
  ASSERT_TRUE(clear);
  const Json ok = nav({"diagnostics", "--until", "fault=none"});
  EXPECT_EQ(ok["level"], 0);
}

TEST_F(StaadOverRos, BadOdometryIsCountedDroppedAndBrakesAndALocalizationJumpIsApplied) {
  startMap({depotYaml().string()});
  startBase();
  startStaad(writeConfig());
  for (const char* kind : {"nan", "inf", "back"}) nav({"bad-odom", kind, "5"});
  // Each message judged as it arrives (a subscriber queue of 1 may drop one of them).
  const auto counted = pollStatus([](const Json& s) { return s["base"]["bad_frames"].get<int>() >= 12; },
                                  milliseconds(3000));
  ASSERT_TRUE(counted);
  const Json s = *status();
  EXPECT_NEAR(s["pose"][0].get<double>(), kStartX, 0.05) << "the bad samples moved nothing";
  EXPECT_TRUE(s["fault"].is_null()) << "the next good sample cleared the fault";
  EXPECT_THAT(staad_->err(), HasSubstr("base reports a fault, braking: odometry invalid"));
  EXPECT_THAT(staad_->err(), HasSubstr("base reports a fault, braking: odometry stamp went back"));

  // Localization says the robot is 0.5 m further along y: applied at a cycle boundary, the
  // jump in the status.
  nav({"pose", std::to_string(kStartX), std::to_string(kStartY + 0.5), "0"});
  const auto jumped = pollStatus([](const Json& j) { return j["base"]["localization"]["fixes"] == 1; },
                                 milliseconds(3000));
  ASSERT_TRUE(jumped);
  EXPECT_NEAR((*jumped)["base"]["localization"]["last_jump_m"].get<double>(), 0.5, 0.02);
  EXPECT_NEAR((*jumped)["pose"][1].get<double>(), kStartY + 0.5, 0.02);
}

// localization.source: tf: map -> base_footprint through a map -> odom transform (AMCL's) and
// the base's odom -> base_footprint; and a goal given in the odom frame, transformed into map.
TEST_F(StaadOverRos, LocalizationFromTfAndAGoalInTheOdomFrame) {
  startMap({depotYaml().string()});
  startBase(0.0, 0.0, 0.0);  // odometry starts at the odom frame's origin
  // One lookup a second: every lookup after the first is a fix with no jump, so at 20 Hz a
  // status read 30 ms after the first fix could already show a later one's jump of 0.
  startStaad(writeConfig("  localization: {source: tf, tf_hz: 1}\n"));
  EXPECT_NEAR((*status())["pose"][0].get<double>(), 0.0, 0.01) << "no transform yet: the odometry as it is";
  // The odom frame sits at the depot's start spot.
  RosProcess tf = master_->spawn("tf", {kNav, "static-tf", "map", "odom", std::to_string(kStartX), std::to_string(kStartY),
                                        "0", "60"});
  const auto located = pollStatus([](const Json& s) { return s["base"]["localization"]["fixes"].get<int>() >= 1; },
                                  milliseconds(5000));
  ASSERT_TRUE(located) << tf.err();
  EXPECT_NEAR((*located)["pose"][0].get<double>(), kStartX, 0.01);
  EXPECT_NEAR((*located)["pose"][1].get<double>(), kStartY, 0.01);
  EXPECT_NEAR((*located)["base"]["localization"]["last_jump_m"].get<double>(), std::hypot(kStartX, kStartY), 0.01);
  // 1.5 m ahead in the odom frame is (11.5, 2.25) in the map.
  const Json done = nav({"move-base", "1.5", "0", "0", "--frame", "odom"});
  EXPECT_EQ(done["state"], "SUCCEEDED") << done.dump();
  const Json at = *status();
  EXPECT_LE(distance(at, kStartX + 1.5, kStartY), 0.2 + 1e-6);
  EXPECT_DOUBLE_EQ(at["goal"][0].get<double>(), kStartX + 1.5);
}

TEST_F(StaadOverRos, MarkersParseABagRecordsEveryTopicAndAThousandCyclesAllocateNothing) {
  startMap({depotYaml().string()});
  startBase();
  startStaad(writeConfig("  markers: {rate_hz: 10, tree_hz: 2}\n"));
  const fs::path bag = dir_ / "run.bag";
  // The recorder itself, not the `rosbag record` wrapper: on SIGINT the wrapper exits a quarter
  // of a second later while its child may still be closing the bag (run.bag.active).
  const char* const recorder = "/usr/lib/rosbag/record";
  ASSERT_TRUE(fs::exists(recorder)) << recorder << " (Debian's rosbag package) is missing";
  RosProcess record = master_->spawn("rosbag", {recorder, "-O", bag.string(), "/hsrb/command_velocity",
                                                "/hsrb/odom", "/map", "/staad/markers", "/diagnostics",
                                                "/move_base/status", "/move_base/result", "/move_base/feedback"});
  ASSERT_TRUE(master_->waitForSubscriber("/staad/markers", seconds(10)));
  // Back and forth for 1,000 control cycles (34 s), with RViz's markers and the tree.
  const auto t0 = std::chrono::steady_clock::now();
  std::thread drive([&] {
    nav({"move-base", "12.0", "2.0", "0"});
    nav({"move-base", "10.5", "2.25", "3.14159"});
  });
  const Json m = nav({"markers", "--with", "search_tree", "--timeout", "20"});
  for (const char* ns : {"global_path", "trajectory", "subgoal", "footprint", "search_tree"}) {
    EXPECT_TRUE(m["namespaces"].contains(ns)) << ns << " in " << m.dump();
  }
  EXPECT_EQ(m["namespaces"]["footprint"], 17) << "the 16-gon, closed";
  EXPECT_FALSE(m["namespaces"].contains("<no frame>"));
  drive.join();
  const auto thousand = pollStatus([](const Json& s) { return s["cycle"]["count"].get<int>() >= 1000; },
                                   milliseconds(60'000));
  ASSERT_TRUE(thousand);
  EXPECT_EQ((*thousand)["rt_allocations"], 0);
  EXPECT_TRUE(staa::test::noBlockedCycle(*thousand)) << "a control cycle blocked (the ROS bridge must never make it wait)";
  EXPECT_TRUE(staa::test::noBlockedCycle((*thousand)["threads"]["base"])) << "a base cycle blocked";
  std::cout << "1,000 cycles after " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
            << " s: " << (*thousand)["cycle"].dump() << "; odometry to twist " << (*thousand)["ros"]["odometry_to_twist"].dump()
            << "; faulted cycles " << (*thousand)["faulted_cycles"] << "\n";
  record.kill(SIGINT);
  const std::optional<int> recorded = record.wait(milliseconds(30'000));
  ASSERT_TRUE(recorded.has_value()) << "the recorder did not close the bag within 30 s: " << record.err();
  ASSERT_TRUE(fs::exists(bag)) << "exit code " << *recorded << ": " << record.err();
  const RosRun info = master_->run("baginfo", {"/usr/bin/rosbag", "info", "--yaml", "--key", "topics", bag.string()},
                                   milliseconds(20'000));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  for (const char* topic : {"/hsrb/command_velocity", "/hsrb/odom", "/map", "/staad/markers", "/diagnostics",
                            "/move_base/status", "/move_base/result", "/move_base/feedback"}) {
    EXPECT_THAT(info.out, HasSubstr(std::string("topic: ") + topic)) << info.out;
  }
}

// camera.backend: ros through staad: frames from the HSR's depth topics keep the obstacle
// input fresh; wrong encodings and sizes are counted and dropped, and the robot is held
// (stale obstacles) until good frames come again.
TEST_F(StaadOverRos, DepthImagesOverRosFeedPerceptionAndBadOnesAreCountedAndDropped) {
  startMap({depotYaml().string()});
  startBase();
  std::string config = readFile(writeConfig());
  config.replace(config.find("obstacles: none"), 15, "obstacles: depth\ncamera: {backend: ros}");
  const fs::path file = dir_ / "camera.yaml";
  std::ofstream(file) << config;
  startStaad(file);
  const auto waiting = pollStatus([](const Json& s) { return s["fault"] == "stale_obstacles"; }, milliseconds(3000));
  ASSERT_TRUE(waiting) << "no frames yet: held";
  // Frames flowing: the fault clears while they come (16UC1 millimetres, then 32FC1 metres).
  for (const char* encoding : {"16UC1", "32FC1"}) {
    RosProcess images = master_->spawn(std::string("images-") + encoding,
                                       {kNav, "depth-images", encoding, "640", "480", "3"});
    const auto clear = pollStatus([](const Json& s) { return s["fault"].is_null(); }, milliseconds(2500));
    ASSERT_TRUE(clear) << encoding << " frames feed perception: " << images.err();
    EXPECT_EQ((*clear)["ros"]["images"]["dropped"], 0);
    EXPECT_EQ(images.wait(milliseconds(10'000)), 0) << images.err();
  }
  EXPECT_GT((*status())["ros"]["images"]["in"].get<int>(), 60);
  nav({"depth-images", "rgb8", "640", "480", "1"});
  nav({"depth-images", "16UC1", "320", "240", "1"});
  const Json bad = *status();
  EXPECT_GE(bad["ros"]["images"]["dropped"].get<int>(), 40);
  EXPECT_EQ(bad["fault"], "stale_obstacles") << "bad frames do not count as fresh: the robot is held";
  EXPECT_EQ(bad["command"][0], 0.0);
  EXPECT_EQ(bad["rt_allocations"], 0);
}

// scanner.backend: ros through staad: the base's LaserScans on /hsrb/base_scan are perceived
// with the depth frames (the status counts them and their returns); bad scans are counted by
// reason and dropped, and the frames go on alone; nothing is allocated in real time.
TEST_F(StaadOverRos, LaserScansFeedPerceptionWithTheFramesAndBadOnesAreDropped) {
  startMap({depotYaml().string()});
  startBase();
  std::string config = readFile(writeConfig());
  config.replace(config.find("obstacles: none"), 15, "obstacles: depth\ncamera: {backend: ros}\nscanner: {backend: ros}");
  const fs::path file = dir_ / "scanner.yaml";
  std::ofstream(file) << config;
  startStaad(file);
  const auto before = pollStatus([](const Json& s) { return !s["scanner"].is_null(); }, milliseconds(3000));
  ASSERT_TRUE(before);
  EXPECT_EQ((*before)["scanner"]["backend"], "ros");
  EXPECT_EQ((*before)["scanner"]["scans_used"], 0);

  // Frames and scans flowing together: each frame is perceived with the newest scan (every
  // beam returning 1.5 m away: points in the grid).
  {
    RosProcess images = master_->spawn("images", {kNav, "depth-images", "16UC1", "640", "480", "4"});
    RosProcess scans = master_->spawn("scans", {kNav, "laser-scans", "good", "4", "--range", "1.5"});
    const auto used = pollStatus(
        [](const Json& s) { return s["scanner"]["scans_used"].get<int>() >= 30 && s["fault"].is_null(); },
        milliseconds(4000));
    ASSERT_TRUE(used) << images.err() << scans.err();
    EXPECT_GT((*used)["scanner"]["scan_points"].get<int>(), 0);
    EXPECT_GT((*used)["ros"]["scans"]["in"].get<int>(), 30);
    EXPECT_EQ((*used)["ros"]["scans"]["dropped"], 0);
    EXPECT_EQ(images.wait(milliseconds(10'000)), 0) << images.err();
    EXPECT_EQ(scans.wait(milliseconds(10'000)), 0) << scans.err();
  }
  const Json good = *status();
  // Frames and scans started together: at most a few frames came before the first scan.
  EXPECT_LE(good["scanner"]["frames_without_scan"].get<int>(), 5) << "scans came within a moment of the frames";

  // Bad scans beside good frames: each counted under its reason, none used.
  RosProcess images = master_->spawn("images-2", {kNav, "depth-images", "16UC1", "640", "480", "3"});
  nav({"laser-scans", "empty", "0.5"});
  nav({"laser-scans", "nan-increment", "0.5"});
  nav({"laser-scans", "back", "0.5"});
  EXPECT_EQ(images.wait(milliseconds(10'000)), 0) << images.err();
  const Json bad = *status();
  const Json& by = bad["ros"]["scans"]["dropped_by"];
  EXPECT_GE(by["beams"].get<int>(), 10);
  EXPECT_GE(by["geometry"].get<int>(), 10);
  EXPECT_GE(by["stamp"].get<int>(), 10) << "each going back from the good scans' stamps";
  EXPECT_EQ(by["sweep"], 0);
  EXPECT_EQ(bad["ros"]["scans"]["dropped"].get<int>(),
            by["beams"].get<int>() + by["geometry"].get<int>() + by["stamp"].get<int>());
  EXPECT_GT(bad["scanner"]["scans_too_old"].get<int>(), 0) << "the frames went on without a recent scan";
  EXPECT_EQ(bad["rt_allocations"], 0);
}

TEST_F(StaadOverRos, RoslaunchStartsStaadWithTheLaunchFile) {
  // The package as installed: package.xml, the launch file and staad beside them.
  const fs::path pkg = dir_ / "pkgs/staa";
  fs::create_directories(pkg);
  fs::copy_file(sourceDir() / "config/ros/package.xml", pkg / "package.xml");
  fs::copy_file(sourceDir() / "config/ros/staad.launch", pkg / "staad.launch");
  fs::create_symlink(kStaad, pkg / "staad");
  startMap({depotYaml().string()});
  startBase();
  const fs::path config = writeConfig();
  RosProcess launch = master_->spawn("roslaunch", {"/usr/bin/roslaunch", "staa", "staad.launch", "config:=" + config.string()},
                                     {"ROS_PACKAGE_PATH=" + (dir_ / "pkgs").string()});
  const auto up = pollStatus([](const Json& s) { return s["state"] == "idle"; }, milliseconds(30'000));
  ASSERT_TRUE(up) << launch.out() << launch.err();
  EXPECT_TRUE(master_->waitForSubscriber("/move_base_simple/goal", seconds(5)));
  // roslaunch names the node: staad took __name:= from its command line.
  EXPECT_FALSE(master_->publishers("/diagnostics").empty());
  EXPECT_THAT(master_->publishers("/diagnostics")[0], HasSubstr("staad"));
  launch.kill(SIGINT);
  EXPECT_TRUE(launch.wait(milliseconds(15'000)).has_value()) << launch.out() << launch.err();
}

}  // namespace
}  // namespace staa::test
