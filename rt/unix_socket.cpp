#include "rt/unix_socket.hpp"

#include "rt/errors.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <utility>
#include <vector>

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

namespace staa::rt {

static_assert(kMaxUnixPathBytes + 1 == sizeof(sockaddr_un{}.sun_path), "kMaxUnixPathBytes: sun_path without its NUL");

namespace {

std::string quoted(const std::string& s) {
  std::string q = "'";
  q.append(s).append("'");
  return q;
}

// "call: the system's text".
std::string failed(const char* call, int error) {
  std::string what = call;
  what.append(": ").append(errnoText(error));
  return what;
}

sockaddr_un addressOf(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() > kMaxUnixPathBytes) {
    throw SocketError(SocketError::Kind::kPath, 0,
                      "the path must be 1.." + std::to_string(kMaxUnixPathBytes) + " bytes long");
  }
  std::memcpy(addr.sun_path, path.data(), path.size());
  return addr;
}

const sockaddr* generic(const sockaddr_un& addr) { return reinterpret_cast<const sockaddr*>(&addr); }

FileDescriptor streamSocket(int flags) {
  FileDescriptor fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | flags, 0));
  if (!fd.valid()) throw SocketError(SocketError::Kind::kSocket, errno, failed("socket(AF_UNIX)", errno));
  return fd;
}

// A socket file left behind by a process that died is removed; a live listener is not
// disturbed. Returns true when a stale file was removed.
bool removeStale(const std::string& path, const sockaddr_un& addr) {
  struct stat st{};
  if (::lstat(path.c_str(), &st) != 0) return false;  // nothing there
  if (!S_ISSOCK(st.st_mode)) {
    throw SocketError(SocketError::Kind::kNotASocket, 0, "exists and is not a socket (refusing to remove it)");
  }
  const FileDescriptor probe = streamSocket(0);
  const int rc = ::connect(probe.get(), generic(addr), sizeof addr);
  const int error = errno;
  if (rc == 0) throw SocketError(SocketError::Kind::kInUse, 0, "another process is already listening there");
  if (error != ECONNREFUSED) {
    throw SocketError(SocketError::Kind::kProbe, error, "exists and cannot be probed: " + errnoText(error));
  }
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    throw SocketError(SocketError::Kind::kStale, errno, "cannot remove the stale socket: " + errnoText(errno));
  }
  return true;
}

}  // namespace

// ---- FileDescriptor ----

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = other.release();
  }
  return *this;
}

void FileDescriptor::reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

// ---- UnixStream ----

UnixStream::Result UnixStream::read(char* buffer, std::size_t size) {
  for (;;) {
    const ssize_t n = ::recv(fd_.get(), buffer, size, MSG_DONTWAIT);
    if (n > 0) return {Io::kDone, static_cast<std::size_t>(n), 0};
    if (n == 0) return {Io::kClosed, 0, 0};
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return {Io::kWouldBlock, 0, 0};
    return {Io::kFailed, 0, errno};
  }
}

UnixStream::Result UnixStream::send(std::string_view data) {
  for (;;) {
    // MSG_NOSIGNAL: a peer that hung up is an error code, not a SIGPIPE death.
    const ssize_t n = ::send(fd_.get(), data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n >= 0) return {Io::kDone, static_cast<std::size_t>(n), 0};
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return {Io::kWouldBlock, 0, 0};
    return {Io::kFailed, 0, errno};
  }
}

// ---- UnixListener ----

UnixListener UnixListener::open(const std::string& path, unsigned mode, int backlog) {
  const sockaddr_un addr = addressOf(path);

  // The directory (e.g. /run/staad/) may not exist yet.
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec) {
      throw SocketError(SocketError::Kind::kDirectory, ec.value(),
                        "cannot create the directory " + quoted(parent.string()) + ": " + ec.message());
    }
  }

  UnixListener listener;
  listener.path_ = path;
  listener.removed_stale_ = removeStale(path, addr);
  listener.fd_ = streamSocket(SOCK_NONBLOCK);
  if (::bind(listener.fd_.get(), generic(addr), sizeof addr) != 0) {
    throw SocketError(SocketError::Kind::kBind, errno, failed("bind", errno));
  }
  listener.created_ = true;  // from here on, the destructor removes the file
  if (::chmod(path.c_str(), static_cast<mode_t>(mode)) != 0) {
    const int error = errno;
    char octal[16];
    std::snprintf(octal, sizeof octal, "%04o", mode);
    throw SocketError(SocketError::Kind::kMode, error, std::string("chmod ") + octal + ": " + errnoText(error));
  }
  if (::listen(listener.fd_.get(), backlog) != 0) {
    throw SocketError(SocketError::Kind::kListen, errno, failed("listen", errno));
  }
  return listener;
}

UnixListener::UnixListener(UnixListener&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(std::move(other.fd_)),
      created_(std::exchange(other.created_, false)),
      removed_stale_(other.removed_stale_) {}

UnixListener& UnixListener::operator=(UnixListener&& other) noexcept {
  if (this != &other) {
    close();
    path_ = std::move(other.path_);
    fd_ = std::move(other.fd_);
    created_ = std::exchange(other.created_, false);
    removed_stale_ = other.removed_stale_;
  }
  return *this;
}

std::optional<UnixStream> UnixListener::accept(int& error) {
  error = 0;
  const int fd = ::accept4(fd_.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd >= 0) return UnixStream(FileDescriptor(fd));
  if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNABORTED) error = errno;
  return std::nullopt;
}

