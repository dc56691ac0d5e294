#include "rt/signals.hpp"

#include <cerrno>
#include <system_error>

#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

namespace staa::rt {

namespace {

sigset_t terminationSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  return set;
}

}  // namespace

const char* toString(TerminationSignal signal) {
  return signal == TerminationSignal::kInterrupt ? "SIGINT" : "SIGTERM";
}

void blockTerminationSignals() {
  const sigset_t set = terminationSet();
  if (const int rc = ::pthread_sigmask(SIG_BLOCK, &set, nullptr); rc != 0) {
    throw std::system_error(rc, std::system_category(), "pthread_sigmask(SIGTERM, SIGINT)");
  }
  ::signal(SIGPIPE, SIG_IGN);
}

TerminationSignals::TerminationSignals() {
  const sigset_t set = terminationSet();
  fd_ = FileDescriptor(::signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC));
  if (!fd_.valid()) throw std::system_error(errno, std::system_category(), "signalfd(SIGTERM, SIGINT)");
}

std::optional<TerminationSignal> TerminationSignals::take() {
  signalfd_siginfo info{};
  if (::read(fd_.get(), &info, sizeof info) != static_cast<ssize_t>(sizeof info)) return std::nullopt;
  return info.ssi_signo == SIGINT ? TerminationSignal::kInterrupt : TerminationSignal::kTerminate;
}

}  // namespace staa::rt
