#include "planner/staa_star.hpp"
#include "planner/collision.hpp"

#include "geometry/clipper_ops.hpp"
#include "geometry/convex.hpp"
#include "geometry/polygon.hpp"
#include "path/global_path.hpp"
#include "path/polygon_set.hpp"

#include <bit>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace staa {
namespace {

Polygon box(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

// Everything a plan() needs around a fixed set of real obstacles.
struct Bench {
  RobotProfile robot;
  std::vector<Polygon> real;
  std::vector<Polygon> inflated;
  PolygonSet real_set;
  LocalMap local;
  DynamicObstacleSet obstacles{8};
  StaaConfig config;

  Bench(RobotProfile r, std::vector<Polygon> obstacles_in, double inflation) : robot(std::move(r)), real(std::move(obstacles_in)) {
    inflated = inflateEachToSimple(real, inflation + 0.03, 0.03);
    real_set.assign(std::span<const Polygon>(real), PolygonSet::Options{0.5});
    config.heuristic.static_inflation_m = inflation;
    config.heuristic.dynamic_inflation_m = inflation;
  }
  StaaStar planner() const { return StaaStar(config, robot, inflated, local.config()); }
  void update(const UnicycleState& s, const Vec2& goal) {
    const Vec2 path[] = {s.position(), goal};
    local.update(s.pose(), real_set, path, 0.0);
  }
};

RobotProfile smallFastRobot() {
  // A 20 cm square robot at the paper's limits: 0.6 m per 0.3 s step, three times its size.
  RobotProfile r;
  r.name = "small";
  r.footprint = box(-0.1, -0.1, 0.1, 0.1);
  r.limits = MotionLimits{2.0, -1.0, 3.0, 2.0, 6.0};
  return r;
}

// The paper's weakness: collisions checked only at end poses 0.3 s apart let a fast robot jump
// a thin wall. Ours checks the motion in between.
TEST(StaaStar, NoTunnellingThroughAFiveCentimetreWall) {
  Bench bench(smallFastRobot(), {box(1.0, -3.0, 1.05, 3.0)}, 0.15);
  const UnicycleState start{0.0, 0.0, 0.0, 2.0, 0.0};
  bench.update(start, Vec2(5.0, 0.0));
  auto crosses = [](std::span<const UnicycleState> traj) {
    for (std::size_t i = 1; i < traj.size(); ++i) {
      const bool before = traj[i - 1].x < 1.0, after = traj[i].x > 1.05;
      if (before && after && std::abs(traj[i].y) < 3.0 && std::abs(traj[i - 1].y) < 3.0) return true;
    }
    return false;
  };
  bench.config.check_swept = false;
  bench.config.brake_safety = false;  // the paper's planner: no braking check of the first action
  StaaStar endpoints_only = bench.planner();
  const PlanResult jumped = endpoints_only.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(400));
  EXPECT_TRUE(crosses(jumped.trajectory)) << "the end-pose check should show the original's weakness";

  bench.config.check_swept = true;
  bench.config.brake_safety = true;
  StaaStar swept = bench.planner();
  const PlanResult safe = swept.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(400));
  EXPECT_FALSE(crosses(safe.trajectory));
  int edges_through = 0;
  swept.forEachEdge([&](const UnicycleState& a, const UnicycleState& b) {
    edges_through += a.x < 1.0 && b.x > 1.05 && std::abs(a.y) < 3.0 && std::abs(b.y) < 3.0;
  });
  EXPECT_EQ(edges_through, 0);
}

// Every successor collides (too fast, too close to a wall): the planner brakes at the limits.
TEST(StaaStar, BrakesWhenEverySuccessorCollides) {
  Bench bench(paperAgentProfile(), {box(0.9, -4.0, 1.2, 4.0)}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 2.0, 1.0};
  bench.update(start, Vec2(5.0, 0.0));
  StaaStar planner = bench.planner();
  const PlanResult r = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(500));
  EXPECT_EQ(r.outcome, PlanResult::Outcome::kBrake);
  EXPECT_EQ(r.depth, 0);
  // Deceleration at the limits, towards (0, 0).
  EXPECT_DOUBLE_EQ(r.first_action.a, -2.0);
  EXPECT_DOUBLE_EQ(r.first_action.b, -1.0 / 0.3);
  const Action b = brakeAction(UnicycleState{0, 0, 0, 0.3, -0.5}, bench.robot.limits, 0.3);
  EXPECT_DOUBLE_EQ(b.a, -1.0);  // not past zero within the step
  EXPECT_NEAR(b.b, 0.5 / 0.3, 1e-12);
}

