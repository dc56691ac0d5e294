#pragma once
// Depth perception (docs/ARCHITECTURE.md sections 2-3, the perception thread): one depth frame and
// the robot's pose in the map become the moving (unmapped) obstacles D as convex polygons in
// the map frame with velocities, the ObstacleFrame the control thread plans against.
//
// The steps, one function each, in the order process() calls them:
//   1. backProject:     every pixel_stride-th pixel of every pixel_stride-th row through the
//                       pinhole model and the mount (CameraModel) into the base frame; points
//                       in the height band above the floor and within range go into a 2-D
//                       occupancy grid around the robot, aligned with the map's axes;
//   2. findClusters:    occupied cells that the static map does not explain (StaticMapMask),
//                       linked into clusters when at most cluster_gap_m apart; the nearest
//                       kMaxObstacles are kept;
//   2b. findCuts:       with a scan, the clusters it sees only in part: a nearer return just
//                       beyond a cluster's first or last beam (a wall's corner, another body)
//                       cuts the body off there;
//   3. outlineClusters: one convex polygon per cluster, the hull of its cells' corners (the
//                       hull of the cell centres grown by half a cell), conservatively reduced
//                       to max_vertices (it only grows);
//   4. trackClusters:   each cluster is matched to the nearest predicted track within a gate;
//                       a constant-velocity Kalman filter on its point centroid gives the
//                       velocity (the smoothed displacement over the time between frames); a
//                       new track starts at 0 m/s. A cut cluster's centroid moves with the
//                       cut (a body coming out from behind a corner grows into view): it is
//                       trusted as little as one cut by the image's edge, and the free end of
//                       the body, its silhouette on the scan, gives the velocity across the
//                       beam instead (its displacement between frames). The turn rate is the
//                       smoothed rate at which that velocity's direction turns (0 for slow
//                       tracks);
//   5. keepUnseenTracks: a track not seen this frame is forgotten after max_missed_frames if
//                       the camera should have seen it (its place in the image, in range, not
//                       hidden behind something nearer); out of view it is kept up to
//                       keep_unseen_s, reported at its predicted place with its outline grown
//                       by its growing uncertainty, and a cluster within the gate grown as
//                       much continues it (a person walking out of the view and back).
//
// Everything is sized at construction (a workspace object, as OMPL and PX4 keep theirs);
// process() allocates nothing, throws nothing and takes time linear in the sampled pixels and
// the grid's cells.

#include "geometry/types.hpp"
#include "hal/depth_camera.hpp"
#include "hal/laser_scan.hpp"
#include "hal/obstacles.hpp"
#include "map/polygon_map.hpp"
#include "hal/camera_model.hpp"
#include "perception/static_map_mask.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

