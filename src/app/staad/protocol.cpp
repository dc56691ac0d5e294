#include "app/staad/protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <optional>

namespace staa::staad {
namespace {

using Json = nlohmann::json;
// Requests and replies keep "cmd" / "ok" first, so a person reading the socket with socat
// sees what a line is before the rest of it.
using OrderedJson = nlohmann::ordered_json;

constexpr std::size_t kMaxShownChars = 40;

// Dumps never throw: a string from the wire may hold invalid UTF-8, which would otherwise
// make dump() throw (type_error 316) while we are only trying to report it.
template <class J>
std::string dumpSafe(const J& j) {
  return j.dump(-1, ' ', false, J::error_handler_t::replace);
}

// Bytes a person can read on one line: control and non-ASCII bytes become \xNN (garbage on
// the socket must not garble the log or the reply).
std::string printable(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", static_cast<unsigned>(u));
      out += buf;
    }
  }
  return out;
}

std::string shortened(std::string text) {
  if (text.size() > kMaxShownChars) {
    text.resize(kMaxShownChars - 3);
    text += "...";
  }
  return text;
}

// A short, single-line description of a JSON value for "got X" in messages.
std::string describe(const Json& v) {
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (std::isnan(d)) return "nan";
    if (std::isinf(d)) return d > 0 ? "inf (a number too large for a double)" : "-inf (a number too large for a double)";
  }
  if (v.is_array()) return "an array of " + std::to_string(v.size()) + " items";
  if (v.is_object()) return "an object";
  return shortened(printable(dumpSafe(v)));
}

const char* kindName(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "a boolean";
    default: return "a number";
  }
}

constexpr const char* kCommands = "goal, pose, stop, status, histograms or record";

// A second, reporting-only pass over a line that nlohmann refused with out_of_range (a
// number beyond a double, such as 1e999): the DOM parser does not say which key held it.
class OverflowLocator final : public nlohmann::json_sax<Json> {
 public:
  std::string top_key;  // the top-level key being read when parsing stopped ("" when none)
  std::string token;    // the text that failed

  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return ++depth_ > 0; }
  bool key(string_t& k) override {
    if (depth_ == 1) top_key = k;
    return true;
  }
  bool end_object() override { return --depth_ >= 0; }
  bool start_array(std::size_t) override { return ++depth_ > 0; }
  bool end_array() override { return --depth_ >= 0; }
  bool parse_error(std::size_t, const std::string& last_token, const nlohmann::detail::exception&) override {
    token = last_token;
    if (depth_ != 1) top_key.clear();  // nested: the top-level key is not the number's own
    return false;
  }

 private:
  int depth_ = 0;
};

std::optional<RequestKind> commandKind(const std::string& cmd) {
  for (const RequestKind k :
       {RequestKind::kGoal, RequestKind::kPose, RequestKind::kStop, RequestKind::kStatus, RequestKind::kHistograms,
        RequestKind::kRecord}) {
    if (cmd == toString(k)) return k;
  }
  return std::nullopt;
}

// One coordinate of a goal or pose: a finite JSON number (booleans are not numbers here,
// though nlohmann would convert them).
std::variant<double, std::string> coordinate(const Json& object, const char* key, std::string_view cmd,
                                             std::optional<double> fallback) {
  const auto it = object.find(key);
  if (it == object.end()) {
    if (fallback) return *fallback;
    return std::string("\"") + key + "\": missing (" + std::string(cmd) + " needs x and y in metres, theta optional)";
  }
  if (!it->is_number()) {
    return std::string("\"") + key + "\": expected a number, got " + describe(*it);
  }
  const double v = it->get<double>();
  if (!std::isfinite(v)) return std::string("\"") + key + "\": must be a finite number, got " + describe(*it);
  return v;
}

std::string joined(std::initializer_list<const char*> keys) {
  std::string out;
  for (const char* k : keys) {
    if (!out.empty()) out += ", ";
    out += k;
  }
  return out;
}

