// The real staactl binary against a fake staad: a thread that accepts on a temporary Unix
// socket, reads one request line per connection, records it and answers with a canned line.

#include "app/staad/protocol.hpp"

#include "read_file.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace staa::staad {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using Json = nlohmann::json;

// Never answer: the client must give up by itself.
const std::string kSilent = "<silent>";

class FakeStaad {
 public:
  // `replies` are sent one per connection, in order; the last one repeats.
  FakeStaad(const fs::path& path, std::vector<std::string> replies) : replies_(std::move(replies)) {
    listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
        ::listen(listen_fd_, 8) != 0 || ::pipe2(wake_, O_CLOEXEC) != 0) {
      ADD_FAILURE() << "cannot listen on " << path << ": " << std::strerror(errno);
      return;
    }
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeStaad() {
    if (thread_.joinable()) {
      const char c = 'x';
      [[maybe_unused]] const auto n = ::write(wake_[1], &c, 1);
      thread_.join();
    }
    for (const int fd : {listen_fd_, wake_[0], wake_[1]}) {
      if (fd >= 0) ::close(fd);
    }
  }
  FakeStaad(const FakeStaad&) = delete;
  FakeStaad& operator=(const FakeStaad&) = delete;

  std::vector<std::string> requests() const {
    std::lock_guard lock(mutex_);
    return requests_;
  }

 private:
  // Waits for `fd` or the stop pipe; false when stopping.
  bool waitReadable(int fd) const {
    pollfd p[2] = {{fd, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    for (;;) {
      const int r = ::poll(p, 2, 10'000);
      if (r < 0 && errno == EINTR) continue;
      return r > 0 && (p[1].revents & POLLIN) == 0;
    }
  }

  void serve() {
    std::size_t served = 0;
    while (waitReadable(listen_fd_)) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;
      std::string line;
      char buf[512];
      while (line.find('\n') == std::string::npos && waitReadable(fd)) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n <= 0) break;
        line.append(buf, static_cast<std::size_t>(n));
      }
      const std::string& reply = replies_[std::min(served++, replies_.size() - 1)];
      {
        std::lock_guard lock(mutex_);
        requests_.push_back(line);
      }
      if (reply == kSilent) {
        while (waitReadable(fd) && ::read(fd, buf, sizeof buf) > 0) {  // until the client gives up
        }
      } else {
        [[maybe_unused]] const auto n = ::send(fd, reply.data(), reply.size(), MSG_NOSIGNAL);
      }
      ::close(fd);
    }
  }

  std::vector<std::string> replies_;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};
  std::thread thread_;
  mutable std::mutex mutex_;
  std::vector<std::string> requests_;
};

struct CtlRun {
  int exit_code = -1;  // -1: killed by the time guard or a signal
  std::string out, err;
};

using staa::test::readFile;

