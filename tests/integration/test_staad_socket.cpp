// The control socket under abuse, staad on the simulated HAL: 16 silent clients holding
// every slot do not lock staactl out (the longest-idle one makes room, and stop and status
// are answered well under a second); a silent client and one that dribbles a line without
// ever ending it are closed after socket.idle_timeout_s; a client that sends a request every
// second under a longer timeout is never dropped.
//
// Every wait has a timeout, and every process this test starts is killed in teardown.
#include "child_process.hpp"
#include "raw_client.hpp"
#include "read_file.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
using staa::test::Child;
using staa::test::environmentWithout;
using staa::test::RawClient;
using staa::test::readFile;

bool isErrorReplyNaming(const std::optional<std::string>& line, const std::string& what) {
  if (!line) return false;
  const auto j = nlohmann::json::parse(*line, nullptr, false);
  return j.is_object() && j.value("ok", true) == false && j.contains("error") && j["error"].is_string() &&
         j["error"].get<std::string>().find(what) != std::string::npos;
}

bool isStatusReply(const std::optional<std::string>& line) {
  if (!line) return false;
  const auto j = nlohmann::json::parse(*line, nullptr, false);
  return j.is_object() && j.value("ok", false) == true && j.contains("status") && j["status"].is_object();
}

long long msSince(Clock::time_point t0) {
  return std::chrono::duration_cast<milliseconds>(Clock::now() - t0).count();
}

