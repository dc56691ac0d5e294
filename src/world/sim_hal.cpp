#include "world/sim_hal.hpp"

#include "geometry/polygon.hpp"
#include "geometry/splitmix64.hpp"
#include "path/global_path.hpp"
#include "world/world.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa::hal {
namespace {

// Margin between a mover's square and the map's obstacles on its walk (m): the square's
// corners, not only its centre, stay this far from every wall.
constexpr double kMoverMargin = 0.05;
// Walks shorter than this make a mover that hardly moves (m).
constexpr double kMinWalk = 1.0;
// Ends of a walk stay at least this far from the robot's start (m), so the robot does not
// begin its life inside a person.
constexpr double kStartKeepAway = 1.0;
// Pairs of places tried per mover before giving up on the map.
constexpr int kTriesPerMover = 200;
// A gap between two reads longer than this (a debugger, a suspended process) is not caught
// up: the world pauses for the rest, instead of a real-time thread stepping for seconds.
constexpr double kMaxCatchUpS = 1.0;
// Bounds on the simulation step: finer than 0.1 ms would make the catch-up above cost
// > 10,000 steps; coarser than 1 s is no simulation of a controller running at 30 Hz.
constexpr double kMinStepS = 1e-4;
constexpr double kMaxStepS = 1.0;
// Shortest text that reads back to the same double.
std::string number(double v) {
  std::array<char, 64> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  return std::string(buf.data(), r.ptr);
}

std::string describePose(const Pose2& p) {
  std::string s = "(";
  s.append(number(p.x)).append(", ").append(number(p.y)).append(", ").append(number(p.theta)).append(")");
  return s;
}

std::string mapName(const PolygonMap& map) {
  std::string s = "map '";
  s.append(map.name).append("'");
  return s;
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("SimHal: " + what); }

void validate(const SimHalConfig& c, const RobotProfile& robot) {
  const auto field = [](const char* name, double value, const char* rule) {
    fail(std::string("config.") + name + " must be " + rule + ", got " + number(value));
  };
  if (!std::isfinite(c.start.x) || !std::isfinite(c.start.y) || !std::isfinite(c.start.theta)) {
    fail("config.start must be finite, got " + describePose(c.start));
  }
  if (c.movers < 0 || c.movers > static_cast<int>(ObstacleFrame::kMaxObstacles)) {
    fail("config.movers must be in 0.." + std::to_string(ObstacleFrame::kMaxObstacles) + ", got " +
         std::to_string(c.movers));
  }
  if (!(c.mover_speed > 0.0) || !std::isfinite(c.mover_speed)) field("mover_speed", c.mover_speed, "finite and > 0 (m/s)");
  if (!(c.mover_radius > 0.0) || !std::isfinite(c.mover_radius)) field("mover_radius", c.mover_radius, "finite and > 0 (m)");
  if (!(c.obstacle_rate_hz > 0.0) || !std::isfinite(c.obstacle_rate_hz)) {
    field("obstacle_rate_hz", c.obstacle_rate_hz, "finite and > 0 (Hz)");
  }
  if (!(c.sensor_range_m > 0.0) || std::isnan(c.sensor_range_m)) field("sensor_range_m", c.sensor_range_m, "> 0 (m)");
  if (!(c.max_step_s >= kMinStepS && c.max_step_s <= kMaxStepS)) field("max_step_s", c.max_step_s, "in [0.0001, 1] (s)");
  if (robot.footprint.size() < 3) {
    fail("robot profile '" + robot.name + "': footprint has " + std::to_string(robot.footprint.size()) +
         " vertices, needs at least 3");
  }
}

// The area random places are drawn from when the map has no goals: its bounds, else the box
// around its obstacles, else 10 m around the start.
Box placeArea(const PolygonMap& map, const Pose2& start) {
  if (map.bounds) return *map.bounds;
  Box area{start.position() - Vec2(5.0, 5.0), start.position() + Vec2(5.0, 5.0)};
  bool first = true;
  for (const Polygon& o : map.obstacles) {
    const Box b = boundingBox(o);
    if (first) area = b;
    area.min = area.min.cwiseMin(b.min);
    area.max = area.max.cwiseMax(b.max);
    first = false;
  }
  return area;
}

// The movers' walks: shortest paths among the map's obstacles, grown by the square's reach
// plus a margin, between places of the map chosen from the seed.
std::vector<Mover> planMovers(const PolygonMap& map, const RobotProfile& robot, const SimHalConfig& config) {
  std::vector<Mover> movers;
  if (config.movers == 0) return movers;
  const double r = config.mover_radius;
  const double reach = r * std::sqrt(2.0);  // centre to a corner of the square
  GlobalPathOptions options;
  options.inflation_radius_m = reach + kMoverMargin;
  GlobalPathPlanner planner(map, options);
  const Box area = placeArea(map, config.start);
  // Far enough that neither the 1 m rule nor the shapes let a mover start on the robot.
  const double keep_away = std::max(kStartKeepAway, robot.circumradius() + reach + kMoverMargin);
  const Vec2 start = config.start.position();
  const Polygon square{{-r, -r}, {r, -r}, {r, r}, {-r, r}};

  const std::vector<Polygon>& grown = planner.inflatedObstacles();
  std::vector<Box> grown_boxes;
  grown_boxes.reserve(grown.size());
  for (const Polygon& g : grown) grown_boxes.push_back(boundingBox(g));
  const auto roomy = [&](const Vec2& p) {
    if (planner.insideRealObstacle(p)) return false;
    for (std::size_t i = 0; i < grown.size(); ++i) {
      if (grown_boxes[i].contains(p) && locatePoint(p, grown[i]) != Containment::kOutside) return false;
    }
    return true;
  };

  SplitMix64 rng(config.seed);
  const auto pick = [&]() -> Vec2 {
    if (!map.goals.empty()) return map.goals[rng.below(map.goals.size())];
    return {rng.uniform(area.min.x(), area.max.x()), rng.uniform(area.min.y(), area.max.y())};
  };
  const int tries = kTriesPerMover * config.movers;
  for (int t = 0; t < tries && movers.size() < static_cast<std::size_t>(config.movers); ++t) {
    const Vec2 a = pick();
    const Vec2 b = pick();
    if ((a - b).norm() < kMinWalk) continue;
    // Both ends must have room for the mover (outside the grown obstacles M'): a place
    // closer to a wall is skipped, rather than walked to as near as the planner can.
    if (!roomy(a) || !roomy(b)) continue;
    const GlobalPath path = planner.plan(a, b);
    if (path.status != PathStatus::kFound) continue;
    // Should the planner still have moved an end to its free neighbour (a place on the
    // very edge of M'), it adds the original point at that end: drop it.
    std::size_t first = path.start_moved ? 1 : 0;
    std::size_t last = path.path.size() - (path.goal_moved ? 1 : 0);
    if (last < first + 2) continue;
    std::vector<Vec2> waypoints(path.path.begin() + static_cast<std::ptrdiff_t>(first),
                                path.path.begin() + static_cast<std::ptrdiff_t>(last));
    double length = 0.0;
    for (std::size_t k = 1; k < waypoints.size(); ++k) length += (waypoints[k] - waypoints[k - 1]).norm();
    if (length < kMinWalk) continue;
    if ((waypoints.front() - start).norm() < keep_away || (waypoints.back() - start).norm() < keep_away) continue;
    movers.push_back(Mover{square, std::move(waypoints), config.mover_speed});
  }
  if (movers.size() < static_cast<std::size_t>(config.movers)) {
    fail(mapName(map) + ": found free walks for only " + std::to_string(movers.size()) + " of config.movers = " +
         std::to_string(config.movers) + " movers in " + std::to_string(tries) + " tries (config.mover_radius = " +
         number(r) + " m; config.seed = " + std::to_string(config.seed) + ")");
  }
  return movers;
}

}  // namespace

