#include "app/staad/service.hpp"

#include "app/staad/io_tasks.hpp"
#include "app/staad/protocol.hpp"
#include "rt/alloc_count.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <system_error>
#include <variant>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

namespace staa::staad {

namespace {

constexpr std::size_t kMaxPendingReplyBytes = 1u << 20;  // a client that never reads is dropped
constexpr int kMaxReadsPerRound = 16;                    // one busy client cannot starve the rest

std::string errnoText(int error) { return std::system_category().message(error); }

std::string quoted(const std::string& s) {
  std::string q = "'";
  q.append(s).append("'");
  return q;
}

sockaddr_un socketAddress(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) {
    std::string message = "control socket ";
    message.append(quoted(path)).append(": the path must be 1..").append(std::to_string(sizeof addr.sun_path - 1));
    message.append(" bytes long");
    throw ServiceError(message);
  }
  std::memcpy(addr.sun_path, path.data(), path.size());
  return addr;
}

const char* levelName(rt::LogLevel level) {
  switch (level) {
    case rt::LogLevel::kInfo: return "info";
    case rt::LogLevel::kWarning: return "warning";
    case rt::LogLevel::kError: return "error";
  }
  return "?";
}

}  // namespace

void blockTerminationSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  const int rc = pthread_sigmask(SIG_BLOCK, &set, nullptr);
  if (rc != 0) throw ServiceError("pthread_sigmask(SIGTERM, SIGINT): " + errnoText(rc));
  // A client that hangs up must not kill the daemon (replies use MSG_NOSIGNAL as well).
  ::signal(SIGPIPE, SIG_IGN);
}

Service::Service(Channels& channels, const rt::Notifier& notifier, ServiceOptions options, std::ostream& log)
    : ch_(channels), notifier_(notifier), options_(std::move(options)), log_(log) {
  clients_.reserve(kMaxClients);
  pollfds_.reserve(kMaxClients + 2);
}

Service::~Service() { close(); }

void Service::info(const std::string& line) { log_ << "staad: " << line << std::endl; }

void Service::open() {
  openSocket();
  if (!options_.telemetry_path.empty()) {
    try {
      telemetry_.open(options_.telemetry_path);
    } catch (const std::exception& e) {
      throw ServiceError(e.what());
    }
  }
  if (!options_.svg_path.empty()) {
    try {
      checkWritable(options_.svg_path);
    } catch (const std::exception& e) {
      std::string message = "svg file ";
      message.append(quoted(options_.svg_path.string())).append(": ").append(e.what());
      throw ServiceError(message);
    }
  }
  openSignalFd();
}

void Service::openSocket() {
  const std::string& path = options_.socket_path;
  const sockaddr_un addr = socketAddress(path);

  // The directory (e.g. /run/staad/) may not exist yet.
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec) {
      std::string message = "control socket ";
      message.append(quoted(path)).append(": cannot create the directory ").append(quoted(parent.string()));
      message.append(": ").append(ec.message());
      throw ServiceError(message);
    }
  }

  // A socket file left behind by a daemon that died is removed; a live daemon is not disturbed.
  struct stat st{};
  if (::lstat(path.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode)) {
      std::string message = "control socket ";
      message.append(quoted(path)).append(": exists and is not a socket (refusing to remove it)");
      throw ServiceError(message);
    }
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (probe < 0) throw ServiceError("socket(AF_UNIX): " + errnoText(errno));
    const int rc = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
    const int error = errno;
    ::close(probe);
    if (rc == 0) {
      std::string message = "control socket ";
      message.append(quoted(path)).append(": another staad is already listening there");
      throw ServiceError(message);
    }
    if (error != ECONNREFUSED) {
      std::string message = "control socket ";
      message.append(quoted(path)).append(": exists and cannot be probed: ").append(errnoText(error));
      throw ServiceError(message);
    }
    if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
      std::string message = "control socket ";
      message.append(quoted(path)).append(": cannot remove the stale socket: ").append(errnoText(errno));
      throw ServiceError(message);
    }
    info("removed a stale control socket at " + path);
  }

  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listen_fd_ < 0) throw ServiceError("socket(AF_UNIX): " + errnoText(errno));
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int error = errno;
    std::string message = "control socket ";
    message.append(quoted(path)).append(": bind: ").append(errnoText(error));
    throw ServiceError(message);
  }
  socket_created_ = true;
  if (::chmod(path.c_str(), static_cast<mode_t>(options_.socket_mode)) != 0) {
    const int error = errno;
    char mode[16];
    std::snprintf(mode, sizeof mode, "%04o", options_.socket_mode);
    std::string message = "control socket ";
    message.append(quoted(path)).append(": chmod ").append(mode).append(": ").append(errnoText(error));
    throw ServiceError(message);
  }
  if (::listen(listen_fd_, static_cast<int>(kMaxClients)) != 0) {
    std::string message = "control socket ";
    message.append(quoted(path)).append(": listen: ").append(errnoText(errno));
    throw ServiceError(message);
  }
}

