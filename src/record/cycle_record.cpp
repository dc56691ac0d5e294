#include "record/cycle_record.hpp"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>

namespace staa::record {

static_assert(std::endian::native == std::endian::little, "the cycle encoding is little-endian; add byte swaps here");

namespace {

// Sequential little-endian writes into a fixed buffer; a write past its end sets `overflow`.
class Writer {
 public:
  explicit Writer(std::span<std::byte> buffer) : buf_(buffer) {}
  template <typename T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (pos_ + sizeof(T) > buf_.size()) {
      overflow_ = true;
      return;
    }
    std::memcpy(buf_.data() + pos_, &v, sizeof(T));
    pos_ += sizeof(T);
  }
  void u8(std::uint8_t v) { put(v); }
  void u16(std::uint16_t v) { put(v); }
  void u32(std::uint32_t v) { put(v); }
  void i32(std::int32_t v) { put(v); }
  void i64(std::int64_t v) { put(v); }
  void u64(std::uint64_t v) { put(v); }
  void f64(double v) { put(v); }
  void pose(const Pose2& p) {
    f64(p.x);
    f64(p.y);
    f64(p.theta);
  }
  void state(const UnicycleState& s) {
    f64(s.x);
    f64(s.y);
    f64(s.theta);
    f64(s.v);
    f64(s.w);
  }
  void points(std::span<const Vec2> p, std::size_t cap) {
    const std::size_t n = std::min(p.size(), cap);
    u32(static_cast<std::uint32_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      f64(p[i].x());
      f64(p[i].y());
    }
  }
  std::size_t size() const { return pos_; }
  bool overflow() const { return overflow_; }

