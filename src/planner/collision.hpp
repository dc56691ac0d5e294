#pragma once
// Collision checking for STAA* (paper, Sec. III-E-3), done better than the original in one
// respect: the whole motion between a node and its child is checked, not only the end pose,
// so a thin wall between two poses 0.3 s apart is found.
//
// Static obstacles: the collision grid C. A distance field of C, computed once per cycle,
// clears most poses with a few circle lookups; the others get the exact grid test of the
// footprint's outline points (every 4.5 cm, finer than a cell, so no cell-wide wall slips
// between two of them) and its centroid. Dynamic obstacles: the footprint polygon against the
// predicted polygons D(t) (SAT for convex footprints, the exact overlap test otherwise),
// after a bounding-circle test. Samples along a motion are close enough that neither the
// robot nor an obstacle moves more than a sample step between two of them, and the footprint
// checked against D(t) is grown by that step, so a contact between samples is not missed.

#include "robot/robot_profile.hpp"
#include "local/dynamic_obstacles.hpp"
#include "local/local_map.hpp"
#include "robot/unicycle.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace staa {

class CollisionChecker {
 public:
  static constexpr std::size_t kMaxCircles = 8;
  static constexpr std::size_t kMaxOutline = 256;

  // `dynamic_clearance_m`: a gap kept to moving obstacles on top of what makes the sampled
  // motion check conservative (the footprint is grown by the sample step plus this).
  CollisionChecker(const RobotProfile& robot, const LocalMapConfig& local, double dynamic_clearance_m = 0.02);

  // Per cycle: the distance field of the local map's grid.
  void prepare(const LocalMap& map);

  // The footprint at `pose` touches no occupied cell.
  bool poseFreeStatic(const Pose2& pose) const;
  // Every pose along the motion from `from` over [0, dt] is free of the grid; samples are
  // close enough that no footprint point moves more than a sample step between them.
  bool motionFreeStatic(const UnicycleState& from, const ArcVelocities& vel, double dt) const;
  bool motionFreeStatic(const ArcMotion& motion) const;
  // The same test, knowing how far every point of the robot may move from the motion's start
  // without touching the grid (`start_slack`, from fastPoseFreeStatic; 0 when unknown): a
  // motion no point of which travels farther is free without a lookup, and the samples within
  // that travel of either end (the end pose's own slack) are not looked up. `end_slack`, when
  // given, receives the end pose's slack, or -1 when the end pose was not looked up.
  // `start_disc` (discSlack of the start; 0 when unknown) clears by the origin's travel alone:
  // every point of the robot stays within the circumradius of the origin, whatever it turns.
  bool motionFreeStatic(const ArcMotion& motion, double start_slack, double* end_slack, double start_disc = 0.0) const;
  // How far the robot's origin may move from (x, y), turning as it likes, before the
  // footprint can touch the grid: the distance field there less the circumradius (0 outside
  // the grid or when closer).
  double discSlack(double x, double y) const {
    const std::ptrdiff_t cell = cellIndex(gridX(x, y), gridY(x, y));
    return cell < 0 ? 0.0 : std::max(0.0, distance_[static_cast<std::size_t>(cell)] - circumradius_);
  }
  // The farthest any point of the robot travels along the motion: its bound on how far a
  // clearance margin must reach.
  double travelBound(const ArcMotion& motion) const {
    return std::abs(motion.v_mid) * motion.dt + std::abs(motion.w_mid) * motion.dt * circumradius_;
  }
  // The footprint at `pose` overlaps none of the obstacles moved to time t. With
  // heading_spread > 0 (rad) each obstacle is grown by heading_spread times the distance it
  // has moved: the room an obstacle needs whose heading is known only to about that angle
  // (one that turns), in proportion to its speed (a slow one barely grows). With `turning`,
  // each obstacle that turns (DynamicObstacleSet::turnRate) must also be clear of it on its
  // circle (predictTurning): the pose is free only if free of both predictions.
  bool poseFreeDynamic(const Pose2& pose, const DynamicObstacleSet& obstacles, double t,
                       double heading_spread = 0.0, bool turning = false) const;
  // The motion, sampled as above, against the obstacles moving over [t0, t0 + dt].
  bool motionFreeDynamic(const UnicycleState& from, const ArcVelocities& vel, double dt,
                         const DynamicObstacleSet& obstacles, double t0, double heading_spread = 0.0,
                         bool turning = false) const;

  // Obstacle k at time t overlaps the footprint at `pose` grown by the dynamic margin (what
  // every motion check above would call a collision).
  bool touches(std::size_t k, const Pose2& pose, const DynamicObstacleSet& obstacles, double t) const {
    bool placed = false;
    return obstacleHits(k, pose, obstacles, t, 0.0, false, placed);
  }

