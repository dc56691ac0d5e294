#include "experiment/agent_camera.hpp"

#include "geometry/polygon.hpp"
#include "robot/unicycle.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace staa {
namespace {

double elapsedUs(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - since).count();
}

const DepthCameraProfile& cameraOf(const RobotProfile& profile) {
  if (!profile.has_camera) {
    throw std::invalid_argument("robot profile '" + profile.name +
                                "' has no camera section: --obstacles depth needs one (config/robots/paper-agent.yaml "
                                "shows the keys)");
  }
  return profile.camera;
}

hal::SimDepthConfig rendererConfig(const RobotProfile& profile, const DepthObstaclesConfig& perception,
                                   std::uint64_t seed) {
  const DepthCameraProfile& c = cameraOf(profile);
  hal::SimDepthConfig r;
  r.intrinsics = cameraIntrinsics(c);
  r.mount = cameraMount(c);
  r.wall_height_m = 2.0;  // rooms' walls and furniture reach above every camera's view of them
  r.mover_height_m = profile.height_m;
  r.floor = true;
  r.min_depth_m = c.min_range_m;
  r.max_depth_m = c.max_range_m;
  r.noise_mm_per_m2 = c.noise_mm_per_m2;
  r.dropout = c.dropout;
  r.grazing_deg = c.grazing_deg;
  r.seed = seed;
  // Only the pixels perception reads (every stride-th of every stride-th row from stride / 2).
  r.pixel_stride = perception.pixel_stride;
  r.rate_hz = c.rate_hz;
  return r;
}

static_assert(ScannerProfile::kMaxBeams == static_cast<int>(hal::LaserScan::kMaxBeams));

hal::SimScanConfig scannerConfig(const RobotProfile& profile, std::uint64_t seed) {
  if (!profile.has_scanner) {
    throw std::invalid_argument("robot profile '" + profile.name +
                                "' has no scanner section: --obstacles depth+scan needs one (config/robots/paper-agent.yaml "
                                "shows the keys)");
  }
  const ScannerProfile& p = profile.scanner;
  hal::SimScanConfig c;
  c.mount = hal::ScanMount{p.x, p.y, p.z, p.yaw};
  c.centredSweep(p.fov_deg, p.beams);
  c.range_min = p.min_range_m;
  c.range_max = p.max_range_m;
  c.noise_m = p.noise_m;
  c.dropout = p.dropout;
  c.seed = seed;
  return c;
}

}  // namespace

hal::CameraIntrinsics cameraIntrinsics(const DepthCameraProfile& c) {
  constexpr double kDeg = kPi / 180.0;
  hal::CameraIntrinsics k;
  k.fx = 0.5 * hal::DepthFrame::kWidth / std::tan(0.5 * c.fov_h_deg * kDeg);
  k.fy = 0.5 * hal::DepthFrame::kHeight / std::tan(0.5 * c.fov_v_deg * kDeg);
  k.cx = 0.5 * (hal::DepthFrame::kWidth - 1);
  k.cy = 0.5 * (hal::DepthFrame::kHeight - 1);
  return k;
}

hal::CameraMount cameraMount(const DepthCameraProfile& c) {
  return hal::CameraMount{c.x, c.y, c.z, c.roll, c.pitch, c.yaw};
}

DepthObstaclesConfig agentPerceptionConfig(const RobotProfile& profile, bool with_scanner) {
  const DepthCameraProfile& c = cameraOf(profile);
  DepthObstaclesConfig p;
  p.min_depth_m = c.min_range_m;
  p.max_range_m = c.max_range_m;
  p.max_speed_mps = 1.25 * std::max(profile.limits.v_max, -profile.limits.v_min);
  // The filter's white acceleration: a_max along the path and as much again across it (an
  // agent at speed turns: v * w reaches a_max at 2 m/s and 1 rad/s). With a_max alone the
  // velocity lagged a braking or swerving agent by up to a second (docs/results.md, "Tracks
  // that lag a manoeuvre").
  p.acceleration_mps2 = 2.0 * profile.limits.a_max;
  // The body's narrower side: seen from any side, at least that much of it is hidden.
  const Box box = boundingBox(profile.footprint);
  p.hidden_depth_m = std::min(box.max.x() - box.min.x(), box.max.y() - box.min.y());
  p.self_clearance_m = profile.circumradius();
  // A new track's velocity is unknown (0, give or take half the top speed): its outline grows
  // by what that covers in a third of a second, shrinking as the velocity settles.
  p.uncertainty_horizon_s = 1.0 / 3.0;
  if (with_scanner && profile.has_scanner) p.scan_range_m = std::min(kScanRangeM, profile.scanner.max_range_m);
  return p;
}

AgentCamera::AgentCamera(const PolygonMap& map, const RobotProfile& profile, const DepthObstaclesConfig& perception,
                         std::uint64_t seed, bool with_scanner)
    : camera_(cameraOf(profile)),
      renderer_(map, rendererConfig(profile, perception, seed)),
      detector_(map, cameraIntrinsics(camera_), cameraMount(camera_), perception),
      image_(std::make_unique<hal::DepthFrame>()),
      ring_(kRing),
      ring_time_(kRing, -1.0),
      period_s_(1.0 / camera_.rate_hz),
      latency_s_(camera_.latency_s),
      loss_rng_(seed ^ 0x9E3779B97F4A7C15ULL) {
  if (with_scanner) {
    // Its own noise stream, apart from the camera's and the frame losses'.
    const hal::SimScanConfig config = scannerConfig(profile, seed ^ 0xD1B54A32D192ED03ULL);
    scanner_ = std::make_unique<hal::ScanRenderer>(map, config);
    scan_ = std::make_unique<hal::LaserScan>();
    scan_mount_ = config.mount;
    scan_half_fov_ = 0.5 * profile.scanner.fov_deg * kPi / 180.0;
  }
  if (latency_s_ > period_s_ * (kRing - 1)) {
    throw std::invalid_argument("robot profile '" + profile.name + "': camera.latency_s " +
                                std::to_string(latency_s_) + " is more than " + std::to_string(kRing - 1) +
                                " frames at camera.rate_hz");
  }
}