// ---- the base: the world's robot, stepped by the base I/O thread ----

class SimHal::SimBase final : public Base {
 public:
  SimBase(SimHal& hal, const SimHalConfig& config, rt::Nanos start_time)
      : hal_(hal), world_(*hal.world_), max_step_s_(config.max_step_s), range_(config.sensor_range_m) {
    // The movers' shapes, copied once into fixed storage: read() places them without the
    // allocating World::moverPolygon.
    shapes_.resize(world_.moverCount());
    for (std::size_t i = 0; i < world_.moverCount(); ++i) {
      const Polygon& p = world_.mover(i).polygon;
      shapes_[i].n = std::min(p.size(), ObstacleFrame::kMaxVertices);
      std::copy_n(p.begin(), shapes_[i].n, shapes_[i].vertices.begin());
    }
    stamp_ = start_time;
    report(start_time);
  }

  void read(rt::Nanos now) override {
    // The first read only sets the time; a clock that went backwards steps nothing.
    if (last_read_ >= 0 && now > last_read_) integrate(now - last_read_);
    if (last_read_ < 0 || now > last_read_) last_read_ = now;
    stamp_ = last_read_;
    hal_.collisions_.store(world_.collisionEpisodes());
    if (!hal_.freeze_odometry_.load()) report(stamp_);
    publishMovers(stamp_);
  }

