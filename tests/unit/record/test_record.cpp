// The flight recorder's pieces: MCAP written and read back byte for byte (and refused with
// the offset when cut, of another version or malformed), the cycle encoding of a real
// control cycle, the control configuration's keys, the budget's cut as a clock-read index,
// and the recording of simulated runs replayed bit for bit (and changed by --set).
#include "experiment/multi_sim.hpp"
#include "experiment/sim_runner.hpp"
#include "map/generate.hpp"
#include "record/budget_tap.hpp"
#include "record/config_keys.hpp"
#include "record/cycle_record.hpp"
#include "record/explain.hpp"
#include "record/mcap.hpp"
#include "record/recorder.hpp"
#include "record/replay.hpp"

#include "shared_dir.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>

namespace staa::record {
namespace {

std::vector<std::byte> bytesOf(const std::string& s) {
  std::vector<std::byte> b(s.size());
  std::memcpy(b.data(), s.data(), s.size());
  return b;
}

std::string writeSmallMcap() {
  std::ostringstream out;
  McapWriter w(out, "x-test", "test");
  const std::uint16_t schema = w.addSchema("pose", "jsonschema", R"({"type":"object"})");
  const std::uint16_t json = w.addChannel(schema, "/pose", "json", {{"agent", "0"}});
  const std::uint16_t raw = w.addChannel(0, "/raw", "x-bytes");
  w.metadata("session", {{"a", "1"}, {"b", "two"}});
  w.message(json, 100, std::string(R"({"x":1})"));
  const std::byte blob[3] = {std::byte{1}, std::byte{0}, std::byte{255}};
  w.message(raw, 200, std::span<const std::byte>(blob, 3));
  w.message(json, 300, std::string(R"({"x":2})"));
  w.close();
  EXPECT_TRUE(w.ok());
  EXPECT_EQ(w.messages(), 3u);
  return out.str();
}

TEST(Mcap, WritesMagicHeaderAndFooterAndReadsEveryRecordBack) {
  const std::string text = writeSmallMcap();
  ASSERT_GE(text.size(), 16u);
  EXPECT_EQ(text.substr(0, 8), std::string("\x89MCAP0\r\n", 8));
  EXPECT_EQ(text.substr(text.size() - 8), std::string("\x89MCAP0\r\n", 8));
  EXPECT_EQ(static_cast<unsigned char>(text[8]), 0x01u) << "the Header comes first";
  // The footer (opcode 0x02, length 20) just before the closing magic.
  const std::size_t footer = text.size() - 8 - 29;
  EXPECT_EQ(static_cast<unsigned char>(text[footer]), 0x02u);
  std::uint64_t summary_start = 0;
  std::memcpy(&summary_start, text.data() + footer + 9, 8);
  EXPECT_GT(summary_start, 8u);
  EXPECT_EQ(static_cast<unsigned char>(text[summary_start]), 0x03u) << "the summary starts with the Schema copies";

  const McapFile f = parseMcap(bytesOf(text), "small.mcap");
  EXPECT_EQ(f.profile, "x-test");
  ASSERT_EQ(f.schemas.size(), 1u);
  EXPECT_EQ(f.schemas.at(1).encoding, "jsonschema");
  ASSERT_EQ(f.channels.size(), 2u);
  EXPECT_EQ(f.channels.at(1).topic, "/pose");
  EXPECT_EQ(f.channels.at(1).metadata, (KeyValues{{"agent", "0"}}));
  EXPECT_EQ(f.channels.at(2).schema_id, 0u);
  ASSERT_EQ(f.messages.size(), 3u);
  EXPECT_EQ(f.messages[1].log_time, 200u);
  ASSERT_EQ(f.messages[1].data.size(), 3u);
  EXPECT_EQ(f.messages[1].data[2], std::byte{255});
  EXPECT_EQ(f.messages[2].sequence, 1u) << "sequences count per channel";
  const McapMetadata* m = f.findMetadata("session");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(*m->find("b"), "two");
  EXPECT_FALSE(f.truncated);
}

TEST(Mcap, ATruncatedFileIsAnErrorNamingTheOffsetOrSalvagedUpToItsLastCompleteRecord) {
  const std::string text = writeSmallMcap();
  // Cut inside the third message: the first two survive a salvage.
  const std::size_t third = text.find(R"({"x":2})");
  ASSERT_NE(third, std::string::npos);
  const std::string cut = text.substr(0, third + 3);
  try {
    parseMcap(bytesOf(cut), "cut.mcap");
    FAIL() << "a truncated file was read";
  } catch (const McapError& e) {
    EXPECT_TRUE(e.truncated());
    EXPECT_NE(std::string(e.what()).find("cut.mcap: truncated at byte"), std::string::npos) << e.what();
  }
  const McapFile salvaged = parseMcap(bytesOf(cut), "cut.mcap", true);
  EXPECT_TRUE(salvaged.truncated);
  EXPECT_EQ(salvaged.messages.size(), 2u);
  // Without its footer (a recorder killed between records).
  const std::size_t data_end = text.find(std::string("\x0f\x04\0\0\0\0\0\0\0", 9));
  ASSERT_NE(data_end, std::string::npos);
  EXPECT_THROW(parseMcap(bytesOf(text.substr(0, data_end)), "nofooter.mcap"), McapError);
  EXPECT_EQ(parseMcap(bytesOf(text.substr(0, data_end)), "nofooter.mcap", true).messages.size(), 3u);
}

TEST(Mcap, AnotherVersionOrNoMagicOrAMessageOnAnUnknownChannelIsRefusedWithTheReason) {
  std::string text = writeSmallMcap();
  std::string v1 = text;
  v1[5] = '1';
  try {
    parseMcap(bytesOf(v1), "v1.mcap");
    FAIL();
  } catch (const McapError& e) {
    EXPECT_NE(std::string(e.what()).find("major version '1'"), std::string::npos) << e.what();
    EXPECT_FALSE(e.truncated());
  }
  EXPECT_THROW(parseMcap(bytesOf("not an mcap file at all"), "x"), McapError);
  // The first message's channel id (2 bytes after opcode and length) pointed at channel 9.
  const std::size_t first = text.find(R"({"x":1})");
  const std::size_t header = first - (2 + 4 + 8 + 8);
  text[header] = 9;
  try {
    parseMcap(bytesOf(text), "bad.mcap");
    FAIL();
  } catch (const McapError& e) {
    EXPECT_NE(std::string(e.what()).find("channel 9"), std::string::npos) << e.what();
  }
}

// A real cycle of the office with two people, its record encoded and decoded.
struct OfficeCycle {
  PolygonMap map = generateOfficeMap();
  RobotProfile robot = paperAgentProfile();
  ControlConfig config;
  std::unique_ptr<ControlCycle> cycle;
  DynamicObstacleSet obstacles{32};
  std::vector<Polygon> polys{{{6.0, 4.0}, {6.5, 4.0}, {6.5, 4.5}, {6.0, 4.5}}, {{8.0, 5.0}, {8.4, 5.0}, {8.2, 5.5}}};
  std::vector<PolygonView> views;
  std::vector<Vec2> velocities{{-0.5, 0.0}, {0.0, -0.3}};
  std::vector<double> turns{0.0, 0.4};
  CycleOutput out;
  OfficeCycle() {
    cycle = std::make_unique<ControlCycle>(map, robot, config);
    for (const Polygon& p : polys) views.emplace_back(p);
    obstacles.set(views, velocities, turns);
    cycle->setGoal(Pose2{10.5, 4.5, 0.0});
  }
};

TEST(CycleRecord, EncodesARealCycleAndDecodesEveryFieldBack) {
  OfficeCycle oc;
  const ControlCycle::Memory before = oc.cycle->memory();
  ASSERT_TRUE(oc.cycle->searchesFresh());
  const UnicycleState robot{4.5, 4.5, 0.0, 0.5, 0.1};
  const CycleOutput out = oc.cycle->step({robot, &oc.obstacles}, PlannerBudget::expansions(300));
  ASSERT_TRUE(out.planned);
  EXPECT_FALSE(oc.cycle->searchesFresh());
  CycleView v;
  v.agent = 3;
  v.cycle = 42;
  v.time_ns = 1'400'000'000;
  v.flags = kGoalSet;
  v.memory = before;
  v.fresh = true;
  v.robot = robot;
  v.budget = budgetRecord(PlannerBudget::expansions(300), {});
  v.obstacles = {oc.views, oc.velocities, oc.turns};
  v.out = &out;
  v.route = oc.cycle->lastPath();
  v.subgoal = oc.cycle->localMap().intermediateGoal().pose;
  v.command = {out.v_cmd, out.w_cmd, false, 0.1, 0.2, false};
  const RecordLimits limits;
  std::vector<std::byte> buffer(maxCycleBytes(limits));
  const std::size_t n = encodeCycle(v, limits, buffer);
  ASSERT_GT(n, 0u);
  const CycleRecord c = decodeCycle(std::span<const std::byte>(buffer.data(), n), "test");
  EXPECT_EQ(c.agent, 3u);
  EXPECT_EQ(c.cycle, 42u);
  EXPECT_EQ(c.time_ns, 1'400'000'000);
  EXPECT_EQ(c.flags, kGoalSet | kFresh);
  EXPECT_TRUE(c.has_goal);
  EXPECT_EQ(c.goal.x, 10.5);
  EXPECT_EQ(c.state, CycleState::kDriving);
  EXPECT_EQ(c.robot.w, 0.1);
  ASSERT_EQ(c.obstacles.size(), 2u);
  EXPECT_EQ(c.obstacles[1].polygon, oc.polys[1]);
  EXPECT_EQ(c.obstacles[1].turn_rate, 0.4);
  EXPECT_EQ(c.obstacles[0].velocity, Vec2(-0.5, 0.0));
  EXPECT_EQ(firstDifference(c.out, stepOutputs(out)), "");
  EXPECT_EQ(c.out.pops, out.plan.stats.pops);
  EXPECT_EQ(c.route.size(), oc.cycle->lastPath().size());
  ASSERT_EQ(c.trajectory.size(), out.plan.trajectory.size());
  EXPECT_EQ(c.trajectory.back().x, static_cast<float>(out.plan.trajectory.back().x)) << "single precision";
  EXPECT_EQ(c.command.next_w, 0.2);
  EXPECT_FALSE(c.budget.wall_clock);
  EXPECT_EQ(c.budget.max_pops, 300u);

  // One changed bit is named.
  StepOutputs other = stepOutputs(out);
  other.w_cmd = std::nextafter(other.w_cmd, 10.0);
  EXPECT_EQ(firstDifference(c.out, other).rfind("w_cmd ", 0), 0u) << firstDifference(c.out, other);

  // A record of another version, or cut short, is refused naming the field.
  std::vector<std::byte> v2(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(n));
  v2[0] = std::byte{2};
  EXPECT_THROW(decodeCycle(v2, "v2"), RecordError);
  try {
    decodeCycle(std::span<const std::byte>(buffer.data(), 30), "short");
    FAIL();
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("short: the cycle record ends inside"), std::string::npos) << e.what();
  }
  // Inputs beyond the limits are flagged: that cycle cannot replay.
  RecordLimits tight;
  tight.obstacles = 1;
  std::vector<std::byte> small(maxCycleBytes(tight));
  const std::size_t m = encodeCycle(v, tight, small);
  ASSERT_GT(m, 0u);
  EXPECT_TRUE(decodeCycle(std::span<const std::byte>(small.data(), m), "tight").flags & kInputsCut);
  // The words for it.
  const std::vector<std::string> why = explainCycle(c, 1.4, "staa");
  ASSERT_GE(why.size(), 3u);
  EXPECT_NE(why[0].find("agent 3, cycle 42"), std::string::npos) << why[0];
}

TEST(RecordConfigKeys, ReadBackBitForBitAndSetOneByNameWithErrorsNamingKeyAndValue) {
  ControlConfig c;
  c.goal_tolerance_m = 0.1 + 0.2;  // not a short decimal
  c.staa.heuristic.kind = HeuristicKind::kDijkstraRtr;
  c.staa.max_nodes = 12345;
  c.path.nudge_start = false;
  c.local.blur_sigma_m = 1.0 / 3.0;
  const ControlConfig back = controlConfigFromJson(controlConfigJson(c));
  EXPECT_EQ(controlConfigJson(back), controlConfigJson(c));
  EXPECT_EQ(back.goal_tolerance_m, 0.1 + 0.2);
  EXPECT_EQ(back.local.blur_sigma_m, 1.0 / 3.0);
  EXPECT_EQ(back.staa.heuristic.kind, HeuristicKind::kDijkstraRtr);
  EXPECT_FALSE(back.path.nudge_start);

  ControlConfig s;
  setControlKey(s, "staa.heuristic.kind", "path-euclid");
  setControlKey(s, "staa.dt", "0.25");
  setControlKey(s, "staa.brake_safety", "off");
  setControlKey(s, "max_moving_obstacles", "8");
  EXPECT_EQ(s.staa.heuristic.kind, HeuristicKind::kPathEuclid);
  EXPECT_EQ(s.staa.dt, 0.25);
  EXPECT_FALSE(s.staa.brake_safety);
  EXPECT_EQ(s.max_moving_obstacles, 8u);
  auto message = [&](const std::string& key, const std::string& value) {
    try {
      setControlKey(s, key, value);
    } catch (const KeyError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("staa.dt", "fast"), "staa.dt: expected a finite number, got 'fast'");
  EXPECT_EQ(message("max_moving_obstacles", "-1"), "max_moving_obstacles: expected an integer >= 0, got '-1'");
  EXPECT_EQ(message("staa.heuristic.kind", "astar"),
            "staa.heuristic.kind: expected path-rtr, path-euclid or dijkstra-rtr, got 'astar'");
  EXPECT_EQ(message("staa.dtt", "1").rfind("unknown key 'staa.dtt' (the keys: rate_hz, ", 0), 0u);
  EXPECT_THROW(controlConfigFromJson(R"({"staa.new_field": 1})"), KeyError);
}

// A field added to the configuration structs needs its key (config_keys.cpp): these sizes
// change with it. Update them once its key is in visitControlConfig.
// Issue 16: the global path's choice between M' and M'' (its hysteresis) is carried from
// cycle to cycle, so it is memory: recorded, decoded and restored, and forgotten by a new goal.
TEST(CycleRecord, TheRouteChoiceBetweenMPrimeAndThePassageMapIsMemory) {
  // A 0.5 x 0.8 m base (circumradius 0.47 m) before a 0.65 m slot M' closes: the route runs
  // in the passage map M''.
  PolygonMap map;
  map.bounds = Box{{0, 0}, {12, 8}};
  map.obstacles = {{{5.9, 0}, {6.1, 0}, {6.1, 3.675}, {5.9, 3.675}}, {{5.9, 4.325}, {6.1, 4.325}, {6.1, 8}, {5.9, 8}}};
  RobotProfile robot = paperAgentProfile();
  robot.footprint = {{0.4, -0.25}, {0.4, 0.25}, {-0.4, 0.25}, {-0.4, -0.25}};
  ControlCycle cycle(map, robot, ControlConfig{});
  ASSERT_TRUE(cycle.pathPlanner().hasPassageMap());
  cycle.setGoal(Pose2{10.0, 4.0, 0.0});
  EXPECT_FALSE(cycle.memory().route_chosen);
  const UnicycleState at{2.0, 4.0, 0.0, 0.0, 0.0};
  const CycleOutput out = cycle.step({at, nullptr}, PlannerBudget::expansions(300));
  ASSERT_EQ(out.path_status, PathStatus::kFound);
  ASSERT_TRUE(out.path_passage);
  const ControlCycle::Memory after = cycle.memory();
  EXPECT_TRUE(after.route_chosen);
  EXPECT_TRUE(after.route_in_passage);
  // The path kept for failed queries is this one, in M''.
  EXPECT_TRUE(after.held_valid);
  EXPECT_TRUE(after.held_passage);

  CycleView v;
  v.memory = after;
  v.robot = at;
  v.budget = budgetRecord(PlannerBudget::expansions(300), {});
  v.out = &out;
  const RecordLimits limits;
  std::vector<std::byte> buffer(maxCycleBytes(limits));
  const std::size_t n = encodeCycle(v, limits, buffer);
  ASSERT_GT(n, 0u);
  const CycleRecord c = decodeCycle(std::span<const std::byte>(buffer.data(), n), "test");
  EXPECT_EQ(c.route_bits, 7u);
  // Restored on a cycle that never planned (a replay from the middle of a recording).
  ControlCycle other(map, robot, ControlConfig{});
  other.restoreMemory(c.memory());
  EXPECT_TRUE(other.memory().route_chosen);
  EXPECT_TRUE(other.memory().route_in_passage);
  EXPECT_TRUE(other.memory().held_passage);
  // A new goal forgets it, as it forgets the searches' trees.
  other.setGoal(Pose2{10.0, 4.0, 0.0});
  EXPECT_FALSE(other.memory().route_chosen);
}

TEST(RecordConfigKeys, CoverEveryField) {
  EXPECT_EQ(controlConfigKeys(ControlConfig{}).size(), 63u);
  EXPECT_EQ(sizeof(StaaConfig), 208u) << "StaaConfig changed: give its new field a key in record/config_keys.cpp";
  EXPECT_EQ(sizeof(HeuristicConfig), 56u) << "HeuristicConfig changed: give its new field a key";
  EXPECT_EQ(sizeof(LocalMapConfig), 48u) << "LocalMapConfig changed: give its new field a key";
  EXPECT_EQ(sizeof(GlobalPathOptions), 80u) << "GlobalPathOptions changed: give its new field a key";
  EXPECT_EQ(sizeof(BlindCornerConfig), 56u) << "BlindCornerConfig changed: give its new field a key";
  EXPECT_EQ(sizeof(ControlConfig), 480u) << "ControlConfig changed: give its new field a key";
}

TEST(RecordConfigKeys, TheRobotProfileReadsBackBitForBit) {
  RobotProfile r = paperAgentProfile();
  r.limits.a_max = 1.0 / 7.0;
  const RobotProfile back = robotProfileFromJson(robotProfileJson(r));
  EXPECT_EQ(back.name, r.name);
  EXPECT_EQ(back.footprint, r.footprint);
  EXPECT_EQ(back.limits.a_max, 1.0 / 7.0);
  EXPECT_THROW(robotProfileFromJson(R"({"name": "x"})"), KeyError);
}

// A clock that advances 1 ms per read.
std::int64_t fake_now = 0;
std::int64_t fakeClock() { return fake_now += 1'000'000; }

TEST(BudgetTap, TheCutIsTheFirstReadAtOrPastTheDeadlineAndTheReplayClockRepeatsIt) {
  BudgetTap::install(&fakeClock);
  BudgetTap::arm(5'000'000);  // 5 ms: reads 0 (start), 1..4 before, 5 at the deadline
  PlannerBudget b = PlannerBudget::wallClock(5'000'000, &BudgetTap::now);
  b.start();
  std::uint32_t pops = 0;
  while (!b.exhausted(pops)) ++pops;
  EXPECT_EQ(pops, 4u);
  EXPECT_EQ(BudgetTap::result().cut_read, 5);
  EXPECT_EQ(BudgetTap::result().reads, 6u);

  ReplayClock::arm(5);
  PlannerBudget r = PlannerBudget::wallClock(5'000'000, &ReplayClock::now);
  r.start();
  std::uint32_t replayed = 0;
  while (!r.exhausted(replayed)) ++replayed;
  EXPECT_EQ(replayed, pops);
  EXPECT_TRUE(r.deadline().passed()) << "past the cut every read has passed";
  ReplayClock::arm(-1);
  PlannerBudget never = PlannerBudget::wallClock(1, &ReplayClock::now);
  never.start();
  EXPECT_FALSE(never.exhausted(1000000));
}

// Records a run into `file` and loads it.
Recording recordMultiAgent(const std::filesystem::path& file, const BudgetSpec& budget, int agents, double seconds) {
  MultiSimOptions o;
  o.agents = agents;
  o.duration_s = seconds;
  o.budget = budget;
  o.seed = 4;
  o.record_path = file;
  o.record_session.source = "test";
  o.record_session.budget = budget.describe();
  runMultiAgent(loadPolygonMap(test::sourceDir() / "config/maps/office.yaml"), paperAgentProfile(), o);
  return loadRecording(file);
}

TEST(Replay, AMultiAgentRunOnTheWallClockReplaysBitForBitAndChangesUnderSet) {
  const auto dir = test::freshDir("Replay", "multi");
  const Recording r = recordMultiAgent(dir / "run.mcap", BudgetSpec::wallClockMs(6.0), 3, 3.0);
  ASSERT_EQ(r.agents.size(), 3u);
  EXPECT_EQ(r.session.agents.size(), 3u);
  EXPECT_EQ(r.agents.at(2).size(), 90u);
  EXPECT_TRUE(r.agents.at(0).front().flags & kFresh);
  EXPECT_TRUE(r.agents.at(0).front().budget.wall_clock);
  const ReplayResult same = replay(r, {});
  EXPECT_EQ(same.cycles, 270u);
  EXPECT_EQ(same.identical, 270u);
  for (const AgentReplay& a : same.agents) {
    EXPECT_EQ(a.exact, a.cycles);
    EXPECT_EQ(a.exact_from, std::optional<std::uint64_t>(0));
    EXPECT_EQ(a.first_difference, "");
  }
  // From the middle: fresh searches, each cycle's pops as its budget (best effort).
  ReplayOptions later;
  later.from_s = 2.0;
  const ReplayResult mid = replay(r, later);
  EXPECT_EQ(mid.cycles, 3u * 30u);
  for (const AgentReplay& a : mid.agents) EXPECT_EQ(a.exact, 0u);
  // Another heuristic changes what the cycles decide.
  ReplayOptions set;
  set.control = r.session.control;
  setControlKey(*set.control, "staa.heuristic.kind", "path-euclid");
  const ReplayResult changed = replay(r, set);
  EXPECT_LT(changed.identical, changed.cycles);
  EXPECT_TRUE(changed.agents[0].first_difference_cycle.has_value());
}

TEST(Replay, AnAlteredMapOrALostSessionIsRefusedNamingTheProblem) {
  const auto dir = test::freshDir("Replay", "bad");
  recordMultiAgent(dir / "run.mcap", BudgetSpec::expansionsOf(100), 2, 1.0);
  std::ifstream in(dir / "run.mcap", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // A digit of the embedded map's first obstacle changed: the checksum no longer matches.
  const std::size_t obstacles = bytes.find("obstacles:");
  ASSERT_NE(obstacles, std::string::npos);
  const std::size_t digit = bytes.find_first_of("123456789", obstacles);
  bytes[digit] = bytes[digit] == '9' ? '8' : static_cast<char>(bytes[digit] + 1);
  std::ofstream(dir / "altered.mcap", std::ios::binary) << bytes;
  try {
    loadRecording(dir / "altered.mcap");
    FAIL() << "an altered map was taken";
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("the embedded map does not match its checksum"), std::string::npos) << e.what();
  }
  // An MCAP file without the session.
  std::ofstream plain(dir / "plain.mcap", std::ios::binary);
  plain << writeSmallMcap();
  plain.close();
  try {
    loadRecording(dir / "plain.mcap");
    FAIL();
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("not a staa recording"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace staa::record