// The passive tier's heading spread grows a moving obstacle by the angle times the distance
// it has moved, so a mover predicted to pass 0.5 m beside the robot counts as in the way when
// its heading is uncertain; a standing obstacle does not grow.
TEST(CollisionChecker, HeadingSpreadGrowsAMovingObstacleByTheDistanceItMoved) {
  const CollisionChecker checker(paperAgentProfile(), LocalMapConfig{}, 0.02);
  const Pose2 robot{0.0, 0.0, 0.0};  // footprint up to y = 0.25
  DynamicObstacleSet movers(4);
  const Polygon passing = box(-1.2, 0.8, -0.8, 1.2);  // at t = 1 s: x in [-0.2, 0.2], 0.55 m above
  const Polygon standing = box(-0.2, 0.85, 0.2, 1.25);
  const PolygonView views[] = {PolygonView{passing.data(), passing.size()}};
  const Vec2 velocity[] = {Vec2(1.0, 0.0)};
  movers.set(views, velocity);
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, 1.0));
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, 1.0, 0.3));   // grown 0.3 m: still clear
  EXPECT_FALSE(checker.poseFreeDynamic(robot, movers, 1.0, 0.6));  // grown 0.6 m: in the way
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, 0.0, 0.6));   // not moved yet: not grown

  DynamicObstacleSet still(4);
  const PolygonView still_views[] = {PolygonView{standing.data(), standing.size()}};
  const Vec2 zero[] = {Vec2(0.0, 0.0)};
  still.set(still_views, zero);
  EXPECT_TRUE(checker.poseFreeDynamic(robot, still, 1.0, 0.6));
}

// An agent 2 m ahead driving across at 1.5 m/s and turning towards the robot at 1.5 rad/s
// (radius 1 m): on its straight line it passes 2 m ahead; on its circle it comes round to
// the robot's side of the road. The passive check with `turning` sees it there, without it
// does not; an obstacle that does not turn is the same either way.
TEST(CollisionChecker, TurningObstaclesAreAlsoCheckedOnTheirCircle) {
  const CollisionChecker checker(paperAgentProfile(), LocalMapConfig{}, 0.02);
  const Polygon agent = box(1.6, -2.2, 2.4, -1.8);  // centre (2, -2), heading +y
  const PolygonView views[] = {PolygonView{agent.data(), agent.size()}};
  const Vec2 velocity[] = {Vec2(0.0, 1.5)};
  const double turn[] = {1.5};  // left, towards -x: centre of the circle at (1, -2)
  DynamicObstacleSet movers(4);
  movers.set(views, velocity, turn);
  // After pi/3 s it has turned by pi/2: centre at (1, -1), heading -x. Straight: at (2, -0.43).
  const double t = kPi / 3.0;
  const Pose2 robot{1.0, -1.0, 0.0};
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, t));
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, t, 0.0, false));
  EXPECT_FALSE(checker.poseFreeDynamic(robot, movers, t, 0.0, true));
  // Where the straight line goes, it is still in the way with `turning` (both predictions).
  EXPECT_FALSE(checker.poseFreeDynamic(Pose2{2.0, -0.43, kPi / 2.0}, movers, t, 0.0, true));
  // And over a motion: standing at (1, -1) for the first 1.2 s.
  const UnicycleState standing{1.0, -1.0, 0.0, 0.0, 0.0};
  const ArcVelocities still{0.0, 0.0, 0.0, 0.0};
  EXPECT_TRUE(checker.motionFreeDynamic(standing, still, 1.2, movers, 0.0, 0.0, false));
  EXPECT_FALSE(checker.motionFreeDynamic(standing, still, 1.2, movers, 0.0, 0.0, true));
  const double no_turn[] = {0.0};
  movers.set(views, velocity, no_turn);
  EXPECT_TRUE(checker.poseFreeDynamic(robot, movers, t, 0.0, true));
}

