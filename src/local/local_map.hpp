#pragma once
// The local map of the paper's Sec. III-C/D: a robot-aligned box (6 m ahead, 2 m behind, 4 m
// to each side), the intermediate goal G~ where the global path leaves it, the collision grid
// C (map polygons drawn in, 5 cm cells) and the costmap C' (C dilated and blurred, 0..1).
//
// Everything is sized at construction; update() allocates nothing.

#include "geometry/types.hpp"
#include "path/polygon_set.hpp"

#include <array>
#include <cstddef>
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

// A grid over the local box for one robot pose: the affine map from world coordinates to
// cell units (cell (i, j) covers [i, i+1) x [j, j+1); i along the robot's x from the rear
// edge, j along its y from the right edge) at a resolution. The local map owns it: the
// rasterizer, the collision checks, the heuristic and STAA*'s closed table use the same one.
struct GridFrame {
  double xx = 0.0, xy = 0.0, x0 = 0.0, yx = 0.0, yy = 0.0, y0 = 0.0;
  double gridX(double x, double y) const { return xx * x + xy * y + x0; }
  double gridY(double x, double y) const { return yx * x + yy * y + y0; }
  Vec2 toGrid(const Vec2& w) const { return {gridX(w.x(), w.y()), gridY(w.x(), w.y())}; }
};

// Cells of a grid over the box at `cell_m`: along x (ahead + behind) and y (2 * side). The
// one rounding rule for every grid over the box (a hair below a whole number of cells counts
// as that number).
struct GridSize {
  int width = 0;
  int height = 0;
  std::size_t cells() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};
GridSize boxGridSize(const LocalMapConfig& config, double cell_m);

// The intermediate goal G~ (paper, Sec. III-C).
struct IntermediateGoal {
  Pose2 pose;              // position, heading along the path (or the final goal's heading)
  bool is_final = false;   // the path's end lies in the box and is reached within it: G~ = G
  std::size_t segment = 0; // index of the path segment on which G~ lies
};

// A piece of the path inside the (closed) box, in order along the path: it enters at `in`
// on segment `first` (the path's start for the first piece, when that lies in the box) and
// leaves at `out` on segment `last`, heading `heading` there (along that segment), or it holds
// the path's end (`ends_path`: `out` is the last point).
struct PathPiece {
  std::size_t first = 0;
  std::size_t last = 0;
  Vec2 in{0.0, 0.0};
  Vec2 out{0.0, 0.0};
  double heading = 0.0;
  bool ends_path = false;
};

// The path's pieces inside the convex counter-clockwise box, written to `out` (at most
// out.size(): later ones are dropped); returns how many. The first piece starts at the path's
// start, or, should that lie outside (a stale path), where the path first enters. No
// allocation.
std::size_t pathPiecesInBox(std::span<const Vec2, 4> box_ccw, std::span<const Vec2> path, std::span<PathPiece> out);

// Grid of the box, robot-aligned. Cell (i, j): i along the robot's x (0 = rear edge),
// j along the robot's y (0 = right edge). Row-major, j * width + i.
class LocalMap {
 public:
  explicit LocalMap(const LocalMapConfig& config = {});
  // The size of the local map's own grid for a config (what every user of the grid sizes
  // its buffers by).
  static GridSize gridSize(const LocalMapConfig& config) { return boxGridSize(config, config.cell_m); }

  const LocalMapConfig& config() const { return config_; }
  int width() const { return width_; }    // cells along x (ahead + behind)
  int height() const { return height_; }  // cells along y (2 * side)

  // Rebuilds everything for the robot at `robot`: the box, C from the real (uninflated)
  // obstacles `real` (draw every polygon overlapping the box: a cell is occupied when any part
  // of it is covered — conservative rasterization, so thin walls are never lost), C', and G~
  // from `global_path` (start to goal, world frame) and the goal's heading `goal_theta`.
  // C' is zero-padded at the box's edges (obstacles outside the box are not drawn, and a
  // map's `bounds` are not obstacles here: pass them as polygons if they should be).
  // `clearance_m`: how far from C the robot's centre keeps when G~ asks whether a later piece
  // of the path is reached within the box (see G~ below).
  // No allocation. About 90 us on the office map (LocalMapTiming test, bench_local).
  void update(const Pose2& robot, const PolygonSet& real, std::span<const Vec2> global_path, double goal_theta,
              double clearance_m = 0.0);

  const Pose2& origin() const { return robot_; }  // the robot pose the box is attached to
  // The box in world coordinates, corners counter-clockwise (rear-right first).
  std::span<const Vec2, 4> boxCorners() const { return std::span<const Vec2, 4>(box_world_); }
  bool inBox(const Vec2& world) const;

  // Collision grid C lookup at a world point; outside the box counts as free (the planner
  // never leaves it far; the polygon checks still apply). Hot path: a transform and a load.
  bool occupied(const Vec2& world) const;
  // Costmap C' at a world point, 0 (far) .. 1 (in an obstacle); 0 outside the box.
  float cost(const Vec2& world) const;

  std::span<const std::uint8_t> grid() const { return grid_; }   // 0 free, 1 occupied
  std::span<const float> costmap() const { return costmap_; }
  const IntermediateGoal& intermediateGoal() const { return goal_; }

