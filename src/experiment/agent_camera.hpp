#pragma once
// What an agent of the simulator sees (staa-sim --obstacles depth): the depth camera its robot
// profile mounts (DepthCameraProfile) renders the world from the agent's pose, and the same
// perception code as staad (DepthObstacleDetector: static map subtraction with the known map,
// clusters, polygons, tracks) turns each frame into the moving obstacles its planner gets.
//
// The camera, as modelled:
//   - the profile's mount, field of view (the 640 x 480 image's focal lengths follow from it),
//     depth range, Kinect-class noise, random and grazing-angle dropouts (DepthRenderer);
//     only the pixels perception samples are rendered (its pixel_stride);
//   - frames at rate_hz on a fixed schedule; frame_loss of them lost at random (the tracks
//     coast through the gap); the obstacles reach the planner latency_s after the exposure
//     (whole frames), as from staad's perception thread;
//   - the head pans towards the direction of travel: where the robot will be look_ahead_m
//     along the arc of its command (v, w), or, slower than kSlowMps (turning on the spot,
//     starting), the global path's point look_ahead_m ahead, sweeping `scan` to either side of
//     it and back; within +-pan_max at up to pan_rate; the pan axis is vertical through the
//     mount.
//     A pan is a turn of the camera about that axis, so a panned frame is rendered and
//     perceived as the fixed mount on a base turned by the pan (the same rays, exactly the
//     same frame; staad's frames with their own mount rebuild the rays instead).
//   - with a scanner (staa-sim --obstacles depth+scan; the profile's `scanner`: the HSR's base
//     laser), a planar scan rendered from the base (not the head) with each camera frame, its
//     returns perceived in the same grid (ScanInput): one cluster and one track whatever saw a
//     body. The scanner's own rate (the UST-20LX's 40 Hz) is not modelled: it scans when the
//     camera's frame is taken, and a lost frame loses its scan too;
//   - what the camera (and scanner) looked at lately (ViewMemory) limits the robot's speed: faster than
//     kBlindSpeedMps only towards where the command's arc goes that the camera has seen within
//     kViewMemoryS (limitSpeed; the controller's command is limited after the cycle, the head
//     turns to where the controller wants to go, and the speed follows it there).
// Not modelled: the projector's shadow beside near edges, motion blur, the time between the
// exposure and the pose the frame is placed at (the sim's poses are exact).
//
// Tools only (the simulator): allocates at construction; perceive() allocates nothing after
// the first frames (the renderer's bins).

#include "geometry/splitmix64.hpp"
#include "geometry/types.hpp"
#include "hal/depth_camera.hpp"
#include "hal/obstacles.hpp"
#include "map/polygon_map.hpp"
#include "perception/depth_obstacles.hpp"
#include "perception/view_memory.hpp"
#include "robot/robot_profile.hpp"
#include "world/sim_depth_camera.hpp"
#include "world/sim_laser_scan.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace staa {

// The camera model of a profile's camera: the mount, and the focal lengths of its field of
// view on the 640 x 480 image (principal point in the middle).
hal::CameraIntrinsics cameraIntrinsics(const DepthCameraProfile& camera);
hal::CameraMount cameraMount(const DepthCameraProfile& camera);

// Perception's settings for agents of this profile: staad's defaults (DepthObstaclesConfig)
// with the camera's range, and the others' dynamics from the profile (every agent has the
// same): their top speed and twice their acceleration bound the filter, their body's depth
// hides behind the face the camera sees.
// with_scanner (--obstacles depth+scan): the scan's returns used up to kScanRangeM.
DepthObstaclesConfig agentPerceptionConfig(const RobotProfile& profile, bool with_scanner = false);
// Agents closing at 2 m/s each come 8 m nearer in 2 s: about what STAA* needs to get out of
// the way of one that does not (a ghost). Perception's grid grows with it (the cost is in
// docs/results.md).
inline constexpr double kScanRangeM = 8.0;

