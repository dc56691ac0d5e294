#include "rt/sd_notify.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <utility>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

namespace staa::rt {

namespace {

constexpr std::size_t kStatusMaxBytes = 200;  // the whole "STATUS=..." datagram

// Why `address` cannot name a notification socket, or "" when it can.
const char* addressProblem(std::string_view address) {
  constexpr std::size_t kPathMax = sizeof(sockaddr_un::sun_path);
  if (address.front() == '/') {
    if (address.size() >= kPathMax) return "path too long for an AF_UNIX address (at most 107 bytes)";
    if (address.find('\0') != std::string_view::npos) return "path contains a NUL byte";
    return "";
  }
  if (address.front() == '@') {
    if (address.size() == 1) return "empty abstract socket name";
    if (address.size() > kPathMax) return "abstract name too long for an AF_UNIX address (at most 107 bytes)";
    return "";
  }
  return "neither an absolute path nor an abstract name starting with '@'";
}

std::string quoted(std::string_view s) {
  std::string out = "'";  // appended: GCC 12 warns falsely (-Wrestrict) on "'" + s + "'"
  out.append(s);
  out += '\'';
  return out;
}

// A positive whole number from an environment variable, or nullopt when unset or empty.
std::optional<std::uint64_t> positiveFromEnv(const char* name, std::uint64_t max) {
  const char* raw = std::getenv(name);
  if (raw == nullptr || *raw == '\0') return std::nullopt;
  const std::string_view s(raw);
  std::uint64_t v = 0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (res.ec == std::errc::result_out_of_range || (res.ec == std::errc{} && res.ptr == s.data() + s.size() && v > max)) {
    throw std::runtime_error(std::string("$") + name + "=" + quoted(s) + ": too large (at most " +
                             std::to_string(max) + ")");
  }
  if (res.ec != std::errc{} || res.ptr != s.data() + s.size() || v == 0) {
    throw std::runtime_error(std::string("$") + name + "=" + quoted(s) + ": not a positive whole number");
  }
  return v;
}

}  // namespace

struct Notifier::Address {
  sockaddr_un addr{};
  socklen_t len = 0;
};

Notifier Notifier::fromEnvironment() {
  const char* raw = std::getenv("NOTIFY_SOCKET");
  if (raw == nullptr || *raw == '\0') return Notifier("");
  const std::string_view address(raw);
  if (const char* problem = addressProblem(address); *problem != '\0') {
    throw std::runtime_error("$NOTIFY_SOCKET=" + quoted(address) + ": " + problem);
  }
  return Notifier(address);
}

Notifier::Notifier(std::string_view address) {
  if (address.empty()) return;  // disabled: not under systemd
  if (const char* problem = addressProblem(address); *problem != '\0') {
    throw std::runtime_error("notify socket address " + quoted(address) + ": " + problem);
  }
  addr_ = std::make_unique<Address>();
  sockaddr_un& addr = addr_->addr;
  addr.sun_family = AF_UNIX;
  if (address.front() == '@') {
    // Abstract namespace: a leading NUL, then the name; the length counts exactly the name's
    // bytes (no terminator), as the kernel compares all addr_len bytes.
    addr.sun_path[0] = '\0';
    std::memcpy(addr.sun_path + 1, address.data() + 1, address.size() - 1);
    addr_->len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + address.size());
  } else {
    std::memcpy(addr.sun_path, address.data(), address.size());
    addr.sun_path[address.size()] = '\0';
    addr_->len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + address.size() + 1);
  }
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw std::system_error(errno, std::generic_category(),
                            "notify socket " + quoted(address) + ": socket(AF_UNIX, SOCK_DGRAM)");
  }
}

Notifier::Notifier(Notifier&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), addr_(std::move(other.addr_)) {}

Notifier& Notifier::operator=(Notifier&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    addr_ = std::move(other.addr_);
  }
  return *this;
}

Notifier::~Notifier() {
  if (fd_ >= 0) ::close(fd_);
}

int Notifier::send(std::string_view message) const {
  if (fd_ < 0) return 0;
  for (;;) {
    // MSG_NOSIGNAL: systemd going away must not kill the daemon with SIGPIPE. MSG_DONTWAIT:
    // a receiver that does not read (its queue full after ~10 datagrams) must not block the
    // service thread; the message is dropped and EAGAIN returned.
    const ssize_t n = ::sendto(fd_, message.data(), message.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                               reinterpret_cast<const sockaddr*>(&addr_->addr), addr_->len);
    if (n >= 0) return 0;
    if (errno != EINTR) return errno;
  }
}

int Notifier::status(std::string_view text) const {
  // A stack buffer: the service thread reports status without allocating.
  constexpr std::string_view kPrefix = "STATUS=";
  char buf[kStatusMaxBytes];
  std::memcpy(buf, kPrefix.data(), kPrefix.size());
  std::size_t n = std::min(text.size(), kStatusMaxBytes - kPrefix.size());
  // Cut on a UTF-8 character boundary (never in the middle of a multi-byte sequence).
  if (n < text.size()) {
    while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;
  }
  for (std::size_t i = 0; i < n; ++i) {
    // One assignment per line in the protocol: a newline in the text would start another
    // assignment (e.g. "READY=1"), so it becomes a space.
    buf[kPrefix.size() + i] = text[i] == '\n' ? ' ' : text[i];
  }
  return send(std::string_view(buf, kPrefix.size() + n));
}

std::optional<Nanos> Notifier::watchdogInterval() {
  // Microseconds that still fit in Nanos once multiplied by 1000.
  constexpr auto kMaxUsec = static_cast<std::uint64_t>(std::numeric_limits<Nanos>::max() / 1000);
  const std::optional<std::uint64_t> usec = positiveFromEnv("WATCHDOG_USEC", kMaxUsec);
  if (!usec) return std::nullopt;
  // WATCHDOG_PID names the process the watchdog is meant for; a child that inherited the
  // environment must not ping in its parent's name.
  const std::optional<std::uint64_t> pid =
      positiveFromEnv("WATCHDOG_PID", static_cast<std::uint64_t>(std::numeric_limits<pid_t>::max()));
  if (pid && static_cast<pid_t>(*pid) != ::getpid()) return std::nullopt;
  // Half the timeout, as sd_watchdog_enabled(3) recommends: one late ping does not kill us.
  return static_cast<Nanos>(*usec) * 1000 / 2;
}

}  // namespace staa::rt
