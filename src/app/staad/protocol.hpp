#pragma once
// The control socket's protocol: line-delimited JSON over a Unix stream socket, one request
// object per line, one reply object per line.
//
//   {"cmd": "goal", "x": 3.0, "y": 4.5, "theta": 1.57}  -> {"ok": true, "goal_id": 1}
//   {"cmd": "pose", "x": 1.0, "y": 1.0, "theta": 0.0}   -> {"ok": true}   (set / correct the pose)
//   {"cmd": "stop"}                                     -> {"ok": true}   (brake, drop the goal)
//   {"cmd": "status"}                                   -> {"ok": true, "status": {...}}
//   {"cmd": "histograms"}                               -> {"ok": true, "histograms": {...}}
//   {"cmd": "record", "save": "/abs/f.mcap"}            -> {"ok": true, "file": "/abs/f.mcap"}
//                                                          (the flight recorder's last
//                                                          recorder.seconds into that file)
//                                                          (each periodic thread's wake-up and
//                                                          execution histograms, sparse bins)
//   {"debug": "overrun", "ms": 80}                      -> {"ok": true}   (tests: the next control
//   {"debug": "stall_obstacles", "on": true}            -> {"ok": true}    cycle busy-waits / obstacle
//                                                                          frames stop; only with
//                                                                          debug.faults: true)
//   anything else                                       -> {"ok": false, "error": "..."}
//
// Each accepted goal gets an id (1, 2, ... in the order the daemon queued them); the status
// says which goal the robot pursues ("goal_id") and which one was queued last
// ("queued_goal_id"), so that a client waits for its own goal, never an earlier one.
// "theta" is optional (0). Lines longer than kMaxRequestBytes are rejected with an error
// (and the rest of that line discarded). Service thread only (allocates freely).

#include "app/staad/status.hpp"

#include "rt/activity.hpp"

#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <variant>

namespace staa::staad {

constexpr std::size_t kMaxRequestBytes = 4096;
// Objects and arrays nested in one request (a request is one flat object): deeper is refused
// before the JSON parser sees it.
constexpr std::size_t kMaxRequestDepth = 8;

// A request, or the reason it is not one (names the field and the value).
std::variant<Request, std::string> parseRequest(std::string_view line);

std::string requestLine(const Request& request);  // the line staactl sends (with '\n')

// The `status --json` object (docs/ARCHITECTURE.md section 6): state, pose [x, y, theta],
// velocity [v, w], goal ([x, y, theta] or null), fault (null or a reason), cycle {p50_us,
// p99_us, max_us, overruns, count}, rt_allocations, plus goal_id and queued_goal_id, wake-up
// latency, staleness and the planner's last call.
nlohmann::json statusJson(const Status& status, std::uint64_t rt_allocations);

// A periodic thread whose histograms a histograms request reports (null or not started:
// left out).
struct ThreadHistograms {
  const char* name;  // "control", "base", "perception"
  const rt::PeriodicActivity* activity;
};

// The `histograms` object (docs/ARCHITECTURE.md section 6): per thread, period_us, cycles,
// wake_us and exec_us {bins: [[us, count], ...] (non-empty 1 us bins), count, overflow,
// bound_us, max_us}, overruns {total, ours, late_wakeup, preempted, stall},
// own_execution_max_us, blocked_cycles, realtime. The bins are read from the threads' histograms (relaxed
// atomics: a few samples behind at most, never torn); the threads never wait for it.
nlohmann::json histogramsJson(std::span<const ThreadHistograms> threads);
// One histogram: {bins: [[us, count], ...] (bin us holds [us, us + 1) us), count, overflow
// (samples at or beyond bound_us), bound_us, max_us (exact)}.
nlohmann::json histogramJson(const rt::LatencyHistogram& histogram);
std::string histogramsReply(std::span<const ThreadHistograms> threads);

std::string okReply();                             // {"ok":true}\n
std::string goalReply(std::uint64_t goal_id);      // {"ok":true,"goal_id":N}\n
std::string errorReply(std::string_view message);  // {"ok":false,"error":...}\n
std::string statusReply(const Status& status, std::uint64_t rt_allocations);
// With the flight recorder's object (status.recorder).
std::string statusReply(const Status& status, std::uint64_t rt_allocations, const nlohmann::json& recorder);
std::string recordReply(const std::string& file);  // {"ok":true,"file":FILE}\n
}  // namespace staa::staad