struct DepthObstaclesConfig {
  // Pixels: every pixel_stride-th column of every pixel_stride-th row (1..16). At 4 the
  // 640 x 480 frame gives 160 x 120 rays, 2.8 cm apart at 4 m: several per 10 cm cell.
  int pixel_stride = 4;
  // Depth readings nearer than this are the Xtion's near-range noise (its spec: 0.8 m;
  // in practice it returns usable depth from ~0.5 m; 0 is "no reading" anyway).
  double min_depth_m = 0.45;
  // Horizontal distance from the camera beyond which points are ignored: the depth error
  // grows with the square of the distance (a few cm at 4 m).
  double max_range_m = 4.5;
  // The height band (m above the floor) of points that can touch the base: below it is the
  // floor and its noise, above it ceiling and lamps.
  double min_height_m = 0.05;
  double max_height_m = 1.8;
  // How far from the base a scan's returns are used (m, ScanInput): the grid spans the larger
  // of this and max_range_m. 0: max_range_m. A planar scanner reads far beyond a depth
  // camera's useful range (a UST-20LX: 20 m), and agents closing at 4 m/s need seconds of
  // warning, not the camera's one.
  double scan_range_m = 0.0;
  // Occupancy grid cells (m); the grid spans max_range_m (or scan_range_m, plus the mount's
  // offset) around the robot in every direction.
  double cell_m = 0.1;
  // A cell is occupied with at least this many points (isolated noisy pixels are not).
  int min_points_per_cell = 3;
  // A cluster with fewer points in all is noise and not reported.
  int min_cluster_points = 8;
  // Occupied cells whose centres are at most this far apart (along x and along y) belong to
  // one cluster: one cell (0.1 m) is 8-connectivity. 0.3 m bridges up to two empty cells
  // between the sparse columns of points on a surface seen at a grazing angle (a box's side
  // face: at 0.2 m a walking box split in two in the corridor test), at the price of merging
  // things less than ~0.2 m apart (conservative: one bigger polygon, one velocity).
  double cluster_gap_m = 0.3;
  // Cells within this distance of the map's obstacles (or outside its bounds) are the map's
  // (walls seen through depth noise and localisation error are not moving obstacles). It
  // hides a real obstacle standing closer than this to a wall, too.
  double static_margin_m = 0.15;
  // Vertices per polygon (4..ObstacleFrame::kMaxVertices): larger hulls grow to fewer.
  std::size_t max_vertices = 16;
  // A cluster continues a track whose predicted centroid lies within this distance (m).
  double gate_m = 0.5;
  // Velocities come from a constant-velocity Kalman filter per track on the clusters' point
  // centroids. centroid_noise_m: how much a centroid jitters from frame to frame (depth noise,
  // and parts of a surface coming into or going out of view as things move).
  double centroid_noise_m = 0.03;
  // A cluster at the image's left or right edge is cut off by it: its centroid moves with the
  // edge as the body enters or leaves the view, not with the body. Its centroid is trusted
  // this little (m) instead.
  double truncated_noise_m = 0.3;
  // How quickly an obstacle may change its velocity (m/s^2; people: about 1).
  double acceleration_mps2 = 1.0;
  // Speeds are clamped to this (m/s): faster is an association slip, not a person.
  double max_speed_mps = 2.5;
  // The turn rate (the planner predicts a turning obstacle on its circle as well as on its
  // line): the rate at which the filtered velocity's direction turns, smoothed with this time
  // constant (s), while the track is at least turn_min_speed_mps fast (slower, the direction
  // is noise and the turn rate 0), clamped to +-max_turn_rate_rps (people: up to ~3 rad/s).
  double turn_rate_time_s = 0.3;
  double turn_min_speed_mps = 0.3;
  double max_turn_rate_rps = 3.0;
  // A track the camera should have seen (in view: see keepUnseenTracks) but did not, for more
  // frames than this, is forgotten.
  int max_missed_frames = 5;
  // A track out of view (outside the image, nearer than min_depth_m or beyond max_range_m,
  // or hidden behind something nearer) is kept this long (s) at its predicted place, then
  // forgotten; 0: out of view is the same as unseen. Only tracks seen in at least
  // confirm_frames frames are kept (a cluster of noise is not).
  double keep_unseen_s = 1.5;
  int confirm_frames = 3;
  // While unseen a track's outline grows by sigma_v * t + acceleration_mps2 * t^2 / 2 (sigma_v:
  // its filtered velocity's standard deviation, t: the time unseen), at most max_growth_m,
  // and so does its gate.
  double max_growth_m = 1.0;
  // The camera sees only the near side of a body: each outline is extended this far (m) away
  // from the camera, for the side it cannot see. 0: the visible cells only.
  double hidden_depth_m = 0.0;
  // A track's velocity is uncertain (a new one's most): its outline is grown by the distance
  // that uncertainty (the filter's standard deviation) covers in this time (s), at most
  // max_growth_m. 0: not grown.
  double uncertainty_horizon_s = 0.0;
  // The robot's own radius about its base centre (the pose process() is given): an unseen
  // track's outline is grown no nearer than this, and one predicted nearer is forgotten (the
  // robot would have met it). 0: not checked.
  double self_clearance_m = 0.0;
  // A gap between frame stamps longer than this (or a stamp going backwards) forgets every
  // track: the velocities would be stale.
  double max_frame_gap_s = 0.5;
};

