// The staad binary end to end, with the simulated HAL: a temporary config (the shipped robot
// and map), a temporary control socket and a temporary NOTIFY_SOCKET that this test binds,
// WATCHDOG_USEC=400000. READY=1 and watchdog pings arrive; `staactl goal` drives the robot to
// the goal and `status --json` says reached with zero real-time allocations; garbage on the
// socket gets error replies while the daemon keeps answering; several clients at once; a
// second daemon on the same socket is refused; SIGTERM while driving gives STOPPING=1 and
// exit 0 within one second; bad or missing config exits 2 naming the key or the path.
// `staactl goal --wait` (and `goal` then `wait`) end only once the robot is at the new goal,
// even right after the previous one was reached; `--svg FILE` leaves a picture of the run.
//
// Every wait has a timeout, and every process this test starts is killed in teardown.
#include "child_process.hpp"
#include "raw_client.hpp"
#include "read_file.hpp"
#include "shared_dir.hpp"
#include "blocked_cycles.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr double kGoalTolerance = 0.2;

using staa::test::readFile;

using staa::test::Child;
using staa::test::environmentWithout;

// The datagram socket that plays systemd's notification socket. Like systemd, it reads every
// datagram as it comes (a background thread): a full receive queue would block the sender.
class NotifySocket {
 public:
  struct Message {
    Clock::time_point when;
    std::string text;
  };

  explicit NotifySocket(const fs::path& path) : path_(path) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    ok_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0;
    if (ok_) reader_ = std::thread([this] { read(); });
  }
  ~NotifySocket() {
    stop_.store(true);
    if (reader_.joinable()) reader_.join();
    if (fd_ >= 0) ::close(fd_);
    ::unlink(path_.c_str());
  }
  bool ok() const { return ok_; }

  // Waits until a message after the last one found contains `what`; its time, or nullopt
  // after `timeout`.
  std::optional<Clock::time_point> waitFor(const std::string& what, milliseconds timeout) {
    std::unique_lock lock(mutex_);
    std::optional<Clock::time_point> found;
    cv_.wait_for(lock, timeout, [&] {
      for (; cursor_ < messages_.size(); ++cursor_) {
        if (messages_[cursor_].text.find(what) != std::string::npos) {
          found = messages_[cursor_++].when;
          return true;
        }
      }
      return false;
    });
    return found;
  }
  // Messages containing `what` received in [from, to).
  int count(const std::string& what, Clock::time_point from, Clock::time_point to) {
    std::lock_guard lock(mutex_);
    int n = 0;
    for (const Message& m : messages_) n += m.when >= from && m.when < to && m.text.find(what) != std::string::npos;
    return n;
  }

 private:
  void read() {
    while (!stop_.load()) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n < 0) continue;
      {
        std::lock_guard lock(mutex_);
        messages_.push_back({Clock::now(), std::string(buf, static_cast<std::size_t>(n))});
      }
      cv_.notify_all();
    }
  }

  fs::path path_;
  int fd_ = -1;
  bool ok_ = false;
  std::atomic<bool> stop_{false};
  std::thread reader_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Message> messages_;
  std::size_t cursor_ = 0;
};

using staa::test::RawClient;

bool isErrorReply(const std::optional<std::string>& line) {
  if (!line) return false;
  const auto j = nlohmann::json::parse(*line, nullptr, false);
  return j.is_object() && j.value("ok", true) == false && j.contains("error") && j["error"].is_string();
}

bool isOkReply(const std::optional<std::string>& line) {
  if (!line) return false;
  const auto j = nlohmann::json::parse(*line, nullptr, false);
  return j.is_object() && j.value("ok", false) == true;
}

