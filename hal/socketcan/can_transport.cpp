#include "hal/socketcan/can_transport.hpp"

#include "hal/socketcan/can_codec.hpp"
#include "hal/socketcan/can_profile.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fcntl.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <string_view>
#include <utility>
#include <vector>

namespace staa::hal {
namespace {

constexpr std::string_view kUnixPrefix = "unix:";

std::string errnoText(int err) { return std::string(std::strerror(err)) + " (errno " + std::to_string(err) + ")"; }

rt::Nanos toNanos(const timespec& ts) { return static_cast<rt::Nanos>(ts.tv_sec) * rt::kNanosPerSecond + ts.tv_nsec; }

// A kernel receive stamp (CLOCK_REALTIME) moved onto CLOCK_MONOTONIC by the current offset
// between the two clocks (vDSO reads: no syscall, no allocation).
rt::Nanos realtimeToMonotonic(const timespec& stamp) {
  timespec real{}, mono{};
  clock_gettime(CLOCK_REALTIME, &real);
  clock_gettime(CLOCK_MONOTONIC, &mono);
  const rt::Nanos m = toNanos(mono);
  const rt::Nanos converted = toNanos(stamp) - toNanos(real) + m;
  return converted > m ? m : converted;  // a received frame is never from the future
}

// The socket's own errno (SO_ERROR) is not needed: every call reports errno directly.
void setNonBlocking(int fd, const std::string& name) {
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) {
    const int err = errno;
    throw CanTransportError(name + ": cannot make the transport non-blocking: " + errnoText(err));
  }
}

// Closes `fd` when an open fails half-way.
class FdGuard {
 public:
  explicit FdGuard(int fd) : fd_(fd) {}
  ~FdGuard() {
    if (fd_ >= 0) ::close(fd_);
  }
  FdGuard(const FdGuard&) = delete;
  FdGuard& operator=(const FdGuard&) = delete;
  int release() { return std::exchange(fd_, -1); }
  int get() const { return fd_; }

 private:
  int fd_;
};

void setOption(int fd, int level, int option, const void* value, socklen_t size, const std::string& name,
               const char* what) {
  if (setsockopt(fd, level, option, value, size) < 0) {
    const int err = errno;
    throw CanTransportError(name + ": cannot set " + what + ": " + errnoText(err));
  }
}

bool fillUnixAddress(const std::string& path, sockaddr_un& addr) {
  addr = sockaddr_un{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) return false;
  std::memcpy(addr.sun_path, path.data(), path.size());
  return true;
}

}  // namespace

const char* toString(CanIo io) {
  switch (io) {
    case CanIo::kOk: return "ok";
    case CanIo::kWouldBlock: return "would block";
    case CanIo::kBadRecord: return "bad record";
    case CanIo::kGone: return "gone";
    case CanIo::kFailed: return "failed";
  }
  return "unknown";
}

CanTransport::CanTransport(int fd, CanTransportKind kind, std::string name) : fd_(fd), kind_(kind), name_(std::move(name)) {
  if (fd_ < 0) throw CanTransportError(name_ + ": no file descriptor");
  try {
    setNonBlocking(fd_, name_);
  } catch (...) {
    closeFd();
    throw;
  }
}

CanTransport::~CanTransport() { closeFd(); }

CanTransport::CanTransport(CanTransport&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      kind_(other.kind_),
      name_(std::move(other.name_)),
      has_path_(other.has_path_),
      path_(other.path_),
      rx_overflows_(other.rx_overflows_),
      last_overflow_raw_(other.last_overflow_raw_),
      last_errno_(other.last_errno_) {}

CanTransport& CanTransport::operator=(CanTransport&& other) noexcept {
  if (this != &other) {
    closeFd();
    fd_ = std::exchange(other.fd_, -1);
    kind_ = other.kind_;
    name_ = std::move(other.name_);
    has_path_ = other.has_path_;
    path_ = other.path_;
    rx_overflows_ = other.rx_overflows_;
    last_overflow_raw_ = other.last_overflow_raw_;
    last_errno_ = other.last_errno_;
  }
  return *this;
}

void CanTransport::closeFd() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CanIo CanTransport::receive(CanRxFrame& out) {
  if (fd_ < 0) return CanIo::kGone;
  // Room for more than one can_frame, so a longer record shows its true size.
  alignas(canfd_frame) unsigned char buf[sizeof(canfd_frame)];
  alignas(cmsghdr) unsigned char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  iovec iov{buf, sizeof buf};
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;

  ssize_t n = 0;
  do {
    n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  if (n < 0) {
    last_errno_ = errno;
    if (last_errno_ == EAGAIN || last_errno_ == EWOULDBLOCK) return CanIo::kWouldBlock;
    if (last_errno_ == ECONNRESET || last_errno_ == ENOTCONN || last_errno_ == EPIPE) return CanIo::kGone;
    return CanIo::kFailed;
  }
  if (n == 0) {
    // On a seqpacket socket 0 is either the peer's end of file or an empty record: the
    // socket's hang-up state tells which.
    pollfd p{fd_, POLLIN | POLLRDHUP, 0};
    if (::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLRDHUP)) != 0) return CanIo::kGone;
    return CanIo::kBadRecord;
  }
  if (static_cast<std::size_t>(n) != sizeof(can_frame) || (msg.msg_flags & MSG_TRUNC) != 0) return CanIo::kBadRecord;

  std::memcpy(&out.frame, buf, sizeof(can_frame));
  out.stamp = -1;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      out.stamp = realtimeToMonotonic(ts);
    } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
      // The kernel's 32-bit cumulative drop count: add the difference (it wraps).
      std::uint32_t dropped = 0;
      std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
      rx_overflows_ += static_cast<std::uint32_t>(dropped - last_overflow_raw_);
      last_overflow_raw_ = dropped;
    }
  }
  return CanIo::kOk;
}