  void write(rt::Nanos now, const VelocityCommand& command) override {
    // World::step throws on non-finite commands; a NaN from upstream is a stop, not a crash.
    const bool stop = command.brake || !std::isfinite(command.v) || !std::isfinite(command.w);
    v_cmd_ = stop ? 0.0 : command.v;
    w_cmd_ = stop ? 0.0 : command.w;
    sent_ = {command.stamp, now};  // no wire: the world takes it at the write
  }

  CommandSent lastCommandSent() const override { return sent_; }

  Odometry odometry() const override { return odometry_; }

  BaseStatus status() const override {
    BaseStatus s;
    s.stamp = stamp_;
    s.enabled = true;
    return s;
  }

  bool setPose(const Pose2& pose) override {
    if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.theta)) return false;
    const Pose2 p{pose.x, pose.y, wrapAngle(pose.theta)};
    if (world_.collides(p)) return false;
    world_.setRobotState(RobotState{p, 0.0, 0.0});
    if (!hal_.freeze_odometry_.load()) report(odometry_.stamp);
    return true;
  }

  // The movers the robot's sensor sees now, into the triple buffer.
  void publishMovers(rt::Nanos stamp) {
    ObstacleFrame& f = hal_.movers_.writeBuffer();
    f.stamp = stamp;
    f.sequence = ++published_;
    f.count = 0;
    f.dropped = 0;
    const Vec2 robot = world_.robot().pose.position();
    for (std::size_t i = 0; i < shapes_.size(); ++i) {
      const Vec2 centre = world_.moverPosition(i);
      if ((centre - robot).norm() > range_) continue;
      if (f.count == ObstacleFrame::kMaxObstacles) {
        ++f.dropped;
        continue;
      }
      ObstacleFrame::Obstacle& o = f.obstacles[f.count++];
      const Shape& shape = shapes_[i];
      o.n = shape.n;
      for (std::size_t k = 0; k < shape.n; ++k) o.vertices[k] = shape.vertices[k] + centre;
      o.velocity = world_.moverVelocity(i);
    }
    hal_.movers_.publish();
  }

 private:
  struct Shape {
    std::array<Vec2, ObstacleFrame::kMaxVertices> vertices{};
    std::size_t n = 0;
  };

  // Equal steps of at most max_step_s over the gap, with the last command held.
  void integrate(rt::Nanos gap) {
    const double gap_s = std::min(static_cast<double>(gap) * 1e-9, kMaxCatchUpS);
    const int steps = std::max(1, static_cast<int>(std::ceil(gap_s / max_step_s_ - 1e-9)));
    const double dt = gap_s / steps;
    for (int k = 0; k < steps; ++k) world_.step(dt, v_cmd_, w_cmd_);
  }

  void report(rt::Nanos stamp) {
    const RobotState& s = world_.robot();
    odometry_.stamp = stamp;
    odometry_.pose = s.pose;
    odometry_.v = s.v;
    odometry_.w = s.w;
  }

  SimHal& hal_;
  World& world_;
  double max_step_s_;
  double range_;
  std::vector<Shape> shapes_;
  rt::Nanos last_read_ = -1;
  rt::Nanos stamp_ = -1;
  double v_cmd_ = 0.0;
  double w_cmd_ = 0.0;
  CommandSent sent_;
  // The last odometry report: while frozen it stays as it was (a stalled odometry stream),
  // though the world moves on; unfrozen, the next read reports the truth again.
  Odometry odometry_;
  std::uint64_t published_ = 0;
};

