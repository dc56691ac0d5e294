#pragma once
// Test support: a child process (the real staad, staactl, basesim) started with posix_spawn,
// stdin from /dev/null and stdout/stderr to files, killed (SIGKILL) and reaped when it goes
// out of scope; and the test's environment without some variables (NOTIFY_SOCKET, so a
// daemon under test never talks to the systemd of whoever runs the tests).

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace staa::test {

// The current environment without the entries that start with any of `drop_prefixes`.
inline std::vector<std::string> environmentWithout(const std::vector<std::string>& drop_prefixes) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    bool keep = true;
    for (const std::string& p : drop_prefixes) keep = keep && entry.rfind(p, 0) != 0;
    if (keep) env.push_back(entry);
  }
  return env;
}

// The environment for a daemon under test: this process's, without NOTIFY_SOCKET and
// WATCHDOG_* (staad must not talk to the systemd of whoever runs the tests), with `extra`
// ("NAME=value") added, replacing NAME.
inline std::vector<std::string> daemonEnvironment(const std::vector<std::string>& extra = {}) {
  std::vector<std::string> drop{"NOTIFY_SOCKET=", "WATCHDOG_"};
  for (const std::string& x : extra) drop.push_back(x.substr(0, x.find('=') + 1));
  std::vector<std::string> env = environmentWithout(drop);
  env.insert(env.end(), extra.begin(), extra.end());
  return env;
}

class Child {
 public:
  Child() = default;
  // With daemonEnvironment(extra_env).
  Child(const std::vector<std::string>& argv, const std::filesystem::path& out, const std::filesystem::path& err,
        const std::vector<std::string>& extra_env = {})
      : Child(argv, daemonEnvironment(extra_env), out, err) {}
  Child(const std::vector<std::string>& argv, const std::vector<std::string>& env, const std::filesystem::path& out,
        const std::filesystem::path& err) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::vector<char*> envp;
    for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    const int rc = posix_spawn(&pid_, argv[0].c_str(), &fa, nullptr, args.data(), envp.data());
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) pid_ = -1;
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  Child(Child&& o) noexcept : pid_(o.pid_), status_(o.status_), reaped_(o.reaped_) { o.pid_ = -1; }
  Child& operator=(Child&& o) noexcept {
    if (this != &o) {
      kill();
      pid_ = o.pid_;
      status_ = o.status_;
      reaped_ = o.reaped_;
      o.pid_ = -1;
    }
    return *this;
  }
  ~Child() { kill(); }

  pid_t pid() const { return pid_; }
  bool started() const { return pid_ > 0; }
  bool alive() { return pid_ > 0 && !reaped_ && !poll(); }
  // Waits up to `timeout` for the exit; the exit code, or nullopt (still running, or killed
  // by a signal).
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!poll()) {
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (WIFEXITED(status_)) return WEXITSTATUS(status_);
    return std::nullopt;
  }
  // The raw wait status once reaped (for WIFSIGNALED/WTERMSIG checks).
  int rawStatus() const { return status_; }
  bool reaped() const { return reaped_; }
  void signal(int sig) {
    if (pid_ > 0 && !reaped_) ::kill(pid_, sig);
  }
  void kill() {
    if (pid_ <= 0 || reaped_) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
    reaped_ = true;
  }

 private:
  bool poll() {
    if (reaped_ || pid_ <= 0) return true;
    if (::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
    return reaped_;
  }

  pid_t pid_ = -1;
  int status_ = 0;
  bool reaped_ = false;
};

}  // namespace staa::test