class AgentCamera {
 public:
  // Throws std::invalid_argument when the profile has no camera (or, with_scanner, no scanner)
  // or a value is out of range.
  AgentCamera(const PolygonMap& map, const RobotProfile& profile, const DepthObstaclesConfig& perception,
              std::uint64_t seed, bool with_scanner = false);

  // The camera's frame due at `time_s` (none when not due yet, or lost): rendered from the
  // base at `robot` with the head at its pan among `others` (prisms of the other bodies),
  // perceived into frame(). mover_pixels (empty or one per other): each one's pixels in it.
  // Returns whether a frame was taken.
  bool perceive(double time_s, const Pose2& robot, std::span<const hal::PrismView> others,
                std::span<std::uint32_t> mover_pixels = {});
  // The newest perceived frame whose obstacles have reached the planner by `time_s`
  // (latency_s after its exposure); null before the first.
  const hal::ObstacleFrame* delivered(double time_s) const;
  // The last depth image rendered (only the pixels perception samples are set).
  const hal::DepthFrame& image() const { return *image_; }
  // The last scan (null without a scanner).
  const hal::LaserScan* scan() const { return scan_.get(); }
  // The last frame perceived (not delayed), and its exposure time.
  const hal::ObstacleFrame& frame() const { return ring_[newest_]; }
  double frameTime() const { return ring_time_[newest_]; }

  // Below this speed (m/s) the head looks along the path, not along the command's arc.
  static constexpr double kSlowMps = 0.2;
  // The speed (m/s) in a direction the camera has not seen within kViewMemoryS (s).
  static constexpr double kBlindSpeedMps = 0.3;
  static constexpr double kViewMemoryS = 0.5;

  // Turns the head for dt seconds at most pan_rate towards the direction of travel: the arc
  // of the command (v, w) of the robot at `robot`, or `path` (the global path from the robot
  // on, map frame) when slow; to the front when slow without a path.
  void aimHead(const Pose2& robot, double v, double w, std::span<const Vec2> path, double dt);
  double pan() const { return pan_; }
  // The command's speed v, or +-kBlindSpeedMps when faster towards a direction (where the arc
  // of (v, w) is look_ahead_m on) the camera has not seen within kViewMemoryS.
  double limitSpeed(double time_s, const Pose2& robot, double v, double w) const;
  // The pose perception and the renderer see the frame from: the base turned by the pan about
  // the camera's vertical axis.
  Pose2 viewPose(const Pose2& robot) const;

  std::uint64_t frames() const { return frames_; }
  std::uint64_t framesLost() const { return lost_; }
  const DepthObstaclesStats& lastStats() const { return stats_; }
  // Wall time of the last frame's rendering and perception (microseconds).
  double renderUs() const { return render_us_; }
  double perceptionUs() const { return perception_us_; }

 private:
  // Frames in flight: the profile's latency is at most kMaxLatencyFrames.
  static constexpr std::size_t kRing = DepthCameraProfile::kMaxLatencyFrames + 1;

  DepthCameraProfile camera_;
  hal::DepthRenderer renderer_;
  DepthObstacleDetector detector_;
  std::unique_ptr<hal::DepthFrame> image_;
  std::unique_ptr<hal::ScanRenderer> scanner_;  // with_scanner only
  std::unique_ptr<hal::LaserScan> scan_;
  hal::ScanMount scan_mount_;
  double scan_half_fov_ = 0.0;
  std::vector<hal::ObstacleFrame> ring_;
  std::vector<double> ring_time_;
  std::size_t newest_ = 0;
  std::uint64_t taken_ = 0;  // frames in the ring so far
  double period_s_;
  double latency_s_;
  double next_due_s_ = 0.0;
  SplitMix64 loss_rng_;
  double pan_ = 0.0;
  double sweep_ = 1.0;  // the side the scan heads for: +1 left, -1 right
  ViewMemory view_;
  std::uint64_t frames_ = 0;
  std::uint64_t lost_ = 0;
  std::uint64_t sequence_ = 0;
  DepthObstaclesStats stats_;
  double render_us_ = 0.0;
  double perception_us_ = 0.0;
};

}  // namespace staa
