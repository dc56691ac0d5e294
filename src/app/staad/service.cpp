#include "app/staad/service.hpp"

#include "app/staad/io_tasks.hpp"
#include "app/staad/protocol.hpp"
#include "app/staad/text.hpp"
#include "rt/alloc_count.hpp"
#include "rt/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <system_error>
#include <variant>

namespace staa::staad {

namespace {

constexpr std::size_t kMaxPendingReplyBytes = 1u << 20;  // a client that never reads is dropped
constexpr int kMaxReadsPerRound = 16;                    // one busy client cannot starve the rest

std::string seconds(rt::Nanos t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g s", static_cast<double>(t) / static_cast<double>(rt::kNanosPerSecond));
  return text;
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

Service::Service(Channels& channels, const rt::Notifier& notifier, ServiceOptions options, std::ostream& log)
    : ch_(channels), notifier_(notifier), options_(std::move(options)), log_(log), poller_(options_.max_clients + 2) {
  clients_.reserve(options_.max_clients);
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
  try {
    signals_.emplace();
  } catch (const std::system_error& e) {
    throw ServiceError(e.what());
  }
}

void Service::openSocket() {
  const std::string& path = options_.socket_path;
  try {
    listener_.emplace(rt::UnixListener::open(path, options_.socket_mode, static_cast<int>(options_.max_clients)));
  } catch (const rt::SocketError& e) {
    std::string message = "control socket ";
    message.append(quoted(path)).append(": ");
    message.append(e.kind() == rt::SocketError::Kind::kInUse ? "another staad is already listening there" : e.what());
    throw ServiceError(message);
  }
  if (listener_->removedStale()) info("removed a stale control socket at " + path);
}

void Service::watchTiming(const rt::PeriodicActivity* control, const rt::PeriodicActivity* base,
                          const BaseTask* base_task, const rt::PeriodicActivity* perception) {
  control_activity_ = control;
  base_activity_ = base;
  base_task_ = base_task;
  perception_activity_ = perception;
}

const Status& Service::latest() {
  if (ch_.status.update()) {
    status_ = ch_.status.readBuffer();
    if (!options_.svg_path.empty()) run_.observe(status_);
  }
  status_.queued_goal_id = last_goal_id_;
  return status_;
}

const Status& Service::status() {
  latest();
  if (control_activity_ != nullptr) status_.control_thread = control_activity_->timing();
  if (base_activity_ != nullptr) status_.base_thread = base_activity_->timing();
  if (base_task_ != nullptr) status_.command_to_wire = {base_task_->commandToWire().summary(), base_task_->commandsUnsent()};
  if (complete_) complete_(status_);
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
  poller_.clear();
  const std::size_t listening = poller_.watch(listener_->fd(), true, false);
  const std::size_t signalled = poller_.watch(signals_->fd(), true, false);
  const std::size_t first_client = listening + 2;
  for (const Client& c : clients_) poller_.watch(c.stream.fd(), true, !c.out.empty());
  const rt::Poller::Result polled = poller_.wait(timeout_ms);
  if (polled.error != 0) info("poll: " + rt::errnoText(polled.error));
  const std::size_t watched = clients_.size();
  if (polled.ready > 0) {
    if (poller_.readable(signalled) && takeSignals()) terminate_ = true;
    if (poller_.readable(listening)) acceptClients(now);
    // New connections first: an operator's stop must not wait behind a round of busy clients.
    for (std::size_t i = watched; i < clients_.size(); ++i) readClient(clients_[i], now);
    for (std::size_t i = 0; i < watched; ++i) {
      Client& c = clients_[i];
      if (!c.stream.isOpen()) continue;  // dropped to make room
      if (poller_.readable(first_client + i) || poller_.hungUp(first_client + i)) readClient(c, now);
      if (c.stream.isOpen() && poller_.writable(first_client + i)) flushClient(c);
    }
  }
  dropIdleClients(now);
  std::erase_if(clients_, [](const Client& c) { return !c.stream.isOpen(); });
  latest();
  drainLogs();
  drainTelemetry();
  drainRecorder();
  notifyStatus();
  watchdog(now);
  return terminate_;
}

void Service::drain() {
  latest();
  drainLogs();
  drainTelemetry();
  drainRecorder();
}

bool Service::takeSignals() {
  bool got = false;
  while (const std::optional<rt::TerminationSignal> signal = signals_->take()) {
    info(std::string("received ") + rt::toString(*signal) + ": stopping");
    got = true;
  }
  return got;
}

void Service::acceptClients(rt::Nanos now) {
  for (;;) {
    int error = 0;
    std::optional<rt::UnixStream> stream = listener_->accept(error);
    if (!stream) {
      if (error != 0) info("accept: " + rt::errnoText(error));
      return;
    }
    const auto open = std::count_if(clients_.begin(), clients_.end(), [](const Client& c) { return c.stream.isOpen(); });
    if (static_cast<std::size_t>(open) >= options_.max_clients) makeRoom(now);
    Client c;
    c.stream = std::move(*stream);
    c.last_line = now;
    clients_.push_back(std::move(c));
  }
}

// The newest connection is likely an operator's: the longest-idle client goes instead. It is
// closed, not erased: the round's poll results are indexed by the clients' places.
void Service::makeRoom(rt::Nanos now) {
  Client* longest = nullptr;
  for (Client& c : clients_) {
    if (c.stream.isOpen() && (longest == nullptr || c.last_line < longest->last_line)) longest = &c;
  }
  if (longest == nullptr) return;
  const std::string slots = std::to_string(options_.max_clients);
  dropClient(*longest, "all " + slots + " client slots (socket.max_clients) are taken: the longest idle, this one, is closed",
             "control socket: all " + slots + " client slots (socket.max_clients) taken: dropped the longest-idle client (" +
                 seconds(now - longest->last_line) + " since its last line) to make room");
}

void Service::dropIdleClients(rt::Nanos now) {
  for (Client& c : clients_) {
    if (!c.stream.isOpen() || now - c.last_line < options_.idle_timeout) continue;
    const std::string limit = seconds(options_.idle_timeout) + " (socket.idle_timeout_s)";
    dropClient(c, "no complete request line within " + limit + ": closed",
               "control socket: dropped a client with no complete line within " + limit +
                   (c.in.empty() ? "" : ", " + std::to_string(c.in.size()) + " bytes of a line pending"));
  }
}

// One best-effort error reply (the client may not read), then closed.
void Service::dropClient(Client& c, const std::string& reply, const std::string& log_line) {
  flushClient(c);
  if (c.stream.isOpen() && c.out.empty()) (void)c.stream.send(errorReply(reply));
  info(log_line);
  closeClient(c);
}

void Service::readClient(Client& c, rt::Nanos now) {
  char buf[4096];
  for (int reads = 0; reads < kMaxReadsPerRound && c.stream.isOpen(); ++reads) {
    const rt::UnixStream::Result r = c.stream.read(buf, sizeof buf);
    if (r.io == rt::UnixStream::Io::kWouldBlock) break;
    if (r.io == rt::UnixStream::Io::kFailed) {
      closeClient(c);  // ECONNRESET and the like
      return;
    }
    if (r.io == rt::UnixStream::Io::kClosed) {
      // The peer closed its side: a last line without its newline still counts.
      if (!c.discarding && !c.in.empty()) {
        const std::string last = std::move(c.in);
        c.in.clear();
        handleLine(c, last);
      }
      c.closing = true;
      flushClient(c);
      if (c.stream.isOpen()) closeClient(c);
      return;
    }
    const std::string_view data(buf, r.bytes);
    std::size_t start = 0;
    while (start < data.size()) {
      const std::size_t nl = data.find('\n', start);
      const std::string_view piece = data.substr(start, nl == std::string_view::npos ? std::string_view::npos : nl - start);
      if (nl != std::string_view::npos) c.last_line = now;
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
    if (options_.recorder == nullptr) {
      c.out.append(statusReply(status(), rt::realtimeAllocations()));
    } else {
      c.out.append(statusReply(status(), rt::realtimeAllocations(), recorderJson()));
    }
    return;
  }
  if (request.kind == RequestKind::kRecord) {
    handleRecord(c, request);
    return;
  }
  if (request.kind == RequestKind::kHistograms) {
    const ThreadHistograms threads[] = {
        {"control", control_activity_}, {"base", base_activity_}, {"perception", perception_activity_}};
    c.out.append(histogramsReply(threads));
    return;
  }
  if (request.kind == RequestKind::kDebug) {
    handleDebug(c, request);
    return;
  }
  const Submitted submitted = submit(request);
  if (!submitted.error.empty()) {
    c.out.append(errorReply(submitted.error));
    return;
  }
  c.out.append(request.kind == RequestKind::kGoal ? goalReply(submitted.goal_id) : okReply());
}

Service::Submitted Service::submit(const Request& request) {
  if (ch_.shutdown.load(std::memory_order_relaxed)) return {0, "staad is stopping"};
  // A goal's id is given as it is queued: a refused goal takes none.
  Request queued = request;
  if (queued.kind == RequestKind::kGoal) queued.goal_id = last_goal_id_ + 1;
  if (!ch_.requests.push(queued)) return {0, "busy: the control thread is not taking requests, try again"};
  if (queued.kind != RequestKind::kGoal) return {0, {}};
  last_goal_id_ = queued.goal_id;
  if (!options_.svg_path.empty()) run_.addGoal(queued.goal_id, queued.pose);
  return {queued.goal_id, {}};
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
  while (c.stream.isOpen() && !c.out.empty()) {
    const rt::UnixStream::Result r = c.stream.send(c.out);
    if (r.io == rt::UnixStream::Io::kWouldBlock) break;
    if (r.io != rt::UnixStream::Io::kDone) {
      closeClient(c);
      return;
    }
    c.out.erase(0, r.bytes);
  }
  if (c.stream.isOpen() && c.out.size() > kMaxPendingReplyBytes) {
    info("dropping a control-socket client that does not read its replies");
    closeClient(c);
  }
}

void Service::closeClient(Client& c) {
  c.stream.close();
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
        std::snprintf(text, sizeof text, "fault: base (%s, code %u)", hal::toString(s.base.fault),
                      static_cast<unsigned>(s.base.fault_code));
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

void Service::drainRecorder() {
  if (!ch_.recorder || options_.recorder == nullptr) return;
  while (ch_.recorder->pop(recorder_record_)) options_.recorder->take(recorder_record_);
  const std::uint64_t dropped = ch_.recorder->dropped();
  if (dropped > recorder_dropped_seen_) {
    info("recorder: " + std::to_string(dropped - recorder_dropped_seen_) + " cycles dropped (ring full: recorder.ring_kb)");
    recorder_dropped_seen_ = dropped;
  }
}

// {"cmd": "record", "save": FILE}: the last recorder.seconds into FILE, answered here.
void Service::handleRecord(Client& c, const Request& request) {
  if (options_.recorder == nullptr) {
    c.out.append(errorReply("the flight recorder is off (recorder.enabled: false)"));
    return;
  }
  drainRecorder();  // up to the latest cycle
  const std::string file(request.file.data());
  const std::string error = options_.recorder->save(file);
  if (!error.empty()) {
    info("recorder: record save " + file + " failed: " + error);
    c.out.append(errorReply("record save: " + error));
    return;
  }
  info("recorder: saving the last " + std::to_string(static_cast<int>(options_.recorder->options().seconds)) + " s to " + file);
  c.out.append(recordReply(file));
}

// The recorder's status object (service side).
nlohmann::json Service::recorderJson() const {
  const record::RecorderStats& s = options_.recorder->stats();
  nlohmann::json j;
  j["cycles"] = s.cycles;
  j["dropped"] = ch_.recorder ? ch_.recorder->dropped() : 0;
  j["seconds"] = options_.recorder->options().seconds;
  j["file"] = s.current_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.current_file);
  j["bytes_written"] = s.bytes_written;
  j["files"] = s.files;
  j["fault_files"] = s.fault_files;
  j["last_fault_file"] = s.last_fault_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.last_fault_file);
  j["write_failures"] = s.write_failures;
  j["last_error"] = s.last_error.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.last_error);
  return j;
}

void Service::close() {
  for (Client& c : clients_) closeClient(c);
  clients_.clear();
  listener_.reset();  // closes it and removes the socket file
  signals_.reset();
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