// Every rule of the config (the ranges above, max_height_m > min_height_m, cluster_gap_m in
// [cell_m, 5 * cell_m], max_range_m at most 998 cells from the camera): the one check, used
// by the detector and by staad's config reader. `camera_offset_m`: the camera's horizontal
// distance from the base centre (cameraOffset). Throws io::FieldError (an
// std::invalid_argument) naming the field, the rule and the value.
void validateDepthObstaclesConfig(const DepthObstaclesConfig& config, double camera_offset_m = 0.0);
inline double cameraOffset(const hal::CameraMount& mount) { return std::hypot(mount.x, mount.y); }

// A planar scan perceived with a depth frame (the HSR's base scanner beside its head camera):
// its returns join the frame's points in the same grid, so one cluster, one outline and one
// track come from whatever saw a body. A return weighs as much as min_points_per_cell camera
// points (a laser return is a surface, not a speckle of depth noise): one occupies its cell.
// The scan is also asked whether a track should have been seen (keepUnseenTracks).
struct ScanInput {
  const hal::LaserScan* scan = nullptr;  // none: the frame alone
  hal::ScanMount mount;
  Pose2 robot;  // the base when the scan was taken (map frame)
};

// What one frame produced (for telemetry and tests).
struct DepthObstaclesStats {
  std::size_t points = 0;          // points in the height band and range, inside the grid
  std::size_t scan_points = 0;     // ... of them the scan's returns
  std::size_t occupied_cells = 0;  // cells with >= min_points_per_cell points
  std::size_t map_cells = 0;       // ... of which the static map explains
  std::size_t clusters = 0;        // clusters with >= min_cluster_points (before the cut)
  std::size_t tracks = 0;          // live tracks after the frame
};

class DepthObstacleDetector {
 public:
  // Up to this many clusters per frame are measured; the nearest kMaxObstacles are reported.
  static constexpr std::size_t kMaxClusters = 256;
  static constexpr std::size_t kMaxTracks = 2 * hal::ObstacleFrame::kMaxObstacles;

  // Throws std::invalid_argument for a bad config, intrinsics or mount (naming the field).
  DepthObstacleDetector(const PolygonMap& map, const hal::CameraIntrinsics& intrinsics, const hal::CameraMount& mount,
                        const DepthObstaclesConfig& config = {});

  // One frame taken when the robot's base was at `robot` (map frame). Fills `out`: stamp and
  // sequence from the frame, the obstacles nearest first. No allocation, no exception.
  // A frame with its own mount (frame.has_mount: a head that pans and tilts) is seen from
  // that mount, else from the constructor's. The rays of a frame's mount are rebuilt when it
  // differs from the previous frame's (19,200 rays at pixel_stride 4, a few times the cost of
  // the rest of the frame, test_perception_alloc prints it; nothing when the head holds still). The grid still reaches max_range_m from the constructor's mount: a frame
  // mount farther from the base centre loses that much range on its far side. A frame mount
  // must pass validateCamera (hal/ros drops those that do not); one that is not finite or
  // not above the floor is seen as no points.
  DepthObstaclesStats process(const hal::DepthFrame& frame, const Pose2& robot, hal::ObstacleFrame& out);
  // The same with a scan's returns in the grid beside the frame's points (ScanInput). The scan
  // must pass hal::scanProblem (hal/ros drops those that do not); its returns farther from the
  // base than the grid reaches (max_range_m) are not used.
  DepthObstaclesStats process(const hal::DepthFrame& frame, const Pose2& robot, hal::ObstacleFrame& out,
                              const ScanInput& scan);

  // Forgets every track (after a relocalisation, say): the next frame's velocities are 0.
  void resetTracks();