// {"debug": "overrun", "ms": 80} or {"debug": "stall_obstacles", "on": true}.
std::variant<Request, std::string> parseDebug(const Json& j) {
  const Json& kind = j.at("debug");
  constexpr const char* kKinds = "overrun or stall_obstacles";
  if (!kind.is_string()) return std::string("\"debug\": expected a string (") + kKinds + "), got " + describe(kind);
  const std::string name = kind.get<std::string>();
  Request request;
  request.kind = RequestKind::kDebug;
  const char* param = nullptr;
  if (name == toString(DebugKind::kOverrun)) {
    request.debug = DebugKind::kOverrun;
    param = "ms";
  } else if (name == toString(DebugKind::kStallObstacles)) {
    request.debug = DebugKind::kStallObstacles;
    param = "on";
  } else {
    return "\"debug\": unknown fault injection " + describe(kind) + " (expected " + kKinds + ")";
  }
  for (const auto& item : j.items()) {
    if (item.key() != "debug" && item.key() != param) {
      return "unknown key " + describe(Json(item.key())) + " for debug " + name + " (expected debug, " + param + ")";
    }
  }
  const auto it = j.find(param);
  if (request.debug == DebugKind::kOverrun) {
    const std::string range = "an integer number of milliseconds in 1.." + std::to_string(kMaxDebugOverrunMs);
    if (it == j.end()) return "\"ms\": missing (debug overrun needs " + range + ")";
    const bool integral = it->is_number() && std::isfinite(it->get<double>()) && std::floor(it->get<double>()) == it->get<double>();
    if (!integral || it->get<double>() < 1.0 || it->get<double>() > kMaxDebugOverrunMs) {
      return "\"ms\": expected " + range + ", got " + describe(*it);
    }
    request.debug_ms = static_cast<std::uint32_t>(it->get<double>());
  } else {
    if (it == j.end()) return std::string("\"on\": missing (debug stall_obstacles needs on: true or false)");
    if (!it->is_boolean()) return "\"on\": expected true or false, got " + describe(*it);
    request.debug_on = it->get<bool>();
  }
  return request;
}

// The deepest nesting of objects and arrays in `line`, brackets in strings not counted; stops
// counting past `limit`.
std::size_t nestingDepth(std::string_view line, std::size_t limit) {
  std::size_t depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (const char c : line) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      deepest = std::max(deepest, ++depth);
      if (deepest > limit) break;
    } else if ((c == '}' || c == ']') && depth > 0) {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

std::variant<Request, std::string> parseRequest(std::string_view line) {
  // A line as read from the socket may still end in "\n" or "\r\n" (socat, telnet).
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() > kMaxRequestBytes) {
    return "request too long: " + std::to_string(line.size()) + " bytes (at most " + std::to_string(kMaxRequestBytes) + ")";
  }
  if (line.find_first_not_of(" \t") == std::string_view::npos) {
    return std::string(R"(empty request (expected one JSON object per line, e.g. {"cmd": "status"}))");
  }
  if (nestingDepth(line, kMaxRequestDepth) > kMaxRequestDepth) {
    return "nested too deep: at most " + std::to_string(kMaxRequestDepth) + " levels of objects and arrays";
  }
  Json j;
  try {
    j = Json::parse(line.begin(), line.end());
  } catch (const Json::out_of_range&) {
    OverflowLocator where;
    Json::sax_parse(line.begin(), line.end(), &where);
    const std::string got = shortened(printable(where.token));
    if (!where.top_key.empty()) {
      return "\"" + printable(where.top_key) + "\": must be a finite number, got " + got + " (out of range for a double)";
    }
    return "number out of range for a double: " + got;
  } catch (const Json::exception& e) {
    // what() is "[json.exception.parse_error.101] parse error at ...": keep the useful part.
    std::string_view what = e.what();
    if (const auto at = what.find("] "); at != std::string_view::npos) what.remove_prefix(at + 2);
    return "not valid JSON: " + printable(what);
  }
  if (!j.is_object()) return std::string("expected a JSON object such as {\"cmd\": \"status\"}, got ") + kindName(j);
  if (j.contains("debug")) {
    if (j.contains("cmd")) return std::string("a request has \"cmd\" or \"debug\", not both");
    return parseDebug(j);
  }

  const auto cmd_it = j.find("cmd");
  if (cmd_it == j.end()) return std::string("\"cmd\": missing (expected ") + kCommands + ")";
  if (!cmd_it->is_string()) return "\"cmd\": expected a string (" + std::string(kCommands) + "), got " + describe(*cmd_it);
  const std::string cmd = cmd_it->get<std::string>();
  const auto kind = commandKind(cmd);
  if (!kind) return "\"cmd\": unknown command " + describe(*cmd_it) + " (expected " + kCommands + ")";

  const bool has_pose = *kind == RequestKind::kGoal || *kind == RequestKind::kPose;
  const bool record = *kind == RequestKind::kRecord;
  // Unknown keys are errors: a typo ("thta") must not silently become theta = 0.
  for (const auto& item : j.items()) {
    const std::string& key = item.key();
    const bool known = key == "cmd" || (has_pose && (key == "x" || key == "y" || key == "theta")) || (record && key == "save");
    if (!known) {
      return "unknown key " + describe(Json(key)) + " for " + cmd + " (expected " +
             (has_pose ? joined({"cmd", "x", "y", "theta"}) : record ? joined({"cmd", "save"}) : std::string("cmd only")) + ")";
    }
  }
  if (record) {
    // {"cmd": "record", "save": "/abs/file.mcap"}: the recorder's history into that file.
    const auto it = j.find("save");
    if (it == j.end()) return std::string("\"save\": missing (record needs the absolute path of the file to save to)");
    if (!it->is_string()) return "\"save\": expected a file path, got " + describe(*it);
    const std::string file = it->get<std::string>();
    if (file.empty() || file.front() != '/') return "\"save\": expected an absolute path, got " + describe(*it);
    if (file.size() > kMaxRecordFile || file.find('\0') != std::string::npos) {
      return "\"save\": a path of at most " + std::to_string(kMaxRecordFile) + " bytes without NUL, got " + describe(*it);
    }
    Request request;
    request.kind = RequestKind::kRecord;
    std::copy(file.begin(), file.end(), request.file.begin());
    return request;
  }

  Request request;
  request.kind = *kind;
  if (has_pose) {
    const auto x = coordinate(j, "x", cmd, std::nullopt);
    if (const auto* err = std::get_if<std::string>(&x)) return *err;
    const auto y = coordinate(j, "y", cmd, std::nullopt);
    if (const auto* err = std::get_if<std::string>(&y)) return *err;
    const auto theta = coordinate(j, "theta", cmd, 0.0);
    if (const auto* err = std::get_if<std::string>(&theta)) return *err;
    request.pose = Pose2{std::get<double>(x), std::get<double>(y), std::get<double>(theta)};
  }
  return request;
}

