// Hardware in the loop: the real staad binary with `hal: socketcan` against basesim, the
// simulated base firmware speaking config/can/hsr_base.yaml over a Unix SOCK_SEQPACKET socket
// (the HSR robot profile, the office map, the simulated camera's movers). Each test starts
// its own basesim and staad in a temporary folder, drives along the office's corridor, and
// injects one fault through basesim's control socket or staad's debug requests.
//
// For every fault that must stop the robot: basesim's TRUE v and w reach standstill within
// a bound computed from the deceleration limit (the fault's detection time + v/a + 0.5 s
// margin; each test states its detection time), staad's status names the fault, staad still
// answers, the robot stays stopped while the fault holds, and it drives toward the goal again
// when the fault clears (except after SIGKILL, where basesim stops on its own 0.5 s command
// timeout). Each fault prints one summary line, e.g.
//   HIL fault=estop detect_ms=21 standstill_ms=463 bound_ms=960 v0=0.220
// The goal test also checks the base I/O path's timing in the status (`threads.base`,
// `base.command_to_wire`) and prints it (`HIL base_io ...`).
//
// Every wait polls with a deadline; every process this test starts is killed in teardown.
#include "shared_dir.hpp"

#include "child_process.hpp"
#include "read_file.hpp"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
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
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// basesim's limits (its command line) and the HSR profile's top speed.
constexpr double kAccel = 0.5;           // m/s^2, basesim --accel: also the brake's deceleration
constexpr double kAlpha = 1.5;           // rad/s^2, basesim --alpha
constexpr double kBaseTimeoutS = 0.5;    // basesim --command-timeout (the HSR's)
constexpr double kMarginS = 0.5;         // the bound's margin (a loaded 2-core machine, ASan)
constexpr double kControlPeriodS = 1.0 / 30.0;
constexpr double kBasePeriodS = 0.01;
// Standstill: basesim ramps to exactly 0, this only absorbs rounding.
constexpr double kStillV = 0.005;
constexpr double kStillW = 0.005;
constexpr double kCruiseV = 0.21;   // "driving": at about the HSR's 0.22 m/s
constexpr double kResumeV = 0.10;   // driving again after a fault
const Json kStart = {4.5, 4.5, 0.0};  // the office corridor (y 3..6 m), heading east
const Json kFarGoal = {22.5, 4.5, 0.0};

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

using staa::test::readFile;

using staa::test::Child;

// One line-delimited JSON connection (staad's control socket, basesim's control socket).
class LineClient {
 public:
  LineClient() = default;
  explicit LineClient(const fs::path& path) : path_(path) {}
  ~LineClient() { close(); }
  LineClient& operator=(LineClient&& o) noexcept {
    close();
    path_ = o.path_;
    fd_ = o.fd_;
    buffer_ = std::move(o.buffer_);
    o.fd_ = -1;
    return *this;
  }

  // One request, its reply parsed (nullopt: no connection, no reply within `timeout`, or not
  // JSON). Reconnects when needed.
  std::optional<Json> request(const std::string& line, milliseconds timeout = milliseconds(3000)) {
    if (fd_ < 0 && !connect()) return std::nullopt;
    const std::string data = line + "\n";
    if (::send(fd_, data.data(), data.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(data.size())) {
      close();
      return std::nullopt;
    }
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        const std::string reply = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        Json j = Json::parse(reply, nullptr, false);
        if (j.is_discarded()) return std::nullopt;
        return j;
      }
      const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now()).count();
      pollfd p{fd_, POLLIN, 0};
      if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0) {
        close();  // a late reply would answer the next request
        return std::nullopt;
      }
      char buf[8192];
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) {
        close();
        return std::nullopt;
      }
      buffer_.append(buf, static_cast<std::size_t>(n));
    }
  }

 private:
  bool connect() {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof addr.sun_path - 1);
    if (fd_ < 0 || ::connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      close();
      return false;
    }
    return true;
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    buffer_.clear();
  }

  fs::path path_;
  int fd_ = -1;
  std::string buffer_;
};

