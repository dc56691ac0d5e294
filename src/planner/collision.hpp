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

  // Distance from the robot's position to the nearest predicted obstacle edge (for Eq. 3).
  double distanceToDynamic(const Vec2& p, const DynamicObstacleSet& obstacles, double t) const;

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
  Vec2 centroid_{0.0, 0.0};
  std::vector<float> distance_;  // per cell, metres, conservative
  const PolygonSet* exact_ = nullptr;  // this cycle's real obstacles, when the map asks for exact tests
  Polygon footprint_exact_;            // grown by kExactMargin (mitred)
  mutable std::array<Vec2, 64> exact_placed_{};
  mutable FixedPolygon scratch_;
  mutable std::array<Vec2, 64> placed_{};
};

}  // namespace staa
