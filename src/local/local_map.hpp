#pragma once
// The local map of the paper's Sec. III-C/D: a robot-aligned box (6 m ahead, 2 m behind, 4 m
// to each side), the intermediate goal G~ where the global path leaves it, the collision grid
// C (map polygons drawn in, 5 cm cells) and the costmap C' (C dilated and blurred, 0..1).
//
// Everything is sized at construction; update() allocates nothing.

#include "geometry/types.hpp"
#include "path/polygon_set.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace staa {

struct LocalMapConfig {
  double ahead_m = 6.0;
  double behind_m = 2.0;
  double side_m = 4.0;
  double cell_m = 0.05;       // 8 m / 0.05 m = 160 x 160 cells
  double dilate_m = 0.05;     // C' : dilation of C before blurring
  double blur_sigma_m = 0.12; // C' : Gaussian blur (the paper's code: blur radius 0.24 m = 2 sigma)
};

// The intermediate goal G~ (paper, Sec. III-C).
struct IntermediateGoal {
  Pose2 pose;              // position, heading along the path (or the final goal's heading)
  bool is_final = false;   // the whole remaining path lies inside the box: G~ = G
  std::size_t segment = 0; // index of the path segment on which G~ lies
};

// Grid of the box, robot-aligned. Cell (i, j): i along the robot's x (0 = rear edge),
// j along the robot's y (0 = right edge). Row-major, j * width + i.
class LocalMap {
 public:
  explicit LocalMap(const LocalMapConfig& config = {});

  const LocalMapConfig& config() const { return config_; }
  int width() const { return width_; }    // cells along x (ahead + behind)
  int height() const { return height_; }  // cells along y (2 * side)

  // Rebuilds everything for the robot at `robot`: the box, C from the real (uninflated)
  // obstacles `real` (draw every polygon overlapping the box: a cell is occupied when any part
  // of it is covered — conservative rasterization, so thin walls are never lost), C', and G~
  // from `global_path` (start to goal, world frame) and the goal's heading `goal_theta`.
  // No allocation.
  void update(const Pose2& robot, const PolygonSet& real, std::span<const Vec2> global_path, double goal_theta);

  const Pose2& origin() const { return robot_; }  // the robot pose the box is attached to
  // The box in world coordinates, corners counter-clockwise (rear-right first).
  std::span<const Vec2, 4> boxCorners() const { return box_world_; }
  bool inBox(const Vec2& world) const;

  // Collision grid C lookup at a world point; outside the box counts as free (the planner
  // never leaves it far; the polygon checks still apply). Hot path: a transform and a load.
  bool occupied(const Vec2& world) const;
  // Costmap C' at a world point, 0 (far) .. 1 (in an obstacle); 0 outside the box.
  float cost(const Vec2& world) const;

  std::span<const std::uint8_t> grid() const { return grid_; }   // 0 free, 1 occupied
  std::span<const float> costmap() const { return costmap_; }
  const IntermediateGoal& intermediateGoal() const { return goal_; }

  // World <-> cell helpers (for drawing and tests). cellOf returns false outside the box.
  bool cellOf(const Vec2& world, int& i, int& j) const;
  Vec2 cellCenter(int i, int j) const;

 private:
  LocalMapConfig config_;
  int width_ = 0;
  int height_ = 0;
  Pose2 robot_;
  double cos_ = 1.0, sin_ = 0.0;
  Vec2 box_world_storage_[4];
  std::span<const Vec2, 4> box_world_{box_world_storage_, 4};
  std::vector<std::uint8_t> grid_;
  std::vector<float> costmap_;
  std::vector<float> scratch_;
  IntermediateGoal goal_;
};

// Where the path first leaves the box (the paper's G~), or the goal if it never does.
IntermediateGoal findIntermediateGoal(std::span<const Vec2, 4> box_ccw, std::span<const Vec2> path, double goal_theta);

}  // namespace staa
