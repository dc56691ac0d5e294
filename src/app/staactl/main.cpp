// staactl: the command-line client of staad's control socket (docs/ARCHITECTURE.md section 6).
//
//   staactl [--socket PATH] goal X Y [TH] [--wait [--timeout S]] | stop | pose X Y [TH]
//                           | status [--json] | wait [--timeout S] [--state STATE]
//                           | histograms [--json] | record save FILE
//
// The socket is --socket, else $STAAD_SOCKET, else /run/staad/staad.sock. One request line
// out, one reply line back (protocol.hpp), with a 2 s limit on the whole exchange: a daemon
// that hangs makes staactl fail, never hang. Exit status: 0 ok (wait, goal --wait: the goal
// was reached), 1 staad refused or could not be reached (wait, goal --wait: the goal became
// unreachable, or was stopped or replaced), 2 bad arguments, 3 wait timed out. Errors are one
// line on stderr naming the value.
//
// Goals have ids (staad numbers them 1, 2, ... as it queues them): `goal --wait` waits for
// its own goal's id, and `wait` for the newest goal staad had queued at its first status
// read, so neither mistakes the previous goal's "reached" for the new goal's.

#include "app/cli_support.hpp"
#include "app/staad/protocol.hpp"
#include "rt/errors.hpp"
#include "rt/unix_socket.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>

namespace {

using Json = nlohmann::ordered_json;  // keeps the daemon's key order for --json
using SteadyClock = std::chrono::steady_clock;
using staa::cli::InputError;

constexpr int kExitOk = 0;
constexpr int kExitFailed = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitTimeout = 3;

constexpr const char* kDefaultSocket = "/run/staad/staad.sock";
constexpr auto kReplyTimeout = std::chrono::seconds(2);
constexpr std::size_t kMaxReplyBytes = 1u << 20;  // far above any status; guards against a runaway peer
// Three threads' histograms of up to 100000 non-empty 1 us bins each, at ~12 bytes a bin.
constexpr std::size_t kMaxHistogramsReplyBytes = 16u << 20;
constexpr auto kWaitPoll = std::chrono::milliseconds(100);
constexpr auto kWaitProgress = std::chrono::seconds(1);

// staad could not be asked, or refused: what() is the line after "staactl: " (exit 1).
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string inQuotes(std::string_view s) {
  std::string q = "'";  // appended: GCC 12 warns falsely (-Wrestrict) on "'" + s + "'"
  q.append(s).append("'");
  return q;
}

// ---- transport: one connection, one request line, one reply line, within a deadline ----

// What went wrong with the exchange, in staactl's words.
Failure exchangeFailure(const staa::rt::SocketError& e, const std::string& path) {
  using Kind = staa::rt::SocketError::Kind;
  using Stage = staa::rt::SocketError::Stage;
  switch (e.kind()) {
    case Kind::kConnect: {
      std::string msg = "cannot connect to " + path + ": " + staa::rt::errnoText(e.error());
      if (e.error() == EAGAIN) msg += " (staad's connection queue is full)";
      msg += " (is staad running? --socket or STAAD_SOCKET)";
      return Failure(msg);
    }
    case Kind::kTimeout: {
      const char* doing = e.stage() == Stage::kConnecting ? "connecting"
                          : e.stage() == Stage::kSending  ? "sending the request"
                                                          : "waiting for the reply";
      return Failure("no reply from staad at " + path + " within " + std::to_string(kReplyTimeout.count()) + " s (" +
                     doing + ")");
    }
    case Kind::kSend: return Failure("cannot send to " + path + ": " + staa::rt::errnoText(e.error()));
    case Kind::kReceive: return Failure("cannot read from " + path + ": " + staa::rt::errnoText(e.error()));
    case Kind::kClosed:
      return Failure("staad at " + path + " closed the connection without a reply" +
                     (e.bytes() == 0 ? std::string() : " (after " + std::to_string(e.bytes()) + " bytes of a line)"));
    case Kind::kTooLong: return Failure("reply from " + path + " is longer than 1 MiB without a line end");
    default: return Failure(e.what());  // socket(), poll: the call and the system's text
  }
}

// Sends one request and returns the reply object; a reply with "ok": false becomes a Failure
// carrying staad's own error text.
Json ask(const std::string& socket_path, const staa::staad::Request& request, std::size_t max_reply = kMaxReplyBytes) {
  std::string line;
  try {
    const auto timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(kReplyTimeout);
    staa::rt::UnixLineClient c(socket_path, timeout.count());
    c.send(staa::staad::requestLine(request));
    line = c.receiveLine(max_reply);
  } catch (const staa::rt::SocketError& e) {
    throw exchangeFailure(e, socket_path);
  }
  Json reply;
  try {
    reply = Json::parse(line);
  } catch (const Json::parse_error&) {
    throw Failure("staad at " + socket_path + " replied with something that is not JSON: " +
                  inQuotes(line.size() > 80 ? line.substr(0, 77) + "..." : line));
  }
  if (!reply.is_object() || !reply.contains("ok") || !reply["ok"].is_boolean()) {
    throw Failure("staad at " + socket_path + " replied without an \"ok\" field: " + inQuotes(line.substr(0, 80)));
  }
  if (!reply["ok"].get<bool>()) {
    const auto it = reply.find("error");
    throw Failure("staad: " + (it != reply.end() && it->is_string() ? it->get<std::string>() : std::string("request refused (no reason given)")));
  }
  return reply;
}

Json fetchStatus(const std::string& socket_path) {
  staa::staad::Request request;
  request.kind = staa::staad::RequestKind::kStatus;
  Json reply = ask(socket_path, request);
  if (!reply.contains("status") || !reply["status"].is_object()) {
    throw Failure("staad at " + socket_path + " replied to status without a \"status\" object");
  }
  return reply["status"];
}

Json fetchHistograms(const std::string& socket_path) {
  staa::staad::Request request;
  request.kind = staa::staad::RequestKind::kHistograms;
  Json reply = ask(socket_path, request, kMaxHistogramsReplyBytes);
  if (!reply.contains("histograms") || !reply["histograms"].is_object()) {
    throw Failure("staad at " + socket_path + " replied to histograms without a \"histograms\" object (an older staad?)");
  }
  return reply["histograms"];
}

// ---- reading the status leniently: a field missing or of another type prints as "?" ----

std::string num(const Json& j, const char* key, int decimals) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return "?";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, it->get<double>());
  return buf;
}