void Service::openSignalFd() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  signal_fd_ = ::signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
  if (signal_fd_ < 0) throw ServiceError("signalfd(SIGTERM, SIGINT): " + errnoText(errno));
}

void Service::setControlTiming(const rt::LatencyHistogram* execution, const rt::LatencyHistogram* wake, bool realtime) {
  exec_hist_ = execution;
  wake_hist_ = wake;
  realtime_ = realtime;
}

void Service::setBaseTiming(const BaseTask* task, const rt::LatencyHistogram* execution,
                            const rt::LatencyHistogram* wake, bool realtime) {
  base_task_ = task;
  base_exec_hist_ = execution;
  base_wake_hist_ = wake;
  base_realtime_ = realtime;
}

const Status& Service::latest() {
  if (ch_.status.update()) {
    status_ = ch_.status.readBuffer();
    if (!options_.svg_path.empty()) run_.observe(status_);
  }
  status_.realtime = realtime_;
  status_.queued_goal_id = last_goal_id_;
  return status_;
}

const Status& Service::status() {
  latest();
  // p50 / p99 / max of a histogram (when there is one) into three status fields.
  auto summarize = [](const auto* hist, auto& p50, auto& p99, auto& max) {
    if (hist == nullptr) return;
    const rt::TimingSummary t = hist->summary();
    p50 = t.p50_us;
    p99 = t.p99_us;
    max = t.max_us;
  };
  summarize(exec_hist_, status_.cycle_p50_us, status_.cycle_p99_us, status_.cycle_max_us);
  summarize(wake_hist_, status_.wake_p50_us, status_.wake_p99_us, status_.wake_max_us);
  ThreadTiming& bt = status_.base_thread;
  bt.realtime = base_realtime_;
  summarize(base_exec_hist_, bt.exec_p50_us, bt.exec_p99_us, bt.exec_max_us);
  summarize(base_wake_hist_, bt.wake_p50_us, bt.wake_p99_us, bt.wake_max_us);
  if (base_task_ != nullptr) {
    const rt::PeriodicCounters c = base_task_->loopCounters();
    bt.cycles = c.cycles;
    bt.overruns = c.overruns;
    bt.execution_overruns = c.execution_overruns;
    bt.late_wakeups = c.late_wakeups;
    bt.preempted = c.preempted;
    bt.skipped_periods = c.skipped_periods;
    const rt::TimingSummary t = base_task_->commandToWire().summary();
    CommandToWire& cw = status_.command_to_wire;
    cw.count = t.count;
    cw.unsent = base_task_->commandsUnsent();
    cw.p50_us = t.p50_us;
    cw.p99_us = t.p99_us;
    cw.max_us = t.max_us;
  }
  return status_;
}

void Service::ready(rt::Nanos now) {
  ready_ = true;
  notifier_.ready();
  latest();
  notifyStatus();
  if (options_.watchdog_interval) {
    next_ping_ = now;  // the first ping right away
    ping_heartbeat_ = 0;
  }
}