// What a fault test measured.
struct Measured {
  double detect_ms = -1.0;      // injection -> staad's status names the fault (-1: never)
  double standstill_ms = -1.0;  // injection -> basesim's true v, w at standstill (-1: never)
  double v0 = 0.0;              // basesim's v at the injection
  double bound_ms = 0.0;
};

class Hil : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/staa-hil-XXXXXX";  // short: socket paths are at most 107 bytes
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    daemon_.kill();
    basesim_.kill();
    if (HasFailure()) {
      std::cerr << "---- staad's stderr ----\n" << readFile(dir_ / "staad.err") << "---- basesim's stdout ----\n"
                << readFile(dir_ / "basesim.out") << readFile(dir_ / "basesim.err") << "------------------------\n";
    }
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string config(int movers, bool debug_faults = true) const {
    const fs::path src = staa::test::sourceDir();
    std::string y;
    y += "format: staad-config/1\n";
    y += "robot: " + (src / "config/robots/hsr.yaml").string() + "\n";
    y += "map: " + (src / "config/maps/office.yaml").string() + "\n";
    y += "hal: socketcan\n";
    y += "socketcan: {interface: \"unix:" + (dir_ / "base.sock").string() + "\", profile: " +
         (src / "config/can/hsr_base.yaml").string() + "}\n";
    y += "obstacles: sim\n";
    // The simulated camera's world is anchored at the robot's start; its movers walk
    // between the office's rooms at walking pace.
    y += "sim: {start: [4.5, 4.5, 0.0], movers: " + std::to_string(movers) + ", mover_speed: 0.5, seed: 3}\n";
    y += "rates: {control_hz: 30, base_hz: 100, perception_hz: 30}\n";
    y += "budget: {ms: 15}\n";
    // Normal scheduling: a busy-waiting control thread must never starve a CI machine.
    y += "threads: {control: {priority: 0}, base: {priority: 0}, perception: {priority: 0}}\n";
    y += "socket: {path: " + (dir_ / "staad.sock").string() + "}\n";
    y += "limits: {odometry_timeout_s: 0.1, obstacles_timeout_s: 0.2}\n";
    y += "memory: {heap_prefault_mb: 16, stack_prefault_kb: 256}\n";
    y += std::string("debug: {faults: ") + (debug_faults ? "true" : "false") + "}\n";
    return y;
  }

  void startBasesim() {
    const fs::path src = staa::test::sourceDir();
    char accel[32], alpha[32], timeout[32], start[96];
    std::snprintf(accel, sizeof accel, "%g", kAccel);
    std::snprintf(alpha, sizeof alpha, "%g", kAlpha);
    std::snprintf(timeout, sizeof timeout, "%g", kBaseTimeoutS);
    std::snprintf(start, sizeof start, "%g,%g,%g", kStart[0].get<double>(), kStart[1].get<double>(), kStart[2].get<double>());
    basesim_ = Child({BASESIM_EXE, "--socket", (dir_ / "base.sock").string(), "--control", (dir_ / "basesim.ctl").string(),
                      "--profile", (src / "config/can/hsr_base.yaml").string(), "--accel", accel, "--alpha", alpha,
                      "--command-timeout", timeout, "--start", start},
                     dir_ / "basesim.out", dir_ / "basesim.err");
    ASSERT_GT(basesim_.pid(), 0);
    base_ = LineClient(dir_ / "basesim.ctl");
    const auto deadline = Clock::now() + milliseconds(10'000);
    while (!base_.request("state") && Clock::now() < deadline) std::this_thread::sleep_for(milliseconds(20));
    ASSERT_TRUE(baseState().has_value()) << "basesim does not answer";
  }

  void startDaemon(const std::string& text) {
    const fs::path file = dir_ / "staad.yaml";
    std::ofstream(file) << text;
    daemon_ = Child({STAAD_EXE, "--config", file.string()}, dir_ / "staad.out", dir_ / "staad.err");
    ASSERT_GT(daemon_.pid(), 0);
    staad_ = LineClient(dir_ / "staad.sock");
    const auto deadline = Clock::now() + milliseconds(30'000);  // ASan start-up
    while (!status() && Clock::now() < deadline && daemon_.alive()) std::this_thread::sleep_for(milliseconds(50));
    ASSERT_TRUE(status().has_value()) << "staad does not answer";
  }

  // basesim and staad up, the pose anchored where basesim's robot truly is, no fault.
  void startBoth(int movers = 0) {
    ASSERT_NO_FATAL_FAILURE(startBasesim());
    ASSERT_NO_FATAL_FAILURE(startDaemon(config(movers)));
    ASSERT_TRUE(isOk(staad_.request(poseLine("pose", kStart))));
    const auto anchored = waitStatus(
        [](const Json& s) {
          return std::hypot(s["pose"][0].get<double>() - kStart[0].get<double>(),
                            s["pose"][1].get<double>() - kStart[1].get<double>()) < 0.01 &&
                 s["fault"].is_null();
        },
        milliseconds(10'000));
    ASSERT_TRUE(anchored.has_value()) << "pose not anchored, or a fault at start-up: " << status().value_or(Json()).dump();
  }

  static std::string poseLine(const char* cmd, const Json& p) {
    return Json{{"cmd", cmd}, {"x", p[0]}, {"y", p[1]}, {"theta", p[2]}}.dump();
  }
  static bool isOk(const std::optional<Json>& reply) { return reply && reply->value("ok", false); }

  std::optional<Json> status() {
    const auto r = staad_.request(R"({"cmd":"status"})");
    if (!isOk(r) || !r->contains("status")) return std::nullopt;
    return (*r)["status"];
  }
  std::optional<Json> baseState() {
    const auto r = base_.request("state");
    if (!isOk(r) || !r->contains("state")) return std::nullopt;
    return (*r)["state"];
  }
  void inject(const std::string& what) {
    const auto r = base_.request(what);
    ASSERT_TRUE(isOk(r)) << what << ": " << r.value_or(Json()).dump();
  }
  void debug(const Json& request) {
    const auto r = staad_.request(request.dump());
    ASSERT_TRUE(isOk(r)) << request.dump() << ": " << r.value_or(Json()).dump();
  }

  template <typename Done>
  std::optional<Json> waitStatus(Done done, milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (const auto s = status(); s && done(*s)) return s;
      std::this_thread::sleep_for(milliseconds(20));
    }
    return std::nullopt;
  }
  template <typename Done>
  std::optional<Json> waitBase(Done done, milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (const auto s = baseState(); s && done(*s)) return s;
      std::this_thread::sleep_for(milliseconds(10));
    }
    return std::nullopt;
  }

  static bool still(const Json& b) {
    return std::abs(b["v"].get<double>()) < kStillV && std::abs(b["w"].get<double>()) < kStillW;
  }

  // Sends the far goal and waits until basesim truly drives at cruise speed.
  void cruise() {
    const auto r = staad_.request(poseLine("goal", kFarGoal));
    ASSERT_TRUE(isOk(r)) << r.value_or(Json()).dump();
    const auto b = waitBase([](const Json& s) { return s["v"].get<double>() > kCruiseV; }, milliseconds(20'000));
    ASSERT_TRUE(b.has_value()) << "basesim never reached " << kCruiseV << " m/s: " << baseState().value_or(Json()).dump()
                               << "\nstatus: " << status().value_or(Json()).dump();
  }

  // From the injection (now): polls basesim and staad until the robot stands and the
  // status names the fault (`named`), or `bound_s` + 2 s passed. v0: basesim's v just before.
  Measured measure(double v0, double detect_s, const std::function<bool(const Json&)>& named, Clock::time_point t0,
                   bool need_status = true) {
    Measured m;
    m.v0 = v0;
    m.bound_ms = 1000.0 * (detect_s + std::abs(v0) / kAccel + kMarginS);
    const auto deadline = t0 + milliseconds(static_cast<int>(m.bound_ms) + 2000);
    while (Clock::now() < deadline && (m.standstill_ms < 0.0 || (need_status && m.detect_ms < 0.0))) {
      if (m.standstill_ms < 0.0) {
        if (const auto b = baseState(); b && still(*b)) m.standstill_ms = msSince(t0);
      }
      if (need_status && m.detect_ms < 0.0) {
        if (const auto s = status(); s && named(*s)) m.detect_ms = msSince(t0);
      }
      std::this_thread::sleep_for(milliseconds(5));
    }
    return m;
  }

  // The robot stays stopped for `hold` while the fault holds (nothing sneaks it forward).
  void expectHeldStill(milliseconds hold) {
    const auto until = Clock::now() + hold;
    while (Clock::now() < until) {
      const auto b = baseState();
      ASSERT_TRUE(b.has_value());
      ASSERT_TRUE(still(*b)) << "moving again while the fault holds: " << b->dump();
      std::this_thread::sleep_for(milliseconds(20));
    }
  }

  // After the fault cleared: staad answers without a fault, and basesim drives again.
  void expectResumes(const char* fault) {
    const auto s = waitStatus([](const Json& j) { return j["fault"].is_null() && j["state"] == "driving"; },
                              milliseconds(10'000));
    ASSERT_TRUE(s.has_value()) << fault << ": the fault did not clear: " << status().value_or(Json()).dump();
    const auto b = waitBase([](const Json& j) { return j["v"].get<double>() > kResumeV; }, milliseconds(10'000));
    ASSERT_TRUE(b.has_value()) << fault << ": the robot did not drive again: " << baseState().value_or(Json()).dump();
    const auto last = status();
    ASSERT_TRUE(last.has_value());
    EXPECT_EQ((*last)["rt_allocations"], 0) << last->dump();
  }

  static void report(const char* fault, const Measured& m, const std::string& extra = "") {
    std::printf("HIL fault=%s detect_ms=%.0f standstill_ms=%.0f bound_ms=%.0f v0=%.3f%s\n", fault, m.detect_ms,
                m.standstill_ms, m.bound_ms, m.v0, extra.c_str());
    std::fflush(stdout);
  }

  // The common shape: cruise, inject, standstill within the bound with the fault named,
  // held while it holds, staad answers, clear, driving again.
  void stopsAndResumes(const char* fault, double detect_s, const std::function<void()>& injectFault,
                       const std::function<bool(const Json&)>& named, const std::function<void()>& clearFault) {
    ASSERT_NO_FATAL_FAILURE(cruise());
    const auto before = baseState();
    ASSERT_TRUE(before.has_value());
    const auto t0 = Clock::now();
    ASSERT_NO_FATAL_FAILURE(injectFault());
    const Measured m = measure((*before)["v"].get<double>(), detect_s, named, t0);
    report(fault, m);
    ASSERT_GE(m.standstill_ms, 0.0) << fault << ": no standstill: " << baseState().value_or(Json()).dump();
    EXPECT_LE(m.standstill_ms, m.bound_ms) << fault;
    ASSERT_GE(m.detect_ms, 0.0) << fault << ": the status never named it: " << status().value_or(Json()).dump();
    const auto s = status();
    ASSERT_TRUE(s.has_value()) << fault << ": staad stopped answering";
    EXPECT_EQ((*s)["state"], "fault") << s->dump();
    ASSERT_NO_FATAL_FAILURE(expectHeldStill(milliseconds(300)));
    EXPECT_TRUE(daemon_.alive());
    ASSERT_NO_FATAL_FAILURE(clearFault());
    ASSERT_NO_FATAL_FAILURE(expectResumes(fault));
  }

  std::function<bool(const Json&)> faultIs(const std::string& text) {
    return [text](const Json& s) { return s["fault"].is_string() && s["fault"].get<std::string>() == text; };
  }

  fs::path dir_;
  Child basesim_;
  Child daemon_;
  LineClient base_;
  LineClient staad_;
};

// The goal over CAN: staad says reached, and basesim's true pose is there too.
TEST_F(Hil, DrivesToAGoalOverCanAndTheBaseTrulyEndsThere) {
  ASSERT_NO_FATAL_FAILURE(startBoth(/*movers=*/2));
  const Json goal = {6.5, 4.5, 0.0};
  const auto t0 = Clock::now();
  ASSERT_TRUE(isOk(staad_.request(poseLine("goal", goal))));
  const auto reached = waitStatus([](const Json& s) { return s["state"] == "reached" && s["goal_id"] == 1; },
                                  milliseconds(40'000));
  ASSERT_TRUE(reached.has_value()) << status().value_or(Json()).dump();
  const auto b = waitBase([](const Json& j) { return still(j); }, milliseconds(3'000));
  ASSERT_TRUE(b.has_value()) << "the base did not stop at the goal";
  const Json& p = (*b)["pose"];
  const double off = std::hypot(p[0].get<double>() - goal[0].get<double>(), p[1].get<double>() - goal[1].get<double>());
  // The goal tolerance (0.2 m) plus the braking distance after "reached" (v^2/2a < 5 cm).
  EXPECT_LE(off, 0.25) << b->dump();
  // staad's dead reckoning from the odometry frames agrees with the truth.
  const auto s = status();
  ASSERT_TRUE(s.has_value());
  const double drift = std::hypot((*s)["pose"][0].get<double>() - p[0].get<double>(),
                                  (*s)["pose"][1].get<double>() - p[1].get<double>());
  EXPECT_LE(drift, 0.02) << s->dump() << "\n" << b->dump();
  EXPECT_EQ((*s)["rt_allocations"], 0);
  EXPECT_EQ((*s)["base"]["bad_frames"], 0) << s->dump();
  EXPECT_EQ((*b)["bad_frames"], 0) << "basesim refused frames of staad: " << b->dump();
  std::printf("HIL goal reached_ms=%.0f base_off_goal_m=%.3f odometry_drift_m=%.4f\n", msSince(t0), off, drift);

  // The base I/O path's timing: the base thread's loop and the command-to-wire latency (a
  // control command's stamp to the driver's sendmsg of its first frame), with sane values.
  const Json& thread = (*s)["threads"]["base"];
  const Json& wire = (*s)["base"]["command_to_wire"];
  for (const Json* h : {&thread["cycle"], &thread["wake"], &wire}) {
    EXPECT_GT((*h)["p50_us"].get<double>(), 0.0) << s->dump();
    EXPECT_GE((*h)["p99_us"].get<double>(), (*h)["p50_us"].get<double>()) << s->dump();
    EXPECT_GE((*h)["max_us"].get<double>(), (*h)["p99_us"].get<double>()) << s->dump();
    EXPECT_LT((*h)["max_us"].get<double>(), 1e6) << s->dump();
  }
  // 100 Hz while driving (several seconds); commands at the profile's 30 Hz.
  EXPECT_GT(thread["cycle"]["count"].get<std::uint64_t>(), 300u) << s->dump();
  EXPECT_GT(wire["count"].get<std::uint64_t>(), 90u) << s->dump();
  EXPECT_FALSE(thread["realtime"].get<bool>()) << "the HIL config asks for normal scheduling";
  // A command's way to the wire: the rest of its control cycle (the planner's budget), the
  // base thread's next period, the driver's next 30 Hz slot; older than 3 control periods it
  // is never sent.
  EXPECT_LT(wire["p50_us"].get<double>(), 1e6 * 3 * kControlPeriodS) << s->dump();
  std::printf("HIL base_io wake_us=%.0f/%.0f/%.0f exec_us=%.0f/%.0f/%.0f command_to_wire_us=%.0f/%.0f/%.0f "
              "commands=%llu unsent=%llu overruns=%llu (p50/p99/max)\n",
              thread["wake"]["p50_us"].get<double>(), thread["wake"]["p99_us"].get<double>(),
              thread["wake"]["max_us"].get<double>(), thread["cycle"]["p50_us"].get<double>(),
              thread["cycle"]["p99_us"].get<double>(), thread["cycle"]["max_us"].get<double>(),
              wire["p50_us"].get<double>(), wire["p99_us"].get<double>(), wire["max_us"].get<double>(),
              static_cast<unsigned long long>(wire["count"].get<std::uint64_t>()),
              static_cast<unsigned long long>(wire["unsent"].get<std::uint64_t>()),
              static_cast<unsigned long long>(thread["cycle"]["overruns"].get<std::uint64_t>()));

  // SIGTERM: staad brakes and exits 0.
  daemon_.signal(SIGTERM);
  const auto code = daemon_.wait(milliseconds(5'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0);
}

// Odometry silence: stale after limits.odometry_timeout_s (0.1 s), then a brake.
TEST_F(Hil, OdometrySilenceBrakesToStandstillAndRecovers) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  stopsAndResumes(
      "odometry_silence", 0.1 + kControlPeriodS + kBasePeriodS, [&] { inject("silence_odometry on"); },
      faultIs("stale_odometry"), [&] { inject("silence_odometry off"); });
}

// Status and heartbeat silence: heartbeat lost after the profile's status timeout (0.2 s) or
// heartbeat timeout (0.3 s), then a brake.
TEST_F(Hil, HeartbeatLossBrakesToStandstillAndRecovers) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  stopsAndResumes(
      "heartbeat_loss", 0.3 + kControlPeriodS + kBasePeriodS, [&] { inject("silence_heartbeat on"); },
      faultIs("base: heartbeat lost"), [&] { inject("silence_heartbeat off"); });
}

// Bus-off: the host's controller is off the bus, so no brake reaches the base: it stops on its
// own command timeout (0.5 s). The status says bus off at once; CAN_ERR_RESTARTED resumes.
TEST_F(Hil, BusOffIsNamedTheBaseStopsOnItsOwnAndRestartResumes) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  const auto before = status();
  ASSERT_TRUE(before.has_value());
  const auto errors0 = (*before)["base"]["error_frames"].get<std::uint64_t>();
  stopsAndResumes(
      "busoff", kBaseTimeoutS, [&] { inject("busoff"); }, faultIs("base: bus off"), [&] { inject("restart"); });
  const auto after = status();
  ASSERT_TRUE(after.has_value());
  EXPECT_GE((*after)["base"]["error_frames"].get<std::uint64_t>(), errors0 + 2) << "bus-off and restarted";
}

// The base's emergency stop: the base decelerates by itself; staad names it and holds.
TEST_F(Hil, BaseEmergencyStopIsNamedAndHeldUntilReleased) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  stopsAndResumes(
      "estop", 1.0 / 50.0, [&] { inject("estop on"); }, faultIs("base: emergency stop"), [&] { inject("estop off"); });
}

// A depth stall (no obstacle frames): stale after limits.obstacles_timeout_s (0.2 s).
TEST_F(Hil, DepthStallBrakesToStandstillAndRecovers) {
  ASSERT_NO_FATAL_FAILURE(startBoth(/*movers=*/1));
  stopsAndResumes(
      "depth_stall", 0.2 + kControlPeriodS + kBasePeriodS,
      [&] { debug({{"debug", "stall_obstacles"}, {"on", true}}); }, faultIs("stale_obstacles"),
      [&] { debug({{"debug", "stall_obstacles"}, {"on", false}}); });
}

// Bad frames among the good ones: counted, dropped, and the robot drives on undisturbed.
TEST_F(Hil, CorruptAndReorderedFramesAreCountedAndDoNotDisturbTheRobot) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  ASSERT_NO_FATAL_FAILURE(cruise());
  const auto s0 = status();
  ASSERT_TRUE(s0.has_value());
  const auto bad0 = (*s0)["base"]["bad_frames"].get<std::uint64_t>();
  constexpr int kFrames = 60;  // 0.6 s of odometry, each with a bad frame beside it
  const auto t0 = Clock::now();
  inject("corrupt " + std::to_string(kFrames));
  double min_v = 1.0;
  double max_drift = 0.0;
  bool faulted = false;
  while (msSince(t0) < 1200.0) {
    const auto b = baseState();
    const auto s = status();
    ASSERT_TRUE(b && s);
    min_v = std::min(min_v, (*b)["v"].get<double>());
    faulted = faulted || !(*s)["fault"].is_null();
    max_drift = std::max(max_drift, std::hypot((*s)["pose"][0].get<double>() - (*b)["pose"][0].get<double>(),
                                               (*s)["pose"][1].get<double>() - (*b)["pose"][1].get<double>()));
    std::this_thread::sleep_for(milliseconds(10));
  }
  const auto b = baseState();
  const auto s = status();
  ASSERT_TRUE(b && s);
  EXPECT_EQ((*b)["corrupt_left"], 0);
  const Json& sent = (*b)["corrupt_sent"];
  // Checksum, DLC and range errors are bad frames; a counter going back and a reordered frame
  // are dropped as stale (counted by the driver apart from bad_frames).
  const auto malformed = sent["bad_checksum"].get<std::uint64_t>() + sent["wrong_dlc"].get<std::uint64_t>() +
                         sent["huge_v"].get<std::uint64_t>();
  EXPECT_GE(malformed, static_cast<std::uint64_t>(kFrames * 3 / 5 - 1)) << b->dump();
  const auto bad = (*s)["base"]["bad_frames"].get<std::uint64_t>() - bad0;
  EXPECT_GE(bad, malformed) << s->dump();
  EXPECT_FALSE(faulted) << "a fault while bad frames came";
  EXPECT_GT(min_v, kCruiseV - 0.03) << "the robot was disturbed";
  // Velocity, not position, feeds staad's pose: a dropped reordered frame loses its 10 ms.
  EXPECT_LE(max_drift, 0.05);
  EXPECT_EQ((*s)["state"], "driving");
  EXPECT_EQ((*s)["rt_allocations"], 0);
  std::printf("HIL fault=corrupt frames=%d malformed_sent=%llu bad_frames_counted=%llu min_v=%.3f odometry_drift_m=%.4f "
              "fault=none\n",
              kFrames, static_cast<unsigned long long>(malformed), static_cast<unsigned long long>(bad), min_v, max_drift);
}

// A forced overrun. 80 ms: the base thread bridges it with the plan's next action (then a
// short brake) and the robot drives on. 1200 ms: after 3 control periods the base thread
// brakes to standstill; when the control thread is back, driving resumes.
TEST_F(Hil, ForcedOverrunFallsBackToPlanNextThenBrakesAndRecovers) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  ASSERT_NO_FATAL_FAILURE(cruise());
  const auto s0 = status();
  ASSERT_TRUE(s0.has_value());
  const auto overruns0 = (*s0)["cycle"]["overruns"].get<std::uint64_t>();

  {
    const auto t0 = Clock::now();
    ASSERT_NO_FATAL_FAILURE(debug({{"debug", "overrun"}, {"ms", 80}}));
    double min_v = 1.0;
    while (msSince(t0) < 600.0) {
      const auto b = baseState();
      ASSERT_TRUE(b.has_value());
      min_v = std::min(min_v, (*b)["v"].get<double>());
      std::this_thread::sleep_for(milliseconds(5));
    }
    const auto s = waitStatus([&](const Json& j) { return j["cycle"]["overruns"].get<std::uint64_t>() > overruns0; },
                              milliseconds(3000));
    ASSERT_TRUE(s.has_value()) << "the overrun was not counted: " << status().value_or(Json()).dump();
    EXPECT_GT(min_v, kResumeV) << "an 80 ms overrun stopped the robot";
    std::printf("HIL fault=overrun_80ms min_v=%.3f overruns=%llu\n", min_v,
                static_cast<unsigned long long>((*s)["cycle"]["overruns"].get<std::uint64_t>()));
  }
  // The base thread's fallback is in the log (the service thread drains it every 10 ms).
  const auto logged = [&](const char* what) {
    const auto deadline = Clock::now() + milliseconds(3000);
    while (Clock::now() < deadline) {
      if (readFile(dir_ / "staad.err").find(what) != std::string::npos) return true;
      std::this_thread::sleep_for(milliseconds(20));
    }
    return false;
  };
  EXPECT_TRUE(logged("on its plan's next action")) << readFile(dir_ / "staad.err");

  ASSERT_NO_FATAL_FAILURE(cruise());
  const auto s1 = status();
  ASSERT_TRUE(s1.has_value());
  const auto overruns1 = (*s1)["cycle"]["overruns"].get<std::uint64_t>();
  const auto before = baseState();
  ASSERT_TRUE(before.has_value());
  const auto t0 = Clock::now();
  ASSERT_NO_FATAL_FAILURE(debug({{"debug", "overrun"}, {"ms", 1200}}));
  // Detection: the command is 3 control periods old, seen by the next base period.
  const Measured m = measure(
      (*before)["v"].get<double>(), 3 * kControlPeriodS + kBasePeriodS,
      [&](const Json& j) { return j["cycle"]["overruns"].get<std::uint64_t>() > overruns1; }, t0);
  report("overrun_1200ms", m, " (detect: the overrun counted, after the busy-wait)");
  ASSERT_GE(m.standstill_ms, 0.0) << baseState().value_or(Json()).dump();
  EXPECT_LE(m.standstill_ms, m.bound_ms);
  EXPECT_LT(m.standstill_ms, 1200.0) << "stopped only when the control thread was back";
  EXPECT_TRUE(logged("no fresh command from the control thread, braking")) << readFile(dir_ / "staad.err");
  EXPECT_TRUE(daemon_.alive());
  ASSERT_NO_FATAL_FAILURE(expectResumes("overrun"));
}

// SIGKILL: nobody brakes; the base stops on its own 0.5 s command timeout.
TEST_F(Hil, SigkillOfTheDaemonLeavesTheBaseToStopOnItsCommandTimeout) {
  ASSERT_NO_FATAL_FAILURE(startBoth());
  ASSERT_NO_FATAL_FAILURE(cruise());
  const auto before = baseState();
  ASSERT_TRUE(before.has_value());
  const auto t0 = Clock::now();
  daemon_.signal(SIGKILL);
  const Measured m = measure((*before)["v"].get<double>(), kBaseTimeoutS, [](const Json&) { return false; }, t0,
                             /*need_status=*/false);
  report("sigkill", m, " (detect: basesim's own command timeout)");
  ASSERT_GE(m.standstill_ms, 0.0) << baseState().value_or(Json()).dump();
  EXPECT_LE(m.standstill_ms, m.bound_ms);
  const auto b = baseState();
  ASSERT_TRUE(b.has_value());
  EXPECT_GE((*b)["since_cmd_s"].get<double>(), kBaseTimeoutS) << "stopped by a command, not by its timeout: " << b->dump();
  EXPECT_FALSE((*b)["connected"].get<bool>());
  EXPECT_FALSE(daemon_.wait(milliseconds(1000)).has_value()) << "killed, not exited";
}

// No base at the configured socket: one line naming it, exit 3.
TEST_F(Hil, MissingBaseSocketExits3NamingIt) {
  const fs::path file = dir_ / "staad.yaml";
  std::ofstream(file) << config(0);
  Child c({STAAD_EXE, "--config", file.string()}, dir_ / "staad.out", dir_ / "staad.err");
  const auto code = c.wait(milliseconds(20'000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 3);
  const std::string err = readFile(dir_ / "staad.err");
  EXPECT_NE(err.find("socketcan.interface"), std::string::npos) << err;
  EXPECT_NE(err.find((dir_ / "base.sock").string()), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir_ / "staad.sock")) << "no control socket is left behind";
}

// Fault injection is for tests only: without debug.faults it is refused, nothing happens.
TEST_F(Hil, DebugRequestsAreRefusedUnlessTheConfigAllowsThem) {
  ASSERT_NO_FATAL_FAILURE(startBasesim());
  ASSERT_NO_FATAL_FAILURE(startDaemon(config(0, /*debug_faults=*/false)));
  for (const Json& r : {Json{{"debug", "overrun"}, {"ms", 80}}, Json{{"debug", "stall_obstacles"}, {"on", true}}}) {
    const auto reply = staad_.request(r.dump());
    ASSERT_TRUE(reply.has_value());
    EXPECT_FALSE(reply->value("ok", true)) << reply->dump();
    EXPECT_NE(reply->value("error", "").find("debug: {faults: true}"), std::string::npos) << reply->dump();
  }
  std::this_thread::sleep_for(milliseconds(300));  // a stall would show as stale_obstacles by now
  const auto s = status();
  ASSERT_TRUE(s.has_value());
  EXPECT_TRUE((*s)["fault"].is_null()) << s->dump();
  EXPECT_EQ(readFile(dir_ / "staad.err").find("forced overrun"), std::string::npos);
}

}  // namespace
