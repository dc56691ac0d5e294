#include "app/staad/protocol.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace staa::staad {
namespace {

using ::testing::HasSubstr;
using Json = nlohmann::json;

Request parsedOk(std::string_view line) {
  auto r = parseRequest(line);
  if (const auto* err = std::get_if<std::string>(&r)) {
    ADD_FAILURE() << "rejected " << line << ": " << *err;
    return {};
  }
  return std::get<Request>(r);
}

std::string parsedError(std::string_view line) {
  auto r = parseRequest(line);
  if (const auto* err = std::get_if<std::string>(&r)) return *err;
  ADD_FAILURE() << "accepted " << line;
  return "";
}

TEST(Protocol, EveryRequestKindRoundTripsBitForBit) {
  const std::vector<Pose2> poses = {{3.0, 4.5, 1.57},
                                    {0.1, -0.2, 0.3},
                                    {-1e-300, 1e300, -3.141592653589793},
                                    {12.000000000000002, 4.9406564584124654e-324, 0.0}};
  for (const RequestKind kind : {RequestKind::kGoal, RequestKind::kPose}) {
    for (const Pose2& p : poses) {
      const std::string line = requestLine(Request{kind, p});
      ASSERT_FALSE(line.empty());
      EXPECT_EQ(line.back(), '\n');
      EXPECT_EQ(line.find('\n'), line.size() - 1) << "one line: " << line;
      EXPECT_LE(line.size(), kMaxRequestBytes);
      const Request back = parsedOk(line);
      EXPECT_EQ(back.kind, kind) << line;
      // Exact: the text is the shortest that reads back to the same double.
      EXPECT_EQ(std::memcmp(&back.pose.x, &p.x, sizeof(double)), 0) << line;
      EXPECT_EQ(std::memcmp(&back.pose.y, &p.y, sizeof(double)), 0) << line;
      EXPECT_EQ(std::memcmp(&back.pose.theta, &p.theta, sizeof(double)), 0) << line;
    }
  }
  for (const RequestKind kind : {RequestKind::kStop, RequestKind::kStatus}) {
    const std::string line = requestLine(Request{kind, {}});
    EXPECT_EQ(line, std::string("{\"cmd\":\"") + toString(kind) + "\"}\n");
    EXPECT_EQ(parsedOk(line).kind, kind);
  }
}

TEST(Protocol, AcceptsWhatPeopleTypeBySocat) {
  const Request goal = parsedOk(R"({"cmd": "goal", "x": 3, "y": -4.5})");
  EXPECT_EQ(goal.kind, RequestKind::kGoal);
  EXPECT_DOUBLE_EQ(goal.pose.x, 3.0);  // integers are numbers too
  EXPECT_DOUBLE_EQ(goal.pose.y, -4.5);
  EXPECT_DOUBLE_EQ(goal.pose.theta, 0.0);  // theta is optional
  EXPECT_EQ(parsedOk("{\"cmd\":\"status\"}\r\n").kind, RequestKind::kStatus);  // telnet's line end
  EXPECT_EQ(parsedOk("  { \"cmd\" : \"stop\" }  ").kind, RequestKind::kStop);
  const Request pose = parsedOk(R"({"theta": -1.5e0, "y": 2, "x": 1, "cmd": "pose"})");  // any key order
  EXPECT_EQ(pose.kind, RequestKind::kPose);
  EXPECT_DOUBLE_EQ(pose.pose.theta, -1.5);
}

struct Malformed {
  std::string line;
  std::vector<std::string> expected;  // substrings of the reason
};

// Binary garbage, a NUL and a terminal escape sequence included.
constexpr char kGarbage[] = "\xff\xfe\x00\x01\x80garbage\x1b[2J";

TEST(Protocol, MalformedRequestsAreRejectedWithTheFieldAndValue) {
  const std::vector<Malformed> cases = {
      {"", {"empty request"}},
      {"   \t ", {"empty request"}},
      {"{", {"not valid JSON", "column 2"}},
      {"[]", {"expected a JSON object", "an array"}},
      {"42", {"expected a JSON object", "a number"}},
      {R"("goal")", {"expected a JSON object", "a string"}},
      {R"({"cmd":5})", {"\"cmd\"", "expected a string", "got 5"}},
      {R"({"cmd":"fly"})", {"\"cmd\"", "unknown command \"fly\"", "goal, pose, stop, status, histograms or record"}},
      {R"({"x":1,"y":2})", {"\"cmd\": missing"}},
      {R"({"cmd":"goal","x":1})", {"\"y\": missing", "goal needs x and y"}},
      {R"({"cmd":"pose","y":1})", {"\"x\": missing", "pose"}},
      {R"({"cmd":"goal","x":"a","y":1})", {"\"x\"", "expected a number", "got \"a\""}},
      {R"({"cmd":"goal","x":1,"y":true})", {"\"y\"", "expected a number", "got true"}},
      {R"({"cmd":"goal","x":1,"y":2,"theta":null})", {"\"theta\"", "expected a number", "got null"}},
      {R"({"cmd":"goal","x":[1],"y":2})", {"\"x\"", "an array of 1 items"}},
      {R"({"cmd":"goal","x":1e999,"y":1})", {"\"x\"", "finite", "got 1e999"}},
      {R"({"cmd":"goal","y":1,"x":-1e999})", {"\"x\"", "finite", "got -1e999"}},
      {R"({"cmd":"goal","x":1,"y":[1e400]})", {"out of range", "1e400"}},
      {R"({"cmd":"goal","x":NaN,"y":1})", {"not valid JSON"}},
      {R"({"cmd":"goal","x":1,"y":2,"thta":1})", {"unknown key \"thta\"", "for goal", "cmd, x, y, theta"}},
      {R"({"cmd":"stop","x":1})", {"unknown key \"x\"", "for stop", "cmd only"}},
      {R"({"cmd":"status"} {"cmd":"stop"})", {"not valid JSON"}},
      {std::string(5000, ' ') + R"({"cmd":"status"})", {"request too long", "5016 bytes", "at most 4096"}},
      {std::string(kGarbage, sizeof kGarbage - 1), {"not valid JSON"}},
      {"{\"cmd\":\"\xff\xfe\"}", {"not valid JSON"}},  // invalid UTF-8 inside a string
      {"{\"cmd\":\"goal\",\"x\":1,\"y\":2,\"\xc3\xa9\":1}", {"unknown key", "\\xc3\\xa9"}},
  };
  for (const Malformed& c : cases) {
    const std::string error = parsedError(c.line);
    SCOPED_TRACE(c.line.substr(0, 60) + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    // The reason is one printable line: garbage on the socket must not garble logs or replies.
    for (const char ch : error) {
      EXPECT_TRUE(ch >= 0x20 && ch < 0x7f) << "byte " << static_cast<int>(static_cast<unsigned char>(ch));
    }
    EXPECT_LE(error.size(), 400u);
    // And it travels back as a valid error reply.
    const std::string reply = errorReply(error);
    ASSERT_EQ(reply.back(), '\n');
    const Json j = Json::parse(reply);
    EXPECT_EQ(j["ok"], false);
    EXPECT_EQ(j["error"], error);
  }
}

TEST(Protocol, ErrorReplyStaysValidJsonForAnyBytes) {
  const Json j = Json::parse(errorReply("bad \xff\"quote\"\nnewline"));
  EXPECT_EQ(j["ok"], false);
  EXPECT_THAT(j["error"].get<std::string>(), HasSubstr("\"quote\""));
  EXPECT_EQ(okReply(), "{\"ok\":true}\n");
  EXPECT_EQ(errorReply("x").find('\n'), errorReply("x").size() - 1);
}

Status filledStatus() {
  Status s;
  s.state = DaemonState::kDriving;
  s.pose = {1.5, 4.5, 0.25};
  s.v = 0.2;
  s.w = -0.1;
  s.v_cmd = 0.22;
  s.w_cmd = -0.05;
  s.has_goal = true;
  s.goal = {12.0, 4.5, 1.57};
  s.goal_id = 41;
  s.queued_goal_id = 42;
  s.cycles = 12345;
  rt::ActivityTiming& control = s.control_thread;
  control.execution.p50_us = 850.0;
  control.execution.p99_us = 4100.0;
  control.execution.max_us = 9000.5;
  control.wake.p50_us = 40.0;
  control.wake.p99_us = 120.0;
  control.wake.max_us = 600.0;
  control.counters.overruns = 2;
  control.counters.execution_overruns = 1;
  control.counters.late_wakeups = 3;
  control.counters.skipped_periods = 4;
  control.counters.cycles = 12344;  // the loop's finished cycles: `count` is the task's own
  control.realtime = true;
  s.odometry_age_s = 0.004;
  s.obstacles_age_s = -1.0;
  s.expansions = 1000;
  s.depth = 7.5;
  s.time_s = 321.5;
  return s;
}

TEST(Protocol, StatusJsonHasEveryContractKeyWithItsValue) {
  const Json j = statusJson(filledStatus(), 17);
  EXPECT_EQ(j["state"], "driving");
  EXPECT_EQ(j["pose"], Json({1.5, 4.5, 0.25}));
  EXPECT_EQ(j["velocity"], Json({0.2, -0.1}));
  EXPECT_EQ(j["goal"], Json({12.0, 4.5, 1.57}));
  ASSERT_TRUE(j.contains("fault"));
  EXPECT_TRUE(j["fault"].is_null());
  const Json& cycle = j["cycle"];
  EXPECT_EQ(cycle["p50_us"], 850.0);
  EXPECT_EQ(cycle["p99_us"], 4100.0);
  EXPECT_EQ(cycle["max_us"], 9000.5);
  EXPECT_EQ(cycle["overruns"], 2);
  EXPECT_EQ(cycle["count"], 12345);
  EXPECT_EQ(j["rt_allocations"], 17);
  EXPECT_TRUE(j["rt_allocations"].is_number_unsigned());
  // The extra keys.
  EXPECT_EQ(j["command"], Json({0.22, -0.05}));
  EXPECT_EQ(j["wake"]["p50_us"], 40.0);
  EXPECT_EQ(j["wake"]["p99_us"], 120.0);
  EXPECT_EQ(j["wake"]["max_us"], 600.0);
  EXPECT_EQ(j["execution_overruns"], 1);
  EXPECT_EQ(j["late_wakeups"], 3);
  EXPECT_EQ(j["skipped_periods"], 4);
  EXPECT_EQ(j["staleness"]["odometry_s"], 0.004);
  ASSERT_TRUE(j["staleness"].contains("obstacles_s"));
  EXPECT_TRUE(j["staleness"]["obstacles_s"].is_null());  // never seen: null, not -1
  EXPECT_EQ(j["planner"]["expansions"], 1000);
  EXPECT_EQ(j["planner"]["depth"], 7.5);
  EXPECT_EQ(j["realtime"], true);
  EXPECT_EQ(j["time_s"], 321.5);
  EXPECT_EQ(j["goal_id"], 41);
  EXPECT_EQ(j["queued_goal_id"], 42);
}

TEST(Protocol, GoalReplyCarriesTheGoalsId) {
  EXPECT_EQ(goalReply(1), "{\"ok\":true,\"goal_id\":1}\n");
  const std::string reply = goalReply(std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(reply.find('\n'), reply.size() - 1);
  const Json j = Json::parse(reply);
  EXPECT_EQ(j["ok"], true);
  ASSERT_TRUE(j["goal_id"].is_number_unsigned());
  EXPECT_EQ(j["goal_id"].get<std::uint64_t>(), std::numeric_limits<std::uint64_t>::max());  // exact, not a double
}

TEST(Protocol, StatusJsonSaysWhichGoalItsStateIsAbout) {
  Status s = filledStatus();
  s.state = DaemonState::kReached;
  s.goal_id = 7;
  s.queued_goal_id = 8;  // queued, not taken by the control thread yet
  const Json j = statusJson(s, 0);
  EXPECT_EQ(j["state"], "reached");
  ASSERT_TRUE(j["goal_id"].is_number_unsigned());
  EXPECT_EQ(j["goal_id"].get<std::uint64_t>(), 7u);
  EXPECT_EQ(j["queued_goal_id"].get<std::uint64_t>(), 8u);
  // Before any goal: 0, never null (a client compares ids as numbers).
  const Json idle = statusJson(Status{}, 0);
  EXPECT_EQ(idle["goal_id"], 0);
  EXPECT_EQ(idle["queued_goal_id"], 0);
}

TEST(Protocol, StatusJsonSaysWhyAGoalIsUnreachable) {
  Status s = filledStatus();
  s.state = DaemonState::kUnreachable;
  s.reason = "no passage wider than the footprint";
  EXPECT_EQ(statusJson(s, 0)["reason"], "no passage wider than the footprint");
  const Json driving = statusJson(Status{}, 0);
  ASSERT_TRUE(driving.contains("reason"));
  EXPECT_TRUE(driving["reason"].is_null());
}

TEST(Protocol, GoalIdsAreTheDaemonsNeverTheClients) {
  Request r{RequestKind::kGoal, {1.0, 2.0, 0.0}};
  r.goal_id = 5;
  EXPECT_EQ(requestLine(r).find("goal_id"), std::string::npos) << requestLine(r);
  EXPECT_EQ(parsedOk(requestLine(r)).goal_id, 0u);
  EXPECT_THAT(parsedError(R"({"cmd":"goal","x":1,"y":2,"goal_id":3})"), HasSubstr("unknown key \"goal_id\""));
}

TEST(Protocol, StatusJsonGoalIsNullWithoutAGoalAndEveryStateHasItsName) {
  Status s = filledStatus();
  s.has_goal = false;
  EXPECT_TRUE(statusJson(s, 0)["goal"].is_null());
  const std::vector<std::pair<DaemonState, const char*>> states = {
      {DaemonState::kIdle, "idle"},       {DaemonState::kDriving, "driving"}, {DaemonState::kReached, "reached"},
      {DaemonState::kUnreachable, "unreachable"}, {DaemonState::kStopped, "stopped"}, {DaemonState::kFault, "fault"}};
  for (const auto& [state, name] : states) {
    s.state = state;
    EXPECT_EQ(statusJson(s, 0)["state"], name);
  }
}

TEST(Protocol, StatusJsonFaultNamesTheReason) {
  Status s = filledStatus();
  s.state = DaemonState::kFault;
  s.fault = FaultKind::kStaleOdometry;
  EXPECT_EQ(statusJson(s, 0)["fault"], "stale_odometry");
  s.fault = FaultKind::kStaleObstacles;
  EXPECT_EQ(statusJson(s, 0)["fault"], "stale_obstacles");
  s.fault = FaultKind::kBase;
  s.base.fault = hal::BaseFault::kEmergencyStop;
  s.base.fault_code = 0;
  EXPECT_EQ(statusJson(s, 0)["fault"], std::string("base: ") + hal::toString(hal::BaseFault::kEmergencyStop));
  s.base.fault = hal::BaseFault::kDriverFault;
  s.base.fault_code = 0x2310;
  EXPECT_EQ(statusJson(s, 0)["fault"], std::string("base: ") + hal::toString(hal::BaseFault::kDriverFault) + " (code 8976)");
}

TEST(Protocol, StatusReplyCarriesTheStatusObject) {
  const std::string reply = statusReply(filledStatus(), 3);
  ASSERT_EQ(reply.back(), '\n');
  EXPECT_EQ(reply.find('\n'), reply.size() - 1);
  const Json j = Json::parse(reply);
  EXPECT_EQ(j["ok"], true);
  EXPECT_EQ(j["status"], statusJson(filledStatus(), 3));
}

TEST(Protocol, DebugRequestsParseAndRoundTrip) {
  const Request overrun = parsedOk(R"({"debug": "overrun", "ms": 80})");
  EXPECT_EQ(overrun.kind, RequestKind::kDebug);
  EXPECT_EQ(overrun.debug, DebugKind::kOverrun);
  EXPECT_EQ(overrun.debug_ms, 80u);
  const Request stall = parsedOk(R"({"debug": "stall_obstacles", "on": true})");
  EXPECT_EQ(stall.debug, DebugKind::kStallObstacles);
  EXPECT_TRUE(stall.debug_on);
  EXPECT_FALSE(parsedOk(R"({"debug": "stall_obstacles", "on": false})").debug_on);
  for (const Request& r : {overrun, stall}) {
    const Request back = parsedOk(requestLine(r));
    EXPECT_EQ(back.kind, RequestKind::kDebug);
    EXPECT_EQ(back.debug, r.debug);
    EXPECT_EQ(back.debug_ms, r.debug_ms);
    EXPECT_EQ(back.debug_on, r.debug_on);
  }
  EXPECT_EQ(requestLine(overrun), "{\"debug\":\"overrun\",\"ms\":80}\n");
}

TEST(Protocol, MalformedDebugRequestsAreRejectedWithTheFieldAndValue) {
  const std::vector<Malformed> cases = {
      {R"({"debug": "explode"})", {"\"debug\"", "unknown fault injection \"explode\"", "overrun or stall_obstacles"}},
      {R"({"debug": 3})", {"\"debug\"", "expected a string", "got 3"}},
      {R"({"debug": "overrun"})", {"\"ms\": missing", "1..5000"}},
      {R"({"debug": "overrun", "ms": 0})", {"\"ms\"", "1..5000", "got 0"}},
      {R"({"debug": "overrun", "ms": 5001})", {"\"ms\"", "got 5001"}},
      {R"({"debug": "overrun", "ms": 2.5})", {"\"ms\"", "integer", "got 2.5"}},
      {R"({"debug": "overrun", "ms": "80"})", {"\"ms\"", "got \"80\""}},
      {R"({"debug": "overrun", "ms": 80, "on": true})", {"unknown key \"on\"", "debug, ms"}},
      {R"({"debug": "stall_obstacles"})", {"\"on\": missing"}},
      {R"({"debug": "stall_obstacles", "on": 1})", {"\"on\"", "true or false", "got 1"}},
      {R"({"cmd": "status", "debug": "overrun", "ms": 5})", {"\"cmd\" or \"debug\", not both"}},
  };
  for (const Malformed& c : cases) {
    const std::string error = parsedError(c.line);
    SCOPED_TRACE(c.line + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
  }
}

TEST(Protocol, StatusJsonCarriesTheBaseDriversCounters) {
  Status s = filledStatus();
  s.base.fault = hal::BaseFault::kBusOff;
  s.base.fault_code = 0;
  s.base.enabled = true;
  s.base.bad_frames = 12;
  s.base.rx_overflows = 3;
  s.base.error_frames = 2;
  const Json base = statusJson(s, 0)["base"];
  EXPECT_EQ(base["fault"], "bus off");
  EXPECT_EQ(base["enabled"], true);
  EXPECT_EQ(base["bad_frames"], 12);
  EXPECT_EQ(base["rx_overflows"], 3);
  EXPECT_EQ(base["error_frames"], 2);
  s.base.fault = hal::BaseFault::kNone;
  EXPECT_TRUE(statusJson(s, 0)["base"]["fault"].is_null());
}

TEST(Protocol, StatusJsonCarriesTheScannersCountsAndTheRosScansDropsByReason) {
  Status s = filledStatus();
  EXPECT_TRUE(statusJson(s, 0)["scanner"].is_null()) << "no scanner: null";
  s.scanner.enabled = true;
  s.scanner.backend = "ros";
  s.scanner.scans_used = 900;
  s.scanner.scans_too_old = 7;
  s.scanner.frames_without_scan = 2;
  s.scanner.scan_points = 412;
  const Json scanner = statusJson(s, 0)["scanner"];
  EXPECT_EQ(scanner, Json({{"backend", "ros"}, {"scans_used", 900}, {"scans_too_old", 7}, {"frames_without_scan", 2},
                           {"scan_points", 412}}));
  s.ros.enabled = true;
  s.ros.scans_in = 1000;
  s.ros.scans_dropped = 10;
  s.ros.scans_dropped_by = {1, 2, 3, 4};
  const Json scans = statusJson(s, 0)["ros"]["scans"];
  EXPECT_EQ(scans["in"], 1000);
  EXPECT_EQ(scans["dropped"], 10);
  EXPECT_EQ(scans["dropped_by"], Json({{"beams", 1}, {"geometry", 2}, {"sweep", 3}, {"stamp", 4}}));
}

TEST(Protocol, StatusJsonCarriesTheBaseThreadsTimingAndCommandToWire) {
  Status s = filledStatus();
  s.base_thread.counters.cycles = 5000;
  s.base_thread.execution.p50_us = 41.0;
  s.base_thread.execution.max_us = 310.0;
  s.base_thread.wake.p99_us = 77.0;
  s.base_thread.counters.overruns = 2;
  s.base_thread.counters.late_wakeups = 1;
  s.base_thread.realtime = true;
  s.command_to_wire.latency.count = 900;
  s.command_to_wire.unsent = 4;
  s.command_to_wire.latency.p99_us = 2500.0;
  const Json j = Json::parse(statusReply(s, 0))["status"];
  const Json& thread = j["threads"]["base"];
  EXPECT_EQ(thread["cycle"]["count"], 5000);
  EXPECT_EQ(thread["cycle"]["p50_us"], 41.0);
  EXPECT_EQ(thread["cycle"]["max_us"], 310.0);
  EXPECT_EQ(thread["cycle"]["overruns"], 2);
  EXPECT_EQ(thread["wake"]["p99_us"], 77.0);
  EXPECT_EQ(thread["late_wakeups"], 1);
  EXPECT_EQ(thread["realtime"], true);
  const Json& wire = j["base"]["command_to_wire"];
  EXPECT_EQ(wire["count"], 900);
  EXPECT_EQ(wire["unsent"], 4);
  EXPECT_EQ(wire["p99_us"], 2500.0);
  EXPECT_EQ(j["base"]["bad_frames"], s.base.bad_frames);  // beside the driver's counters
}

TEST(Protocol, NamesOfEnumsAreTheContractSpellings) {
  EXPECT_STREQ(toString(FaultKind::kNone), "none");
  EXPECT_STREQ(toString(FaultKind::kStaleOdometry), "stale_odometry");
  EXPECT_STREQ(toString(FaultKind::kStaleObstacles), "stale_obstacles");
  EXPECT_STREQ(toString(FaultKind::kBase), "base");
  EXPECT_STREQ(toString(RequestKind::kGoal), "goal");
  EXPECT_STREQ(toString(RequestKind::kStop), "stop");
  EXPECT_STREQ(toString(RequestKind::kPose), "pose");
  EXPECT_STREQ(toString(RequestKind::kStatus), "status");
  EXPECT_STREQ(toString(RequestKind::kDebug), "debug");
  EXPECT_STREQ(toString(DebugKind::kOverrun), "overrun");
  EXPECT_STREQ(toString(DebugKind::kStallObstacles), "stall_obstacles");
  EXPECT_STREQ(toString(static_cast<DaemonState>(200)), "unknown");
}

TEST(Protocol, HistogramsIsACommandWithoutParameters) {
  EXPECT_EQ(parsedOk(R"({"cmd": "histograms"})").kind, RequestKind::kHistograms);
  EXPECT_EQ(requestLine(Request{RequestKind::kHistograms, {}}), "{\"cmd\":\"histograms\"}\n");
  EXPECT_THAT(parsedError(R"({"cmd": "histograms", "thread": "control"})"),
              HasSubstr("unknown key \"thread\" for histograms (expected cmd only)"));
  EXPECT_STREQ(toString(RequestKind::kHistograms), "histograms");
}

TEST(Protocol, RecordSavesToAnAbsolutePathAndReadsBackFromItsLine) {
  const Request r = parsedOk(R"({"cmd": "record", "save": "/var/log/staad/why.mcap"})");
  EXPECT_EQ(r.kind, RequestKind::kRecord);
  EXPECT_STREQ(r.file.data(), "/var/log/staad/why.mcap");
  EXPECT_EQ(requestLine(r), "{\"cmd\":\"record\",\"save\":\"/var/log/staad/why.mcap\"}\n");
  EXPECT_STREQ(parsedOk(requestLine(r)).file.data(), r.file.data());
  EXPECT_THAT(parsedError(R"({"cmd": "record"})"), HasSubstr("\"save\": missing"));
  EXPECT_THAT(parsedError(R"({"cmd": "record", "save": "why.mcap"})"),
              HasSubstr("\"save\": expected an absolute path, got \"why.mcap\""));
  EXPECT_THAT(parsedError(R"({"cmd": "record", "save": 3})"), HasSubstr("\"save\": expected a file path, got 3"));
  EXPECT_THAT(parsedError(R"({"cmd": "record", "save": "/a", "seconds": 3})"),
              HasSubstr("unknown key \"seconds\" for record (expected cmd, save)"));
  EXPECT_THAT(parsedError("{\"cmd\": \"record\", \"save\": \"/" + std::string(600, 'a') + "\"}"),
              HasSubstr("a path of at most 511 bytes"));
  EXPECT_STREQ(toString(RequestKind::kRecord), "record");
}

TEST(Protocol, AHistogramIsItsNonEmptyBinsWithCountOverflowAndMax) {
  rt::LatencyHistogram h(100);  // 1 us bins up to 100 us
  h.record(1'500);              // bin 1
  h.record(1'999);              // bin 1
  h.record(42'000);             // bin 42
  h.record(250'000);            // beyond the bound: overflow, the exact max
  const Json j = histogramJson(h);
  EXPECT_EQ(j["bins"], Json::parse("[[1, 2], [42, 1]]"));
  EXPECT_EQ(j["count"], 4);
  EXPECT_EQ(j["overflow"], 1);
  EXPECT_EQ(j["bound_us"], 100);
  EXPECT_DOUBLE_EQ(j["max_us"].get<double>(), 250.0);
  EXPECT_EQ(histogramJson(rt::LatencyHistogram(10))["bins"], Json::array());
}

TEST(Protocol, HistogramsLeaveOutThreadsThatDoNotRun) {
  const ThreadHistograms none[] = {{"control", nullptr}, {"base", nullptr}};
  EXPECT_EQ(histogramsJson(none), Json::object());
  const Json reply = Json::parse(histogramsReply(none));
  EXPECT_EQ(reply["ok"], true);
  EXPECT_EQ(reply["histograms"], Json::object());
}

TEST(Protocol, StatusNamesStallsAndThePlannersBoundBesideTheOtherCauses) {
  Status s;
  s.control_thread.counters.stalls = 3;
  s.control_thread.counters.preempted = 2;
  s.control_thread.counters.max_own_execution = 19'500'000;
  s.base_thread.counters.stalls = 1;
  s.budget_ms = 19.0;
  s.path_max_ns = 1'250'000;
  s.local_max_ns = 300'000;
  const Json j = statusJson(s, 0);
  EXPECT_EQ(j["stalls"], 3);
  EXPECT_EQ(j["preempted"], 2);
  EXPECT_DOUBLE_EQ(j["own_execution_max_us"].get<double>(), 19'500.0);
  EXPECT_EQ(j["threads"]["base"]["stalls"], 1);
  EXPECT_DOUBLE_EQ(j["planner"]["budget_ms"].get<double>(), 19.0);
  EXPECT_DOUBLE_EQ(j["planner"]["path_max_us"].get<double>(), 1'250.0);
  EXPECT_DOUBLE_EQ(j["planner"]["local_max_us"].get<double>(), 300.0);
  s.budget_ms = 0.0;  // an expansion budget
  EXPECT_TRUE(statusJson(s, 0)["planner"]["budget_ms"].is_null());
}


TEST(Protocol, RequestsNestedEightLevelsParseAndNineAreRefusedNamingTheBound) {
  const auto nested = [](std::size_t levels) {
    return R"({"cmd":"status","x":)" + std::string(levels - 1, '[') + "1" + std::string(levels - 1, ']') + "}";
  };
  // Eight levels reach the request's own checks (an unknown key), nine stop before parsing.
  EXPECT_THAT(parsedError(nested(kMaxRequestDepth)), HasSubstr("unknown key \"x\""));
  EXPECT_EQ(parsedError(nested(kMaxRequestDepth + 1)), "nested too deep: at most 8 levels of objects and arrays");
  // Brackets inside strings are text, not nesting.
  EXPECT_THAT(parsedError(R"({"cmd":"[[[[[[[[[[{{{{{{{{{{"})"), HasSubstr("unknown command"));
}

TEST(Protocol, ARequestOf4096BytesIsReadAnd4097AreRefusedNamingTheBound) {
  const std::string body = R"({"cmd":"status"})";
  const std::string inside = std::string(kMaxRequestBytes - body.size(), ' ') + body;
  ASSERT_EQ(inside.size(), kMaxRequestBytes);
  EXPECT_TRUE(std::holds_alternative<Request>(parseRequest(inside)));
  EXPECT_EQ(parsedError(" " + inside), "request too long: 4097 bytes (at most 4096)");
}

}  // namespace
}  // namespace staa::staad