std::string requestLine(const Request& request) {
  OrderedJson j;
  if (request.kind == RequestKind::kDebug) {
    j["debug"] = toString(request.debug);
    if (request.debug == DebugKind::kOverrun) j["ms"] = request.debug_ms;
    if (request.debug == DebugKind::kStallObstacles) j["on"] = request.debug_on;
    return dumpSafe(j) + "\n";
  }
  j["cmd"] = toString(request.kind);
  if (request.kind == RequestKind::kRecord) j["save"] = std::string(request.file.data());
  if (request.kind == RequestKind::kGoal || request.kind == RequestKind::kPose) {
    // nlohmann writes the shortest text that reads back to the same double: exact round trip.
    j["x"] = request.pose.x;
    j["y"] = request.pose.y;
    j["theta"] = request.pose.theta;
  }
  return dumpSafe(j) + "\n";
}

namespace {

// Each struct of the status in one place: the contract's keys (docs/ARCHITECTURE.md section 6).

// p50 / p99 / max of a histogram, microseconds.
Json timingJson(const rt::TimingSummary& t) { return {{"p50_us", t.p50_us}, {"p99_us", t.p99_us}, {"max_us", t.max_us}}; }

// A periodic thread's numbers, into `j`: cycle {p50_us, p99_us, max_us, overruns, count},
// wake {p50_us, p99_us, max_us}, the overruns by cause, skipped periods and realtime. The
// control thread's are at the status's top level (the contract's `cycle`), the base
// thread's under threads.base. `count`: the cycles run.
void addThreadJson(Json& j, const rt::ActivityTiming& t, std::uint64_t count) {
  j["cycle"] = timingJson(t.execution);
  j["cycle"]["overruns"] = t.counters.overruns;
  j["cycle"]["count"] = count;
  j["wake"] = timingJson(t.wake);
  j["execution_overruns"] = t.counters.execution_overruns;
  j["late_wakeups"] = t.counters.late_wakeups;
  j["preempted"] = t.counters.preempted;
  j["stalls"] = t.counters.stalls;
  j["blocked_cycles"] = t.counters.blocked_cycles;
  j["faulted_cycles"] = t.counters.faulted_cycles;
  j["last_blocked_cycle"] = t.counters.last_blocked_cycle;
  j["blocked_faulted_cycles"] = t.counters.blocked_faulted_cycles;
  // The longest cycle less its measured stall: the cycle's own work at its longest.
  j["own_execution_max_us"] = static_cast<double>(t.counters.max_own_execution) * 1e-3;
  j["skipped_periods"] = t.counters.skipped_periods;
  j["realtime"] = t.realtime;
}

// The base driver's view: its fault (as in "fault", also while another fault is reported)
// and the frames it refused on the bus.
Json baseJson(const hal::BaseStatus& b) {
  return {{"fault", b.fault == hal::BaseFault::kNone ? Json(nullptr) : Json(hal::toString(b.fault))},
          {"fault_code", b.fault_code},
          {"enabled", b.enabled},
          {"bad_frames", b.bad_frames},
          {"rx_overflows", b.rx_overflows},
          {"error_frames", b.error_frames},
          {"localization", {{"fixes", b.localization_fixes},
                            {"dropped", b.localization_dropped},
                            {"last_jump_m", b.last_jump_m},
                            {"last_jump_rad", b.last_jump_rad}}}};
}

// scanner.backend ros's LaserScans: received, dropped, and dropped by the first check failed.
Json scansJson(const RosLinkStatus& r) {
  Json by = Json::object();
  for (std::size_t i = 0; i < hal::kRosScanDropReasons; ++i) {
    by[hal::toString(static_cast<hal::RosScanDrop>(i))] = r.scans_dropped_by[i];
  }
  return {{"in", r.scans_in}, {"dropped", r.scans_dropped}, {"dropped_by", std::move(by)}};
}

Json rosJson(const RosLinkStatus& r) {
  if (!r.enabled) return nullptr;
  Json latency = timingJson(r.odometry_to_twist);
  latency["count"] = r.odometry_to_twist.count;
  return {{"master", r.master},
          {"odometry_to_twist", latency},
          {"odometry_in", r.odometry_in},
          {"localization_in", r.localization_in},
          {"twists_out", r.twists_out},
          {"goals_in", r.goals_in},
          {"goals_refused", r.goals_refused},
          {"maps", {{"in", r.maps_in}, {"applied", r.maps_applied}, {"refused", r.maps_refused},
                    {"import_s", r.map_import_s}}},
          {"images", {{"in", r.images_in}, {"dropped", r.images_dropped}}},
          {"scans", scansJson(r)}};
}

// obstacles: depth's laser scanner; null without one.
Json scannerJson(const ScannerStatus& s) {
  if (!s.enabled) return nullptr;
  return {{"backend", s.backend},
          {"scans_used", s.scans_used},
          {"scans_too_old", s.scans_too_old},
          {"frames_without_scan", s.frames_without_scan},
          {"scan_points", s.scan_points}};
}

Json commandToWireJson(const CommandToWire& w) {
  Json j = timingJson(w.latency);
  j["count"] = w.latency.count;
  j["unsent"] = w.unsent;
  return j;
}

Json faultJson(const Status& status) {
  switch (status.fault) {
    case FaultKind::kNone: return nullptr;
    case FaultKind::kStaleOdometry:
    case FaultKind::kStaleObstacles: return toString(status.fault);
    case FaultKind::kBase: {
      std::string reason = "base: ";
      reason += hal::toString(status.base.fault);
      // The base's own code is what a technician looks up in its manual.
      if (status.base.fault_code != 0) reason += " (code " + std::to_string(status.base.fault_code) + ")";
      return reason;
    }
  }
  return "unknown";
}

}  // namespace