CanIo CanTransport::send(const can_frame& frame) {
  if (fd_ < 0) return CanIo::kGone;
  iovec iov{const_cast<can_frame*>(&frame), sizeof(can_frame)};
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  ssize_t n = 0;
  do {
    n = ::sendmsg(fd_, &msg, MSG_DONTWAIT | MSG_NOSIGNAL);  // no SIGPIPE: a hang-up is kGone
  } while (n < 0 && errno == EINTR);
  if (n < 0) {
    last_errno_ = errno;
    if (last_errno_ == EAGAIN || last_errno_ == EWOULDBLOCK) return CanIo::kWouldBlock;
    if (last_errno_ == EPIPE || last_errno_ == ECONNRESET || last_errno_ == ENOTCONN) return CanIo::kGone;
    return CanIo::kFailed;
  }
  if (static_cast<std::size_t>(n) != sizeof(can_frame)) {
    last_errno_ = EMSGSIZE;
    return CanIo::kFailed;
  }
  return CanIo::kOk;
}

bool CanTransport::reconnect() {
  if (!has_path_) return false;
  closeFd();
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    last_errno_ = errno;
    return false;
  }
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&path_), sizeof path_) < 0) {
    last_errno_ = errno;
    ::close(fd);
    return false;
  }
  fd_ = fd;
  last_overflow_raw_ = 0;
  return true;
}

CanTransport openSocketCan(const std::string& ifname, std::span<const canid_t> rx_ids) {
  const std::string name = ifname.empty() ? std::string("(empty interface name)") : ifname;
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) {
    throw CanTransportError(name + ": not a valid network interface name (1.." + std::to_string(IFNAMSIZ - 1) +
                            " characters)");
  }
  const int raw = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (raw < 0) {
    const int err = errno;
    std::string msg = name + ": cannot open a SocketCAN socket (socket(PF_CAN, SOCK_RAW, CAN_RAW): " + errnoText(err) + ")";
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      msg += "; this kernel has no CAN support (modules can, can_raw), so there is no " + name;
    }
    throw CanTransportError(msg);
  }
  FdGuard fd(raw);

  const unsigned index = ::if_nametoindex(ifname.c_str());
  if (index == 0) {
    const int err = errno;
    throw CanTransportError(name + ": no such network interface (" + errnoText(err) + ")");
  }

  // Exactly the wanted 11-bit data frames: the mask covers the EFF and RTR flags too.
  std::vector<can_filter> filters;
  for (canid_t id : rx_ids) filters.push_back({id & CAN_SFF_MASK, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
  setOption(fd.get(), SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(), static_cast<socklen_t>(filters.size() * sizeof(can_filter)),
            name, "the receive filter (CAN_RAW_FILTER)");
  const can_err_mask_t errors = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_ACK | CAN_ERR_RESTARTED;
  setOption(fd.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors, name, "the error filter (CAN_RAW_ERR_FILTER)");
  const int on = 1;
  setOption(fd.get(), SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on, name, "receive timestamps (SO_TIMESTAMPNS)");
  setOption(fd.get(), SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on, name, "the overflow counter (SO_RXQ_OVFL)");

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) {
    const int err = errno;
    throw CanTransportError(name + ": cannot bind a CAN socket to it (" + errnoText(err) +
                            (err == ENODEV ? "; is it a CAN interface?" : "") + ")");
  }
  return CanTransport(fd.release(), CanTransportKind::kSocketCan, name);
}

CanTransport openSeqPacket(const std::string& path) {
  const std::string name = std::string(kUnixPrefix) + path;
  sockaddr_un addr{};
  if (!fillUnixAddress(path, addr)) {
    throw CanTransportError(name + ": not a valid socket path (1.." + std::to_string(sizeof addr.sun_path - 1) +
                            " characters)");
  }
  const int raw = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (raw < 0) {
    const int err = errno;
    throw CanTransportError(name + ": cannot open a Unix seqpacket socket: " + errnoText(err));
  }
  FdGuard fd(raw);
  // Connected blocking (start-up, not the cycle); the transport makes it non-blocking.
  if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) < 0) {
    const int err = errno;
    std::string why = errnoText(err);
    if (err == ENOENT) why = "no socket at " + path + " (is the base simulator running?)";
    if (err == ECONNREFUSED) why = "nobody is listening at " + path + " (" + why + ")";
    throw CanTransportError(name + ": cannot connect: " + why);
  }
  CanTransport transport(fd.release(), CanTransportKind::kSeqPacket, name);
  transport.setPath(addr);
  return transport;
}

CanTransport adoptSeqPacket(int fd, std::string name) {
  int type = 0;
  socklen_t size = sizeof type;
  if (fd < 0 || ::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &size) < 0 || type != SOCK_SEQPACKET) {
    if (fd >= 0) ::close(fd);
    throw CanTransportError(name + ": not a SOCK_SEQPACKET socket");
  }
  return CanTransport(fd, CanTransportKind::kSeqPacket, std::move(name));
}

CanTransport openCanTransport(const std::string& interface, const CanProfile& profile) {
  if (interface.starts_with(kUnixPrefix)) return openSeqPacket(interface.substr(kUnixPrefix.size()));
  const std::array<canid_t, 3> ids = baseToHostIds(profile);
  return openSocketCan(interface, ids);
}

}  // namespace staa::hal