// Head-on with another agent (an 0.8 m body at 1.8 m/s towards the robot, which goes 1.8 m/s
// too): far away, some first action passes a braking check; close, none does, and the robot
// must not keep its speed. It may only take the least bad actions: those after which braking
// meets the agent latest (before, every action was allowed then, and two agents in the
// experiment sped up towards each other once neither could stop in time).
TEST(StaaStar, WhenNoFirstActionCanStopInTimeItSlowsDownInsteadOfKeepingItsSpeed) {
  auto planAt = [](double gap_x) {
    Bench bench(paperAgentProfile(), {}, 0.5);
    const Polygon agent = box(gap_x - 0.4, -0.4, gap_x + 0.4, 0.4);
    const PolygonView views[] = {PolygonView{agent.data(), agent.size()}};
    const Vec2 velocities[] = {Vec2(-1.8, 0.0)};
    bench.obstacles.set(views, velocities);
    const UnicycleState start{0.0, 0.0, 0.0, 1.8, 0.0};
    bench.update(start, Vec2(9.0, 0.0));
    StaaStar planner = bench.planner();
    return planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(1000));
  };
  const PlanResult far = planAt(7.5);
  EXPECT_GE(far.brake_safety_tier, 1);
  EXPECT_GT(far.brake_safe_actions, 0u);

  const PlanResult close = planAt(2.6);
  EXPECT_EQ(close.brake_safety_tier, 0);
  EXPECT_GT(close.brake_safe_actions, 0u);
  EXPECT_LT(close.brake_safe_actions, 49u);
  EXPECT_LT(close.first_action.a, 0.0) << "linear acceleration of the chosen first action";
}

// Another agent stands nose to nose with the robot, touching it (the goal lies beyond it):
// every motion touches that obstacle, so without separate_contacts (the default) the planner
// brakes and the robot stays for good. With it the first action backs the robot away from the
// contact, and the rest of the plan goes round it; a moving robot is left to brake first.
TEST(StaaStar, ARobotTouchingAMovingObstacleMovesAwayFromItInsteadOfStaying) {
  Bench bench(paperAgentProfile(), {}, 0.5);
  const Polygon other = box(0.4, -0.3, 1.2, 0.3);  // the robot's front edge is x = 0.4
  const PolygonView views[] = {PolygonView{other.data(), other.size()}};
  const Vec2 velocities[] = {Vec2(0.0, 0.0)};
  bench.obstacles.set(views, velocities);
  const UnicycleState start{0.0, 0.0, 0.0, 0.0, 0.0};
  bench.update(start, Vec2(4.0, 0.0));

  StaaStar stays = bench.planner();
  const PlanResult stuck = stays.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(1000));
  EXPECT_EQ(stuck.outcome, PlanResult::Outcome::kBrake);
  EXPECT_EQ(stuck.contacts, 0);

  bench.config.separate_contacts = true;
  StaaStar moves = bench.planner();
  const PlanResult r = moves.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(1000));
  EXPECT_EQ(r.contacts, 1);
  EXPECT_NE(r.outcome, PlanResult::Outcome::kBrake);
  ASSERT_GE(r.trajectory.size(), 2u);
  // Backing away: the first step ends behind the start, farther from the other's centre.
  EXPECT_LT(r.first_action.a, 0.0);
  EXPECT_LT(r.trajectory[1].x, start.x);
  EXPECT_GT((r.trajectory[1].position() - Vec2(0.8, 0.0)).norm(), 0.8);

  // Still moving (0.5 m/s towards it): braking comes first, nothing is left out.
  const UnicycleState moving{0.0, 0.0, 0.0, 0.5, 0.0};
  EXPECT_EQ(moves.plan(moving, bench.local, bench.obstacles, PlannerBudget::expansions(1000)).contacts, 0);

  // Beyond the margin every motion check keeps (the sample step and 2 cm): nothing is left out.
  const Polygon apart = box(0.55, -0.3, 1.35, 0.3);
  const PolygonView apart_views[] = {PolygonView{apart.data(), apart.size()}};
  bench.obstacles.set(apart_views, velocities);
  EXPECT_EQ(moves.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(1000)).contacts, 0);
}

