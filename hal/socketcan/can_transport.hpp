#pragma once
// A CAN transport is a file descriptor carrying one `struct can_frame` per record, read and
// written non-blocking through one recvmsg/sendmsg code path, of two kinds:
//  - SocketCAN: a PF_CAN/SOCK_RAW/CAN_RAW socket bound to an interface ("can0", "vcan0"),
//    with kernel receive filters for the given IDs, error frames (bus-off, controller, no
//    ACK, restarted), receive timestamps (SO_TIMESTAMPNS, converted to CLOCK_MONOTONIC)
//    and the kernel's receive-overflow count (SO_RXQ_OVFL);
//  - seqpacket: a Unix SOCK_SEQPACKET socket, connected to a path ("unix:/run/base.sock")
//    or adopted (one end of a socketpair in tests). No filters or timestamps; error frames
//    (can_id & CAN_ERR_FLAG) pass through like the kernel's.
// Opening throws CanTransportError naming the interface; receive()/send() never allocate,
// lock or block, and report what happened as a CanIo code.

#include "hal/socketcan/socketcan.hpp"
#include "rt/clock.hpp"

#include <linux/can.h>
#include <sys/un.h>

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

namespace staa::hal {

struct CanProfile;

enum class CanIo : std::uint8_t {
  kOk,          // one frame received / sent
  kWouldBlock,  // receive: nothing pending; send: the buffer is full (EAGAIN/EWOULDBLOCK)
  kBadRecord,   // receive: a record that is not one 16-byte can_frame (dropped)
  kGone,        // the peer hung up (EOF, EPIPE, ECONNRESET) or the transport is closed
  kFailed,      // any other error (errno in CanTransport::lastError()): ENOBUFS, ENETDOWN, ...
};
const char* toString(CanIo io);

enum class CanTransportKind : std::uint8_t { kSocketCan, kSeqPacket };

struct CanRxFrame {
  can_frame frame{};
  rt::Nanos stamp = -1;  // CLOCK_MONOTONIC receive time; -1 when the transport has none
};

class CanTransport {
 public:
  // Adopts `fd` (made non-blocking; closed by the destructor). `name` is for messages.
  CanTransport(int fd, CanTransportKind kind, std::string name);
  ~CanTransport();
  CanTransport(CanTransport&& other) noexcept;
  CanTransport& operator=(CanTransport&& other) noexcept;
  CanTransport(const CanTransport&) = delete;
  CanTransport& operator=(const CanTransport&) = delete;

  CanIo receive(CanRxFrame& out);
  CanIo send(const can_frame& frame);

  // A transport opened from a "unix:" path can connect again after its peer went away (a
  // restarted simulated base); the others cannot. Never allocates; non-blocking.
  bool canReconnect() const { return has_path_; }
  bool reconnect();
  bool open() const { return fd_ >= 0; }

  int fd() const { return fd_; }
  CanTransportKind kind() const { return kind_; }
  const std::string& name() const { return name_; }
  // Frames the kernel dropped because the socket's receive queue was full (SO_RXQ_OVFL,
  // cumulative); 0 on seqpacket.
  std::uint64_t rxOverflows() const { return rx_overflows_; }
  int lastError() const { return last_errno_; }

  // Where reconnect() connects (openSeqPacket sets it).
  void setPath(const sockaddr_un& path) {
    path_ = path;
    has_path_ = true;
  }

 private:
  void closeFd();

  int fd_ = -1;
  CanTransportKind kind_ = CanTransportKind::kSeqPacket;
  std::string name_;
  bool has_path_ = false;
  sockaddr_un path_{};
  std::uint64_t rx_overflows_ = 0;
  std::uint32_t last_overflow_raw_ = 0;  // the kernel's last SO_RXQ_OVFL value
  int last_errno_ = 0;
};

// "unix:/path" -> openSeqPacket(path); anything else is an interface name -> openSocketCan
// receiving the profile's base->host IDs. Throws CanTransportError naming `interface`.
CanTransport openCanTransport(const std::string& interface, const CanProfile& profile);
// A raw CAN socket on `ifname` receiving exactly `rx_ids` (11-bit data frames) and error frames.
CanTransport openSocketCan(const std::string& ifname, std::span<const canid_t> rx_ids);
CanTransport openSeqPacket(const std::string& path);
// One end of socketpair(AF_UNIX, SOCK_SEQPACKET, ...) or an accepted connection.
CanTransport adoptSeqPacket(int fd, std::string name = "socketpair");

}  // namespace staa::hal