class Staactl : public ::testing::Test {
 protected:
  void SetUp() override {
    // Short: a Unix socket path is at most 107 bytes.
    dir_ = fs::temp_directory_path() / ("staactl-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    socket_ = dir_ / "staad.sock";
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // Runs staactl with `args`; STAAD_SOCKET is removed from its environment unless given.
  // A hang is killed after 20 s and fails the test instead of blocking CI.
  CtlRun ctl(const std::vector<std::string>& args, const std::string& staad_socket_env = "") const {
    const fs::path out_file = dir_ / "stdout.txt", err_file = dir_ / "stderr.txt";
    std::vector<std::string> argv_s = {STAACTL_EXE};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> env_s;
    for (char** e = environ; *e != nullptr; ++e) {
      if (std::strncmp(*e, "STAAD_SOCKET=", 13) != 0) env_s.emplace_back(*e);
    }
    if (!staad_socket_env.empty()) env_s.push_back("STAAD_SOCKET=" + staad_socket_env);
    std::vector<char*> envp;
    for (auto& e : env_s) envp.push_back(e.data());
    envp.push_back(nullptr);

    const pid_t pid = ::fork();
    if (pid == 0) {
      const int o = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int e = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (o < 0 || e < 0 || ::dup2(o, 1) < 0 || ::dup2(e, 2) < 0) ::_exit(127);
      ::execve(argv[0], argv.data(), envp.data());
      ::_exit(127);
    }
    CtlRun r;
    if (pid < 0) {
      ADD_FAILURE() << "fork: " << std::strerror(errno);
      return r;
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    int status = 0;
    for (;;) {
      if (::waitpid(pid, &status, WNOHANG) == pid) break;
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        ADD_FAILURE() << "staactl hung (killed after 20 s)";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = readFile(out_file);
    r.err = readFile(err_file);
    return r;
  }

  // A status reply in `state` about goal `goal_id`, with `queued_goal_id` the newest goal
  // the daemon queued (0: as goal_id).
  static std::string statusWith(const char* state, std::uint64_t goal_id = 0, std::uint64_t queued_goal_id = 0) {
    Status s;
    s.goal_id = goal_id;
    s.queued_goal_id = std::max(goal_id, queued_goal_id);
    s.state = state == std::string("driving") ? DaemonState::kDriving
              : state == std::string("reached") ? DaemonState::kReached
              : state == std::string("unreachable") ? DaemonState::kUnreachable
              : state == std::string("stopped")     ? DaemonState::kStopped
                                                    : DaemonState::kIdle;
    s.has_goal = true;
    s.goal = {12.0, 4.5, 1.57};
    if (s.state == DaemonState::kUnreachable) s.reason = "no passage wider than the footprint";
    return statusReply(s, 0);
  }

  static inline int counter_ = 0;
  fs::path dir_;
  fs::path socket_;
};

std::string line(const Request& r) { return requestLine(r); }

TEST_F(Staactl, GoalSendsTheRequestAndPrintsTheGoalsId) {
  FakeStaad staad(socket_, {goalReply(7)});
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "1.57"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "ok (goal 7)\n");
  EXPECT_EQ(r.err, "");
  ASSERT_EQ(staad.requests().size(), 1u);
  EXPECT_EQ(staad.requests()[0], line({RequestKind::kGoal, {3.0, 4.5, 1.57}}));
}

TEST_F(Staactl, GoalWithoutAnIdFromAnOlderStaadPrintsOkButCannotWait) {
  FakeStaad staad(socket_, {okReply()});
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "ok\n");
  const CtlRun w = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait"});
  EXPECT_EQ(w.exit_code, 1);
  EXPECT_THAT(w.err, HasSubstr("did not give the goal an id"));
  EXPECT_EQ(staad.requests().size(), 2u);  // no status polled
}

// The race this guards against: the status read right after the goal was queued still shows
// the previous goal's "reached" (the control thread takes the new goal within one period).
TEST_F(Staactl, GoalWaitIgnoresThePreviousGoalsReachedAndEndsOnItsOwn) {
  FakeStaad staad(socket_, {goalReply(2), statusWith("reached", 1, 2), statusWith("reached", 1, 2),
                            statusWith("driving", 2), statusWith("reached", 2)});
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "ok (goal 2)\nreached\n");
  const auto got = staad.requests();
  ASSERT_EQ(got.size(), 5u) << "returned before the status about goal 2 said reached";
  EXPECT_EQ(got[0], line({RequestKind::kGoal, {3.0, 4.5, 0.0}}));
  for (std::size_t k = 1; k < got.size(); ++k) EXPECT_EQ(got[k], "{\"cmd\":\"status\"}\n");
}

TEST_F(Staactl, GoalWaitTimesOutWhileOnlyThePreviousGoalIsReached) {
  FakeStaad staad(socket_, {goalReply(2), statusWith("reached", 1, 2)});
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait", "--timeout", "0.3"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_EQ(r.out, "ok (goal 2)\n");
  EXPECT_THAT(r.err, HasSubstr("goal: timed out after 0.3 s waiting for goal 2 to be reached (state reached for goal 1, "));
}

TEST_F(Staactl, GoalWaitFailsWhenItsOwnGoalIsUnreachableStoppedOrReplaced) {
  {
    // The previous goal's unreachable does not count; its own does.
    FakeStaad staad(socket_, {goalReply(3), statusWith("unreachable", 2, 3), statusWith("unreachable", 3)});
    const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("goal 3 is unreachable: no passage wider than the footprint"));
    EXPECT_EQ(staad.requests().size(), 3u);
  }
  fs::remove(socket_);
  {
    FakeStaad staad(socket_, {goalReply(3), statusWith("driving", 3), statusWith("stopped", 3)});
    const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("goal 3 was dropped"));
  }
  fs::remove(socket_);
  {
    FakeStaad staad(socket_, {goalReply(3), statusWith("driving", 3), statusWith("reached", 4)});
    const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4.5", "--wait"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("goal 3 was replaced by goal 4"));
  }
}