void UnixListener::close() {
  fd_.reset();
  if (created_) {
    ::unlink(path_.c_str());
    created_ = false;
  }
}

// ---- UnixLineClient ----

UnixLineClient::UnixLineClient(const std::string& path, Nanos timeout) : deadline_(clock_.now() + timeout) {
  const sockaddr_un addr = addressOf(path);
  // Non-blocking from the start: a peer whose accept backlog is full, or that never answers,
  // costs at most the deadline.
  FileDescriptor fd = streamSocket(SOCK_NONBLOCK);
  if (::connect(fd.get(), generic(addr), sizeof addr) != 0) {
    const int error = errno;
    if (error != EINPROGRESS) throw SocketError(SocketError::Kind::kConnect, error, failed("connect", error));
    stream_ = UnixStream(std::move(fd));
    waitFor(true, SocketError::Stage::kConnecting);
    int so_error = 0;
    socklen_t len = sizeof so_error;
    if (::getsockopt(stream_.fd(), SOL_SOCKET, SO_ERROR, &so_error, &len) != 0) so_error = errno;
    if (so_error != 0) throw SocketError(SocketError::Kind::kConnect, so_error, failed("connect", so_error));
    return;
  }
  stream_ = UnixStream(std::move(fd));
}

void UnixLineClient::send(std::string_view data) {
  std::size_t sent = 0;
  while (sent < data.size()) {
    const UnixStream::Result r = stream_.send(data.substr(sent));
    switch (r.io) {
      case UnixStream::Io::kDone: sent += r.bytes; break;
      case UnixStream::Io::kWouldBlock: waitFor(true, SocketError::Stage::kSending); break;
      case UnixStream::Io::kClosed:
      case UnixStream::Io::kFailed:
        throw SocketError(SocketError::Kind::kSend, r.error, failed("send", r.error), SocketError::Stage::kSending);
    }
  }
}

std::string UnixLineClient::receiveLine(std::size_t max_bytes) {
  std::string line;
  char buffer[4096];
  for (;;) {
    const UnixStream::Result r = stream_.read(buffer, sizeof buffer);
    switch (r.io) {
      case UnixStream::Io::kDone:
        line.append(buffer, r.bytes);
        if (const auto nl = line.find('\n'); nl != std::string::npos) return line.substr(0, nl);
        if (line.size() > max_bytes) {
          throw SocketError(SocketError::Kind::kTooLong, 0,
                            "no line end within " + std::to_string(max_bytes) + " bytes",
                            SocketError::Stage::kReceiving, line.size());
        }
        break;
      case UnixStream::Io::kWouldBlock: waitFor(false, SocketError::Stage::kReceiving); break;
      case UnixStream::Io::kClosed:
        throw SocketError(SocketError::Kind::kClosed, 0, "the peer closed the connection before a line end",
                          SocketError::Stage::kReceiving, line.size());
      case UnixStream::Io::kFailed:
        throw SocketError(SocketError::Kind::kReceive, r.error, failed("recv", r.error),
                          SocketError::Stage::kReceiving);
    }
  }
}

void UnixLineClient::waitFor(bool writable, SocketError::Stage stage) const {
  for (;;) {
    const Nanos left_ms = (deadline_ - clock_.now()) / kNanosPerMilli;
    if (left_ms <= 0) throw SocketError(SocketError::Kind::kTimeout, 0, "timed out", stage);
    pollfd p{stream_.fd(), static_cast<short>(writable ? POLLOUT : POLLIN), 0};
    const int r = ::poll(&p, 1, static_cast<int>(left_ms) + 1);
    if (r > 0) return;  // ready, or an error or hang-up that the next call reports with its errno
    if (r < 0 && errno != EINTR) throw SocketError(SocketError::Kind::kPoll, errno, failed("poll", errno), stage);
  }
}

// ---- Poller ----

struct Poller::Set {
  std::vector<pollfd> fds;
};

Poller::Poller(std::size_t capacity) : set_(std::make_unique<Set>()) { set_->fds.reserve(capacity); }

Poller::~Poller() = default;

void Poller::clear() { set_->fds.clear(); }

std::size_t Poller::watch(int fd, bool readable, bool writable) {
  const auto events = static_cast<short>((readable ? POLLIN : 0) | (writable ? POLLOUT : 0));
  set_->fds.push_back(pollfd{fd, events, 0});
  return set_->fds.size() - 1;
}

Poller::Result Poller::wait(int timeout_ms) {
  const int n = ::poll(set_->fds.data(), set_->fds.size(), timeout_ms);
  if (n >= 0) return {static_cast<std::size_t>(n), 0};
  return {0, errno == EINTR ? 0 : errno};
}

bool Poller::readable(std::size_t index) const { return (set_->fds[index].revents & POLLIN) != 0; }
bool Poller::writable(std::size_t index) const { return (set_->fds[index].revents & POLLOUT) != 0; }
bool Poller::hungUp(std::size_t index) const { return (set_->fds[index].revents & (POLLHUP | POLLERR)) != 0; }

}  // namespace staa::rt