std::string numAt(const Json& j, const char* key, std::size_t i, int decimals) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_array() || it->size() <= i || !(*it)[i].is_number()) return "?";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, (*it)[i].get<double>());
  return buf;
}

// ": REASON" when the status says why the goal is unreachable (staad's `reason`), else "".
std::string reasonOf(const Json& status) {
  const auto it = status.find("reason");
  return it != status.end() && it->is_string() ? ": " + it->get<std::string>() : std::string();
}

std::string text(const Json& j, const char* key, const char* if_null = "?") {
  const auto it = j.find(key);
  if (it == j.end()) return "?";
  if (it->is_null()) return if_null;
  if (it->is_string()) return it->get<std::string>();
  return it->dump();
}

const Json& sub(const Json& j, const char* key) {
  static const Json kEmpty = Json::object();
  const auto it = j.find(key);
  return it != j.end() && it->is_object() ? *it : kEmpty;
}

std::string age(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it != j.end() && it->is_null()) return "never";
  const std::string s = num(j, key, 3);
  return s == "?" ? s : s + " s";
}

void printSummary(const Json& s) {
  std::ostringstream out;
  out << "state           " << text(s, "state") << "\n";
  out << "pose            x " << numAt(s, "pose", 0, 3) << " m, y " << numAt(s, "pose", 1, 3) << " m, theta "
      << numAt(s, "pose", 2, 3) << " rad\n";
  out << "velocity        v " << numAt(s, "velocity", 0, 3) << " m/s, w " << numAt(s, "velocity", 1, 3) << " rad/s\n";
  if (const auto g = s.find("goal"); g != s.end() && g->is_array()) {
    out << "goal            x " << numAt(s, "goal", 0, 3) << " m, y " << numAt(s, "goal", 1, 3) << " m, theta "
        << numAt(s, "goal", 2, 3) << " rad";
    if (const auto id = s.find("goal_id"); id != s.end() && id->is_number_unsigned()) out << " (goal " << id->dump() << ")";
    out << "\n";
  } else {
    out << "goal            " << text(s, "goal", "none") << "\n";
  }
  out << "fault           " << text(s, "fault", "none") << "\n";
  const Json& cycle = sub(s, "cycle");
  out << "cycle           p50 " << num(cycle, "p50_us", 0) << " us, p99 " << num(cycle, "p99_us", 0) << " us, max "
      << num(cycle, "max_us", 0) << " us, " << num(cycle, "overruns", 0) << " overruns in " << num(cycle, "count", 0)
      << " cycles\n";
  const Json& staleness = sub(s, "staleness");
  out << "staleness       odometry " << age(staleness, "odometry_s") << ", obstacles " << age(staleness, "obstacles_s") << "\n";
  out << "rt_allocations  " << num(s, "rt_allocations", 0) << "\n";
  std::cout << out.str() << std::flush;
}