nlohmann::json statusJson(const Status& status, std::uint64_t rt_allocations) {
  Json j;
  j["state"] = toString(status.state);
  j["pose"] = {status.pose.x, status.pose.y, status.pose.theta};
  j["velocity"] = {status.v, status.w};
  j["goal"] = status.has_goal ? Json{status.goal.x, status.goal.y, status.goal.theta} : Json(nullptr);
  // Which goal `state` is about: a client waiting for its goal ignores "reached" of an older one.
  j["goal_id"] = status.goal_id;
  j["queued_goal_id"] = status.queued_goal_id;
  j["fault"] = faultJson(status);
  j["reason"] = status.reason != nullptr ? Json(status.reason) : Json(nullptr);
  // cycle (the contract's), and beyond it what an engineer looks at when the contract's
  // numbers look wrong: wake, the overruns by cause, realtime.
  addThreadJson(j, status.control_thread, status.cycles);
  j["rt_allocations"] = rt_allocations;
  j["base"] = baseJson(status.base);
  // The base I/O path's timing: `threads.base` in the shape of the control thread's numbers,
  // and how long a command took from the planner to the wire.
  addThreadJson(j["threads"]["base"], status.base_thread, status.base_thread.counters.cycles);
  j["base"]["command_to_wire"] = commandToWireJson(status.command_to_wire);
  j["command"] = {status.v_cmd, status.w_cmd};
  // Never seen is null, not -1: a script comparing ages against a limit must not read -1 as fresh.
  auto age = [](double s) { return s < 0.0 ? Json(nullptr) : Json(s); };
  j["staleness"] = {{"odometry_s", age(status.odometry_age_s)}, {"obstacles_s", age(status.obstacles_age_s)}};
  // budget_ms null: an expansion budget. path_max_us / local_max_us: the longest path and
  // local-map steps so far (a cycle's work ends by the budget plus those).
  j["planner"] = {{"expansions", status.expansions},
                  {"depth", status.depth},
                  {"budget_ms", status.budget_ms > 0.0 ? Json(status.budget_ms) : Json(nullptr)},
                  {"path_max_us", static_cast<double>(status.path_max_ns) * 1e-3},
                  {"local_max_us", static_cast<double>(status.local_max_ns) * 1e-3}};
  // cap_mps null: no blind corner ahead (or the limit is off).
  j["blind_corners"] = {{"enabled", status.blind_corners},
                        {"cap_mps", std::isfinite(status.speed_cap) ? Json(status.speed_cap) : Json(nullptr)},
                        {"capped_cycles", status.capped_cycles}};
  j["time_s"] = status.time_s;
  j["ros"] = rosJson(status.ros);
  j["scanner"] = scannerJson(status.scanner);
  return j;
}