TEST_F(Staactl, GoalWaitShowsProgressWithTheDistanceToTheGoal) {
  FakeStaad staad(socket_, {goalReply(1), statusWith("driving", 1)});  // the robot at (0, 0)
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "3", "4", "--wait", "--timeout", "1.5"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr("staactl: waiting for goal 1 to be reached: driving at (0.00, 0.00), 5.00 m to the goal, "
                               "fault none, 1 s\n"));
}

TEST_F(Staactl, PoseAndStopSendTheirRequests) {
  FakeStaad staad(socket_, {okReply()});
  // Negative numbers are values, not options; theta defaults to 0; --socket may follow.
  EXPECT_EQ(ctl({"pose", "-1.5", "-2", "--socket", socket_.string()}).exit_code, 0);
  EXPECT_EQ(ctl({"--socket", socket_.string(), "stop"}).exit_code, 0);
  EXPECT_EQ(ctl({"--socket", socket_.string(), "goal", "-1", "2", "-0.5"}).exit_code, 0);
  const auto got = staad.requests();
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0], line({RequestKind::kPose, {-1.5, -2.0, 0.0}}));
  EXPECT_EQ(got[1], line({RequestKind::kStop, {}}));
  EXPECT_EQ(got[2], line({RequestKind::kGoal, {-1.0, 2.0, -0.5}}));
}

TEST_F(Staactl, SocketComesFromTheEnvironmentUnlessGiven) {
  FakeStaad staad(socket_, {okReply()});
  EXPECT_EQ(ctl({"stop"}, socket_.string()).exit_code, 0);
  const CtlRun r = ctl({"--socket", (dir_ / "other.sock").string(), "stop"}, socket_.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr((dir_ / "other.sock").string()));
  EXPECT_EQ(staad.requests().size(), 1u);
}

