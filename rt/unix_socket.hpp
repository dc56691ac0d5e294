#pragma once
// Unix stream sockets for a line protocol (the daemon's control socket and its client):
// every descriptor is owned by an object that closes it, every stream is non-blocking, and
// every failure is a SocketError that names the call and carries the errno and what the
// caller needs to word its own message (the stage of a timed-out exchange, the bytes of a
// line cut short). Callers poll the descriptors with rt::Poller.
//
//   server: UnixListener::open(path, mode, backlog), then accept() -> UnixStream
//   client: UnixLineClient(path, timeout): send(), receiveLine(), all within one deadline

#include "rt/clock.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace staa::rt {

// The longest path a Unix socket address holds (sun_path without its NUL).
inline constexpr std::size_t kMaxUnixPathBytes = 107;

class SocketError : public std::runtime_error {
 public:
  enum class Kind : std::uint8_t {
    kPath,        // the path is empty or too long for a socket address
    kDirectory,   // the socket's directory cannot be created
    kNotASocket,  // something else exists at the path (left alone)
    kInUse,       // another process accepts connections at the path
    kProbe,       // the file at the path cannot be probed (neither live nor refused)
    kStale,       // a stale socket file cannot be removed
    kSocket,      // socket() failed
    kBind,
    kMode,        // chmod of the socket file
    kListen,
    kConnect,
    kTimeout,     // the exchange's deadline passed (stage() says in which step)
    kSend,
    kReceive,
    kClosed,      // the peer closed before a whole line (bytes() of it had arrived)
    kTooLong,     // no line end within the limit
    kPoll,
  };
  enum class Stage : std::uint8_t { kConnecting, kSending, kReceiving };

  SocketError(Kind kind, int error, std::string what, Stage stage = Stage::kConnecting, std::size_t bytes = 0)
      : std::runtime_error(std::move(what)), kind_(kind), error_(error), stage_(stage), bytes_(bytes) {}

  Kind kind() const { return kind_; }
  int error() const { return error_; }  // errno, 0 when the failure is not the OS's
  Stage stage() const { return stage_; }
  std::size_t bytes() const { return bytes_; }

 private:
  Kind kind_;
  int error_;
  Stage stage_;
  std::size_t bytes_;
};

// An open file descriptor, closed by the destructor.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(other.release()) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept;
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() { reset(); }

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  void reset();
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_ = -1;
};

// One connected, non-blocking Unix stream (an accepted client, or the client's own end).
// read() and send() never block and never raise SIGPIPE; EINTR is retried inside.
class UnixStream {
 public:
  enum class Io : std::uint8_t {
    kDone,        // bytes moved (> 0)
    kWouldBlock,  // nothing to read, or no room to send: poll and try again
    kClosed,      // read: the peer closed its side
    kFailed,      // error() says why (ECONNRESET, EPIPE, ...)
  };
  struct Result {
    Io io = Io::kDone;
    std::size_t bytes = 0;
    int error = 0;
  };

  UnixStream() = default;
  explicit UnixStream(FileDescriptor fd) : fd_(std::move(fd)) {}

  Result read(char* buffer, std::size_t size);
  Result send(std::string_view data);

  bool isOpen() const { return fd_.valid(); }
  void close() { fd_.reset(); }
  int fd() const { return fd_.get(); }

 private:
  FileDescriptor fd_;
};

// A listening Unix stream socket at a path. open() creates the path's directory, removes a
// stale socket file that nobody accepts on (and says so: removedStale()), refuses when
// another process listens there or something else exists there, binds, sets the file's mode
// and listens, non-blocking. The destructor (or close()) closes it and removes the file.
class UnixListener {
 public:
  static UnixListener open(const std::string& path, unsigned mode, int backlog);

  UnixListener(UnixListener&& other) noexcept;
  UnixListener& operator=(UnixListener&& other) noexcept;
  UnixListener(const UnixListener&) = delete;
  UnixListener& operator=(const UnixListener&) = delete;
  ~UnixListener() { close(); }

  // The next pending connection, non-blocking; nullopt when none is pending (or one was
  // aborted, or the call was interrupted). Other failures: nullopt and `error` set.
  std::optional<UnixStream> accept(int& error);

  bool removedStale() const { return removed_stale_; }
  const std::string& path() const { return path_; }
  int fd() const { return fd_.get(); }
  void close();

 private:
  UnixListener() = default;

  std::string path_;
  FileDescriptor fd_;
  bool created_ = false;  // the socket file is ours to remove
  bool removed_stale_ = false;
};

// The client of a line protocol: one connection, and every step of the exchange (connect,
// send, receive) within one deadline, `timeout` after the constructor began, so that a peer
// that hangs costs at most the timeout. Throws SocketError (kTimeout with the stage).
class UnixLineClient {
 public:
  UnixLineClient(const std::string& path, Nanos timeout);

  // Sends all of `data`.
  void send(std::string_view data);
  // The bytes up to the first '\n' (without it); kTooLong when `max_bytes` arrive without one.
  std::string receiveLine(std::size_t max_bytes);

 private:
  void waitFor(bool writable, SocketError::Stage stage) const;

  MonotonicClock clock_;
  Nanos deadline_;
  UnixStream stream_;
};

// poll() over a set of descriptors, rebuilt each round: watch() them, wait(), then ask what
// each one is ready for by the index watch() returned. Room for `capacity` descriptors is
// made at construction.
class Poller {
 public:
  struct Result {
    std::size_t ready = 0;  // descriptors with events (0: timed out, or interrupted)
    int error = 0;          // poll's errno (never EINTR), 0 normally
  };

  explicit Poller(std::size_t capacity);
  ~Poller();
  Poller(const Poller&) = delete;
  Poller& operator=(const Poller&) = delete;

  void clear();
  std::size_t watch(int fd, bool readable, bool writable);
  Result wait(int timeout_ms);

  bool readable(std::size_t index) const;  // data, or a connection to accept
  bool writable(std::size_t index) const;
  bool hungUp(std::size_t index) const;    // hang-up or error: a read reports which

 private:
  struct Set;
  std::unique_ptr<Set> set_;
};

}  // namespace staa::rt