nlohmann::json histogramJson(const rt::LatencyHistogram& h) {
  Json bins = Json::array();
  h.forEachBin([&bins](std::uint32_t us, std::uint64_t count) { bins.push_back({us, count}); });
  const rt::TimingSummary s = h.summary();
  return {{"bins", std::move(bins)}, {"count", s.count}, {"overflow", s.overflow}, {"bound_us", h.boundUs()},
          {"max_us", s.max_us}};
}

nlohmann::json histogramsJson(std::span<const ThreadHistograms> threads) {
  Json j = Json::object();
  for (const ThreadHistograms& t : threads) {
    if (t.activity == nullptr || !t.activity->started()) continue;
    const rt::PeriodicCounters c = t.activity->counters();
    j[t.name] = {{"period_us", static_cast<double>(t.activity->period()) * 1e-3},
                 {"cycles", c.cycles},
                 {"wake_us", histogramJson(t.activity->wakeLatency())},
                 {"exec_us", histogramJson(t.activity->execution())},
                 {"overruns", {{"total", c.overruns},
                               {"ours", c.execution_overruns},
                               {"late_wakeup", c.late_wakeups},
                               {"preempted", c.preempted},
                               {"stall", c.stalls}}},
                 {"own_execution_max_us", static_cast<double>(c.max_own_execution) * 1e-3},
                 {"blocked_cycles", c.blocked_cycles},
                 {"faulted_cycles", c.faulted_cycles},
                 {"blocked_faulted_cycles", c.blocked_faulted_cycles},
                 {"realtime", t.activity->realtime()}};
  }
  return j;
}

std::string histogramsReply(std::span<const ThreadHistograms> threads) {
  Json j;
  j["ok"] = true;
  j["histograms"] = histogramsJson(threads);
  return dumpSafe(j) + "\n";
}

std::string okReply() { return "{\"ok\":true}\n"; }

std::string goalReply(std::uint64_t goal_id) {
  OrderedJson j;
  j["ok"] = true;
  j["goal_id"] = goal_id;
  return dumpSafe(j) + "\n";
}

std::string errorReply(std::string_view message) {
  OrderedJson j;
  j["ok"] = false;
  j["error"] = std::string(message);
  return dumpSafe(j) + "\n";
}

std::string statusReply(const Status& status, std::uint64_t rt_allocations) {
  Json j;  // keys sorted: "ok" comes before "status" anyway
  j["ok"] = true;
  j["status"] = statusJson(status, rt_allocations);
  return dumpSafe(j) + "\n";
}

std::string statusReply(const Status& status, std::uint64_t rt_allocations, const nlohmann::json& recorder) {
  Json j;
  j["ok"] = true;
  j["status"] = statusJson(status, rt_allocations);
  j["status"]["recorder"] = recorder;
  return dumpSafe(j) + "\n";
}

std::string recordReply(const std::string& file) {
  OrderedJson j;
  j["ok"] = true;
  j["file"] = file;
  return dumpSafe(j) + "\n";
}

}  // namespace staa::staad