void Service::stopping() {
  notifier_.status("stopping");
  notifier_.stopping();
}

bool Service::runOnce(rt::Nanos now, int timeout_ms) {
  pollfds_.clear();
  pollfds_.push_back(::pollfd{listen_fd_, POLLIN, 0});
  pollfds_.push_back(::pollfd{signal_fd_, POLLIN, 0});
  for (const Client& c : clients_) {
    pollfds_.push_back(::pollfd{c.fd, static_cast<short>(POLLIN | (c.out.empty() ? 0 : POLLOUT)), 0});
  }
  const int n = ::poll(pollfds_.data(), pollfds_.size(), timeout_ms);
  if (n < 0 && errno != EINTR) {
    info("poll: " + errnoText(errno));
  }
  if (n > 0) {
    if ((pollfds_[1].revents & POLLIN) != 0 && readSignal()) terminate_ = true;
    for (std::size_t i = 0; i < clients_.size(); ++i) {
      const short revents = pollfds_[i + 2].revents;
      Client& c = clients_[i];
      if ((revents & (POLLIN | POLLHUP | POLLERR)) != 0) readClient(c);
      if (c.fd >= 0 && (revents & POLLOUT) != 0) flushClient(c);
    }
    std::erase_if(clients_, [](const Client& c) { return c.fd < 0; });
    if ((pollfds_[0].revents & POLLIN) != 0) acceptClients();
  }
  latest();
  drainLogs();
  drainTelemetry();
  notifyStatus();
  watchdog(now);
  return terminate_;
}

void Service::drain() {
  latest();
  drainLogs();
  drainTelemetry();
}

bool Service::readSignal() {
  bool got = false;
  signalfd_siginfo info_buf{};
  while (::read(signal_fd_, &info_buf, sizeof info_buf) == static_cast<ssize_t>(sizeof info_buf)) {
    info(std::string("received ") + (info_buf.ssi_signo == SIGINT ? "SIGINT" : "SIGTERM") + ": stopping");
    got = true;
  }
  return got;
}

void Service::acceptClients() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNABORTED) {
        info("accept: " + errnoText(errno));
      }
      return;
    }
    if (clients_.size() >= kMaxClients) {
      const std::string reply = errorReply("too many clients (at most 16)");
      (void)!::send(fd, reply.data(), reply.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      ::close(fd);
      continue;
    }
    Client c;
    c.fd = fd;
    clients_.push_back(std::move(c));
  }
}

void Service::readClient(Client& c) {
  char buf[4096];
  for (int reads = 0; reads < kMaxReadsPerRound && c.fd >= 0; ++reads) {
    const ssize_t n = ::read(c.fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      closeClient(c);  // ECONNRESET and the like
      return;
    }
    if (n == 0) {
      // The peer closed its side: a last line without its newline still counts.
      if (!c.discarding && !c.in.empty()) {
        const std::string last = std::move(c.in);
        c.in.clear();
        handleLine(c, last);
      }
      c.closing = true;
      flushClient(c);
      if (c.fd >= 0) closeClient(c);
      return;
    }
    const std::string_view data(buf, static_cast<std::size_t>(n));
    std::size_t start = 0;
    while (start < data.size()) {
      const std::size_t nl = data.find('\n', start);
      const std::string_view piece = data.substr(start, nl == std::string_view::npos ? std::string_view::npos : nl - start);
      if (c.discarding) {
        if (nl != std::string_view::npos) c.discarding = false;  // the over-long line ends here
      } else {
        c.in.append(piece);
        if (c.in.size() > kMaxRequestBytes) {
          // Over-long: one error reply, the rest of the line discarded.
          c.in.clear();
          c.discarding = nl == std::string_view::npos;
          std::string message = "request longer than ";
          message.append(std::to_string(kMaxRequestBytes)).append(" bytes");
          c.out.append(errorReply(message));
        } else if (nl != std::string_view::npos) {
          const std::string line = std::move(c.in);
          c.in.clear();
          handleLine(c, line);
        }
      }
      if (nl == std::string_view::npos) break;
      start = nl + 1;
    }
    flushClient(c);
  }
}