// One line per thread: its cycles, the wake-up and execution maxima, the overruns by cause,
// the cycles that blocked.
void printHistograms(const Json& h) {
  std::ostringstream out;
  for (const auto& [name, t] : h.items()) {
    const Json& o = sub(t, "overruns");
    out << name << ": " << num(t, "cycles", 0) << " cycles; wake-up max " << num(sub(t, "wake_us"), "max_us", 0)
        << " us, execution max " << num(sub(t, "exec_us"), "max_us", 0) << " us; overruns " << num(o, "ours", 0)
        << " ours, " << num(o, "late_wakeup", 0) << " late wake-ups, " << num(o, "preempted", 0) << " preempted, "
        << num(o, "stall", 0) << " stalls; " << num(t, "blocked_cycles", 0) << " cycles blocked\n";
  }
  std::cout << out.str() << std::flush;
}

// ---- command-line values ----

double coordinate(const std::string& command, const char* name, const std::string& value, const char* unit) {
  const auto v = staa::cli::parseDouble(value);
  if (!v) throw InputError(command + ": " + name + ": expected a finite number (" + unit + "), got " + inQuotes(value));
  return *v;
}

staa::Pose2 poseArgs(const std::string& command, const std::string& x, const std::string& y, const std::string& theta) {
  return {coordinate(command, "X", x, "metres"), coordinate(command, "Y", y, "metres"),
          theta.empty() ? 0.0 : coordinate(command, "TH", theta, "radians")};
}

std::string socketPath(const std::string& option) {
  std::string path = option;
  std::string from = "--socket";
  if (path.empty()) {
    if (const char* env = std::getenv("STAAD_SOCKET"); env != nullptr && *env != '\0') {
      path = env;
      from = "STAAD_SOCKET";
    } else {
      path = kDefaultSocket;
    }
  }
  if (path.size() > staa::rt::kMaxUnixPathBytes) {
    throw InputError(from + ": a Unix socket path is at most " + std::to_string(staa::rt::kMaxUnixPathBytes) +
                     " bytes, got " + std::to_string(path.size()) + ": " + path);
  }
  return path;
}

constexpr const char* kStates[] = {"idle", "driving", "reached", "unreachable", "stopped", "fault"};

// A goal id in the status (an unsigned integer), or nullopt (a staad without goal ids).
std::optional<std::uint64_t> idOf(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_unsigned()) return std::nullopt;
  return it->get<std::uint64_t>();
}

