#include "rt/sd_notify.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>
#include <vector>

namespace staa::rt {
namespace {

// A datagram socket standing in for systemd's notification socket.
class Receiver {
 public:
  // A file-system socket at `path`.
  explicit Receiver(const std::string& path) : fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    bind(addr, static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() + 1));
  }
  // An abstract socket named `name` (no leading NUL or '@').
  static Receiver abstract(const std::string& name) { return Receiver(name, 0); }
  Receiver(Receiver&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  ~Receiver() {
    if (fd_ >= 0) ::close(fd_);
  }

  // The next datagram already queued, or nullopt (never waits: a local datagram is queued
  // by the time sendto returns).
  std::optional<std::string> next() const {
    char buf[1024];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
    if (n < 0) return std::nullopt;
    return std::string(buf, static_cast<std::size_t>(n));
  }

 private:
  Receiver(const std::string& name, int) : fd_(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    addr.sun_path[0] = '\0';
    std::memcpy(addr.sun_path + 1, name.data(), name.size());
    bind(addr, static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size()));
  }
  void bind(const sockaddr_un& addr, socklen_t len) {
    if (fd_ < 0) throw std::runtime_error("test receiver: socket: " + std::string(std::strerror(errno)));
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), len) != 0) {
      throw std::runtime_error("test receiver: bind: " + std::string(std::strerror(errno)));
    }
  }
  int fd_;
};

// A fresh directory for socket files, removed afterwards.
class SocketDir : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/staa-notify-XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr) << std::strerror(errno);
    dir_ = tmpl;
  }
  void TearDown() override {
    for (const std::string& p : files_) ::unlink(p.c_str());
    if (!dir_.empty()) ::rmdir(dir_.c_str());
  }
  std::string socketPath(const std::string& name) {
    files_.push_back(dir_ + "/" + name);
    return files_.back();
  }
  std::string dir_;
  std::vector<std::string> files_;
};