TEST(StaaStar, AbortsWithinBudgetAndReturnsTheLowestHeuristicState) {
  Bench bench(paperAgentProfile(), {box(3.0, -0.5, 3.5, 0.5)}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 0.0, 0.0};
  bench.update(start, Vec2(5.5, 0.0));
  StaaStar planner = bench.planner();
  const PlanResult r = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(60));
  EXPECT_EQ(r.outcome, PlanResult::Outcome::kAborted);
  EXPECT_EQ(r.stats.pops, 60u);
  EXPECT_EQ(r.stats.successors, r.stats.expansions * 49u);
  // The returned state is the one with the lowest h of all generated states.
  double lowest = 1e18;
  int nodes = 0;
  planner.forEachEdge([&](const UnicycleState&, const UnicycleState& b) {
    lowest = std::min(lowest, planner.heuristic().evaluate(b, 4));  // depth > 3: static h
    ++nodes;
  });
  EXPECT_GT(nodes, 100);
  EXPECT_NEAR(planner.heuristic().evaluate(r.best, 4), lowest, 1e-9);
  ASSERT_GE(r.trajectory.size(), 2u);
  EXPECT_EQ(r.trajectory.front().x, start.x);
  // The first action leads from the start to the trajectory's second state.
  const UnicycleState first = predictArc(start, r.first_action, 0.3, bench.robot.limits);
  EXPECT_NEAR(first.x, r.trajectory[1].x, 1e-12);
  EXPECT_NEAR(first.y, r.trajectory[1].y, 1e-12);
}

TEST(StaaStar, FinishesEarlyWhenTheGoalIsReachable) {
  Bench bench(paperAgentProfile(), {}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 0.0, 0.0};
  bench.update(start, Vec2(1.5, 0.0));  // G~ = G, inside the box
  StaaStar planner = bench.planner();
  const PlanResult r = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(5000));
  EXPECT_EQ(r.outcome, PlanResult::Outcome::kFinished);
  EXPECT_LT(r.best_h, 0.1);
  EXPECT_LT(r.stats.pops, 5000u);
  EXPECT_NEAR(r.best.x, 1.5, 0.25);
  EXPECT_LT(std::abs(r.best.v), 0.3);  // it plans to stand at the final goal
}

TEST(StaaStar, AvoidsAPredictedMoverOnItsWay) {
  Bench bench(paperAgentProfile(), {}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 1.5, 0.0};
  // A person crossing from the right, arriving on the robot's line in about 0.6 s.
  const Polygon person = box(1.4, -1.05, 1.9, -0.55);
  const PolygonView views[] = {person};
  const Vec2 velocities[] = {{0.0, 1.3}};
  bench.obstacles.set(views, velocities);
  bench.update(start, Vec2(5.5, 0.0));
  StaaStar planner = bench.planner();
  const PlanResult r = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(1000));
  ASSERT_GE(r.trajectory.size(), 4u);
  FixedPolygon at;
  for (std::size_t d = 1; d <= 3; ++d) {
    bench.obstacles.predict(0, 0.3 * static_cast<double>(d), at);
    Polygon robot;
    for (const Vec2& p : bench.robot.footprint) robot.push_back(r.trajectory[d].pose().transform(p));
    EXPECT_FALSE(convexIntersect(robot, at.view())) << "depth " << d;
  }
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