std::optional<staa::Vec2> pointAt(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_array() || it->size() < 2 || !(*it)[0].is_number() || !(*it)[1].is_number()) {
    return std::nullopt;
  }
  return staa::Vec2{(*it)[0].get<double>(), (*it)[1].get<double>()};
}

// What a wait waits for.
struct WaitTarget {
  std::string state = "reached";
  // goal --wait: the id staad gave the goal. The wait ends only on a status about this goal
  // (or a newer one that replaced it). 0: the plain `wait`.
  std::uint64_t goal_id = 0;
  std::optional<staa::Vec2> goal;  // goal --wait: the goal sent (for the distance shown)
};

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

// Polls the status until the wanted state (exit 0), unreachable (exit 1) or the timeout (3).
// Waiting for reached (the plain `wait`), a status about an older goal than the newest one
// queued at the first read is not the goal's; goal --wait accepts only its own goal's id.
int waitFor(const std::string& socket_path, const WaitTarget& target, double timeout_s) {
  const auto start = SteadyClock::now();
  const auto deadline = start + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(timeout_s));
  auto next_progress = start + kWaitProgress;
  const bool own_goal = target.goal_id != 0;
  const std::string what = own_goal ? "goal " + std::to_string(target.goal_id) + " to be " + target.state : target.state;
  const std::string who = own_goal ? "goal" : "wait";
  // The plain wait: the goal current at the first status read (ids never go back).
  std::optional<std::uint64_t> min_id;
  std::string state;
  std::string shown;
  std::string to_go;
  for (;;) {
    const Json status = fetchStatus(socket_path);
    state = text(status, "state");
    const std::uint64_t id = idOf(status, "goal_id").value_or(0);
    if (!min_id) min_id = std::max(id, idOf(status, "queued_goal_id").value_or(0));
    // Shown: the state, and whose it is while staad still reports another goal.
    shown = state;
    if (own_goal && id != target.goal_id) shown += " for goal " + std::to_string(id);

    const std::optional<staa::Vec2> pose = pointAt(status, "pose");
    const std::optional<staa::Vec2> goal = own_goal ? target.goal : pointAt(status, "goal");
    to_go.clear();
    if (pose && goal) {
      char buf[48];
      std::snprintf(buf, sizeof buf, ", %.2f m to the goal", (*pose - *goal).norm());
      to_go = buf;
    }

    if (own_goal) {
      if (id > target.goal_id) {
        std::cerr << "staactl: goal: goal " << target.goal_id << " was replaced by goal " << id
                  << " (sent by another client) before it was " << target.state << "\n";
        return kExitFailed;
      }
      if (id == target.goal_id) {
        if (state == target.state) {
          std::cout << state << "\n";
          return kExitOk;
        }
        if (state == "unreachable") {
          std::cerr << "staactl: goal: goal " << target.goal_id << " is unreachable" << reasonOf(status)
                    << " (state unreachable at (" << numAt(status, "pose", 0, 2) << ", " << numAt(status, "pose", 1, 2)
                    << "))\n";
          return kExitFailed;
        }
        // A stop request (or staad stopping) dropped the goal: it will not be reached.
        if (state == "stopped") {
          std::cerr << "staactl: goal: goal " << target.goal_id << " was dropped: staad stopped the robot\n";
          return kExitFailed;
        }
      }
      // id < goal_id: the control thread has not taken this goal yet (one control period).
    } else {
      // Waiting for reached, a status about a goal older than the current one is not it.
      const bool current = target.state != "reached" || id >= *min_id;
      if (state == target.state && current) {
        std::cout << state << "\n";
        return kExitOk;
      }
      // Unreachable is final for this goal: waiting longer cannot bring the robot there.
      if (state == "unreachable" && current) {
        std::cerr << "staactl: wait: the goal is unreachable" << reasonOf(status) << " (waiting for " << target.state
                  << ")\n";
        return kExitFailed;
      }
    }
    const auto now = SteadyClock::now();
    if (now >= deadline) break;
    if (now >= next_progress) {
      const double elapsed = std::chrono::duration<double>(now - start).count();
      std::cerr << "staactl: waiting for " << what << ": " << shown << " at (" << numAt(status, "pose", 0, 2) << ", "
                << numAt(status, "pose", 1, 2) << ")" << to_go << ", fault " << text(status, "fault", "none") << ", "
                << static_cast<long>(elapsed) << " s\n";
      next_progress += kWaitProgress;
    }
    std::this_thread::sleep_until(std::min(now + kWaitPoll, deadline));
  }
  std::cerr << "staactl: " << who << ": timed out after " << seconds(timeout_s) << " s waiting for " << what
            << " (state " << shown << (own_goal ? to_go : std::string()) << ")\n";
  return kExitTimeout;
}