void Service::handleLine(Client& c, std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.find_first_not_of(" \t\r") == std::string_view::npos) return;  // blank lines are ignored
  auto parsed = parseRequest(line);
  if (std::holds_alternative<std::string>(parsed)) {
    c.out.append(errorReply(std::get<std::string>(parsed)));
    return;
  }
  const Request& request = std::get<Request>(parsed);
  if (request.kind == RequestKind::kStatus) {
    c.out.append(statusReply(status(), rt::realtimeAllocations()));
    return;
  }
  if (request.kind == RequestKind::kDebug) {
    handleDebug(c, request);
    return;
  }
  if (ch_.shutdown.load(std::memory_order_relaxed)) {
    c.out.append(errorReply("staad is stopping"));
    return;
  }
  // A goal's id is given as it is queued: a refused goal takes none.
  Request queued = request;
  if (queued.kind == RequestKind::kGoal) queued.goal_id = last_goal_id_ + 1;
  if (!ch_.requests.push(queued)) {
    c.out.append(errorReply("busy: the control thread is not taking requests, try again"));
    return;
  }
  if (queued.kind != RequestKind::kGoal) {
    c.out.append(okReply());
    return;
  }
  last_goal_id_ = queued.goal_id;
  if (!options_.svg_path.empty()) run_.addGoal(queued.goal_id, queued.pose);
  c.out.append(goalReply(queued.goal_id));
}

void Service::handleDebug(Client& c, const Request& request) {
  if (!options_.debug_faults) {
    c.out.append(errorReply("debug requests are off: they inject faults for tests, and are taken only with debug: "
                            "{faults: true} in the config"));
    return;
  }
  switch (request.debug) {
    case DebugKind::kOverrun:
      ch_.debug_overrun_ms.store(request.debug_ms, std::memory_order_release);
      info("debug: the next control cycle busy-waits " + std::to_string(request.debug_ms) + " ms (a forced overrun)");
      break;
    case DebugKind::kStallObstacles:
      ch_.debug_stall_obstacles.store(request.debug_on, std::memory_order_release);
      info(request.debug_on ? "debug: obstacle frames stalled" : "debug: obstacle frames resumed");
      break;
    case DebugKind::kNone: break;
  }
  c.out.append(okReply());
}

void Service::flushClient(Client& c) {
  while (c.fd >= 0 && !c.out.empty()) {
    const ssize_t n = ::send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      closeClient(c);
      return;
    }
    c.out.erase(0, static_cast<std::size_t>(n));
  }
  if (c.fd >= 0 && c.out.size() > kMaxPendingReplyBytes) {
    info("dropping a control-socket client that does not read its replies");
    closeClient(c);
  }
}

void Service::closeClient(Client& c) {
  if (c.fd >= 0) ::close(c.fd);
  c.fd = -1;
  c.in.clear();
  c.out.clear();
}

void Service::drainLogs() {
  struct Source {
    rt::LogRing* ring;
    const char* thread;
  };
  const Source sources[] = {{&ch_.control_log, "control"}, {&ch_.base_log, "base"}, {&ch_.perception_log, "perception"}};
  rt::LogRecord r;
  for (const Source& s : sources) {
    while (s.ring->pop(r)) {
      char line[512];
      int n = std::snprintf(line, sizeof line, "staad: [%s] %s: %s", s.thread, levelName(r.level),
                            r.message != nullptr ? r.message : "");
      for (std::uint8_t i = 0; i < r.value_count && i < 3 && n > 0 && static_cast<std::size_t>(n) < sizeof line; ++i) {
        n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), "%s%.6g", i == 0 ? ": " : " ",
                           r.values[i]);
      }
      log_ << line << '\n';
    }
  }
  log_.flush();
}