// The clearance shortcut the heuristic uses must never call a segment free that the exact
// test blocks: random segments in the local box on the office map, against the real
// obstacles grown by the reach it is asked for.
TEST(CollisionChecker, SegmentClearNeverVouchesForABlockedSegment) {
  const PolygonMap office = [] {
    PolygonMap m;
    m.bounds = Box{{0, 0}, {27, 27}};
    // Walls of two rooms and a pillar, enough to make most segments near something.
    m.obstacles = {box(3, 3, 9, 3.12), box(3, 3, 3.12, 9), box(8.88, 3, 9, 5), box(8.88, 6.5, 9, 9), box(5, 5.5, 5.4, 5.9)};
    return m;
  }();
  const double reach = 0.33;
  std::vector<Polygon> real = office.obstacles;
  for (const Polygon& w : boundsWalls(*office.bounds, 1.0)) real.push_back(w);
  const std::vector<Polygon> grown = inflateEachToSimple(real, reach, 0.03);
  PolygonSet real_set, grown_set;
  real_set.assign(std::span<const Polygon>(real), PolygonSet::Options{0.5});
  grown_set.assign(std::span<const Polygon>(grown), PolygonSet::Options{0.5});
  LocalMap local;
  CollisionChecker checker(paperAgentProfile(), local.config());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int vouched = 0, tested = 0;
  for (int pose = 0; pose < 20; ++pose) {
    const Pose2 robot{6.0 + 2.0 * u(rng), 6.0 + 2.0 * u(rng), 3.0 * u(rng)};
    const Vec2 path[] = {robot.position(), robot.position() + Vec2(5, 0)};
    local.update(robot, real_set, path, 0.0);
    checker.prepare(local);
    for (int k = 0; k < 500; ++k) {
      const Vec2 a = robot.transform({2.0 + 4.0 * u(rng), 4.0 * u(rng)});
      const Vec2 b = a + Vec2(3.0 * u(rng), 3.0 * u(rng));
      ++tested;
      if (!checker.segmentClear(a, b, reach)) continue;
      ++vouched;
      ASSERT_FALSE(grown_set.pointBlocked(a)) << a.transpose();
      ASSERT_FALSE(grown_set.segmentBlocked(a, b)) << a.transpose() << " -> " << b.transpose();
    }
  }
  EXPECT_GT(vouched, tested / 10);  // and it does vouch for many
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

// The lazy option evaluates h only for popped states: far fewer queries, the same early
// finish, and the returned state is still the lowest-h one it evaluated.
TEST(StaaStar, LazyHeuristicQueriesFarLessAndStillFinishes) {
  Bench bench(paperAgentProfile(), {}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 0.0, 0.0};
  bench.update(start, Vec2(1.5, 0.0));  // as in FinishesEarlyWhenTheGoalIsReachable
  StaaStar eager = bench.planner();
  const PlanResult a = eager.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(8000));
  bench.config.lazy_heuristic = true;
  StaaStar lazy = bench.planner();
  const PlanResult b = lazy.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(8000));
  EXPECT_EQ(a.outcome, PlanResult::Outcome::kFinished);
  EXPECT_EQ(b.outcome, PlanResult::Outcome::kFinished);
  EXPECT_LT(b.best_h, 0.1);
  EXPECT_LT(b.stats.heuristic_calls * 3, a.stats.heuristic_calls);
  // The lower bound never exceeds the true value (else the order of expansions would change).
  lazy.forEachEdge([&](const UnicycleState&, const UnicycleState& s) {
    EXPECT_LE(lazy.heuristic().lowerBound(s), lazy.heuristic().evaluate(s, 4) + 1e-12);
  });
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

// Two rooms' walls and a pillar, and the local box over them at a pose near the pillar.
struct Walls {
  std::vector<Polygon> real{box(3, 3, 9, 3.12), box(3, 3, 3.12, 9), box(8.88, 3, 9, 5), box(8.88, 6.5, 9, 9),
                            box(5, 5.5, 5.4, 5.9)};
  PolygonSet set;
  LocalMap local;
  Walls() { set.assign(std::span<const Polygon>(real), PolygonSet::Options{0.5}); }
  void at(const Pose2& robot) {
    const Vec2 path[] = {robot.position(), robot.position() + Vec2(5, 0)};
    local.update(robot, set, path, 0.0);
  }
};

// The swept static check looks up every sample of the motion (no point moves more than a
// sample step between two of them) unless a looked-up pose's clearance already covers it.
// The reference here looks up every sample and the end pose, without shortcuts.
bool everySampleFree(const CollisionChecker& checker, const ArcMotion& m) {
  if (!checker.fastPoseFreeStatic({m.x1, m.y1, m.c1, m.s1})) return false;
  const int n = std::max(1, static_cast<int>(std::ceil(checker.travelBound(m) / (0.9 * LocalMapConfig{}.cell_m))));
  const double step = m.w_mid * m.dt / n;
  double cs, ss;
  sinCos(step, cs, ss);
  const bool straight = std::abs(m.w_mid * m.dt) < 1e-6;
  const double r = straight ? 0.0 : m.v_mid / m.w_mid;
  double c = m.c0, sn = m.s0;
  for (int k = 1; k < n; ++k) {
    const double nc = c * cs - sn * ss;
    sn = sn * cs + c * ss;
    c = nc;
    CollisionChecker::FastPose p{0.0, 0.0, c, sn};
    if (straight) {
      const double d = m.v_mid * m.dt * k / n;
      p.x = m.x0 + d * m.c0;
      p.y = m.y0 + d * m.s0;
    } else {
      p.x = m.x0 + r * (sn - m.s0);
      p.y = m.y0 - r * (c - m.c0);
    }
    if (!checker.fastPoseFreeStatic(p)) return false;
  }
  return true;
}