// Sets (or unsets) an environment variable for one test, restoring it afterwards.
class EnvVar {
 public:
  EnvVar(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~EnvVar() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

template <typename F>
std::string thrownMessage(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

TEST_F(SocketDir, SendsEachMessageAsOneDatagramToAPathSocket) {
  const std::string path = socketPath("notify");
  Receiver systemd(path);
  const Notifier n(path);
  ASSERT_TRUE(n.enabled());
  EXPECT_EQ(n.ready(), 0);
  EXPECT_EQ(n.status("planning 3 of 5"), 0);
  EXPECT_EQ(n.watchdog(), 0);
  EXPECT_EQ(n.stopping(), 0);
  EXPECT_EQ(systemd.next(), "READY=1");
  EXPECT_EQ(systemd.next(), "STATUS=planning 3 of 5");
  EXPECT_EQ(systemd.next(), "WATCHDOG=1");
  EXPECT_EQ(systemd.next(), "STOPPING=1");
  EXPECT_EQ(systemd.next(), std::nullopt);  // exactly those four
}

TEST(Notifier, SendsToAnAbstractSocket) {
  const std::string name = "staa-test-notify-" + std::to_string(::getpid());
  Receiver systemd = Receiver::abstract(name);
  const Notifier n("@" + name);
  ASSERT_TRUE(n.enabled());
  EXPECT_EQ(n.ready(), 0);
  EXPECT_EQ(n.status("ok"), 0);
  EXPECT_EQ(n.watchdog(), 0);
  EXPECT_EQ(n.stopping(), 0);
  EXPECT_EQ(systemd.next(), "READY=1");
  EXPECT_EQ(systemd.next(), "STATUS=ok");
  EXPECT_EQ(systemd.next(), "WATCHDOG=1");
  EXPECT_EQ(systemd.next(), "STOPPING=1");
  EXPECT_EQ(systemd.next(), std::nullopt);
}

TEST_F(SocketDir, StatusIsTruncatedTo200BytesOnACharacterBoundary) {
  const std::string path = socketPath("notify");
  Receiver systemd(path);
  const Notifier n(path);

  EXPECT_EQ(n.status(std::string(300, 'x')), 0);
  const std::optional<std::string> cut = systemd.next();
  ASSERT_TRUE(cut.has_value());
  EXPECT_EQ(cut->size(), 200u);
  EXPECT_EQ(*cut, "STATUS=" + std::string(193, 'x'));

  // 192 + a two-byte character would end at byte 201: the whole character is left out.
  EXPECT_EQ(n.status(std::string(192, 'a') + "\xC3\xA9tat"), 0);
  const std::optional<std::string> utf8 = systemd.next();
  ASSERT_TRUE(utf8.has_value());
  EXPECT_EQ(*utf8, "STATUS=" + std::string(192, 'a'));

  // A newline cannot smuggle in another assignment.
  EXPECT_EQ(n.status("bad\nREADY=1"), 0);
  EXPECT_EQ(systemd.next(), "STATUS=bad READY=1");
}

TEST_F(SocketDir, MovedNotifierKeepsTheSocket) {
  const std::string path = socketPath("notify");
  Receiver systemd(path);
  Notifier a(path);
  Notifier b(std::move(a));
  EXPECT_FALSE(a.enabled());  // NOLINT(bugprone-use-after-move): the moved-from state is the point
  EXPECT_EQ(a.ready(), 0);
  ASSERT_TRUE(b.enabled());
  EXPECT_EQ(b.ready(), 0);
  Notifier c("");
  c = std::move(b);
  EXPECT_EQ(c.watchdog(), 0);
  EXPECT_EQ(systemd.next(), "READY=1");
  EXPECT_EQ(systemd.next(), "WATCHDOG=1");
  EXPECT_EQ(systemd.next(), std::nullopt);
}

TEST_F(SocketDir, SendingToANonexistentSocketReturnsTheErrorInsteadOfThrowing) {
  const Notifier n(dir_ + "/nobody-listens");
  ASSERT_TRUE(n.enabled());
  const int err = n.ready();
  EXPECT_TRUE(err == ENOENT || err == ECONNREFUSED) << "errno " << err;
}

TEST_F(SocketDir, FromEnvironmentUsesNotifySocket) {
  const std::string path = socketPath("notify");
  Receiver systemd(path);
  const EnvVar env("NOTIFY_SOCKET", path.c_str());
  const Notifier n = Notifier::fromEnvironment();
  ASSERT_TRUE(n.enabled());
  EXPECT_EQ(n.ready(), 0);
  EXPECT_EQ(systemd.next(), "READY=1");
}

TEST(Notifier, WithoutNotifySocketEverythingIsANoOp) {
  {
    const EnvVar env("NOTIFY_SOCKET", nullptr);
    const Notifier n = Notifier::fromEnvironment();
    EXPECT_FALSE(n.enabled());
    EXPECT_EQ(n.ready(), 0);
    EXPECT_EQ(n.status("anything"), 0);
    EXPECT_EQ(n.send("WATCHDOG=1"), 0);
  }
  {
    const EnvVar env("NOTIFY_SOCKET", "");
    EXPECT_FALSE(Notifier::fromEnvironment().enabled());
  }
  EXPECT_FALSE(Notifier("").enabled());
}

TEST(Notifier, UnusableNotifySocketThrowsNamingTheVariableAndValue) {
  {
    const EnvVar env("NOTIFY_SOCKET", "relative/path");
    const std::string msg = thrownMessage([] { (void)Notifier::fromEnvironment(); });
    EXPECT_NE(msg.find("NOTIFY_SOCKET"), std::string::npos) << msg;
    EXPECT_NE(msg.find("relative/path"), std::string::npos) << msg;
  }
  {
    const std::string too_long = "/" + std::string(200, 'p');
    const EnvVar env("NOTIFY_SOCKET", too_long.c_str());
    const std::string msg = thrownMessage([] { (void)Notifier::fromEnvironment(); });
    EXPECT_NE(msg.find("NOTIFY_SOCKET"), std::string::npos) << msg;
    EXPECT_NE(msg.find("too long"), std::string::npos) << msg;
  }
  EXPECT_THROW(Notifier("@"), std::runtime_error);
  const std::string msg = thrownMessage([] { Notifier n("vsock:2:1234"); });
  EXPECT_NE(msg.find("vsock:2:1234"), std::string::npos) << msg;
}

TEST(Notifier, WatchdogIntervalIsHalfOfWatchdogUsec) {
  {
    const EnvVar usec("WATCHDOG_USEC", nullptr);
    EXPECT_EQ(Notifier::watchdogInterval(), std::nullopt);
  }
  const EnvVar usec("WATCHDOG_USEC", "2000000");
  {
    const EnvVar pid("WATCHDOG_PID", nullptr);
    EXPECT_EQ(Notifier::watchdogInterval(), std::optional<Nanos>(kNanosPerSecond));
  }
  {
    const std::string self = std::to_string(::getpid());
    const EnvVar pid("WATCHDOG_PID", self.c_str());
    EXPECT_EQ(Notifier::watchdogInterval(), std::optional<Nanos>(kNanosPerSecond));
  }
  {
    // Meant for another process (we inherited our parent's environment): not ours to ping.
    const std::string other = std::to_string(::getpid() + 1);
    const EnvVar pid("WATCHDOG_PID", other.c_str());
    EXPECT_EQ(Notifier::watchdogInterval(), std::nullopt);
  }
}

TEST(Notifier, MalformedWatchdogVariablesThrowNamingThem) {
  const EnvVar pid("WATCHDOG_PID", nullptr);
  for (const char* bad : {"abc", "0", "-5", "12x", " 7", "99999999999999999999999"}) {
    const EnvVar usec("WATCHDOG_USEC", bad);
    const std::string msg = thrownMessage([] { (void)Notifier::watchdogInterval(); });
    EXPECT_NE(msg.find("WATCHDOG_USEC"), std::string::npos) << bad << ": " << msg;
    EXPECT_NE(msg.find(bad), std::string::npos) << bad << ": " << msg;
  }
  const EnvVar usec("WATCHDOG_USEC", "1000");
  const EnvVar bad_pid("WATCHDOG_PID", "me");
  const std::string msg = thrownMessage([] { (void)Notifier::watchdogInterval(); });
  EXPECT_NE(msg.find("WATCHDOG_PID='me'"), std::string::npos) << msg;
}

}  // namespace
}  // namespace staa::rt