TEST_F(Staactl, StatusJsonPrintsTheStatusObject) {
  Status s;
  s.state = DaemonState::kDriving;
  s.pose = {1.5, 4.5, 0.25};
  s.has_goal = true;
  s.goal = {12.0, 4.5, 1.57};
  s.cycles = 99;
  s.control_thread.execution.p99_us = 4100.0;
  s.obstacles_age_s = 0.02;
  FakeStaad staad(socket_, {statusReply(s, 7)});
  const CtlRun r = ctl({"--socket", socket_.string(), "status", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Json::parse(r.out), statusJson(s, 7));
  ASSERT_EQ(staad.requests().size(), 1u);
  EXPECT_EQ(staad.requests()[0], "{\"cmd\":\"status\"}\n");
}

TEST_F(Staactl, HistogramsJsonPrintsTheHistogramsObject) {
  const std::string histograms =
      R"({"control":{"period_us":33333.3,"cycles":3,"wake_us":{"bins":[[12,2],[80,1]],"count":3,"overflow":0,)"
      R"("bound_us":100000,"max_us":80.5},"exec_us":{"bins":[[19100,3]],"count":3,"overflow":0,"bound_us":100000,)"
      R"("max_us":19100.9},"overruns":{"total":1,"ours":0,"late_wakeup":0,"preempted":0,"stall":1},)"
      R"("blocked_cycles":2}})";
  FakeStaad staad(socket_, {"{\"ok\":true,\"histograms\":" + histograms + "}\n"});
  const CtlRun r = ctl({"--socket", socket_.string(), "histograms", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Json::parse(r.out), Json::parse(histograms));
  const CtlRun summary = ctl({"--socket", socket_.string(), "histograms"});
  ASSERT_EQ(summary.exit_code, 0) << summary.err;
  EXPECT_EQ(summary.out,
            "control: 3 cycles; wake-up max 80 us, execution max 19101 us; overruns 0 ours, 0 late wake-ups, 0 preempted, "
            "1 stalls; 2 cycles blocked\n");
  ASSERT_EQ(staad.requests().size(), 2u);
  EXPECT_EQ(staad.requests()[0], "{\"cmd\":\"histograms\"}\n");
}

TEST_F(Staactl, HistogramsFromAStaadWithoutThemIsAFailure) {
  FakeStaad staad(socket_, {okReply()});
  const CtlRun r = ctl({"--socket", socket_.string(), "histograms", "--json"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("without a \"histograms\" object"));
}

TEST_F(Staactl, StatusPrintsAHumanSummary) {
  Status s;
  s.state = DaemonState::kFault;
  s.fault = FaultKind::kStaleOdometry;
  s.pose = {1.5, 4.5, 0.25};
  s.cycles = 99;
  s.control_thread.execution.p50_us = 800;
  s.control_thread.execution.p99_us = 4100.0;
  s.control_thread.execution.max_us = 9000;
  s.control_thread.counters.overruns = 2;
  s.odometry_age_s = 0.35;
  FakeStaad staad(socket_, {statusReply(s, 7)});
  const CtlRun r = ctl({"--socket", socket_.string(), "status"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* want : {"state           fault", "x 1.500 m, y 4.500 m, theta 0.250 rad", "goal            none",
                           "fault           stale_odometry", "p50 800 us, p99 4100 us, max 9000 us, 2 overruns in 99 cycles",
                           "odometry 0.350 s, obstacles never", "rt_allocations  7"}) {
    EXPECT_THAT(r.out, HasSubstr(want));
  }
}

TEST_F(Staactl, ErrorReplyExitsOneWithTheMessage) {
  FakeStaad staad(socket_, {errorReply("goal (99, 99): outside the map")});
  const CtlRun r = ctl({"--socket", socket_.string(), "goal", "99", "99"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "");
  EXPECT_THAT(r.err, HasSubstr("staad: goal (99, 99): outside the map"));
}

TEST_F(Staactl, GarbageOrNoReplyIsAFailureNotAHang) {
  {
    FakeStaad staad(socket_, {"\xff\xfe not json\n"});
    const CtlRun r = ctl({"--socket", socket_.string(), "stop"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("not JSON"));
  }
  fs::remove(socket_);
  {
    FakeStaad staad(socket_, {kSilent});
    const CtlRun r = ctl({"--socket", socket_.string(), "status"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("no reply from staad at " + socket_.string() + " within 2 s"));
  }
}

TEST_F(Staactl, NoServerSaysCannotConnect) {
  CtlRun r = ctl({"--socket", socket_.string(), "status"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("staactl: cannot connect to " + socket_.string() + ": "));
  EXPECT_THAT(r.err, HasSubstr("is staad running? --socket or STAAD_SOCKET"));

  // A socket file left behind by a daemon that died: nobody listens on it.
  {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, socket_.c_str(), sizeof addr.sun_path - 1);
    ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0);
    ::close(fd);
  }
  r = ctl({"--socket", socket_.string(), "goal", "1", "2"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot connect to " + socket_.string() + ": Connection refused (is staad running?"));
}

TEST_F(Staactl, BadArgumentsExitTwoNamingTheValue) {
  FakeStaad staad(socket_, {okReply()});
  struct Bad {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Bad> cases = {
      {{"goal", "x", "y"}, "goal: X: expected a finite number (metres), got 'x'"},
      {{"goal", "1", "abc"}, "goal: Y: expected a finite number (metres), got 'abc'"},
      {{"pose", "1", "2", "north"}, "pose: TH: expected a finite number (radians), got 'north'"},
      {{"goal", "1", "inf"}, "got 'inf'"},
      {{"goal", "1"}, "Y"},
      {{"goal", "1", "2", "3", "4"}, "4"},
      {{"fly"}, "unknown command 'fly'"},
      {{}, "subcommand"},
      {{"status", "--yaml"}, "--yaml"},
      {{"wait", "--timeout", "soon"}, "wait: --timeout: expected seconds (a finite number > 0), got 'soon'"},
      {{"wait", "--timeout", "-1"}, "got '-1'"},
      {{"wait", "--state", "arrived"}, "wait: --state: expected idle, driving, reached, unreachable, stopped or fault, got 'arrived'"},
      {{"goal", "1", "2", "--timeout", "5"}, "goal: --timeout: only with --wait"},
      {{"goal", "1", "2", "--wait", "--timeout", "0"}, "goal: --timeout: expected seconds (a finite number > 0), got '0'"},
  };
  for (const Bad& b : cases) {
    std::vector<std::string> args = {"--socket", socket_.string()};
    args.insert(args.end(), b.args.begin(), b.args.end());
    const CtlRun r = ctl(args);
    SCOPED_TRACE(r.err);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_THAT(r.err, HasSubstr(b.expected));
  }
  const CtlRun long_path = ctl({"--socket", "/" + std::string(120, 'x'), "stop"});
  EXPECT_EQ(long_path.exit_code, 2);
  EXPECT_THAT(long_path.err, HasSubstr("--socket: a Unix socket path is at most 107 bytes"));
  EXPECT_TRUE(staad.requests().empty()) << "bad arguments must not reach staad";
}

TEST_F(Staactl, WaitPollsUntilReached) {
  FakeStaad staad(socket_, {statusWith("driving"), statusWith("driving"), statusWith("reached")});
  const CtlRun r = ctl({"--socket", socket_.string(), "wait"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "reached\n");
  const auto got = staad.requests();
  ASSERT_EQ(got.size(), 3u);
  for (const auto& g : got) EXPECT_EQ(g, "{\"cmd\":\"status\"}\n");
}

TEST_F(Staactl, WaitIgnoresReachedOfAGoalOlderThanTheNewestQueued) {
  // `staactl goal` just queued goal 2; the control thread still reports goal 1 reached.
  FakeStaad staad(socket_, {statusWith("reached", 1, 2), statusWith("unreachable", 1, 2), statusWith("driving", 2),
                            statusWith("reached", 2)});
  const CtlRun r = ctl({"--socket", socket_.string(), "wait"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "reached\n");
  EXPECT_EQ(staad.requests().size(), 4u);
}

TEST_F(Staactl, WaitForAnotherStateAndUnreachableAndTimeout) {
  {
    FakeStaad staad(socket_, {statusWith("driving"), statusWith("idle")});
    EXPECT_EQ(ctl({"--socket", socket_.string(), "wait", "--state", "idle"}).exit_code, 0);
  }
  fs::remove(socket_);
  {
    FakeStaad staad(socket_, {statusWith("driving"), statusWith("unreachable")});
    const CtlRun r = ctl({"--socket", socket_.string(), "wait"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("unreachable"));
  }
  fs::remove(socket_);
  {
    FakeStaad staad(socket_, {statusWith("driving")});
    const CtlRun r = ctl({"--socket", socket_.string(), "wait", "--timeout", "0.3"});
    EXPECT_EQ(r.exit_code, 3);
    EXPECT_THAT(r.err, HasSubstr("timed out after 0.3 s waiting for reached (state driving)"));
  }
}

}  // namespace
}  // namespace staa::staad