double timeoutSeconds(const std::string& command, const std::string& text) {
  const auto timeout = staa::cli::parseDouble(text);
  if (!timeout || *timeout <= 0.0) {
    throw InputError(command + ": --timeout: expected seconds (a finite number > 0), got " + inQuotes(text));
  }
  return *timeout;
}

int run(int argc, char** argv) {
  CLI::App app{"staactl: send goals and queries to staad's control socket"};
  app.require_subcommand(1);
  app.fallthrough();  // --socket may also follow the subcommand
  std::string socket_option;
  app.add_option("--socket", socket_option, "staad's control socket (default: $STAAD_SOCKET, else /run/staad/staad.sock)");

  std::string x, y, theta;
  auto poseCommand = [&](const char* name, const char* what) {
    CLI::App* sub = app.add_subcommand(name, what);
    sub->add_option("X", x, "x, metres")->required();
    sub->add_option("Y", y, "y, metres")->required();
    sub->add_option("TH", theta, "heading, radians (default 0)");
    return sub;
  };
  CLI::App* goal = poseCommand("goal", "drive to the pose X Y [TH]; prints the goal's id");
  bool goal_wait = false;
  std::string goal_timeout_text = "120";
  goal->add_flag("--wait", goal_wait,
                 "then wait until this goal is reached (exit 0), unreachable (1) or the timeout (3)");
  goal->add_option("--timeout", goal_timeout_text, "with --wait: seconds (default 120)");
  CLI::App* pose = poseCommand("pose", "set (correct) the robot's pose estimate to X Y [TH]");
  CLI::App* stop = app.add_subcommand("stop", "brake and drop the goal");
  CLI::App* status = app.add_subcommand("status", "print the daemon's state, pose, timing and faults");
  bool json = false;
  status->add_flag("--json", json, "print the status object as JSON");
  CLI::App* histograms =
      app.add_subcommand("histograms", "print each periodic thread's wake-up and execution histograms (1 us bins)");
  bool histograms_json = false;
  histograms->add_flag("--json", histograms_json, "print the histograms object as JSON (sparse bins [[us, count], ...])");
  CLI::App* wait = app.add_subcommand("wait", "wait until the goal is reached (exit 0), unreachable (1) or the timeout (3)");
  std::string timeout_text = "120";
  std::string wanted = "reached";
  wait->add_option("--timeout", timeout_text, "seconds (default 120)");
  wait->add_option("--state", wanted, "the state to wait for (default reached)");
  CLI::App* record = app.add_subcommand("record", "the flight recorder: record save FILE writes its last recorder.seconds");
  std::string record_action, record_file;
  record->add_option("ACTION", record_action, "save")->required();
  record->add_option("FILE", record_file, "the MCAP file to write (staa-replay reads it)")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string where;
    for (const CLI::App* sub : app.get_subcommands()) where += sub->get_name() + ": ";
    if (where.empty()) {
      // CLI11 only says "A subcommand is required" for a misspelt command: name it.
      for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg == "--socket") {
          ++i;
        } else if (!arg.empty() && arg.front() != '-') {
          std::cerr << "staactl: unknown command " << inQuotes(arg) << " (expected goal, pose, stop, status, histograms, wait or record; try --help)\n";
          return kExitBadInput;
        }
      }
    }
    std::cerr << "staactl: " << where << e.what() << " (try --help)\n";
    return kExitBadInput;
  }

  // Every argument is checked before the socket is touched.
  const std::string socket_path = socketPath(socket_option);
  staa::staad::Request request;
  if (goal->parsed()) {
    request.kind = staa::staad::RequestKind::kGoal;
    request.pose = poseArgs("goal", x, y, theta);
    std::optional<double> timeout;
    if (goal_wait) {
      timeout = timeoutSeconds("goal", goal_timeout_text);
    } else if (goal->count("--timeout") > 0) {
      throw InputError("goal: --timeout: only with --wait, got --timeout " + goal_timeout_text + " without it");
    }
    const Json reply = ask(socket_path, request);
    const std::optional<std::uint64_t> id = idOf(reply, "goal_id");
    if (!id) {
      std::cout << "ok" << std::endl;
      if (goal_wait) {
        throw Failure("staad at " + socket_path + " did not give the goal an id (an older staad?): cannot wait for it");
      }
      return kExitOk;
    }
    std::cout << "ok (goal " << *id << ")" << std::endl;
    if (!goal_wait) return kExitOk;
    WaitTarget target;
    target.goal_id = *id;
    target.goal = staa::Vec2{request.pose.x, request.pose.y};
    return waitFor(socket_path, target, *timeout);
  }
  if (pose->parsed()) {
    request.kind = staa::staad::RequestKind::kPose;
    request.pose = poseArgs("pose", x, y, theta);
  } else if (stop->parsed()) {
    request.kind = staa::staad::RequestKind::kStop;
  } else if (status->parsed()) {
    const Json s = fetchStatus(socket_path);
    if (json) {
      std::cout << s.dump(2, ' ', false, Json::error_handler_t::replace) << std::endl;
    } else {
      printSummary(s);
    }
    return kExitOk;
  } else if (histograms->parsed()) {
    const Json h = fetchHistograms(socket_path);
    if (histograms_json) {
      std::cout << h.dump(-1, ' ', false, Json::error_handler_t::replace) << std::endl;
    } else {
      printHistograms(h);
    }
    return kExitOk;
  } else if (record->parsed()) {
    if (record_action != "save") throw InputError("record: expected save FILE, got " + inQuotes(record_action));
    std::error_code ec;
    const std::string file = std::filesystem::absolute(record_file, ec).lexically_normal().string();
    if (ec || file.size() > staa::staad::kMaxRecordFile) {
      throw InputError("record save: " + inQuotes(record_file) + " is not a usable path (at most " +
                       std::to_string(staa::staad::kMaxRecordFile) + " bytes)");
    }
    request.kind = staa::staad::RequestKind::kRecord;
    std::copy(file.begin(), file.end(), request.file.begin());
    const Json reply = ask(socket_path, request);
    std::cout << "saving to " << reply.value("file", file) << std::endl;
    return kExitOk;
  } else if (wait->parsed()) {
    const double timeout = timeoutSeconds("wait", timeout_text);
    if (std::find(std::begin(kStates), std::end(kStates), wanted) == std::end(kStates)) {
      throw InputError("wait: --state: expected idle, driving, reached, unreachable, stopped or fault, got " + inQuotes(wanted));
    }
    WaitTarget target;
    target.state = wanted;
    return waitFor(socket_path, target, timeout);
  }
  ask(socket_path, request);
  std::cout << "ok\n";
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const InputError& e) {
    std::cerr << "staactl: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const Failure& e) {
    std::cerr << "staactl: " << e.what() << "\n";
    return kExitFailed;
  } catch (const std::exception& e) {  // never a crash: anything else is a failure with its reason
    std::cerr << "staactl: " << e.what() << "\n";
    return kExitFailed;
  }
}
