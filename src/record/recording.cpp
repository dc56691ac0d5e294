#include "record/recording.hpp"

#include "record/config_keys.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "git_revision.hpp"  // STAA_GIT_REVISION, written at build time

#ifndef STAA_VERSION
#define STAA_VERSION "unknown"
#endif
#ifndef STAA_BUILD_TYPE
#define STAA_BUILD_TYPE ""
#endif

namespace staa::record {

namespace {

using json = nlohmann::ordered_json;

// FNV-1a, 64 bits: the map text's checksum (a corrupted or edited map is refused).
std::string checksum(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
  return s;
}

const char* faultName(std::uint8_t fault) {
  switch (fault) {
    case 0: return "none";
    case 1: return "stale_odometry";
    case 2: return "stale_obstacles";
    case 3: return "base";
  }
  return "unknown";
}

const char* stepName(StepKind s) {
  switch (s) {
    case StepKind::kStepped: return "stepped";
    case StepKind::kFault: return "fault";
    case StepKind::kStopped: return "stopped";
  }
  return "unknown";
}

double seconds(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

// The plotted channels carry 0.1 mm, 0.1 mrad: short numbers (the cycle channel is exact).
double q(double v) { return std::round(v * 1e4) / 1e4; }

json points(std::span<const Vec2> p) {
  json a = json::array();
  for (const Vec2& v : p) a.push_back({q(v.x()), q(v.y())});
  return a;
}

// The JSON Schemas of the plotted channels.
const char* schemaText(const std::string& name) {
  if (name == "pose") {
    return R"J({"title":"staa pose","description":"The robot's state as the cycle saw it (odometry and localization)","type":"object",)J"
           R"J("properties":{"t":{"type":"number","description":"s"},"x":{"type":"number"},"y":{"type":"number"},)J"
           R"J("theta":{"type":"number"},"v":{"type":"number"},"w":{"type":"number"}},"required":["t","x","y","theta","v","w"]})J";
  }
  if (name == "command") {
    return R"J({"title":"staa command","description":"The velocity command sent to the base, its fallback, and the cycle's own","type":"object",)J"
           R"J("properties":{"t":{"type":"number"},"v":{"type":"number"},"w":{"type":"number"},"brake":{"type":"boolean"},)J"
           R"J("next_v":{"type":"number"},"next_w":{"type":"number"},"next_brake":{"type":"boolean"},)J"
           R"J("v_cmd":{"type":"number"},"w_cmd":{"type":"number"}},"required":["t","v","w","brake","v_cmd","w_cmd"]})J";
  }
  if (name == "state") {
    return R"J({"title":"staa state","type":"object","properties":{"t":{"type":"number"},"cycle":{"type":"integer"},)J"
           R"J("step":{"type":"string"},"fault":{"type":"string"},"state":{"type":"string"},"path_status":{"type":"string"},)J"
           R"J("path_held":{"type":"boolean"},"path_dynamic":{"type":"boolean"},"planned":{"type":"boolean"},)J"
           R"J("outcome":{"type":"string"},"tier":{"type":"integer"},"fresh":{"type":"boolean"},)J"
           R"J("goal":{"type":["object","null"],"properties":{"x":{"type":"number"},"y":{"type":"number"},"theta":{"type":"number"}}}},)J"
           R"J("required":["t","cycle","step","fault","state","path_status","planned"]})J";
  }
  if (name == "plan") {
    return R"J({"title":"staa plan","type":"object","properties":{"t":{"type":"number"},)J"
           R"J("route":{"type":"array","items":{"type":"array","items":{"type":"number"}}},)J"
           R"J("trajectory":{"type":"array","items":{"type":"array","items":{"type":"number"}},"description":"[x, y, theta, v, w] per step"},)J"
           R"J("subgoal":{"type":"object","properties":{"x":{"type":"number"},"y":{"type":"number"},"theta":{"type":"number"},"final":{"type":"boolean"}}},)J"
           R"J("first_action":{"type":"object","properties":{"a":{"type":"number"},"b":{"type":"number"}}},)J"
           R"J("best_h":{"type":"number"},"depth":{"type":"integer"}},"required":["t","route","trajectory","subgoal"]})J";
  }
  if (name == "obstacles") {
    return R"J({"title":"staa obstacles","description":"The moving obstacles D the cycle planned against","type":"object",)J"
           R"J("properties":{"t":{"type":"number"},"obstacles":{"type":"array","items":{"type":"object","properties":{)J"
           R"J("polygon":{"type":"array","items":{"type":"array","items":{"type":"number"}}},)J"
           R"J("velocity":{"type":"array","items":{"type":"number"}},"turn_rate":{"type":"number"}}}}},"required":["t","obstacles"]})J";
  }
  if (name == "timing") {
    return R"J({"title":"staa timing","type":"object","properties":{"t":{"type":"number"},"path_us":{"type":"number"},)J"
           R"J("local_us":{"type":"number"},"plan_us":{"type":"number"},"pops":{"type":"integer"},"expansions":{"type":"integer"},)J"
           R"J("successors":{"type":"integer"},"budget_ms":{"type":["number","null"]},"budget_expansions":{"type":["integer","null"]},)J"
           R"J("cut_read":{"type":"integer"},"reads":{"type":"integer"}},"required":["t","path_us","local_us","plan_us","pops"]})J";
  }
  return R"J({"type":"object"})J";  // events
}

}  // namespace

std::string softwareVersion() {
  const std::string rev = STAA_GIT_REVISION;
  return std::string("staa ") + STAA_VERSION + (rev.empty() ? std::string() : " (" + rev + ")");
}
std::string buildType() { return STAA_BUILD_TYPE; }

std::string utcNow() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char s[32];
  std::strftime(s, sizeof s, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return s;
}

std::string agentPrefix(std::uint16_t agent, bool several) {
  return several ? "/agent" + std::to_string(agent) : std::string("/staa");
}

KeyValues sessionMetadata(const Session& s) {
  json agents = json::array();
  for (const AgentInfo& a : s.agents) {
    auto j = decltype(agents)::object();
    j["agent"] = a.agent;
    j["controller"] = a.controller;
    if (a.ghost) j["ghost"] = true;  // absent: false (files before it have none)
    agents.push_back(std::move(j));
  }
  const std::string map_text = toYaml(s.map);
  return {
      {"format", kRecordingFormat},
      {"source", s.source},
      {"software", s.software},
      {"build_type", s.build_type},
      {"recorded_at", s.recorded_at},
      {"budget", s.budget},
      {"cycle_encoding", std::string(kCycleEncoding) + "/" + std::to_string(kCycleEncodingVersion)},
      {"control", controlConfigJson(s.control)},
      {"robot", robotProfileJson(s.robot)},
      {"map", map_text},
      {"map_checksum", checksum(map_text)},
      {"agents", agents.dump()},
      {"config_text", s.config_text},
      {"robot_text", s.robot_text},
  };
}

Session sessionFromMetadata(const McapMetadata& m, const std::string& source) {
  auto need = [&](const char* key) -> const std::string& {
    const std::string* v = m.find(key);
    if (v == nullptr) throw RecordError(source + ": the session has no '" + key + "' (not written by staa's recorder?)");
    return *v;
  };
  if (need("format") != kRecordingFormat) {
    throw RecordError(source + ": recording format '" + need("format") + "', this reader reads '" + kRecordingFormat + "'");
  }
  const std::string encoding = std::string(kCycleEncoding) + "/" + std::to_string(kCycleEncodingVersion);
  if (need("cycle_encoding") != encoding) {
    throw RecordError(source + ": cycle encoding '" + need("cycle_encoding") + "', this reader reads '" + encoding + "'");
  }
  Session s;
  s.source = need("source");
  s.software = need("software");
  s.build_type = need("build_type");
  s.recorded_at = need("recorded_at");
  s.budget = need("budget");
  try {
    s.control = controlConfigFromJson(need("control"));
    s.robot = robotProfileFromJson(need("robot"));
  } catch (const KeyError& e) {
    throw RecordError(source + ": " + e.what());
  }
  const std::string& map_text = need("map");
  if (checksum(map_text) != need("map_checksum")) {
    throw RecordError(source + ": the embedded map does not match its checksum (" + need("map_checksum") + ", the text gives " +
                      checksum(map_text) + "): the file was altered or damaged");
  }
  try {
    s.map = parsePolygonMap(map_text, source + " (embedded map)");
  } catch (const std::exception& e) {
    throw RecordError(e.what());
  }
  try {
    for (const auto& a : nlohmann::json::parse(need("agents"))) {
      s.agents.push_back({a.at("agent").get<std::uint16_t>(), a.at("controller").get<std::string>(), a.value("ghost", false)});
    }
  } catch (const nlohmann::json::exception& e) {
    throw RecordError(source + ": the session's agents are not as written: " + e.what());
  }
  if (const std::string* t = m.find("config_text")) s.config_text = *t;
  if (const std::string* t = m.find("robot_text")) s.robot_text = *t;
  return s;
}

std::vector<std::pair<std::string, std::string>> cycleJson(const CycleRecord& c) {
  const double t = std::round(seconds(c.time_ns) * 1e6) / 1e6;
  std::vector<std::pair<std::string, std::string>> out;
  const UnicycleState& r = c.robot;
  out.emplace_back("pose", json{{"t", t}, {"x", q(r.x)}, {"y", q(r.y)}, {"theta", q(r.theta)}, {"v", q(r.v)}, {"w", q(r.w)}}.dump());
  out.emplace_back("command", json{{"t", t},
                                   {"v", q(c.command.v)},
                                   {"w", q(c.command.w)},
                                   {"brake", c.command.brake},
                                   {"next_v", q(c.command.next_v)},
                                   {"next_w", q(c.command.next_w)},
                                   {"next_brake", c.command.next_brake},
                                   {"v_cmd", q(c.out.v_cmd)},
                                   {"w_cmd", q(c.out.w_cmd)}}
                                  .dump());
  json goal = nullptr;
  if (c.has_goal) goal = {{"x", q(c.goal.x)}, {"y", q(c.goal.y)}, {"theta", q(c.goal.theta)}};
  out.emplace_back("state", json{{"t", t},
                                 {"cycle", c.cycle},
                                 {"step", stepName(c.step)},
                                 {"fault", faultName(c.fault)},
                                 {"state", toString(c.out.state)},
                                 {"path_status", toString(c.out.path_status)},
                                 {"path_held", c.out.path_held},
                                 {"path_dynamic", c.out.path_dynamic},
                                 {"planned", c.out.planned},
                                 {"outcome", c.out.planned ? toString(c.out.outcome) : "none"},
                                 {"tier", c.out.planned ? c.out.tier : -1},
                                 {"fresh", (c.flags & kFresh) != 0},
                                 {"pose_corrected", (c.flags & kPoseCorrected) != 0},
                                 {"goal", goal}}
                                .dump());
  json traj = json::array();
  for (const UnicycleState& s : c.trajectory) traj.push_back({q(s.x), q(s.y), q(s.theta), q(s.v), q(s.w)});
  out.emplace_back("plan", json{{"t", t},
                                {"route", points(c.route)},
                                {"trajectory", traj},
                                {"subgoal", {{"x", q(c.subgoal.x)}, {"y", q(c.subgoal.y)}, {"theta", q(c.subgoal.theta)}, {"final", c.subgoal_final}}},
                                {"first_action", {{"a", q(c.out.first_action.a)}, {"b", q(c.out.first_action.b)}}},
                                {"best_h", q(c.out.best_h)},
                                {"depth", c.out.depth}}
                               .dump());
  json obstacles = json::array();
  for (const RecordedObstacle& o : c.obstacles) {
    obstacles.push_back({{"polygon", points(o.polygon)}, {"velocity", {q(o.velocity.x()), q(o.velocity.y())}}, {"turn_rate", q(o.turn_rate)}});
  }
  out.emplace_back("obstacles", json{{"t", t}, {"obstacles", obstacles}}.dump());
  out.emplace_back("timing", json{{"t", t},
                                  {"path_us", q(static_cast<double>(c.path_ns) * 1e-3)},
                                  {"local_us", q(static_cast<double>(c.local_ns) * 1e-3)},
                                  {"plan_us", q(static_cast<double>(c.plan_ns) * 1e-3)},
                                  {"pops", c.out.pops},
                                  {"expansions", c.out.expansions},
                                  {"successors", c.out.successors},
                                  {"budget_ms", c.budget.wall_clock ? json(static_cast<double>(c.budget.limit_ns) * 1e-6) : json(nullptr)},
                                  {"budget_expansions", c.budget.wall_clock ? json(nullptr) : json(c.budget.max_pops)},
                                  {"cut_read", c.budget.cut.cut_read},
                                  {"reads", c.budget.cut.reads}}
                                 .dump());
  return out;
}

RecordingFile::RecordingFile(const std::filesystem::path& path, const Session& session)
    : path_(path), several_(session.agents.size() > 1) {
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) {
    error_ = path.string() + ": cannot be opened for writing";
    return;
  }
  writer_ = std::make_unique<McapWriter>(out_, "", softwareVersion() + " flight recorder");
  writer_->metadata(kSessionMetadata, sessionMetadata(session));
  for (const AgentInfo& a : session.agents) channelsFor(a.agent);
  if (!writer_->ok()) error_ = path.string() + ": writing failed (disk full?)";
}

RecordingFile::~RecordingFile() { close(); }

RecordingFile::Channels& RecordingFile::channelsFor(std::uint16_t agent) {
  const auto it = channels_.find(agent);
  if (it != channels_.end()) return it->second;
  const std::string prefix = agentPrefix(agent, several_);
  auto schema = [&](const std::string& name) {
    const auto s = schemas_.find(name);
    if (s != schemas_.end()) return s->second;
    const std::uint16_t id = writer_->addSchema("staa." + name, "jsonschema", schemaText(name));
    schemas_[name] = id;
    return id;
  };
  const KeyValues meta{{"agent", std::to_string(agent)}};
  Channels c{};
  c.cycle = writer_->addChannel(0, prefix + "/cycle", kCycleEncoding, meta);
  c.pose = writer_->addChannel(schema("pose"), prefix + "/pose", "json", meta);
  c.command = writer_->addChannel(schema("command"), prefix + "/command", "json", meta);
  c.state = writer_->addChannel(schema("state"), prefix + "/state", "json", meta);
  c.plan = writer_->addChannel(schema("plan"), prefix + "/plan", "json", meta);
  c.obstacles = writer_->addChannel(schema("obstacles"), prefix + "/obstacles", "json", meta);
  c.timing = writer_->addChannel(schema("timing"), prefix + "/timing", "json", meta);
  return channels_[agent] = c;
}

void RecordingFile::add(std::span<const std::byte> bytes) {
  if (!writer_ || !error_.empty()) return;
  const CycleRecord c = decodeCycle(bytes, path_.string());
  const Channels& ch = channelsFor(c.agent);
  const auto t = static_cast<std::uint64_t>(std::max<std::int64_t>(0, c.time_ns));
  writer_->message(ch.cycle, t, bytes);
  for (const auto& [topic, text] : cycleJson(c)) {
    const std::uint16_t id = topic == "pose"      ? ch.pose
                             : topic == "command" ? ch.command
                             : topic == "state"   ? ch.state
                             : topic == "plan"    ? ch.plan
                             : topic == "obstacles" ? ch.obstacles
                                                    : ch.timing;
    writer_->message(id, t, text);
  }
  ++cycles_;
  if (!writer_->ok()) error_ = path_.string() + ": writing failed (disk full?)";
}

void RecordingFile::event(const std::string& topic, std::int64_t time_ns, const std::string& text) {
  if (!writer_ || !error_.empty()) return;
  auto it = event_channels_.find(topic);
  if (it == event_channels_.end()) {
    std::uint16_t schema = 0;
    const auto s = schemas_.find("event");
    if (s != schemas_.end()) {
      schema = s->second;
    } else {
      schema = schemas_["event"] = writer_->addSchema("staa.event", "jsonschema", schemaText("event"));
    }
    it = event_channels_.emplace(topic, writer_->addChannel(schema, topic, "json")).first;
  }
  writer_->message(it->second, static_cast<std::uint64_t>(std::max<std::int64_t>(0, time_ns)), text);
  if (!writer_->ok()) error_ = path_.string() + ": writing failed (disk full?)";
}

void RecordingFile::close() {
  if (!writer_) return;
  writer_->close();
  out_.close();
  if (!out_ && error_.empty()) error_ = path_.string() + ": closing failed (disk full?)";
  writer_.reset();
}

bool RecordingFile::ok() const { return error_.empty(); }

}  // namespace staa::record