void Service::drainTelemetry() {
  TelemetryRecord r;
  bool wrote = false;
  const bool keep_run = !options_.svg_path.empty();
  while (ch_.telemetry.pop(r)) {
    if (keep_run) run_.addPose(r.t_s, Pose2{r.x, r.y, r.theta});
    if (telemetry_.isOpen()) {
      telemetry_.write(r);
      wrote = true;
    }
  }
  if (wrote) telemetry_.flush();
  const std::uint64_t dropped = ch_.telemetry.dropped();
  if (dropped > telemetry_dropped_seen_) {
    info("telemetry: " + std::to_string(dropped - telemetry_dropped_seen_) + " records dropped (ring full)");
    telemetry_dropped_seen_ = dropped;
  }
}

void Service::notifyStatus() {
  if (!ready_) return;
  const Status& s = status_;
  char text[200];
  switch (s.state) {
    case DaemonState::kDriving:
      std::snprintf(text, sizeof text, "driving to (%.2f, %.2f, %.2f)", s.goal.x, s.goal.y, s.goal.theta);
      break;
    case DaemonState::kReached:
      std::snprintf(text, sizeof text, "reached (%.2f, %.2f, %.2f)", s.goal.x, s.goal.y, s.goal.theta);
      break;
    case DaemonState::kUnreachable:
      std::snprintf(text, sizeof text, "unreachable (%.2f, %.2f, %.2f)", s.goal.x, s.goal.y, s.goal.theta);
      break;
    case DaemonState::kFault:
      if (s.fault == FaultKind::kBase) {
        std::snprintf(text, sizeof text, "fault: base (%s, code %u)", hal::toString(s.base_fault),
                      static_cast<unsigned>(s.base_fault_code));
      } else {
        std::snprintf(text, sizeof text, "fault: %s", toString(s.fault));
      }
      break;
    default: std::snprintf(text, sizeof text, "%s", toString(s.state)); break;
  }
  if (last_status_text_ == text) return;
  last_status_text_ = text;
  notifier_.status(last_status_text_);
}

void Service::watchdog(rt::Nanos now) {
  if (!ready_ || !options_.watchdog_interval || now < next_ping_) return;
  const std::uint64_t heartbeat = ch_.heartbeat.load(std::memory_order_acquire);
  if (heartbeat != ping_heartbeat_) {
    notifier_.watchdog();
    ++watchdog_pings_;
    ping_heartbeat_ = heartbeat;
    next_ping_ = now + *options_.watchdog_interval;
    if (withheld_logged_) info("control thread running again: watchdog pings resumed");
    withheld_logged_ = false;
    return;
  }
  // The control thread is stuck: no ping (systemd's watchdog will act); check every round.
  if (!withheld_logged_) {
    ++withheld_pings_;
    info("watchdog ping withheld: the control thread's heartbeat is not advancing");
    withheld_logged_ = true;
  }
}

void Service::close() {
  for (Client& c : clients_) closeClient(c);
  clients_.clear();
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    listen_fd_ = -1;
  }
  if (socket_created_) {
    ::unlink(options_.socket_path.c_str());
    socket_created_ = false;
  }
  if (signal_fd_ >= 0) {
    ::close(signal_fd_);
    signal_fd_ = -1;
  }
  telemetry_.flush();
  telemetry_.close();
}

void Service::writeRunSvg(const PolygonMap& map, const Polygon& footprint) {
  if (options_.svg_path.empty()) return;
  const std::string path = options_.svg_path.string();
  try {
    writeFileAtomically(options_.svg_path, runSvg(run_, map, footprint));
  } catch (const std::exception& e) {
    info("svg: the run's picture was not written: " + std::string(e.what()));
    return;
  }
  char line[200];
  std::snprintf(line, sizeof line, "%.1f s, %.2f m driven, %zu of %zu goals reached", run_.durationS(),
                run_.distanceM(), run_.goalsReached(), run_.goals().size());
  info("svg: wrote the run's picture to " + path + " (" + line + ")");
}

}  // namespace staa::staad
