#pragma once
// Test support for the ROS 1 tests (plain C++20, no ROS header): a ROS master of the test's
// own on a free port of 127.0.0.1 with its ROS_HOME and logs in a fresh temporary folder, and
// the ROS programs under test started as child processes in that graph. Every process runs
// in its own process group, which is killed when its handle goes out of scope, and the
// folder is removed with the master (set STAA_KEEP_ROS_TEST_DIRS=1 to keep it), so parallel
// tests share nothing and leave nothing behind.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace staa::test {

// A child process in a process group of its own (its pid is the group's id), stdin from
// /dev/null, stdout and stderr to files, SIGINT/SIGTERM/SIGUSR1 at their defaults. Its
// destructor kills the whole group (SIGKILL) and reaps the child. The child also gets
// SIGKILL when the thread that started it ends (PR_SET_PDEATHSIG, so a test killed by its
// timeout leaves nothing): start processes from the test's own thread.
class RosProcess {
 public:
  RosProcess() = default;
  // Starts argv[0] (a path; PATH is not searched) with exactly `env` ("NAME=value").
  // Throws std::runtime_error when it cannot be started.
  RosProcess(const std::vector<std::string>& argv, const std::vector<std::string>& env,
             const std::filesystem::path& out, const std::filesystem::path& err);
  RosProcess(const RosProcess&) = delete;
  RosProcess& operator=(const RosProcess&) = delete;
  RosProcess(RosProcess&& o) noexcept;
  RosProcess& operator=(RosProcess&& o) noexcept;
  ~RosProcess();

  pid_t pid() const { return pid_; }
  bool alive();
  // Sends `sig` to the whole process group (nothing once the child is reaped).
  void kill(int sig);
  // Waits up to `timeout` for the child to exit; its exit code, or nullopt (still running,
  // or ended by a signal: see reaped() and rawStatus()).
  std::optional<int> wait(std::chrono::milliseconds timeout);
  // SIGTERM to the group, then SIGKILL after `grace`; reaps the child. The exit code as wait's.
  std::optional<int> stop(std::chrono::milliseconds grace = std::chrono::milliseconds(3000));
  bool reaped() const { return reaped_; }
  int rawStatus() const { return status_; }

  const std::filesystem::path& outPath() const { return out_; }
  const std::filesystem::path& errPath() const { return err_; }
  std::string out() const;  // what it wrote to stdout so far
  std::string err() const;
  // Waits until stdout holds at least `lines` complete lines (or the child has exited);
  // the complete lines read.
  std::vector<std::string> waitForLines(std::size_t lines, std::chrono::milliseconds timeout);

 private:
  bool poll();
  void killGroupAndReap();

  pid_t pid_ = -1;
  int status_ = 0;
  bool reaped_ = false;
  std::filesystem::path out_, err_;
};

// The result of a program run to its end by RosMaster::run.
struct RosRun {
  std::optional<int> exit_code;  // nullopt: timed out (then killed) or ended by a signal
  std::string out, err;
  // The stdout lines (without their newline).
  std::vector<std::string> lines() const;
};

class RosMaster {
 public:
  // Starts `rosmaster --core` on a free port in a fresh folder named after `name` (the test's
  // name, for the folder's name only) and waits until it answers getPid with its own pid.
  // Throws std::runtime_error naming what failed (with the master's log) after `timeout`.
  explicit RosMaster(const std::string& name, std::chrono::milliseconds timeout = std::chrono::seconds(20));
  RosMaster(const RosMaster&) = delete;
  RosMaster& operator=(const RosMaster&) = delete;
  // Stops the master (SIGINT, then SIGKILL) and removes the folder.
  ~RosMaster();

  int port() const { return port_; }
  std::string uri() const;  // "http://127.0.0.1:PORT"
  pid_t pid() const { return master_.pid(); }
  const std::filesystem::path& dir() const { return dir_; }
  // How long the start took (spawn to the first answer, retries included).
  std::chrono::milliseconds startupTime() const { return startup_; }
  // The entries a ROS process of this graph needs: ROS_MASTER_URI, ROS_HOME, ROS_LOG_DIR,
  // ROS_IP=127.0.0.1.
  std::vector<std::string> env() const;
  // This process's environment without the variables that would join another graph
  // (ROS_MASTER_URI, ROS_HOSTNAME, ROS_IP, ROS_HOME, ROS_LOG_DIR, ROS_NAMESPACE) or talk to
  // systemd (NOTIFY_SOCKET, WATCHDOG_*), with env() and `extra` ("NAME=value") added.
  std::vector<std::string> childEnvironment(const std::vector<std::string>& extra = {}) const;

  // Starts argv in this graph, stdout and stderr to dir()/NAME.out and dir()/NAME.err.
  // Private parameters given as _name:=value stay on this master after the node ends: a
  // second run of the same node with other values needs another __name:=.
  RosProcess spawn(const std::string& name, const std::vector<std::string>& argv,
                   const std::vector<std::string>& extra_env = {}) const;
  // Spawns and waits up to `timeout` for the exit (killed after it).
  RosRun run(const std::string& name, const std::vector<std::string>& argv, std::chrono::milliseconds timeout,
             const std::vector<std::string>& extra_env = {}) const;

  // One XML-RPC call of the master API with string parameters (the caller id is the first);
  // the raw response body, nullopt when the master does not answer within `timeout`.
  std::optional<std::string> call(std::string_view method, const std::vector<std::string>& params,
                                  std::chrono::milliseconds timeout = std::chrono::milliseconds(2000)) const;
  // The nodes the master lists as publishers / subscribers of `topic` (getSystemState).
  std::vector<std::string> publishers(const std::string& topic) const;
  std::vector<std::string> subscribers(const std::string& topic) const;
  // Waits until `topic` has at least one publisher / subscriber.
  bool waitForPublisher(const std::string& topic, std::chrono::milliseconds timeout) const;
  bool waitForSubscriber(const std::string& topic, std::chrono::milliseconds timeout) const;

 private:
  bool tryStart(std::chrono::steady_clock::time_point deadline, std::string& why);
  std::optional<long> masterPid() const;

  std::filesystem::path dir_;
  int port_ = 0;
  RosProcess master_;
  std::chrono::milliseconds startup_{0};
  bool keep_dir_ = false;
};

// A free TCP port on 127.0.0.1 (bound to port 0 and closed again: another process may take it
// before it is used, so users retry on a collision).
int freeLocalPort();

}  // namespace staa::test
