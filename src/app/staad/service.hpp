#pragma once
// staad's service thread (normal priority; the daemon's main thread): the control socket,
// the log and telemetry rings drained, sd_notify. One poll() round at a time over the
// listening socket, up to kMaxClients clients and a signalfd for SIGTERM/SIGINT, with a short
// timeout so that the rings are drained and the watchdog pinged on time.
//
// Control socket: a Unix stream socket speaking line-delimited JSON (protocol.hpp). Each
// client has its own line buffer of at most kMaxRequestBytes; a longer line gets an error
// reply and is discarded up to its newline, the client stays connected. Goal, stop and pose
// requests go to the control thread through the request ring; status is answered here from
// the latest Status snapshot. Goals are numbered here (1, 2, ...) as they are queued. Debug
// requests (tests' fault injection, only with debug.faults) set Channels' debug atomics.
//
// With an SVG path (`--svg`, telemetry.svg) the service keeps the run as it goes (the poses of
// the telemetry records, decimated; the goals it queued) and draws it when staad stops.
//
// The OS calls of the daemon (sockets, poll, signalfd) live in service.cpp only.

#include "app/staad/channels.hpp"
#include "app/staad/run_picture.hpp"
#include "rt/sd_notify.hpp"
#include "rt/timing_stats.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

struct pollfd;  // <poll.h>, kept out of this header

namespace staa::staad {

class BaseTask;

// A failure to start the service (socket busy, path unusable): staad exits 1.
class ServiceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Blocks SIGTERM and SIGINT in the calling thread (and every thread it creates afterwards),
// so that they arrive only through the service's signalfd. Call before any thread starts.
void blockTerminationSignals();

struct ServiceOptions {
  std::string socket_path;
  unsigned socket_mode = 0660;
  std::filesystem::path telemetry_path;  // empty: off
  std::filesystem::path svg_path;        // the run's picture at shutdown; empty: off
  std::optional<rt::Nanos> watchdog_interval;  // rt::Notifier::watchdogInterval()
  bool debug_faults = false;  // {"debug": ...} requests taken (config debug.faults), else refused
};

class Service {
 public:
  static constexpr std::size_t kMaxClients = 16;

  Service(Channels& channels, const rt::Notifier& notifier, ServiceOptions options, std::ostream& log);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Start-up, before the real-time threads: the control socket (unlinks a stale socket file
  // nobody accepts on; refuses when another daemon listens there), the telemetry file, and
  // the signalfd (call blockTerminationSignals() first). Throw ServiceError.
  void open();

  // The control thread's timing (its periodic loop's histograms, read through their atomics)
  // and whether it runs under SCHED_FIFO: they complete the status.
  void setControlTiming(const rt::LatencyHistogram* execution, const rt::LatencyHistogram* wake, bool realtime);
  // The same for the base thread, and its task (the loop's counters and the command-to-wire
  // latency, read through their atomics): `threads.base` and `base.command_to_wire`.
  void setBaseTiming(const BaseTask* task, const rt::LatencyHistogram* execution, const rt::LatencyHistogram* wake,
                     bool realtime);

  // READY=1 (and the first STATUS=); starts the watchdog pings.
  void ready(rt::Nanos now);
  // One round: poll (up to the timeout), accept, read, answer; drain logs and telemetry;
  // STATUS= on a state change; WATCHDOG=1 when due and the control heartbeat advanced.
  // Returns true once a termination signal (SIGTERM/SIGINT) has arrived.
  bool runOnce(rt::Nanos now, int timeout_ms);
  // Logs and telemetry only (while shutting down).
  void drain();
  // The latest status from the control thread, completed by the service's fields (timing
  // percentiles: costly, only when asked).
  const Status& status();
  // The latest status as published (cheap).
  const Status& latest();
  // STOPPING=1.
  void stopping();
  // Closes the clients and the socket (unlinks its file) and the telemetry file.
  void close();
  // With an SVG path: draws the run over `map` with the robot's `footprint` and writes it
  // atomically; logs what it wrote, or why it could not (staad's exit code stays 0). Call
  // after the threads ended and drain() took the last records.
  void writeRunSvg(const PolygonMap& map, const Polygon& footprint);

  const std::string& socketPath() const { return options_.socket_path; }
  std::uint64_t watchdogPings() const { return watchdog_pings_; }
  std::uint64_t withheldPings() const { return withheld_pings_; }

  // Logs one line to the log stream ("staad: " prefix), from the service thread.
  void info(const std::string& line);

 private:
  struct Client {
    int fd = -1;
    std::string in;
    std::string out;
    bool discarding = false;  // dropping the rest of an over-long line
    bool closing = false;     // peer closed its side: close once `out` is sent
  };

  void openSocket();
  void openSignalFd();
  void acceptClients();
  void readClient(Client& client);
  void handleLine(Client& client, std::string_view line);
  void handleDebug(Client& client, const Request& request);
  void flushClient(Client& client);
  void closeClient(Client& client);
  bool readSignal();
  void drainLogs();
  void drainTelemetry();
  void notifyStatus();
  void watchdog(rt::Nanos now);

  Channels& ch_;
  const rt::Notifier& notifier_;
  ServiceOptions options_;
  std::ostream& log_;
  int listen_fd_ = -1;
  int signal_fd_ = -1;
  bool socket_created_ = false;
  std::vector<Client> clients_;
  std::vector<::pollfd> pollfds_;
  TelemetryWriter telemetry_;
  Status status_;
  const rt::LatencyHistogram* exec_hist_ = nullptr;
  const rt::LatencyHistogram* wake_hist_ = nullptr;
  bool realtime_ = false;
  const BaseTask* base_task_ = nullptr;
  const rt::LatencyHistogram* base_exec_hist_ = nullptr;
  const rt::LatencyHistogram* base_wake_hist_ = nullptr;
  bool base_realtime_ = false;
  bool ready_ = false;
  bool terminate_ = false;
  // sd_notify
  rt::Nanos next_ping_ = 0;
  std::uint64_t ping_heartbeat_ = 0;
  std::uint64_t watchdog_pings_ = 0;
  std::uint64_t withheld_pings_ = 0;
  bool withheld_logged_ = false;
  std::string last_status_text_;
  std::uint64_t telemetry_dropped_seen_ = 0;
  std::uint64_t last_goal_id_ = 0;  // the newest goal queued (ids start at 1)
  RunRecord run_;                   // kept only with an SVG path
};

}  // namespace staa::staad
