#pragma once
// The systemd notification protocol, written from its description (sd_notify(3)): one
// datagram per message to the AF_UNIX socket named by $NOTIFY_SOCKET, a file-system path or,
// with a leading '@', an abstract name. Messages: READY=1, STATUS=..., STOPPING=1,
// WATCHDOG=1. Without $NOTIFY_SOCKET every call is a no-op that succeeds (not under systemd).
// The socket is opened at construction; send() does not allocate (service thread only).

#include "rt/clock.hpp"

#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace staa::rt {

class Notifier {
 public:
  // From $NOTIFY_SOCKET (unset or empty: disabled). Throws std::runtime_error naming the
  // variable and its value when it is set but unusable (too long, not absolute nor '@').
  static Notifier fromEnvironment();
  // An explicit address (tests): "/path/to/socket" or "@abstract-name"; "" disables.
  explicit Notifier(std::string_view address);
  Notifier(Notifier&& other) noexcept;
  Notifier& operator=(Notifier&& other) noexcept;
  Notifier(const Notifier&) = delete;
  Notifier& operator=(const Notifier&) = delete;
  ~Notifier();

  bool enabled() const { return fd_ >= 0; }
  // Sends one datagram; 0 on success (or when disabled), else the errno of sendto.
  int send(std::string_view message) const;
  int ready() const { return send("READY=1"); }
  int stopping() const { return send("STOPPING=1"); }
  int watchdog() const { return send("WATCHDOG=1"); }
  int status(std::string_view text) const;  // "STATUS=<text>", truncated to 200 bytes

  // The watchdog ping interval: half of $WATCHDOG_USEC when set (and $WATCHDOG_PID, if set,
  // is this process); nullopt otherwise. Throws std::runtime_error on a malformed value.
  static std::optional<Nanos> watchdogInterval();

 private:
  struct Address;  // the sockaddr_un, kept out of this header
  int fd_ = -1;
  std::unique_ptr<Address> addr_;
};

}  // namespace staa::rt