// ---- the obstacle sensor: the latest movers, rate-limited, on the perception thread ----

class SimHal::SimObstacles final : public ObstacleSensor {
 public:
  SimObstacles(SimHal& hal, const SimHalConfig& config)
      : hal_(hal),
        period_(std::max<rt::Nanos>(1, std::llround(1e9 / config.obstacle_rate_hz))),
        tolerance_(period_ / 20),
        movers_only_(config.movers_only) {}

  bool read(rt::Nanos now, ObstacleFrame& out) override {
    // No SimBase steps the world: this (perception) thread is its only user, and advances it
    // with the world's robot standing still.
    if (movers_only_) hal_.base_->read(now);
    if (hal_.freeze_obstacles_.load()) return false;
    // A fixed schedule (due times a period apart), not "a period since the last frame":
    // polled at 100 Hz, a 30 Hz camera gives 30 frames a second, not 25.
    if (next_due_ >= 0 && now < next_due_ - tolerance_) return false;
    if (hal_.movers_.update()) has_frame_ = true;
    if (!has_frame_) return false;
    out = hal_.movers_.readBuffer();
    out.stamp = now;
    out.sequence = ++sequence_;
    next_due_ = (next_due_ < 0 ? now : next_due_) + period_;
    if (next_due_ <= now) next_due_ = now + period_;  // fell behind: skip, do not burst
    return true;
  }

 private:
  SimHal& hal_;
  rt::Nanos period_;
  rt::Nanos tolerance_;  // a poll this much early still takes its frame (wake-up jitter)
  bool movers_only_;
  rt::Nanos next_due_ = -1;
  bool has_frame_ = false;
  std::uint64_t sequence_ = 0;
};

// ---- SimHal ----

SimHal::SimHal(const PolygonMap& map, const RobotProfile& robot, const SimHalConfig& config, rt::Nanos start_time) {
  validate(config, robot);
  {
    // The start against the map alone first, so the message says which it hit.
    const World empty(map, robot, config.start);
    if (empty.collides(config.start)) {
      fail("config.start " + describePose(config.start) + " collides with an obstacle of " + mapName(map) +
           " or reaches its bounds (robot '" + robot.name + "')");
    }
  }
  world_ = std::make_unique<World>(map, robot, config.start, planMovers(map, robot, config));
  if (world_->collides(config.start)) {
    fail("config.start " + describePose(config.start) + " collides with a mover at the start time");
  }
  base_ = std::make_unique<SimBase>(*this, config, start_time);
  obstacles_ = std::make_unique<SimObstacles>(*this, config);
  movers_only_ = config.movers_only;
  // A first frame, so perception has the movers before the base thread's first read.
  base_->publishMovers(start_time);
}

SimHal::~SimHal() = default;

Base& SimHal::base() {
  // Two threads would step one world: with movers_only the obstacle sensor owns it.
  if (movers_only_) {
    throw std::logic_error("SimHal: base() is not available with movers_only (the obstacle sensor steps the world)");
  }
  return *base_;
}
ObstacleSensor& SimHal::obstacles() { return *obstacles_; }
const World& SimHal::world() const { return *world_; }

}  // namespace staa::hal