// The clearances of a motion's start (of its footprint, and of a disc of the circumradius about
// its origin) let whole motions, and samples near either end, go without lookups: the answers
// must be those of looking up every sample, on real walls, for the paper's agent's 49 motions
// from many states (near walls and in the open).
TEST(CollisionChecker, SweptStaticCheckWithEndClearancesAnswersAsEverySampleLookedUp) {
  Walls walls;
  const RobotProfile robot = paperAgentProfile();
  CollisionChecker checker(robot, walls.local.config());
  const ActionSet actions(robot.limits, 7);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int shortcut = 0, blocked = 0, motions = 0, turns_in_walls = 0;
  for (int pose = 0; pose < 12; ++pose) {
    const Pose2 centre{6.0 + 2.0 * u(rng), 6.0 + 2.0 * u(rng), 3.0 * u(rng)};
    walls.at(centre);
    checker.prepare(walls.local);
    for (int k = 0; k < 40; ++k) {
      // Every other state stands, so that some motions turn on the spot (the origin does not
      // move: the disc clearance clears them only when there is one).
      const double v = k % 2 == 0 ? 0.0 : 1.5 + 0.5 * u(rng);
      const UnicycleState s{centre.x + 2.0 * u(rng), centre.y + 2.0 * u(rng), 3.0 * u(rng), v, 3.0 * u(rng)};
      double slack = 0.0;
      if (!checker.fastPoseFreeStatic({s.x, s.y, std::cos(s.theta), std::sin(s.theta)}, &slack)) continue;
      for (std::size_t a = 0; a < actions.size(); ++a) {
        const ArcVelocities vel = arcVelocities(s, actions[a], 0.3, robot.limits);
        const double dth = vel.w_mid * 0.3;
        const ArcMotion m = makeArcMotion(s, std::cos(s.theta), std::sin(s.theta), vel.v_mid, vel.w_mid, 0.3,
                                          std::cos(dth), std::sin(dth));
        double end_slack = -2.0;
        const bool fast = checker.motionFreeStatic(m, slack, &end_slack, checker.discSlack(s.x, s.y));
        const bool reference = everySampleFree(checker, m);
        ASSERT_EQ(fast, reference) << "state " << s.x << ", " << s.y << ", action " << a;
        EXPECT_EQ(checker.motionFreeStatic(m), reference);
        ++motions;
        blocked += reference ? 0 : 1;
        turns_in_walls += m.v_mid == 0.0 && m.w_mid != 0.0 && checker.discSlack(s.x, s.y) == 0.0 ? 1 : 0;
        if (end_slack == -1.0) {
          ++shortcut;
        } else {
          double looked_up = 0.0;
          checker.fastPoseFreeStatic({m.x1, m.y1, m.c1, m.s1}, &looked_up);
          EXPECT_EQ(end_slack, looked_up);
        }
      }
    }
  }
  // Both kinds occur: motions cleared without a lookup, and motions into the walls; and turns
  // on the spot where the disc clearance is 0.
  EXPECT_GT(shortcut, motions / 20);
  EXPECT_GT(blocked, motions / 20);
  EXPECT_GT(turns_in_walls, 20);
}