  // Which moving obstacles can come near a motion from `p0` over [t0, t0 + dt] on which the
  // robot's origin travels at most `travel` (heading_spread and turning as poseFreeDynamic):
  // bit k of `mask` is clear when obstacle k fails the bounding-circle tests of every sample
  // of every such motion. Obstacles from kMaskedObstacles on have no bit: they are always
  // checked. `fastest` is the speed that sets motionFreeDynamic's number of samples.
  static constexpr std::size_t kMaskedObstacles = 64;
  struct NearObstacles {
    std::uint64_t mask = 0;
    double fastest = 0.0;
  };
  NearObstacles nearObstacles(const Vec2& p0, double travel, const DynamicObstacleSet& obstacles, double t0, double dt,
                              double heading_spread = 0.0, bool turning = false) const;
  // motionFreeDynamic against the obstacles `near` found for a reach that covers this motion
  // (same heading_spread and turning): the same samples, the same answer, fewer obstacles.
  bool motionFreeDynamic(const UnicycleState& from, const ArcVelocities& vel, double dt,
                         const DynamicObstacleSet& obstacles, double t0, const NearObstacles& near,
                         double heading_spread = 0.0, bool turning = false) const;

  // Distance from the robot's position to the nearest predicted obstacle edge (for Eq. 3);
  // `beyond` when every edge is at least that far.
  double distanceToDynamic(const Vec2& p, const DynamicObstacleSet& obstacles, double t,
                           double beyond = std::numeric_limits<double>::infinity()) const;

  // A pose with its heading's cosine and sine, so that a pose costs one sincos (or none, when
  // a caller steps along an arc by rotation).
  struct FastPose {
    double x, y, c, s;
  };
  // `slack`, when given, receives how far every point of the robot may still move without
  // possibly touching the grid (0 when only the exact outline test cleared the pose).
  bool fastPoseFreeStatic(const FastPose& pose, double* slack = nullptr) const;

  // True when every point of the segment is certainly farther than `radius` from the
  // obstacles of the collision grid (sphere tracing over the distance field). False means
  // "don't know": near an obstacle, outside the local box, or after too many steps.
  bool segmentClear(const Vec2& a, const Vec2& b, double radius) const;

  // Where the local map asks for it (LocalMap::exactStatic: the route runs through a passage
  // only the footprint fits, issue 16), a pose the grid rejects is decided by the exact test of
  // the footprint grown by this margin against the map's real obstacles.
  static constexpr double kExactMargin = 0.01;
  bool exactStatic() const { return exact_ != nullptr; }

  // This cycle's conservative distance (m) from each grid cell to the nearest occupied one.
  std::span<const float> distanceField() const { return distance_; }

  double circumradius() const { return circumradius_; }
  std::span<const Vec2> outline() const { return {outline_.data(), outline_count_}; }
  const Polygon& footprint() const { return footprint_; }

 private:
  int samplesFor(const ArcVelocities& vel, double dt) const;
  // Whether obstacle k at time t (grown and predicted as poseFreeDynamic says) overlaps the
  // footprint at `pose`; `placed` caches the placed footprint across obstacles of one pose.
  bool obstacleHits(std::size_t k, const Pose2& pose, const DynamicObstacleSet& obstacles, double t,
                    double heading_spread, bool turning, bool& placed) const;
  // The exact static test (see kExactMargin); false without this cycle's exact obstacles.
  bool exactPoseFree(const FastPose& p) const;
  // Grid coordinates (cells) of a world point: the local map's frame of this cycle.
  double gridX(double x, double y) const { return frame_.gridX(x, y); }
  double gridY(double x, double y) const { return frame_.gridY(x, y); }
  // Index of the cell at grid coordinates, or -1 outside the grid.
  std::ptrdiff_t cellIndex(double gx, double gy) const {
    if (!(gx >= 0.0 && gy >= 0.0 && gx < grid_w_ && gy < grid_h_)) return -1;
    return static_cast<std::ptrdiff_t>(gy) * grid_w_ + static_cast<std::ptrdiff_t>(gx);
  }

  const LocalMap* map_ = nullptr;
  const std::uint8_t* grid_ = nullptr;
  int grid_w_ = 0, grid_h_ = 0;
  GridFrame frame_;
  Polygon footprint_;
  Polygon footprint_dynamic_;  // grown by dynamic_margin_ (mitred): checked against D(t)
  double dynamic_margin_ = 0.0;
  bool convex_ = true;
  double cell_ = 0.05;
  double circumradius_ = 0.0;
  double sample_step_ = 0.045;
  std::array<Vec2, kMaxCircles> circle_centers_{};
  std::array<double, kMaxCircles> circle_radii_{};
  std::size_t circle_count_ = 0;
  std::array<Vec2, kMaxOutline> outline_{};
  std::size_t outline_count_ = 0;
  std::array<std::size_t, kMaxCircles + 1> outline_begin_{};  // outline_ grouped by circle
  std::array<double, kMaxOutline> outline_gap_{};             // to the next point of the group
  Vec2 centroid_{0.0, 0.0};
  std::vector<float> distance_;  // per cell, metres, conservative
  const PolygonSet* exact_ = nullptr;  // this cycle's real obstacles, when the map asks for exact tests
  Polygon footprint_exact_;            // grown by kExactMargin (mitred)
  mutable std::array<Vec2, 64> exact_placed_{};
  mutable FixedPolygon scratch_;
  mutable std::array<Vec2, 64> placed_{};
};

}  // namespace staa