class StaadSocket : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/staad-socket-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
    socket_ = dir_ / "staad.sock";
  }
  void TearDown() override {
    daemon_.kill();
    if (HasFailure()) std::cerr << "---- staad's stderr ----\n" << readFile(dir_ / "staad.err") << "------------------------\n";
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Starts staad with `socket_keys` added to the socket section; waits until it answers.
  void startDaemon(const std::string& socket_keys) {
    const fs::path src = staa::test::sourceDir();
    std::string y;
    y += "format: staad-config/1\n";
    y += "robot: " + (src / "config/robots/paper-agent.yaml").string() + "\n";
    y += "map: " + (src / "config/maps/office.yaml").string() + "\n";
    y += "hal: sim\n";
    y += "sim: {start: [4.5, 4.5, 0.0], movers: 0, seed: 1}\n";
    y += "threads:\n";
    y += "  control: {priority: 80, cpu: -1}\n";
    y += "  base: {priority: 85, cpu: -1}\n";
    y += "  perception: {priority: 70, cpu: -1}\n";
    y += "socket: {path: " + socket_.string() + ", mode: \"0660\"" + socket_keys + "}\n";
    y += "memory: {heap_prefault_mb: 16, stack_prefault_kb: 256}\n";
    const fs::path config = dir_ / "staad.yaml";
    std::ofstream(config) << y;
    std::vector<std::string> env = environmentWithout({"NOTIFY_SOCKET=", "WATCHDOG_USEC=", "WATCHDOG_PID="});
    daemon_ = Child({STAAD_EXE, "--config", config.string()}, env, dir_ / "staad.out", dir_ / "staad.err");
    ASSERT_GT(daemon_.pid(), 0);
    const auto deadline = Clock::now() + milliseconds(10'000);
    while (Clock::now() < deadline && staactl({"status"}).first != 0) std::this_thread::sleep_for(milliseconds(50));
    ASSERT_EQ(staactl({"status"}).first, 0) << "staad does not answer";
  }

  // Runs staactl with a timeout: its exit code (nullopt: did not finish) and its stdout.
  std::pair<std::optional<int>, std::string> staactl(const std::vector<std::string>& args,
                                                      milliseconds timeout = milliseconds(5'000)) {
    std::vector<std::string> argv{STAACTL_EXE, "--socket", socket_.string()};
    argv.insert(argv.end(), args.begin(), args.end());
    const fs::path out = dir_ / "staactl.out";
    Child c(argv, environmentWithout({"NOTIFY_SOCKET="}), out, dir_ / "staactl.err");
    const std::optional<int> code = c.wait(timeout);
    return {code, readFile(out)};
  }

  // `count` connections that send nothing; returns once staad has had a few rounds to accept them.
  std::vector<std::unique_ptr<RawClient>> silentClients(int count) {
    std::vector<std::unique_ptr<RawClient>> clients;
    for (int i = 0; i < count; ++i) {
      clients.push_back(std::make_unique<RawClient>(socket_));
      EXPECT_TRUE(clients.back()->connected()) << "client " << i;
      std::this_thread::sleep_for(milliseconds(5));  // accepted one by one, oldest first
    }
    std::this_thread::sleep_for(milliseconds(100));
    return clients;
  }

  int count(const std::string& text, const std::string& what) {
    int n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  }

  fs::path dir_;
  fs::path socket_;
  Child daemon_;
};

TEST_F(StaadSocket, SixteenSilentClientsDoNotLockOutStaactl) {
  startDaemon("");  // the defaults: 16 clients, 5 s
  auto silent = silentClients(16);

  // All 16 slots are taken: staactl's connection makes room by dropping the longest-idle one.
  auto t0 = Clock::now();
  const auto [stop_code, stop_out] = staactl({"stop"});
  const long long stop_ms = msSince(t0);
  ASSERT_TRUE(stop_code.has_value());
  EXPECT_EQ(*stop_code, 0) << stop_out << readFile(dir_ / "staactl.err");
  EXPECT_LT(stop_ms, 500) << "staactl stop took " << stop_ms << " ms with 16 silent clients connected";

  t0 = Clock::now();
  const auto [status_code, status_out] = staactl({"status", "--json"});
  const long long status_ms = msSince(t0);
  ASSERT_TRUE(status_code.has_value());
  EXPECT_EQ(*status_code, 0) << status_out;
  const auto status = nlohmann::json::parse(status_out, nullptr, false);
  EXPECT_TRUE(status.is_object() && status.contains("state") && status["state"].is_string()) << status_out;
  EXPECT_LT(status_ms, 500) << "staactl status took " << status_ms << " ms";
  std::cout << "with 16 silent clients: staactl stop " << stop_ms << " ms, status " << status_ms << " ms\n";

  // The oldest silent client was dropped, with a reply saying why; the others still stand
  // (stop's connection freed its slot again, so status needed no room).
  ASSERT_TRUE(silent[0]->waitClosed(milliseconds(1000)));
  EXPECT_TRUE(isErrorReplyNaming(silent[0]->bufferedLine(), "socket.max_clients"));
  for (std::size_t i = 1; i < silent.size(); ++i) EXPECT_FALSE(silent[i]->waitClosed(milliseconds(0))) << "client " << i;
  ASSERT_TRUE(silent[1]->send("{\"cmd\": \"status\"}\n"));
  EXPECT_TRUE(isStatusReply(silent[1]->readLine(milliseconds(2000))));
  // The control thread's log line reaches the log a few cycles later.
  std::string log = readFile(dir_ / "staad.err");
  for (int i = 0; i < 40 && log.find("stop requested") == std::string::npos; ++i) {
    std::this_thread::sleep_for(milliseconds(50));
    log = readFile(dir_ / "staad.err");
  }
  EXPECT_NE(log.find("stop requested"), std::string::npos) << log;
  EXPECT_EQ(count(log, "dropped the longest-idle client"), 1) << log;
  EXPECT_NE(log.find("all 16 client slots (socket.max_clients) taken"), std::string::npos) << log;
  EXPECT_TRUE(daemon_.alive());
}

TEST_F(StaadSocket, SilentAndUnfinishedLinesAreClosedAfterTheIdleTimeout) {
  startDaemon(", idle_timeout_s: 0.3");
  const auto t0 = Clock::now();
  RawClient silent(socket_);
  RawClient partial(socket_);
  ASSERT_TRUE(silent.connected());
  ASSERT_TRUE(partial.connected());
  ASSERT_TRUE(partial.send("{\"cmd\": \"sta"));  // a request line never finished

  ASSERT_TRUE(silent.waitClosed(milliseconds(3000))) << "a silent client is not closed";
  const long long silent_ms = msSince(t0);
  ASSERT_TRUE(partial.waitClosed(milliseconds(3000))) << "a client with half a line is not closed";
  const long long partial_ms = msSince(t0);
  std::cout << "idle timeout 0.3 s: silent client closed after " << silent_ms << " ms, half a line after "
            << partial_ms << " ms\n";
  EXPECT_GE(silent_ms, 250);
  EXPECT_LT(silent_ms, 1000);
  EXPECT_GE(partial_ms, 250);
  EXPECT_LT(partial_ms, 1000);
  EXPECT_TRUE(isErrorReplyNaming(silent.bufferedLine(), "socket.idle_timeout_s"));
  EXPECT_TRUE(isErrorReplyNaming(partial.bufferedLine(), "socket.idle_timeout_s"));
  const std::string log = readFile(dir_ / "staad.err");
  EXPECT_EQ(count(log, "dropped a client with no complete line within 0.3 s (socket.idle_timeout_s)"), 2) << log;
  EXPECT_NE(log.find("12 bytes of a line pending"), std::string::npos) << log;
  EXPECT_EQ(staactl({"status"}).first, 0);  // staactl itself is well within the timeout
}

TEST_F(StaadSocket, AClientWithARequestEverySecondStaysAndADribblerIsDropped) {
  startDaemon(", idle_timeout_s: 1.5");
  RawClient steady(socket_);
  RawClient dribbler(socket_);
  ASSERT_TRUE(steady.connected());
  ASSERT_TRUE(dribbler.connected());
  // The dribbler sends a byte every 100 ms and never a newline: bytes alone do not keep it.
  const auto t0 = Clock::now();
  std::optional<long long> dribbler_closed_ms;
  int replies = 0;
  auto next_request = t0;
  while (msSince(t0) < 5'000) {
    if (Clock::now() >= next_request) {
      ASSERT_TRUE(steady.send("{\"cmd\": \"status\"}\n")) << "after " << msSince(t0) << " ms";
      ASSERT_TRUE(isStatusReply(steady.readLine(milliseconds(1000)))) << "after " << msSince(t0) << " ms";
      ++replies;
      next_request += milliseconds(1000);
    }
    if (!dribbler_closed_ms) {
      if (dribbler.waitClosed(milliseconds(0))) dribbler_closed_ms = msSince(t0);
      else (void)dribbler.send("a");
    }
    std::this_thread::sleep_for(milliseconds(100));
  }
  EXPECT_EQ(replies, 5);
  EXPECT_FALSE(steady.waitClosed(milliseconds(0)));
  ASSERT_TRUE(dribbler_closed_ms.has_value()) << "the dribbler was never closed";
  EXPECT_GE(*dribbler_closed_ms, 1400);
  EXPECT_LT(*dribbler_closed_ms, 2500);
  std::cout << "idle timeout 1.5 s: " << replies << " requests a second answered, dribbler closed after "
            << *dribbler_closed_ms << " ms\n";
  const std::string log = readFile(dir_ / "staad.err");
  EXPECT_EQ(count(log, "dropped a client with no complete line"), 1) << log;
}

}  // namespace