// A turn on the spot beside a post's corner: the start (heading 0) and the end (heading
// 0.78) are clear of the post, the headings in between sweep the agent's front corner through
// it. The origin does not move and its disc clearance is 0 (the post is nearer than the
// circumradius), so only the looked-up samples can find it.
TEST(CollisionChecker, TurnOnTheSpotIntoAPostCornerIsBlockedWithoutDiscClearance) {
  Walls walls;
  const RobotProfile robot = paperAgentProfile();
  CollisionChecker checker(robot, walls.local.config());
  const UnicycleState s{4.69, 5.19, 0.0, 0.0, 0.0};
  walls.at(Pose2{s.x, s.y, s.theta});
  checker.prepare(walls.local);
  const double w = 2.6, dt = 0.3;
  const ArcMotion m = makeArcMotion(s, 1.0, 0.0, 0.0, w, dt, std::cos(w * dt), std::sin(w * dt));
  double slack = -1.0;
  ASSERT_TRUE(checker.fastPoseFreeStatic({s.x, s.y, 1.0, 0.0}, &slack));
  ASSERT_TRUE(checker.fastPoseFreeStatic({m.x1, m.y1, m.c1, m.s1}));
  ASSERT_EQ(checker.discSlack(s.x, s.y), 0.0);
  ASSERT_LT(slack, checker.travelBound(m));
  EXPECT_FALSE(everySampleFree(checker, m));
  double end_slack = -2.0;
  EXPECT_FALSE(checker.motionFreeStatic(m, slack, &end_slack, checker.discSlack(s.x, s.y)));
  EXPECT_FALSE(checker.motionFreeStatic(m));
}

// A pose is free of the grid when none of the footprint's outline points (no two more than a
// sample step apart) and its centroid lies in an occupied cell; the covering circles and the
// distance field only save lookups. Poses of the paper's agent all over two rooms' walls,
// against every outline point and the centroid looked up.
TEST(CollisionChecker, PoseCheckAnswersAsEveryOutlinePointLookedUp) {
  Walls walls;
  const RobotProfile robot = paperAgentProfile();
  CollisionChecker checker(robot, walls.local.config());
  const Polygon& fp = checker.footprint();
  double area = 0.0;
  Vec2 centroid(0.0, 0.0);
  for (std::size_t i = 0; i < fp.size(); ++i) {
    const double cr = cross(fp[i], fp[(i + 1) % fp.size()]);
    area += cr;
    centroid += (fp[i] + fp[(i + 1) % fp.size()]) * cr;
  }
  centroid /= 3.0 * area;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int blocked = 0, poses = 0;
  for (int box_pose = 0; box_pose < 10; ++box_pose) {
    const Pose2 centre{6.0 + 2.0 * u(rng), 6.0 + 2.0 * u(rng), 3.0 * u(rng)};
    walls.at(centre);
    checker.prepare(walls.local);
    for (int k = 0; k < 400; ++k) {
      // Well inside the box (2 m behind its origin, 6 m ahead, 4 m to each side): every circle's
      // centre is inside the grid.
      const Vec2 at = centre.transform({1.75 + 2.75 * u(rng), 3.0 * u(rng)});
      const Pose2 p{at.x(), at.y(), 3.0 * u(rng)};
      auto occupied = [&](const Vec2& q) {
        int i = 0, j = 0;
        if (!walls.local.cellOf(p.transform(q), i, j)) return false;
        return walls.local.grid()[static_cast<std::size_t>(j * walls.local.width() + i)] != 0;
      };
      bool reference = !occupied(centroid);
      for (const Vec2& q : checker.outline()) reference = reference && !occupied(q);
      ASSERT_EQ(checker.poseFreeStatic(p), reference) << "pose " << p.x << ", " << p.y << ", " << p.theta;
      ++poses;
      blocked += reference ? 0 : 1;
    }
  }
  EXPECT_GT(blocked, poses / 20);
  EXPECT_LT(blocked, poses / 2);
}

