#pragma once
// SIGTERM and SIGINT as a readable file descriptor (signalfd), for a poll loop: blocked in
// every thread first (blockTerminationSignals(), before any thread starts), so that they
// arrive only through the descriptor and never interrupt a real-time thread.

#include "rt/unix_socket.hpp"

#include <cstdint>
#include <optional>

namespace staa::rt {

enum class TerminationSignal : std::uint8_t { kTerminate, kInterrupt };
const char* toString(TerminationSignal signal);  // "SIGTERM", "SIGINT"

// Blocks SIGTERM and SIGINT in the calling thread (and every thread it creates afterwards),
// and ignores SIGPIPE (a peer that hangs up must not kill the process). Throws
// std::system_error naming the call.
void blockTerminationSignals();

class TerminationSignals {
 public:
  // signalfd for SIGTERM and SIGINT, non-blocking. Throws std::system_error naming the call.
  TerminationSignals();

  // The next pending signal, or nullopt when none is pending.
  std::optional<TerminationSignal> take();
  int fd() const { return fd_.get(); }

 private:
  FileDescriptor fd_;
};

}  // namespace staa::rt