  // The real obstacles this update drew C from (the set passed to update(); it must outlive
  // the uses of this update).
  const PolygonSet* realObstacles() const { return real_; }
  // Issue 16: where the route runs through a passage only the footprint fits, the cycle asks
  // the map's users to decide the static obstacles exactly: a pose the grid rejects is checked
  // against realObstacles() (CollisionChecker). C's 5 cm cells, rasterized conservatively,
  // close a slot with 2.5 cm to spare on each side. Every update() clears it.
  void setExactStatic(bool on) { exact_static_ = on; }
  bool exactStatic() const { return exact_static_; }

  // The grid's world -> cell map for this update, and the same box at another resolution
  // (STAA*'s closed table).
  const GridFrame& frame() const { return frame_; }
  GridFrame frameAt(double cell_m) const;

  // World <-> cell helpers (for drawing and tests). cellOf returns false outside the box;
  // nearestCell clamps into the grid (a point a rounding error outside the box).
  bool cellOf(const Vec2& world, int& i, int& j) const;
  void nearestCell(const Vec2& world, int& i, int& j) const;
  Vec2 cellCenter(int i, int j) const;

 private:
  // Rasterizes the polygons overlapping the box into grid_ (conservative, see the .cpp).
  void drawObstacles(const PolygonSet& real, const Box& box_aabb);
  void markEdgeCells(const Vec2& a, const Vec2& b);      // supercover of one edge
  void addEdgeCrossings(const Vec2& a, const Vec2& b, bool convex);  // at the row centres
  void buildCostmap();                                     // C' from grid_
  void dilateGrid(std::vector<std::uint8_t>& out, int r, double r2) const;  // C dilated by a disk
  // G~'s reach test: which of the path's pieces (pieces_[0, count)) the robot reaches
  // without leaving the box, through cells at least clearance_m from C (reached_).
  void reachPieces(std::size_t count, std::span<const Vec2> path, double clearance_m);
  Vec2 toGrid(const Vec2& w) const { return frame_.toGrid(w); }

  LocalMapConfig config_;
  int width_ = 0;
  int height_ = 0;
  Pose2 robot_;
  double cos_ = 1.0, sin_ = 0.0;
  GridFrame frame_;  // frameAt(cell_m), per update
  // Stored by value (a span member into our own storage would dangle after a copy).
  std::array<Vec2, 4> box_world_{};
  std::vector<std::uint8_t> grid_;
  std::vector<float> costmap_;
  std::vector<float> scratch_;            // horizontal blur pass, padded by blur_radius_ rows
  std::vector<std::int16_t> winding_;     // per-row winding increments (non-convex polygons)
  std::vector<std::uint8_t> row_winding_; // rows with winding increments this update
  std::vector<double> span_lo_, span_hi_; // per-row crossing span of the convex polygon drawn
  std::vector<std::uint8_t> dilated8_;    // C dilated, 0/1 bytes
  std::vector<float> cumulative_;         // cumulative Gaussian kernel, see the constructor
  std::vector<std::uint8_t> row_any_;     // rows of scratch_ holding a non-zero value
  std::vector<float> kernel_;             // Gaussian half-kernel, w[0..blur_radius_], sum 1
  int blur_radius_ = 0;
  int dilate_cells_ = 0;
  double dilate_r2_ = 0.0;                // dilation radius squared, in cells^2
  IntermediateGoal goal_;
  // G~'s pieces and reach test (sized at construction).
  static constexpr std::size_t kMaxPieces = 64;
  std::array<PathPiece, kMaxPieces> pieces_{};
  std::array<bool, kMaxPieces> reached_{};
  std::vector<std::uint8_t> reach_blocked_;  // C dilated by the clearance
  std::vector<std::uint8_t> reach_seen_;
  std::vector<std::uint32_t> reach_queue_;
  const PolygonSet* real_ = nullptr;
  bool exact_static_ = false;
};

// G~ (issue 16: the paper's "where the path leaves the box", made steady): the farthest point
// along the path, by arc length, that lies in the box and is reached without leaving it, that
// is, the end of the last of the path's pieces in the box that the robot reaches within it
// (`reached[k]` for piece k; the first piece, which the robot is on, always counts). Where
// the path loops back near the box's edge, the first exit jumps by metres along the path when
// a small turn of the robot moves that edge across the loop; this point moves only as the
// pieces' ends move, and jumps only when its own piece enters or leaves the box. G~ heads
// along the path where it leaves; a reached piece holding the path's end gives G~ = that end
// with heading goal_theta and is_final. With one piece (the path leaves the box once and
// stays out, or never leaves) it is the paper's first exit, to the bit. A path that never
// touches the box gives G~ = its start, heading along its first segment, not final. An empty
// path gives is_final at the origin (update() puts it at the robot).
IntermediateGoal intermediateGoalOf(std::span<const PathPiece> pieces, std::span<const bool> reached,
                                    std::span<const Vec2> path, double goal_theta);
// The same with every piece reached (no obstacles in the box).
IntermediateGoal findIntermediateGoal(std::span<const Vec2, 4> box_ccw, std::span<const Vec2> path, double goal_theta);

}  // namespace staa