// Sorting out the moving obstacles that cannot come near a motion leaves the answer of the
// swept dynamic check as it was with all of them checked at every sample: people walking
// and turning around a robot among them, with and without heading spread and the turning
// prediction; and far ones are sorted out.
TEST(CollisionChecker, NearObstaclesLeaveOutOnlyObstaclesNoSampleCanTouch) {
  const RobotProfile robot = paperAgentProfile();
  const CollisionChecker checker(robot, LocalMapConfig{}, 0.02);
  const ActionSet actions(robot.limits, 7);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int left_out = 0, pairs = 0, hits = 0, motions = 0;
  for (int scene = 0; scene < 30; ++scene) {
    std::vector<Polygon> people;
    std::vector<Vec2> velocities;
    std::vector<double> turns;
    for (int i = 0; i < 8; ++i) {
      const Vec2 c(4.0 * u(rng), 4.0 * u(rng));
      people.push_back(box(c.x() - 0.25, c.y() - 0.25, c.x() + 0.25, c.y() + 0.25));
      velocities.emplace_back(1.5 * u(rng), 1.5 * u(rng));
      turns.push_back(i % 2 == 0 ? 0.0 : 1.5 * u(rng));
    }
    std::vector<PolygonView> views(people.begin(), people.end());
    DynamicObstacleSet movers(8);
    movers.set(views, velocities, turns);
    const UnicycleState s{0.5 * u(rng), 0.5 * u(rng), 3.0 * u(rng), 1.5 + 0.5 * u(rng), 2.0 * u(rng)};
    const double t0 = 0.3 * static_cast<double>(scene % 3);
    for (const double spread : {0.0, 0.2}) {
      for (const bool turning : {false, true}) {
        for (std::size_t a = 0; a < actions.size(); a += 3) {
          const ArcVelocities vel = arcVelocities(s, actions[a], 0.3, robot.limits);
          const CollisionChecker::NearObstacles near =
              checker.nearObstacles(s.position(), std::abs(vel.v_mid) * 0.3, movers, t0, 0.3, spread, turning);
          const CollisionChecker::NearObstacles all{~std::uint64_t{0} >> (64 - movers.size()), near.fastest};
          const bool sorted = checker.motionFreeDynamic(s, vel, 0.3, movers, t0, spread, turning);
          const bool every = checker.motionFreeDynamic(s, vel, 0.3, movers, t0, all, spread, turning);
          ASSERT_EQ(sorted, every) << "scene " << scene << ", action " << a;
          ++motions;
          hits += every ? 0 : 1;
          left_out += static_cast<int>(movers.size()) - std::popcount(near.mask);
          pairs += static_cast<int>(movers.size());
        }
      }
    }
  }
  EXPECT_GT(hits, motions / 20);      // the scenes are crowded enough to hit someone
  EXPECT_GT(left_out, pairs / 4);     // and most people are left out of most checks
  // One person 6 m away, standing: never near a 0.3 s motion; one 1 m away: near.
  const Polygon far_person = box(5.75, -0.25, 6.25, 0.25), close_person = box(0.75, -0.25, 1.25, 0.25);
  const PolygonView two[] = {PolygonView{far_person.data(), far_person.size()}, PolygonView{close_person.data(), close_person.size()}};
  const Vec2 still[] = {Vec2(0.0, 0.0), Vec2(0.0, 0.0)};
  DynamicObstacleSet pair(2);
  pair.set(two, still);
  EXPECT_EQ(checker.nearObstacles(Vec2(0.0, 0.0), 0.6, pair, 0.0, 0.3).mask, 0b10u);
}

// The closed table is cleared between plans: planning the same input twice, and on a fresh
// planner, gives the same search.
TEST(StaaStar, PlanningTheSameInputAgainGivesTheSameSearch) {
  Bench bench(paperAgentProfile(), {box(3.0, -0.5, 3.5, 0.5)}, 0.5);
  const UnicycleState start{0.0, 0.0, 0.0, 1.0, 0.0};
  bench.update(start, Vec2(5.5, 0.0));
  StaaStar planner = bench.planner();
  const PlanResult first = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(300));
  const PlanResult second = planner.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(300));
  StaaStar fresh = bench.planner();
  const PlanResult third = fresh.plan(start, bench.local, bench.obstacles, PlannerBudget::expansions(300));
  for (const PlanResult* r : {&second, &third}) {
    EXPECT_EQ(r->stats.pops, first.stats.pops);
    EXPECT_EQ(r->stats.expansions, first.stats.expansions);
    EXPECT_EQ(r->stats.successors, first.stats.successors);
    EXPECT_EQ(r->best_h, first.best_h);
    EXPECT_EQ(r->first_action.a, first.first_action.a);
    EXPECT_EQ(r->first_action.b, first.first_action.b);
  }
  EXPECT_GT(first.stats.expansions, 100u);
}

}  // namespace
}  // namespace staa