class StaadE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/staad-e2e-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
    socket_ = dir_ / "staad.sock";
    telemetry_ = dir_ / "telemetry.csv";
  }
  void TearDown() override {
    daemon_.kill();
    if (HasFailure()) {
      std::cerr << "---- staad's stderr ----\n" << readFile(dir_ / "staad.err") << "------------------------\n";
    }
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // `telemetry`: the telemetry section's value; empty: the CSV file telemetry_.
  std::string config(const std::string& rates = "{control_hz: 30, base_hz: 100, perception_hz: 30}",
                     const std::string& telemetry = "") const {
    const fs::path src = staa::test::sourceDir();
    std::string y;
    y += "format: staad-config/1\n";
    y += "robot: " + (src / "config/robots/paper-agent.yaml").string() + "\n";
    y += "map: " + (src / "config/maps/office.yaml").string() + "\n";
    y += "hal: sim\n";
    y += "sim: {start: [4.5, 4.5, 0.0], movers: 0, seed: 1}\n";
    y += "rates: " + rates + "\n";
    y += "budget: {ms: 15}\n";
    y += "threads:\n";
    y += "  control: {priority: 80, cpu: -1}\n";
    y += "  base: {priority: 85, cpu: -1}\n";
    y += "  perception: {priority: 70, cpu: -1}\n";
    y += "socket: {path: " + socket_.string() + ", mode: \"0660\"}\n";
    y += "limits: {odometry_timeout_s: 0.1, obstacles_timeout_s: 0.2}\n";
    y += "goal: {tolerance_m: 0.2, heading_tolerance: 0.4}\n";
    y += "telemetry: " + (telemetry.empty() ? "{path: " + telemetry_.string() + ", records: 4096}" : telemetry) + "\n";
    y += "memory: {heap_prefault_mb: 16, stack_prefault_kb: 256}\n";
    return y;
  }
  fs::path writeConfig(const std::string& text, const std::string& name = "staad.yaml") const {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  Child startDaemon(const fs::path& config_file, const std::vector<std::string>& extra_env, const std::string& tag,
                    const std::vector<std::string>& extra_args = {}) {
    std::vector<std::string> env = environmentWithout({"NOTIFY_SOCKET=", "WATCHDOG_USEC=", "WATCHDOG_PID="});
    env.insert(env.end(), extra_env.begin(), extra_env.end());
    std::vector<std::string> argv{STAAD_EXE, "--config", config_file.string(), "--hal", "sim"};
    argv.insert(argv.end(), extra_args.begin(), extra_args.end());
    return Child(argv, env, dir_ / (tag + ".out"), dir_ / (tag + ".err"));
  }

  // Runs staactl with a timeout; the exit code (nullopt: did not finish) and its stdout (its
  // stderr is left in staactl.err).
  std::pair<std::optional<int>, std::string> staactl(const std::vector<std::string>& args,
                                                      milliseconds timeout = milliseconds(10'000)) {
    std::vector<std::string> argv{STAACTL_EXE, "--socket", socket_.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    const fs::path out = dir_ / "staactl.out";
    Child c(argv, environmentWithout({"NOTIFY_SOCKET="}), out, dir_ / "staactl.err");
    const std::optional<int> code = c.wait(timeout);
    return {code, readFile(out)};
  }

  // Waits until the daemon answers status (it is up), or fails after 10 s.
  bool answering() {
    return pollStatus([](const nlohmann::json&) { return true; }, milliseconds(10'000)).has_value();
  }

  static double distance(const nlohmann::json& status, double x, double y) {
    const auto& pose = status["pose"];
    return std::hypot(pose[0].get<double>() - x, pose[1].get<double>() - y);
  }

  std::optional<nlohmann::json> status() {
    const auto [code, out] = staactl({"status", "--json"});
    if (!code || *code != 0) return std::nullopt;
    auto j = nlohmann::json::parse(out, nullptr, false);
    if (j.is_discarded()) return std::nullopt;
    return j;
  }

  // Polls status until `done` (true) or `timeout`.
  template <typename Done>
  std::optional<nlohmann::json> pollStatus(Done done, milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    std::optional<nlohmann::json> last;
    while (Clock::now() < deadline) {
      last = status();
      if (last && done(*last)) return last;
      std::this_thread::sleep_for(milliseconds(50));
    }
    return last;
  }

  fs::path dir_;
  fs::path socket_;
  fs::path telemetry_;
  Child daemon_;
};

TEST_F(StaadE2E, ReadyWatchdogDrivesToTheGoalSurvivesGarbageAndStopsOnSigterm) {
  NotifySocket notify(dir_ / "notify.sock");
  ASSERT_TRUE(notify.ok());
  daemon_ = startDaemon(writeConfig(config()),
                        {"NOTIFY_SOCKET=" + (dir_ / "notify.sock").string(), "WATCHDOG_USEC=400000"}, "staad");
  ASSERT_GT(daemon_.pid(), 0);

  // READY=1, then watchdog pings every 200 ms (half of WATCHDOG_USEC) while the control
  // thread runs.
  const auto ready = notify.waitFor("READY=1", milliseconds(10'000));
  ASSERT_TRUE(ready.has_value()) << "no READY=1";
  std::this_thread::sleep_for(milliseconds(1600));
  const int pings = notify.count("WATCHDOG=1", *ready, *ready + milliseconds(1500));
  EXPECT_GE(pings, 3) << "watchdog pings within 1.5 s";
  EXPECT_LE(pings, 10);
  ASSERT_TRUE(fs::exists(socket_));
  EXPECT_EQ(fs::status(socket_).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::group_write);

  // Idle at the start.
  const auto idle = status();
  ASSERT_TRUE(idle.has_value());
  EXPECT_EQ((*idle)["state"], "idle");

  // staactl goal -> reached.
  {
    const auto [code, out] = staactl({"goal", "10.5", "4.5", "0"});
    ASSERT_TRUE(code.has_value());
    EXPECT_EQ(*code, 0) << out;
    EXPECT_EQ(out, "ok (goal 1)\n");
  }
  const auto goal_sent = Clock::now();
  const auto reached = pollStatus([](const nlohmann::json& j) { return j["state"] == "reached"; }, milliseconds(30'000));
  ASSERT_TRUE(reached.has_value());
  EXPECT_EQ((*reached)["state"], "reached") << reached->dump();
  std::cout << "reached the goal 6 m away in "
            << std::chrono::duration_cast<milliseconds>(Clock::now() - goal_sent).count() << " ms; control cycle p99 "
            << (*reached)["cycle"]["p99_us"] << " us, max " << (*reached)["cycle"]["max_us"] << " us, overruns "
            << (*reached)["cycle"]["overruns"] << "\n";
  const auto& pose = (*reached)["pose"];
  ASSERT_TRUE(pose.is_array());
  EXPECT_LE(std::hypot(pose[0].get<double>() - 10.5, pose[1].get<double>() - 4.5), kGoalTolerance + 0.02)
      << reached->dump();
  EXPECT_EQ((*reached)["rt_allocations"], 0) << reached->dump();
  EXPECT_TRUE(staa::test::noBlockedCycle(*reached)) << "a control cycle blocked: " << reached->dump();
  EXPECT_TRUE(staa::test::noBlockedCycle((*reached)["threads"]["base"])) << "a base cycle blocked: " << reached->dump();
  EXPECT_TRUE((*reached)["fault"].is_null());
  EXPECT_TRUE(notify.waitFor("STATUS=reached", milliseconds(2000)).has_value()) << "STATUS= on the state change";
  EXPECT_GT((*reached)["cycle"]["count"].get<double>(), 30.0);

  // Garbage on a raw connection: an error reply each, the connection and the daemon stay.
  {
    RawClient raw(socket_);
    ASSERT_TRUE(raw.connected());
    const char binary[] = {'\x01', '\x00', '\x02', '\xff', '\xfe', ' ', 'b', 'i', 'n', '\x7f', '\n'};
    ASSERT_TRUE(raw.send(std::string(binary, sizeof binary)));
    EXPECT_TRUE(isErrorReply(raw.readLine(milliseconds(3000))));
    ASSERT_TRUE(raw.send("{\n"));
    EXPECT_TRUE(isErrorReply(raw.readLine(milliseconds(3000))));
    ASSERT_TRUE(raw.send(std::string(10'000, 'a') + "\n"));
    EXPECT_TRUE(isErrorReply(raw.readLine(milliseconds(3000))));
    ASSERT_TRUE(raw.send("{\"cmd\": \"fly\"}\n"));
    EXPECT_TRUE(isErrorReply(raw.readLine(milliseconds(3000))));
    // The same connection still works.
    ASSERT_TRUE(raw.send("{\"cmd\": \"status\"}\n"));
    const auto reply = raw.readLine(milliseconds(3000));
    ASSERT_TRUE(isOkReply(reply)) << reply.value_or("(none)");
    EXPECT_EQ(nlohmann::json::parse(*reply)["status"]["state"], "reached");
  }
  // Two clients at once (and staactl as a third).
  {
    RawClient a(socket_);
    RawClient b(socket_);
    ASSERT_TRUE(a.connected());
    ASSERT_TRUE(b.connected());
    ASSERT_TRUE(a.send("{\"cmd\": \"status\"}\n"));
    ASSERT_TRUE(b.send("{\"cmd\": \"status\"}\n"));
    EXPECT_TRUE(isOkReply(b.readLine(milliseconds(3000))));
    EXPECT_TRUE(isOkReply(a.readLine(milliseconds(3000))));
    const auto third = status();
    ASSERT_TRUE(third.has_value());
    ASSERT_TRUE(b.send("{\"cmd\": \"status\"}\n"));
    EXPECT_TRUE(isOkReply(b.readLine(milliseconds(3000))));
  }
  EXPECT_TRUE(daemon_.alive());

  // A second daemon on the same socket is refused (exit 1), the first one is undisturbed.
  {
    Child second = startDaemon(writeConfig(config(), "second.yaml"), {}, "second");
    const auto code = second.wait(milliseconds(15'000));
    ASSERT_TRUE(code.has_value());
    EXPECT_EQ(*code, 1);
    EXPECT_NE(readFile(dir_ / "second.err").find("already listening"), std::string::npos)
        << readFile(dir_ / "second.err");
    EXPECT_TRUE(fs::exists(socket_));
    EXPECT_TRUE(status().has_value());
  }

  // Drive back, and SIGTERM at speed: brake, STOPPING=1, exit 0 within one second.
  {
    const auto [code, out] = staactl({"goal", "4.5", "4.5", "3.14159"});
    ASSERT_TRUE(code.has_value());
    EXPECT_EQ(*code, 0) << out;
  }
  const auto moving = pollStatus(
      [](const nlohmann::json& j) { return j["state"] == "driving" && std::abs(j["velocity"][0].get<double>()) > 0.3; },
      milliseconds(10'000));
  ASSERT_TRUE(moving.has_value());
  EXPECT_EQ((*moving)["rt_allocations"], 0) << moving->dump();

  const auto t0 = Clock::now();
  daemon_.signal(SIGTERM);
  const auto code = daemon_.wait(milliseconds(5'000));
  const auto elapsed = std::chrono::duration_cast<milliseconds>(Clock::now() - t0);
  ASSERT_TRUE(code.has_value()) << "staad did not exit after SIGTERM";
  EXPECT_EQ(*code, 0);
  EXPECT_LT(elapsed.count(), 1000) << "exit took " << elapsed.count() << " ms";
  std::cout << "SIGTERM at " << (*moving)["velocity"][0] << " m/s -> exit 0 in " << elapsed.count() << " ms\n";
  EXPECT_TRUE(notify.waitFor("STOPPING=1", milliseconds(500)).has_value());
  EXPECT_FALSE(fs::exists(socket_)) << "the socket file is removed on exit";

  // The telemetry file: the documented header, one row per cycle.
  const std::string csv = readFile(telemetry_);
  ASSERT_EQ(csv.rfind("t_s,x,y,theta,v,w,v_cmd,w_cmd,expansions,depth,budget_used_ms,overrun\n", 0), 0u)
      << csv.substr(0, 200);
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  int rows = 0;
  double max_x = 0.0;
  while (std::getline(lines, line)) {
    ++rows;
    std::istringstream fields(line);
    std::string field;
    int n = 0;
    double x = 0.0;
    while (std::getline(fields, field, ',')) {
      if (n == 1) x = std::stod(field);
      ++n;
    }
    EXPECT_EQ(n, 12) << line;
    max_x = std::max(max_x, x);
  }
  EXPECT_GT(rows, 60);
  EXPECT_GT(max_x, 10.0);  // the trip is in it
}

// The race `goal --wait` and `wait` guard against: right after a goal was reached, the next
// goal's first status reads still say "reached" (about the previous goal) until the control
// thread takes the new one. Each wait must end only once the robot is at its new goal.
TEST_F(StaadE2E, GoalWaitAndWaitEndOnlyAtTheNewGoalRightAfterThePreviousWasReached) {
  daemon_ = startDaemon(writeConfig(config()), {}, "staad");
  ASSERT_TRUE(answering());
  constexpr milliseconds kTrip(90'000);

  {
    const auto [code, out] = staactl({"goal", "10.5", "4.5", "0", "--wait", "--timeout", "60"}, kTrip);
    ASSERT_TRUE(code.has_value()) << "goal --wait did not return";
    EXPECT_EQ(*code, 0) << out << readFile(dir_ / "staactl.err");
    EXPECT_EQ(out, "ok (goal 1)\nreached\n");
  }
  const auto first = status();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ((*first)["state"], "reached") << first->dump();
  EXPECT_EQ((*first)["goal_id"], 1);
  EXPECT_LE(distance(*first, 10.5, 4.5), kGoalTolerance + 0.02) << first->dump();

  // At once the second goal, 3.5 m back along the corridor.
  {
    const auto [code, out] = staactl({"goal", "7.0", "4.5", "3.14159", "--wait", "--timeout", "60"}, kTrip);
    ASSERT_TRUE(code.has_value()) << "goal --wait did not return";
    EXPECT_EQ(*code, 0) << out << readFile(dir_ / "staactl.err");
    EXPECT_EQ(out, "ok (goal 2)\nreached\n");
  }
  const auto second = status();
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ((*second)["state"], "reached") << second->dump();
  EXPECT_EQ((*second)["goal_id"], 2);
  EXPECT_LE(distance(*second, 7.0, 4.5), kGoalTolerance + 0.02) << "returned before the robot was at goal 2: "
                                                                 << second->dump();

  // The plain `goal` then `wait`, as scripts did before goal ids.
  {
    const auto [code, out] = staactl({"goal", "9.0", "4.5", "0"});
    ASSERT_TRUE(code.has_value());
    EXPECT_EQ(*code, 0);
    EXPECT_EQ(out, "ok (goal 3)\n");
  }
  {
    const auto [code, out] = staactl({"wait", "--timeout", "60"}, kTrip);
    ASSERT_TRUE(code.has_value()) << "wait did not return";
    EXPECT_EQ(*code, 0) << out << readFile(dir_ / "staactl.err");
    EXPECT_EQ(out, "reached\n");
  }
  const auto third = status();
  ASSERT_TRUE(third.has_value());
  EXPECT_EQ((*third)["goal_id"], 3);
  EXPECT_LE(distance(*third, 9.0, 4.5), kGoalTolerance + 0.02) << "wait returned before the robot was at goal 3: "
                                                                << third->dump();
  EXPECT_EQ((*third)["rt_allocations"], 0);
}

// blind_corners in the config: driving from the corridor into a room, the daemon lowers its
// commands at the door's frame (the status counts the cycles), still reaches the goal, and the
// cycle allocates nothing. (Along the 3 m corridor the doors are 1.5 m aside: not counted.)
TEST_F(StaadE2E, TheBlindCornerLimitSlowsTheRobotAtCornersAndItStillArrives) {
  daemon_ = startDaemon(writeConfig(config() + "blind_corners: {enabled: true}\n"), {}, "staad");
  ASSERT_TRUE(answering());
  const auto before = status();
  ASSERT_TRUE(before.has_value());
  EXPECT_EQ((*before)["blind_corners"]["enabled"], true) << before->dump();
  EXPECT_EQ((*before)["blind_corners"]["capped_cycles"], 0);
  const auto [code, out] = staactl({"goal", "1.5", "7.5", "3.1416", "--wait", "--timeout", "60"}, milliseconds(90'000));
  ASSERT_TRUE(code.has_value()) << "goal --wait did not return";
  EXPECT_EQ(*code, 0) << out << readFile(dir_ / "staactl.err");
  const auto after = status();
  ASSERT_TRUE(after.has_value());
  EXPECT_EQ((*after)["state"], "reached") << after->dump();
  EXPECT_GT((*after)["blind_corners"]["capped_cycles"].get<int>(), 5) << after->dump();
  EXPECT_EQ((*after)["rt_allocations"], 0);
}

// `staad --svg FILE`, with no telemetry file: on SIGTERM the picture of the run is written.
TEST_F(StaadE2E, SvgOfTheRunIsWrittenOnSigtermEvenWithoutATelemetryFile) {
  const fs::path svg = dir_ / "run.svg";
  daemon_ = startDaemon(writeConfig(config("{control_hz: 30, base_hz: 100, perception_hz: 30}", "{path: \"\"}")), {},
                        "staad", {"--svg", svg.string()});
  ASSERT_TRUE(answering());
  EXPECT_FALSE(fs::exists(svg)) << "written when staad stops, not before";
  {
    const auto [code, out] = staactl({"goal", "8.5", "4.5", "0", "--wait", "--timeout", "60"}, milliseconds(90'000));
    ASSERT_TRUE(code.has_value());
    EXPECT_EQ(*code, 0) << out << readFile(dir_ / "staactl.err");
  }
  daemon_.signal(SIGTERM);
  const auto code = daemon_.wait(milliseconds(5'000));
  ASSERT_TRUE(code.has_value()) << "staad did not exit after SIGTERM";
  EXPECT_EQ(*code, 0);
  EXPECT_FALSE(fs::exists(telemetry_)) << "no telemetry file was asked for";

  ASSERT_TRUE(fs::exists(svg)) << readFile(dir_ / "staad.err");
  EXPECT_FALSE(fs::exists(dir_ / "run.svg.tmp")) << "the temporary file is renamed, not left";
  const std::string doc = readFile(svg);
  const auto open = doc.find("<svg");
  ASSERT_NE(open, std::string::npos) << doc.substr(0, 300);
  const auto close = doc.rfind("</svg>");
  ASSERT_NE(close, std::string::npos);
  EXPECT_LT(open, close);
  EXPECT_EQ(doc.find_first_not_of(" \n", close + 6), std::string::npos) << "nothing after </svg>";

  // The path driven: a polyline in the path's colour with one point per 5 cm or so of the
  // 4 m trip (at most one per 5 cm, plus the end pose).
  const auto path = doc.find("<polyline fill=\"none\" stroke=\"#e8590c\"");
  ASSERT_NE(path, std::string::npos) << "no path polyline";
  const auto points_at = doc.find("points=\"", path);
  ASSERT_NE(points_at, std::string::npos);
  const auto points_end = doc.find('"', points_at + 8);
  const std::string points = doc.substr(points_at + 8, points_end - points_at - 8);
  const auto n = std::count(points.begin(), points.end(), ',');
  EXPECT_GE(n, 40) << points;
  EXPECT_LE(n, 200) << points;
  // The goal's marker with its id, and the title's numbers.
  EXPECT_NE(doc.find(">1</text>"), std::string::npos) << "no label for goal 1";
  EXPECT_NE(doc.find("1 of 1 goal reached"), std::string::npos) << doc.substr(0, 2000);
  EXPECT_NE(doc.find(" m driven"), std::string::npos);
  EXPECT_NE(readFile(dir_ / "staad.err").find("svg: wrote the run's picture to " + svg.string()), std::string::npos)
      << readFile(dir_ / "staad.err");
}

TEST_F(StaadE2E, SvgPathThatCannotBeWrittenStopsStartUpWithExit1) {
  const fs::path svg = dir_ / "no-such-dir" / "run.svg";
  daemon_ = startDaemon(writeConfig(config()), {}, "staad", {"--svg", svg.string()});
  const auto code = daemon_.wait(milliseconds(10'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  const std::string err = readFile(dir_ / "staad.err");
  EXPECT_NE(err.find("staad: svg file '" + svg.string() + "'"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(socket_));
}

TEST_F(StaadE2E, BadConfigValueExits2NamingTheKeyAndTheValue) {
  daemon_ = startDaemon(writeConfig(config("{control_hz: -3, base_hz: 100, perception_hz: 30}")), {}, "staad");
  const auto code = daemon_.wait(milliseconds(10'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  const std::string err = readFile(dir_ / "staad.err");
  EXPECT_NE(err.find("rates.control_hz"), std::string::npos) << err;
  EXPECT_NE(err.find("-3"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(socket_));
}

TEST_F(StaadE2E, MissingConfigFileExits2NamingThePath) {
  const fs::path missing = dir_ / "no-such-staad.yaml";
  daemon_ = startDaemon(missing, {}, "staad");
  const auto code = daemon_.wait(milliseconds(10'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  const std::string err = readFile(dir_ / "staad.err");
  EXPECT_NE(err.find(missing.string()), std::string::npos) << err;
}

TEST_F(StaadE2E, BadHalArgumentExits2) {
  Child c({STAAD_EXE, "--config", writeConfig(config()).string(), "--hal", "warp"}, environmentWithout({}),
          dir_ / "staad.out", dir_ / "staad.err");
  const auto code = c.wait(milliseconds(10'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  EXPECT_NE(readFile(dir_ / "staad.err").find("warp"), std::string::npos) << readFile(dir_ / "staad.err");
}

}  // namespace
