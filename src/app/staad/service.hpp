#pragma once
// staad's service thread (normal priority; the daemon's main thread): the control socket,
// the log and telemetry rings drained, sd_notify. One poll round at a time over the
// listening socket, up to max_clients clients and the SIGTERM/SIGINT descriptor, with a short
// timeout so that the rings are drained and the watchdog pinged on time.
//
// Control socket: a Unix stream socket speaking line-delimited JSON (protocol.hpp). Each
// client has its own line buffer of at most kMaxRequestBytes; a longer line gets an error
// reply and is discarded up to its newline, the client stays connected. Goal, stop and pose
// requests go to the control thread through the request ring; status is answered here from
// the latest Status snapshot, histograms from the periodic threads' histograms. Goals are numbered here (1, 2, ...) as they are queued. Debug
// requests (tests' fault injection, only with debug.faults) set Channels' debug atomics.
//
// Abusive clients cannot hold the socket: a client that has not completed a line (any line
// ending in '\n', a request, an error or a blank one) within the idle timeout since its last
// one, or since it connected, is dropped; when all max_clients slots are taken, a new client
// makes room by dropping the longest-idle one. So silent connections cannot lock staactl out.
//
// With an SVG path (`--svg`, telemetry.svg) the service keeps the run as it goes (the poses of
// the telemetry records, decimated; the goals it queued) and draws it when staad stops.
//
// A dispatcher: the sockets, the poll and the signals are rt's (rt/unix_socket.hpp,
// rt/signals.hpp).

#include "app/staad/channels.hpp"
#include "app/staad/run_picture.hpp"
#include "record/recorder.hpp"
#include "rt/activity.hpp"
#include "rt/sd_notify.hpp"
#include "rt/signals.hpp"
#include "rt/unix_socket.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa::staad {

class BaseTask;

// A failure to start the service (socket busy, path unusable): staad exits 1.
class ServiceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ServiceOptions {
  std::string socket_path;
  unsigned socket_mode = 0660;
  std::size_t max_clients = 16;                       // config socket.max_clients
  rt::Nanos idle_timeout = 5 * rt::kNanosPerSecond;   // config socket.idle_timeout_s
  std::filesystem::path telemetry_path;  // empty: off
  std::filesystem::path svg_path;        // the run's picture at shutdown; empty: off
  std::optional<rt::Nanos> watchdog_interval;  // rt::Notifier::watchdogInterval()
  bool debug_faults = false;  // {"debug": ...} requests taken (config debug.faults), else refused
  // The flight recorder's files (Channels::recorder drained into it); null: off. Not owned.
  record::RecordingService* recorder = nullptr;
};

class Service {
 public:
  Service(Channels& channels, const rt::Notifier& notifier, ServiceOptions options, std::ostream& log);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Start-up, before the real-time threads: the control socket (unlinks a stale socket file
  // nobody accepts on; refuses when another daemon listens there), the telemetry file, and
  // the SIGTERM/SIGINT descriptor (call rt::blockTerminationSignals() first). Throw
  // ServiceError.
  void open();

  // The activities whose timing completes the status: the control thread's (the contract's
  // `cycle`) and the base thread's (`threads.base`), with the base task's command-to-wire
  // latency (`base.command_to_wire`). Read through their atomics; null: left empty. The
  // histograms request reports these and the perception thread's histograms.
  void watchTiming(const rt::PeriodicActivity* control, const rt::PeriodicActivity* base, const BaseTask* base_task,
                   const rt::PeriodicActivity* perception = nullptr);

  // Fields of the status that another part of the daemon owns (the ROS link), filled in by
  // `complete` whenever status() is asked for.
  void completeStatusWith(std::function<void(Status&)> complete) { complete_ = std::move(complete); }

  // Queues a goal, stop or pose request for the control thread, as the control socket does
  // (goals are numbered here): the goal's id, or the reason it was refused.
  struct Submitted {
    std::uint64_t goal_id = 0;  // 0 for stop and pose
    std::string error;          // empty: queued
  };
  Submitted submit(const Request& request);

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
    rt::UnixStream stream;
    std::string in;
    std::string out;
    bool discarding = false;  // dropping the rest of an over-long line
    bool closing = false;     // peer closed its side: close once `out` is sent
    rt::Nanos last_line = 0;  // when it connected or last completed a line
  };

  void openSocket();
  void acceptClients(rt::Nanos now);
  void makeRoom(rt::Nanos now);
  void dropIdleClients(rt::Nanos now);
  void dropClient(Client& client, const std::string& reply, const std::string& log_line);
  void readClient(Client& client, rt::Nanos now);
  void handleLine(Client& client, std::string_view line);
  void handleDebug(Client& client, const Request& request);
  void flushClient(Client& client);
  void closeClient(Client& client);
  bool takeSignals();
  void drainLogs();
  void drainTelemetry();
  void drainRecorder();
  void handleRecord(Client& client, const Request& request);
  nlohmann::json recorderJson() const;
  void notifyStatus();
  void watchdog(rt::Nanos now);

  Channels& ch_;
  const rt::Notifier& notifier_;
  ServiceOptions options_;
  std::ostream& log_;
  std::optional<rt::UnixListener> listener_;
  std::optional<rt::TerminationSignals> signals_;
  std::vector<Client> clients_;
  rt::Poller poller_;
  TelemetryWriter telemetry_;
  Status status_;
  const rt::PeriodicActivity* control_activity_ = nullptr;
  const rt::PeriodicActivity* base_activity_ = nullptr;
  const rt::PeriodicActivity* perception_activity_ = nullptr;
  const BaseTask* base_task_ = nullptr;
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
  std::uint64_t recorder_dropped_seen_ = 0;
  std::vector<std::byte> recorder_record_;  // one encoded cycle, popped
  std::uint64_t last_goal_id_ = 0;  // the newest goal queued (ids start at 1)
  RunRecord run_;                   // kept only with an SVG path
  std::function<void(Status&)> complete_;
};

}  // namespace staa::staad