 private:
  std::span<std::byte> buf_;
  std::size_t pos_ = 0;
  bool overflow_ = false;
};

class Reader {
 public:
  Reader(std::span<const std::byte> data, const std::string& where) : data_(data), where_(where) {}
  template <typename T>
  T get(const char* field) {
    if (pos_ + sizeof(T) > data_.size()) {
      throw RecordError(where_ + ": the cycle record ends inside '" + field + "' (byte " + std::to_string(pos_) + " of " +
                        std::to_string(data_.size()) + ")");
    }
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::uint8_t u8(const char* f) { return get<std::uint8_t>(f); }
  std::uint16_t u16(const char* f) { return get<std::uint16_t>(f); }
  std::uint32_t u32(const char* f) { return get<std::uint32_t>(f); }
  std::int32_t i32(const char* f) { return get<std::int32_t>(f); }
  std::int64_t i64(const char* f) { return get<std::int64_t>(f); }
  std::uint64_t u64(const char* f) { return get<std::uint64_t>(f); }
  double f64(const char* f) { return get<double>(f); }
  Pose2 pose(const char* f) {
    Pose2 p;
    p.x = f64(f);
    p.y = f64(f);
    p.theta = f64(f);
    return p;
  }
  UnicycleState state(const char* f) {
    UnicycleState s;
    s.x = f64(f);
    s.y = f64(f);
    s.theta = f64(f);
    s.v = f64(f);
    s.w = f64(f);
    return s;
  }
  // A count followed by that many items of `item_bytes` each: checked against what is left.
  std::uint32_t count(const char* f, std::size_t item_bytes) {
    const std::uint32_t n = u32(f);
    if (static_cast<std::uint64_t>(n) * item_bytes > data_.size() - pos_) {
      throw RecordError(where_ + ": the cycle record's '" + f + "' counts " + std::to_string(n) + " items, only " +
                        std::to_string(data_.size() - pos_) + " bytes are left");
    }
    return n;
  }
  Polygon points(const char* f) {
    const std::uint32_t n = count(f, 16);
    Polygon p(n);
    for (Vec2& v : p) {
      const double x = f64(f);
      v = Vec2(x, f64(f));
    }
    return p;
  }
  std::size_t left() const { return data_.size() - pos_; }

 private:
  std::span<const std::byte> data_;
  const std::string& where_;
  std::size_t pos_ = 0;
};

void putOutputs(Writer& w, const StepOutputs& o) {
  w.f64(o.v_cmd);
  w.f64(o.w_cmd);
  w.u8(static_cast<std::uint8_t>(o.state));
  w.u8(static_cast<std::uint8_t>(o.path_status));
  w.u8(static_cast<std::uint8_t>((o.path_dynamic ? 1 : 0) | (o.path_held ? 2 : 0) | (o.planned ? 4 : 0)));
  w.u8(static_cast<std::uint8_t>(o.outcome));
  w.f64(o.path_length);
  w.u32(o.obstacles_dropped);
  w.f64(o.first_action.a);
  w.f64(o.first_action.b);
  w.state(o.best);
  w.f64(o.best_h);
  w.u32(o.brake_safe_actions);
  w.u8(o.tier);
  w.i32(o.depth);
  w.u32(o.pops);
  w.u32(o.expansions);
  w.u32(o.successors);
  w.u32(o.collisions);
  w.u32(o.heuristic_calls);
}

constexpr std::size_t kOutputBytes = 8 * 2 + 4 + 8 + 4 + 8 * 2 + 8 * 5 + 8 + 4 + 1 + 4 + 4 * 5;

template <typename E>
E enumIn(std::uint8_t v, std::uint8_t last, const char* field, const std::string& where) {
  if (v > last) {
    throw RecordError(where + ": the cycle record's '" + field + "' is " + std::to_string(v) + ", at most " +
                      std::to_string(last) + " is known");
  }
  return static_cast<E>(v);
}

}  // namespace

std::size_t maxCycleBytes(const RecordLimits& l) {
  const std::size_t header = 2 + 2 + 8 + 8 + 4 + 4;
  const std::size_t memory = 4 + 4 + 24;
  const std::size_t robot = 40;
  const std::size_t budget = 4 + 4 + 8 + 8 + 4;
  const std::size_t obstacles = 4 + l.obstacles * (4 + l.vertices * 16 + 24);
  const std::size_t held = 4 + l.path_points * 16;
  const std::size_t out = kOutputBytes + 24 + 2 * (16 + 1) + 24 + 1;
  const std::size_t plot = 4 + l.path_points * 16 + 4 + l.trajectory * 20;
  return header + memory + robot + budget + obstacles + held + out + plot;
}

BudgetRecord budgetRecord(const PlannerBudget& budget, const BudgetCut& cut) {
  BudgetRecord r;
  r.wall_clock = budget.kind() == PlannerBudget::Kind::kWallClock;
  r.max_pops = budget.maxPops();
  r.limit_ns = budget.limitNs();
  r.cut = r.wall_clock ? cut : BudgetCut{};
  return r;
}

StepOutputs stepOutputs(const CycleOutput& out) {
  StepOutputs o;
  o.v_cmd = out.v_cmd;
  o.w_cmd = out.w_cmd;
  o.state = out.state;
  o.path_status = out.path_status;
  o.path_dynamic = out.path_dynamic;
  o.path_held = out.path_held;
  o.planned = out.planned;
  o.path_length = out.path_length;
  o.obstacles_dropped = static_cast<std::uint32_t>(out.obstacles_dropped);
  if (out.planned) {
    const PlanResult& p = out.plan;
    o.outcome = p.outcome;
    o.first_action = p.first_action;
    o.best = p.best;
    o.best_h = p.best_h;
    o.brake_safe_actions = p.brake_safe_actions;
    o.tier = p.brake_safety_tier;
    o.depth = p.depth;
    o.pops = p.stats.pops;
    o.expansions = p.stats.expansions;
    o.successors = p.stats.successors;
    o.collisions = p.stats.collisions;
    o.heuristic_calls = p.stats.heuristic_calls;
  }
  return o;
}

namespace {
bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
std::string num(double v) {
  char s[40];
  std::snprintf(s, sizeof s, "%.17g", v);
  return s;
}
}  // namespace

std::string firstDifference(const StepOutputs& r, const StepOutputs& p) {
  auto d = [](const char* name, double a, double b) -> std::string {
    return sameBits(a, b) ? std::string() : std::string(name) + " " + num(a) + " vs " + num(b);
  };
  auto i = [](const char* name, long long a, long long b) -> std::string {
    return a == b ? std::string() : std::string(name) + " " + std::to_string(a) + " vs " + std::to_string(b);
  };
  for (std::string s : {
           d("v_cmd", r.v_cmd, p.v_cmd), d("w_cmd", r.w_cmd, p.w_cmd),
           r.state == p.state ? std::string()
                              : std::string("state ") + toString(r.state) + " vs " + toString(p.state),
           r.path_status == p.path_status
               ? std::string()
               : std::string("path status ") + toString(r.path_status) + " vs " + toString(p.path_status),
           i("path_dynamic", r.path_dynamic, p.path_dynamic), i("path_held", r.path_held, p.path_held),
           i("planned", r.planned, p.planned), d("path_length", r.path_length, p.path_length),
           i("obstacles_dropped", r.obstacles_dropped, p.obstacles_dropped),
           r.outcome == p.outcome ? std::string()
                                  : std::string("plan outcome ") + toString(r.outcome) + " vs " + toString(p.outcome),
           i("pops", r.pops, p.pops), i("expansions", r.expansions, p.expansions),
           i("successors", r.successors, p.successors), i("collisions", r.collisions, p.collisions),
           i("heuristic_calls", r.heuristic_calls, p.heuristic_calls),
           d("first action a", r.first_action.a, p.first_action.a), d("first action b", r.first_action.b, p.first_action.b),
           d("best.x", r.best.x, p.best.x), d("best.y", r.best.y, p.best.y), d("best.theta", r.best.theta, p.best.theta),
           d("best.v", r.best.v, p.best.v), d("best.w", r.best.w, p.best.w), d("best_h", r.best_h, p.best_h),
           i("brake_safe_actions", r.brake_safe_actions, p.brake_safe_actions),
           i("braking-safety tier", r.tier, p.tier), i("depth", r.depth, p.depth)}) {
    if (!s.empty()) return s;
  }
  return {};
}

std::size_t encodeCycle(const CycleView& v, const RecordLimits& limits, std::span<std::byte> buffer) {
  Writer w(buffer);
  std::uint8_t flags = v.flags & (kGoalSet | kPoseCorrected | kNewCycle);
  if (v.fresh) flags |= kFresh;
  const std::size_t n_obstacles = v.obstacles.polygons.size();
  bool cut = n_obstacles > limits.obstacles;
  for (std::size_t i = 0; i < std::min(n_obstacles, limits.obstacles); ++i) {
    cut = cut || v.obstacles.polygons[i].size() > limits.vertices;
  }
  const bool held = v.memory.held_valid && v.out != nullptr && v.out->path_held;
  if (held && v.memory.held_path.size() > limits.path_points) cut = true;
  if (cut) flags |= kInputsCut;
  if (held) flags |= kHeldPath;

  w.u16(kCycleEncodingVersion);
  w.u16(v.agent);
  w.u64(v.cycle);
  w.i64(v.time_ns);
  w.u32(v.map_sequence);
  w.u8(static_cast<std::uint8_t>(v.step));
  w.u8(v.fault);
  w.u8(flags);
  w.u8(0);
  // The memory before the step.
  w.u8(v.memory.goal.has_value() ? 1 : 0);
  w.u8(static_cast<std::uint8_t>(v.memory.state));
  w.u8(v.memory.held_valid ? 1 : 0);
  w.u8(static_cast<std::uint8_t>((v.memory.held_passage ? 1 : 0) | (v.memory.route_chosen ? 2 : 0) |
                                 (v.memory.route_in_passage ? 4 : 0)));
  w.i32(v.memory.path_misses);
  w.pose(v.memory.goal.value_or(Pose2{}));
  w.state(v.robot);
  // The budget and its cut.
  w.u8(v.budget.wall_clock ? 1 : 0);
  w.u8(0);
  w.u8(0);
  w.u8(0);
  w.u32(v.budget.max_pops);
  w.i64(v.budget.limit_ns);
  w.i64(v.budget.cut.cut_read);
  w.u32(v.budget.cut.reads);
  // The moving obstacles as handed to DynamicObstacleSet::set.
  const std::size_t n = std::min(n_obstacles, limits.obstacles);
  w.u32(static_cast<std::uint32_t>(n));
  for (std::size_t i = 0; i < n; ++i) {
    w.points(v.obstacles.polygons[i], limits.vertices);
    const Vec2 vel = i < v.obstacles.velocities.size() ? v.obstacles.velocities[i] : Vec2(0.0, 0.0);
    w.f64(vel.x());
    w.f64(vel.y());
    w.f64(i < v.obstacles.turn_rates.size() ? v.obstacles.turn_rates[i] : 0.0);
  }
  if (held) w.points(v.memory.held_path, limits.path_points);
  // What came out.
  const StepOutputs o = v.out != nullptr ? stepOutputs(*v.out) : StepOutputs{};
  putOutputs(w, o);
  w.i64(v.out != nullptr ? v.out->path_ns : 0);
  w.i64(v.out != nullptr ? v.out->local_ns : 0);
  w.i64(v.out != nullptr ? v.out->plan_ns : 0);
  w.f64(v.command.v);
  w.f64(v.command.w);
  w.u8(v.command.brake ? 1 : 0);
  w.f64(v.command.next_v);
  w.f64(v.command.next_w);
  w.u8(v.command.next_brake ? 1 : 0);
  // For the plots: G~, the path followed, the plan's states.
  w.pose(v.subgoal);
  w.u8(v.subgoal_final ? 1 : 0);
  w.points(v.route, limits.path_points);
  const std::span<const UnicycleState> traj =
      v.out != nullptr && v.out->planned ? v.out->plan.trajectory : std::span<const UnicycleState>{};
  const std::size_t nt = std::min(traj.size(), limits.trajectory);
  w.u32(static_cast<std::uint32_t>(nt));
  // For the plots only (never compared): single precision, half the bytes of the record's bulk.
  for (std::size_t i = 0; i < nt; ++i) {
    for (const double x : {traj[i].x, traj[i].y, traj[i].theta, traj[i].v, traj[i].w}) w.put(static_cast<float>(x));
  }
  return w.overflow() ? 0 : w.size();
}

CycleRecord decodeCycle(std::span<const std::byte> data, const std::string& where) {
  Reader r(data, where);
  CycleRecord c;
  const std::uint16_t version = r.u16("version");
  if (version != kCycleEncodingVersion) {
    throw RecordError(where + ": cycle encoding version " + std::to_string(version) + ", this reader reads version " +
                      std::to_string(kCycleEncodingVersion));
  }
  c.agent = r.u16("agent");
  c.cycle = r.u64("cycle");
  c.time_ns = r.i64("time_ns");
  c.map_sequence = r.u32("map_sequence");
  c.step = enumIn<StepKind>(r.u8("step"), 2, "step", where);
  c.fault = r.u8("fault");
  c.flags = r.u8("flags");
  r.u8("reserved");
  c.has_goal = r.u8("memory.has_goal") != 0;
  c.state = enumIn<CycleState>(r.u8("memory.state"), 3, "memory.state", where);
  c.held_valid = r.u8("memory.held_valid") != 0;
  c.route_bits = r.u8("memory.route");
  c.path_misses = r.i32("memory.path_misses");
  c.goal = r.pose("memory.goal");
  c.robot = r.state("robot");
  c.budget.wall_clock = r.u8("budget.kind") != 0;
  r.u8("reserved");
  r.u8("reserved");
  r.u8("reserved");
  c.budget.max_pops = r.u32("budget.max_pops");
  c.budget.limit_ns = r.i64("budget.limit_ns");
  c.budget.cut.cut_read = r.i64("budget.cut_read");
  c.budget.cut.reads = r.u32("budget.reads");
  const std::uint32_t n = r.count("obstacles", 4 + 24);
  c.obstacles.resize(n);
  for (RecordedObstacle& o : c.obstacles) {
    o.polygon = r.points("obstacle vertices");
    const double vx = r.f64("obstacle velocity");
    o.velocity = Vec2(vx, r.f64("obstacle velocity"));
    o.turn_rate = r.f64("obstacle turn rate");
  }
  if (c.flags & kHeldPath) c.held_path = r.points("held path");
  StepOutputs& o = c.out;
  o.v_cmd = r.f64("v_cmd");
  o.w_cmd = r.f64("w_cmd");
  o.state = enumIn<CycleState>(r.u8("state"), 3, "state", where);
  o.path_status = enumIn<PathStatus>(r.u8("path_status"), static_cast<std::uint8_t>(PathStatus::kAborted),
                                     "path_status", where);
  const std::uint8_t of = r.u8("output flags");
  o.path_dynamic = (of & 1) != 0;
  o.path_held = (of & 2) != 0;
  o.planned = (of & 4) != 0;
  o.outcome = enumIn<PlanResult::Outcome>(r.u8("plan outcome"), 3, "plan outcome", where);
  o.path_length = r.f64("path_length");
  o.obstacles_dropped = r.u32("obstacles_dropped");
  o.first_action.a = r.f64("first action");
  o.first_action.b = r.f64("first action");
  o.best = r.state("best");
  o.best_h = r.f64("best_h");
  o.brake_safe_actions = r.u32("brake_safe_actions");
  o.tier = r.u8("tier");
  o.depth = r.i32("depth");
  o.pops = r.u32("pops");
  o.expansions = r.u32("expansions");
  o.successors = r.u32("successors");
  o.collisions = r.u32("collisions");
  o.heuristic_calls = r.u32("heuristic_calls");
  c.path_ns = r.i64("path_ns");
  c.local_ns = r.i64("local_ns");
  c.plan_ns = r.i64("plan_ns");
  c.command.v = r.f64("command.v");
  c.command.w = r.f64("command.w");
  c.command.brake = r.u8("command.brake") != 0;
  c.command.next_v = r.f64("command.next_v");
  c.command.next_w = r.f64("command.next_w");
  c.command.next_brake = r.u8("command.next_brake") != 0;
  c.subgoal = r.pose("subgoal");
  c.subgoal_final = r.u8("subgoal_final") != 0;
  c.route = r.points("route");
  const std::uint32_t nt = r.count("trajectory", 20);
  c.trajectory.resize(nt);
  for (UnicycleState& s : c.trajectory) {
    s.x = r.get<float>("trajectory");
    s.y = r.get<float>("trajectory");
    s.theta = r.get<float>("trajectory");
    s.v = r.get<float>("trajectory");
    s.w = r.get<float>("trajectory");
  }
  if (r.left() != 0) {
    throw RecordError(where + ": " + std::to_string(r.left()) + " bytes after the end of the cycle record");
  }
  return c;
}

ControlCycle::Memory CycleRecord::memory() const {
  ControlCycle::Memory m;
  if (has_goal) m.goal = goal;
  m.state = state;
  m.held_valid = held_valid;
  m.path_misses = path_misses;
  m.held_passage = (route_bits & 1) != 0;
  m.route_chosen = (route_bits & 2) != 0;
  m.route_in_passage = (route_bits & 4) != 0;
  m.held_path = held_path;
  return m;
}

}  // namespace staa::record