  const DepthObstaclesConfig& config() const { return config_; }
  const CameraModel& camera() const { return camera_; }
  const StaticMapMask& staticMask() const { return mask_; }
  int gridSize() const { return n_; }

 private:
  // A sampled pixel: its ray in the base frame (optical z = 1) and the depths (mm) at which
  // its point lies inside the height band and range, so the per-pixel test is two compares.
  struct Ray {
    float x, y;
    std::uint32_t pixel;
    std::uint16_t min_mm, max_mm;
  };
  // A camera's rays, and which of them sample the image's first or last column.
  struct Rays {
    std::vector<Ray> rays;
    std::vector<std::uint32_t> edge;  // indices into rays
  };
  struct Cluster {
    std::uint32_t first = 0, last = 0;  // its cells: queue_[first, last)
    std::uint32_t points = 0;
    Vec2 centroid{0.0, 0.0};  // of its points, map frame
    double distance = 0.0;    // centroid to the robot
    int track = -1;
    bool truncated = false;   // some of its points come from the image's left or right edge
    std::int32_t label = 0;   // its id in label_
    // The scan's first and last beam on it (-1: none), their returns (map frame), and whether
    // a nearer return just beyond either end hides the rest of the body there.
    int beam_lo = -1, beam_hi = -1;
    Vec2 edge_lo{0.0, 0.0}, edge_hi{0.0, 0.0};
    bool cut_lo = false, cut_hi = false;
    // Cut off by the image's or the sweep's edge, or by something nearer.
    bool cut() const { return truncated || cut_lo || cut_hi; }
  };
  struct Track {
    bool live = false;
    Vec2 centroid{0.0, 0.0};  // filtered
    Vec2 velocity{0.0, 0.0};
    // The filter's covariance [position, velocity], the same for x and y (it depends only on
    // the times of the measurements).
    double p00 = 0.0, p01 = 0.0, p11 = 0.0;
    rt::Nanos seen = 0;
    int missed = 0;
    double turn_rate = 0.0;  // rad/s, counter-clockwise positive
    int hits = 0;            // frames it was seen in
    // Its outline when last seen, relative to `centroid`.
    std::array<Vec2, hal::ObstacleFrame::kMaxVertices> outline{};
    std::size_t outline_n = 0;
    // While the body was cut off on one side: its free end's return, which end (-1: the first
    // beam's, +1: the last's, 0: none) and when.
    Vec2 edge{0.0, 0.0};
    int edge_side = 0;
    rt::Nanos edge_seen = -1;
  };

  // The sampled rays of a camera with this rotation and position (base frame) into `out`,
  // within its capacity (reserved at construction: no allocation).
  void fillRays(const Eigen::Matrix3d& rotation, const Vec3& position, Rays& out) const;
  void useFrameMount(const hal::CameraMount& mount);
  void backProject(const hal::DepthFrame& frame, const Rays& rays, const Vec3& camera_position, const Pose2& robot,
                   DepthObstaclesStats& stats);
  void addScan(const ScanInput& scan, DepthObstaclesStats& stats);
  // Whether this frame's scan should have seen something at `p` (map frame): in its sweep and
  // range, and its beam there not stopped by something nearer.
  bool scanSees(const Vec2& p) const;
  void findClusters(const Pose2& robot, DepthObstaclesStats& stats);
  void findCuts();
  void outlineClusters(hal::ObstacleFrame& out);
  void trackClusters(rt::Nanos stamp, hal::ObstacleFrame& out);
  void keepUnseenTracks(const hal::DepthFrame& frame, const Pose2& robot, hal::ObstacleFrame& out);
  // Whether the camera of this frame should have seen something at `p` (map frame): its place
  // in the image, in range, and nothing nearer in front of it.
  bool inView(const hal::DepthFrame& frame, const Pose2& robot, const Vec2& p) const;
  // How far a track unseen for t seconds may be from its prediction.
  double growth(const Track& track, double t) const;
  // r, or less so that the outline grown by it stays self_clearance_m from the base centre.
  double clearOfSelf(std::span<const Vec2> outline, double r) const;
  std::size_t outline(const Cluster& cluster, std::span<Vec2> out);
  void filterCentroid(Track& track, const Vec2& measured, double dt, double noise_m,
                      const Vec2& blind = Vec2::Zero()) const;
  // A cluster cut off on one side only: its other end (side -1: the first beam's, +1: the
  // last's, 0: no such end), and the unit vector across the beam there.
  struct FreeEnd {
    int side = 0;
    Vec2 point{0.0, 0.0};
    Vec2 across{0.0, 0.0};
  };
  FreeEnd freeEnd(const Cluster& cluster) const;
  // The free end's motion feeds the track's velocity across the beam (trackClusters).
  void followFreeEnd(Track& track, const FreeEnd& end, rt::Nanos stamp) const;
  void filterTurnRate(Track& track, const Vec2& velocity_before, double dt) const;

