// rt's Unix stream sockets against real sockets in a temporary directory: the listener's
// start-up rules (stale file removed, a live listener or another file left alone, the mode),
// the streams, the poller, the client's deadline, and SIGTERM/SIGINT through signalfd.
#include "rt/signals.hpp"
#include "rt/unix_socket.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

namespace staa::rt {
namespace {

namespace fs = std::filesystem;

class UnixSocketTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("staa-rt-socket-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const char* name) const { return (dir_ / name).string(); }

  // What the peer receives, waiting up to a second.
  static std::string receiveAll(UnixStream& s, std::size_t bytes) {
    Poller poller(1);
    std::string got;
    char buf[256];
    while (got.size() < bytes) {
      poller.clear();
      poller.watch(s.fd(), true, false);
      if (poller.wait(1000).ready == 0) break;
      const UnixStream::Result r = s.read(buf, sizeof buf);
      if (r.io != UnixStream::Io::kDone) break;
      got.append(buf, r.bytes);
    }
    return got;
  }

  // The next connection, waiting up to a second.
  static UnixStream acceptOne(UnixListener& listener) {
    Poller poller(1);
    poller.watch(listener.fd(), true, false);
    EXPECT_EQ(poller.wait(1000).ready, 1u);
    EXPECT_TRUE(poller.readable(0));
    int error = -1;
    std::optional<UnixStream> s = listener.accept(error);
    EXPECT_EQ(error, 0);
    EXPECT_TRUE(s.has_value());
    return s ? std::move(*s) : UnixStream();
  }

  static inline int counter_ = 0;
  fs::path dir_;
};

TEST_F(UnixSocketTest, AListenerTakesALineAndRepliesAndRemovesItsFileWhenClosed) {
  const std::string at = path("sub/dir/ctl.sock");  // the directory is created
  {
    UnixListener listener = UnixListener::open(at, 0600, 4);
    EXPECT_FALSE(listener.removedStale());
    struct stat st{};
    ASSERT_EQ(::lstat(at.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
    EXPECT_EQ(st.st_mode & 0777, 0600u);
    int error = -1;
    EXPECT_FALSE(listener.accept(error).has_value());  // none pending
    EXPECT_EQ(error, 0);

    std::string reply;
    std::thread client([&] {
      UnixLineClient c(at, kNanosPerSecond);
      c.send("{\"cmd\":\"status\"}\n");
      reply = c.receiveLine(1024);
    });
    UnixStream server = acceptOne(listener);
    EXPECT_EQ(receiveAll(server, 17), "{\"cmd\":\"status\"}\n");
    const UnixStream::Result sent = server.send("{\"ok\":true}\nnot this\n");
    EXPECT_EQ(sent.io, UnixStream::Io::kDone);
    client.join();
    EXPECT_EQ(reply, "{\"ok\":true}");  // the first line only, without its '\n'

    char buf[16];
    EXPECT_EQ(server.read(buf, sizeof buf).io, UnixStream::Io::kClosed);  // the client went
  }
  EXPECT_FALSE(fs::exists(at));
}

TEST_F(UnixSocketTest, AStaleSocketFileIsRemovedAndALiveListenerIsNot) {
  const std::string at = path("ctl.sock");
  {
    // A socket file nobody listens on: a daemon that died.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", at.c_str());
    ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0);
    ::close(fd);
  }
  UnixListener first = UnixListener::open(at, 0660, 4);
  EXPECT_TRUE(first.removedStale());
  try {
    UnixListener second = UnixListener::open(at, 0660, 4);
    FAIL() << "a second listener took the path of a live one";
  } catch (const SocketError& e) {
    EXPECT_EQ(e.kind(), SocketError::Kind::kInUse);
    EXPECT_STREQ(e.what(), "another process is already listening there");
  }
  EXPECT_TRUE(fs::exists(at));  // the live listener's file stays
}

TEST_F(UnixSocketTest, SomethingElseAtThePathOrAPathTooLongIsRefusedByName) {
  const std::string at = path("not-a-socket");
  std::ofstream(at) << "keep me";
  try {
    UnixListener::open(at, 0660, 4);
    FAIL() << "a regular file was replaced";
  } catch (const SocketError& e) {
    EXPECT_EQ(e.kind(), SocketError::Kind::kNotASocket);
    EXPECT_STREQ(e.what(), "exists and is not a socket (refusing to remove it)");
  }
  EXPECT_EQ(fs::file_size(at), 7u);

  try {
    UnixListener::open("/tmp/" + std::string(kMaxUnixPathBytes, 'x'), 0660, 4);
    FAIL() << "a path longer than a socket address was taken";
  } catch (const SocketError& e) {
    EXPECT_EQ(e.kind(), SocketError::Kind::kPath);
    EXPECT_STREQ(e.what(), "the path must be 1..107 bytes long");
  }
}

TEST_F(UnixSocketTest, TheClientsFailuresSayWhatHappened) {
  const std::string at = path("ctl.sock");
  try {
    UnixLineClient c(at, kNanosPerSecond);
    FAIL() << "connected to nothing";
  } catch (const SocketError& e) {
    EXPECT_EQ(e.kind(), SocketError::Kind::kConnect);
    EXPECT_EQ(e.error(), ENOENT);
  }

  UnixListener listener = UnixListener::open(at, 0660, 4);
  // A peer that takes the request and never answers: the deadline, in the receiving stage.
  {
    UnixLineClient c(at, 100 * kNanosPerMilli);
    c.send("{\"cmd\":\"status\"}\n");
    UnixStream server = acceptOne(listener);
    try {
      c.receiveLine(1024);
      FAIL() << "a line from a silent peer";
    } catch (const SocketError& e) {
      EXPECT_EQ(e.kind(), SocketError::Kind::kTimeout);
      EXPECT_EQ(e.stage(), SocketError::Stage::kReceiving);
    }
  }
  // A peer that hangs up in the middle of a line: how much of it came.
  {
    UnixLineClient c(at, kNanosPerSecond);
    UnixStream server = acceptOne(listener);
    EXPECT_EQ(server.send("{\"ok\":").bytes, 6u);
    server.close();
    try {
      c.receiveLine(1024);
      FAIL() << "a line from a peer that hung up";
    } catch (const SocketError& e) {
      EXPECT_EQ(e.kind(), SocketError::Kind::kClosed);
      EXPECT_EQ(e.bytes(), 6u);
    }
  }
  // No line end within the limit.
  {
    UnixLineClient c(at, kNanosPerSecond);
    UnixStream server = acceptOne(listener);
    EXPECT_EQ(server.send(std::string(100, 'x')).bytes, 100u);
    try {
      c.receiveLine(50);
      FAIL() << "a line longer than the limit";
    } catch (const SocketError& e) {
      EXPECT_EQ(e.kind(), SocketError::Kind::kTooLong);
    }
  }
}

TEST(TerminationSignals, BlockedSigintAndSigtermArriveThroughTheDescriptor) {
  blockTerminationSignals();
  TerminationSignals signals;
  EXPECT_FALSE(signals.take().has_value());
  ASSERT_EQ(::raise(SIGTERM), 0);  // blocked: pending, read through the signalfd
  ASSERT_EQ(::raise(SIGINT), 0);
  Poller poller(1);
  poller.watch(signals.fd(), true, false);
  EXPECT_EQ(poller.wait(1000).ready, 1u);
  // Pending standard signals are taken lowest number first: SIGINT (2), then SIGTERM (15).
  const std::optional<TerminationSignal> first = signals.take();
  const std::optional<TerminationSignal> second = signals.take();
  ASSERT_TRUE(first && second);
  EXPECT_STREQ(toString(*first), "SIGINT");
  EXPECT_STREQ(toString(*second), "SIGTERM");
  EXPECT_FALSE(signals.take().has_value());
}

}  // namespace
}  // namespace staa::rt