Pose2 AgentCamera::viewPose(const Pose2& robot) const {
  if (pan_ == 0.0) return robot;
  const Vec2 mount(camera_.x, camera_.y);
  const Vec2 camera = robot.transform(mount);
  const double heading = wrapAngle(robot.theta + pan_);
  const double c = std::cos(heading), s = std::sin(heading);
  return Pose2{camera.x() - (c * mount.x() - s * mount.y()), camera.y() - (s * mount.x() + c * mount.y()), heading};
}

bool AgentCamera::perceive(double time_s, const Pose2& robot, std::span<const hal::PrismView> others,
                           std::span<std::uint32_t> mover_pixels) {
  // A fixed schedule a period apart (a step a little early still counts); no burst after a gap.
  if (time_s < next_due_s_ - 0.05 * period_s_) return false;
  next_due_s_ = std::max(next_due_s_ + period_s_, time_s + 0.5 * period_s_);
  if (camera_.frame_loss > 0.0 && loss_rng_.uniform() < camera_.frame_loss) {
    ++lost_;
    return false;
  }
  const Pose2 view = viewPose(robot);
  auto t0 = std::chrono::steady_clock::now();
  renderer_.render(view, others, *image_, mover_pixels);
  render_us_ = elapsedUs(t0);
  image_->stamp = static_cast<rt::Nanos>(std::llround(time_s * 1e9));
  image_->sequence = ++sequence_;
  newest_ = taken_ == 0 ? 0 : (newest_ + 1) % kRing;
  ScanInput scan;
  if (scanner_) {
    t0 = std::chrono::steady_clock::now();
    scanner_->render(robot, others, *scan_);  // from the base: the scanner does not pan
    render_us_ += elapsedUs(t0);
    scan_->stamp = image_->stamp;
    scan_->sequence = image_->sequence;
    scan = ScanInput{scan_.get(), scan_mount_, robot};
  }
  t0 = std::chrono::steady_clock::now();
  stats_ = detector_.process(*image_, view, ring_[newest_], scan);
  perception_us_ = elapsedUs(t0);
  ring_time_[newest_] = time_s;
  ++taken_;
  ++frames_;
  view_.look(time_s, view.theta + camera_.yaw, 0.5 * camera_.fov_h_deg * kPi / 180.0);
  if (scanner_) view_.look(time_s, robot.theta + scan_mount_.yaw, scan_half_fov_);
  return true;
}

double AgentCamera::limitSpeed(double time_s, const Pose2& robot, double v, double w) const {
  if (std::abs(v) <= kBlindSpeedMps) return v;
  const Vec2 ahead = integrateArc(robot, v, w, camera_.look_ahead_m / std::abs(v)).position();
  const Vec2 d = ahead - robot.transform(Vec2(camera_.x, camera_.y));
  if (view_.unseenFor(time_s, std::atan2(d.y(), d.x())) <= kViewMemoryS) return v;
  return std::copysign(kBlindSpeedMps, v);
}

const hal::ObstacleFrame* AgentCamera::delivered(double time_s) const {
  if (taken_ == 0) return nullptr;
  // Newest first: the first whose obstacles have arrived (a small tolerance for rounding).
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(taken_, kRing));
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (newest_ + kRing - k) % kRing;
    if (ring_time_[i] + latency_s_ <= time_s + 1e-6) return &ring_[i];
  }
  return nullptr;
}

void AgentCamera::aimHead(const Pose2& robot, double v, double w, std::span<const Vec2> path, double dt) {
  if (!(camera_.pan_max > 0.0)) return;
  std::optional<Vec2> aim;
  if (std::abs(v) >= kSlowMps) {
    // Where the command's arc is look_ahead_m on (backwards too: the head looks back as far
    // as it can).
    const double t = camera_.look_ahead_m / std::abs(v);
    aim = integrateArc(robot, v, w, t).position();
  } else if (path.size() >= 2) {
    // The path's point look_ahead_m along it (its end when shorter).
    aim = path.back();
    double left = camera_.look_ahead_m;
    for (std::size_t k = 1; k < path.size(); ++k) {
      const double len = (path[k] - path[k - 1]).norm();
      if (len >= left) {
        aim = path[k - 1] + (path[k] - path[k - 1]) * (left / len);
        break;
      }
      left -= len;
    }
  }
  double target = 0.0;
  if (aim) {
    const Vec2 camera = robot.transform(Vec2(camera_.x, camera_.y));
    const Vec2 d = *aim - camera;
    target = d.norm() > 0.05 ? std::clamp(wrapAngle(std::atan2(d.y(), d.x()) - robot.theta - camera_.yaw),
                                          -camera_.pan_max, camera_.pan_max)
                             : pan_;
  }
  const double step = camera_.pan_rate * dt;
  if (camera_.scan > 0.0) {
    // Towards the side of the sweep; at it (or where the limit stops it), the other side.
    const double side = std::clamp(target + sweep_ * camera_.scan, -camera_.pan_max, camera_.pan_max);
    if (std::abs(side - pan_) < 0.5 * step) sweep_ = -sweep_;
    target = std::clamp(target + sweep_ * camera_.scan, -camera_.pan_max, camera_.pan_max);
  }
  pan_ += std::clamp(target - pan_, -step, step);
}

}  // namespace staa