  DepthObstaclesConfig config_;
  CameraModel camera_;
  StaticMapMask mask_;
  Rays rays_;
  // The rays of the last frame's own mount (frame.has_mount), and that mount.
  Rays frame_rays_;
  hal::CameraMount frame_mount_;
  Vec3 frame_position_{0.0, 0.0, 0.0};
  bool frame_rays_built_ = false;
  int n_ = 0;                       // grid cells per side
  int link_ = 1;                    // cluster_gap_m in cells
  std::int64_t gi0_ = 0, gj0_ = 0;  // the grid's lower-left cell on the map lattice (this frame)
  Vec2 origin_{0.0, 0.0};           // its corner in the map frame
  std::vector<std::uint16_t> count_;
  std::vector<std::uint8_t> edge_;    // per cell: a point from the image's left or right edge
  std::vector<std::uint32_t> edge_cells_;  // the cells edge_ marks (cleared next frame)
  std::vector<float> sum_x_, sum_y_;  // point coordinates relative to origin_
  std::vector<std::int32_t> label_;   // -1: no obstacle; 0: unvisited; > 0: cluster id
  std::vector<std::uint32_t> queue_;  // flood fill queue, also the clusters' cell lists
  std::vector<std::int32_t> row_min_, row_max_;
  std::vector<std::int32_t> rows_;
  std::vector<Vec2> corners_, hull_, extended_;
  // This frame's camera: its rotation (base <- body) and position (base frame), and its
  // position in the map frame.
  Eigen::Matrix3d frame_rotation_ = Eigen::Matrix3d::Identity();
  Vec3 frame_camera_{0.0, 0.0, 0.0};
  Vec2 camera_map_{0.0, 0.0};
  Vec2 robot_{0.0, 0.0};  // this frame's base centre (map frame)
  // This frame's scan (null: none; only during process), its sensor (map frame) and the
  // map-frame bearing of its beam 0.
  const hal::LaserScan* scan_ = nullptr;
  Vec2 scan_sensor_{0.0, 0.0};
  double scan_zero_ = 0.0;
  std::array<Cluster, kMaxClusters> clusters_{};
  std::size_t cluster_count_ = 0;
  std::array<std::uint16_t, kMaxClusters> order_{};
  std::size_t kept_ = 0;
  std::array<Track, kMaxTracks> tracks_{};
  rt::Nanos last_stamp_ = -1;
};

// Grows a convex counter-clockwise polygon outwards by r (in place, the same vertices): each
// vertex goes to where its two edges moved out by r meet, at most 4 r out. No allocation.
void growOutline(std::span<Vec2> polygon, double r);

// Grows a convex counter-clockwise polygon of n vertices (in place) to at most max_n >= 4
// vertices that contain it: repeatedly the edge whose neighbours, extended to meet, add the
// least area is replaced by their meeting point. Returns the new vertex count. No allocation.
std::size_t growToFewerVertices(std::span<Vec2> polygon, std::size_t n, std::size_t max_n);

}  // namespace staa
