#include "app/staad/depth_sensor.hpp"

#include "world/sim_hal.hpp"

#if defined(STAA_HAVE_OPENNI2)
#include "hal/openni2/openni2_camera.hpp"
#endif

#include <span>
#include <string>
#include <utility>

namespace staa::staad {

namespace {

// The simulated world's prisms: walls and bounds as tall as a room, movers as tall as people.
constexpr double kWallHeightM = 2.0;
constexpr double kMoverHeightM = 1.7;
// The Xtion reads depth from about 0.45 m to 8 m; beyond that it reports 0 (no reading).
constexpr double kMinDepthM = 0.45;
constexpr double kMaxDepthM = 8.0;

}  // namespace

hal::SimDepthConfig simDepthConfig(const CameraConfig& camera, std::uint64_t seed) {
  hal::SimDepthConfig c;
  c.intrinsics = camera.intrinsics;
  c.mount = camera.mount;
  c.wall_height_m = kWallHeightM;
  c.mover_height_m = kMoverHeightM;
  c.floor = true;
  c.min_depth_m = kMinDepthM;
  c.max_depth_m = kMaxDepthM;
  c.noise_mm_per_m2 = camera.sim_noise_mm_per_m2;
  c.seed = seed;
  // Perception samples every stride-th pixel of every stride-th row, starting at stride / 2:
  // the renderer's stride picks exactly those, the others stay 0 (unread).
  c.pixel_stride = camera.perception.pixel_stride;
  return c;
}

DepthSensor::DepthSensor(const PolygonMap& map, const CameraConfig& camera, std::uint64_t seed,
                         hal::ObstacleSensor& movers, OdometrySlot& pose)
    : pose_(pose),
      detector_(map, camera.intrinsics, camera.mount, camera.perception),
      frame_(std::make_unique<hal::DepthFrame>()),
      movers_(&movers),
      renderer_(std::make_unique<hal::DepthRenderer>(map, simDepthConfig(camera, seed))) {}

DepthSensor::DepthSensor(const PolygonMap& map, const CameraConfig& camera, std::unique_ptr<hal::DepthCamera> device,
                         OdometrySlot& pose)
    : pose_(pose),
      detector_(map, camera.intrinsics, camera.mount, camera.perception),
      frame_(std::make_unique<hal::DepthFrame>()),
      device_(std::move(device)) {
  if (!device_) throw std::invalid_argument("DepthSensor: no camera");
}

DepthSensor::~DepthSensor() = default;

// The simulated camera's frame: the movers as the sim world last published them (the base
// thread steps the world; this thread never touches it), seen from `robot`.
bool DepthSensor::renderSimFrame(rt::Nanos now, const Pose2& robot) {
  if (!movers_->read(now, mover_frame_)) return false;  // not due yet (the camera's rate)
  std::size_t n = 0;
  for (std::size_t i = 0; i < mover_frame_.count; ++i) {
    const hal::ObstacleFrame::Obstacle& o = mover_frame_.obstacles[i];
    // The vertices are already in the map frame: the prism sits at the origin.
    prisms_[n++] = hal::PrismView{PolygonView(o.vertices.data(), o.n), Vec2(0.0, 0.0), kMoverHeightM};
  }
  renderer_->render(robot, std::span<const hal::PrismView>(prisms_.data(), n), *frame_);
  frame_->stamp = now;
  frame_->sequence = ++sequence_;
  return true;
}

bool DepthSensor::read(rt::Nanos now, hal::ObstacleFrame& out) {
  // Without a pose a frame cannot be placed in the map: it is not taken (the camera keeps it
  // or drops it; the control thread sees no fresh obstacles and holds the robot).
  const hal::Odometry& odometry = pose_.latest();
  if (odometry.stamp < 0) {
    ++without_pose_;
    return false;
  }
  const Pose2 robot = odometry.pose;
  const bool taken = device_ ? device_->read(now, *frame_) : renderSimFrame(now, robot);
  if (!taken) return false;
  stats_ = detector_.process(*frame_, robot, out);
  ++frames_;
  return true;
}

std::unique_ptr<DepthSensor> makeDepthSensor(const DaemonConfig& config, hal::SimHal* sim, OdometrySlot& pose,
                                             std::unique_ptr<hal::DepthCamera> ros_camera) {
  const CameraConfig& camera = config.camera;
  if (camera.backend == CameraBackend::kRos) {
    if (ros_camera == nullptr) {
      throw DepthCameraError(
          "ros is not available: this staad was built without ROS 1 (the ROS packages were not found when it was built): "
          "rebuild after toolchain/install-deps.sh, or use camera.backend: openni2");
    }
    return std::make_unique<DepthSensor>(config.map, camera, std::move(ros_camera), pose);
  }
  if (camera.backend == CameraBackend::kSim) {
    if (sim == nullptr) throw std::logic_error("makeDepthSensor: camera.backend sim needs the simulated world");
    return std::make_unique<DepthSensor>(config.map, camera, config.sim.seed, sim->obstacles(), pose);
  }
  if (camera.backend == CameraBackend::kOpenNI2) {
#if defined(STAA_HAVE_OPENNI2)
    hal::OpenNI2Config oc;
    oc.uri = camera.uri;
    oc.intrinsics = camera.intrinsics;
    oc.mount = camera.mount;
    std::unique_ptr<hal::DepthCamera> device;
    try {
      device = std::make_unique<hal::OpenNI2Camera>(oc);
    } catch (const hal::OpenNI2Error& e) {
      throw DepthCameraError(std::string("cannot open the openni2 depth camera: ") + e.what());
    }
    return std::make_unique<DepthSensor>(config.map, camera, std::move(device), pose);
#else
    throw DepthCameraError(
        "openni2 is not available: this staad was built without OpenNI2 (libopenni2-dev was not found when it was "
        "built): rebuild with libopenni2-dev installed, or use camera.backend: sim");
#endif
  }
  throw std::logic_error("makeDepthSensor: camera.backend " + std::string(toString(camera.backend)) + " has no sensor");
}

}  // namespace staa::staad
