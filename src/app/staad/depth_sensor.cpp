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
// The scanner's noise stream, apart from the camera's (the seed is shared).
constexpr std::uint64_t kScanSeedMix = 0xD1B54A32D192ED03ULL;

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

hal::SimScanConfig simScanConfig(const ScannerConfig& scanner, std::uint64_t seed) {
  hal::SimScanConfig c;
  c.mount = scanner.mount;
  c.centredSweep(scanner.fov_deg, scanner.beams);  // a full turn one increment short of it
  c.range_min = scanner.range_min_m;
  c.range_max = scanner.range_max_m;
  c.noise_m = scanner.noise_m;
  c.dropout = 0.0;
  c.seed = seed ^ kScanSeedMix;
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

void DepthSensor::addSimScanner(const PolygonMap& map, const ScannerConfig& scanner, std::uint64_t seed) {
  if (movers_ == nullptr) {
    throw std::logic_error("DepthSensor: the sim scanner scans the sim camera's world; this sensor has another camera");
  }
  scan_renderer_ = std::make_unique<hal::ScanRenderer>(map, simScanConfig(scanner, seed));
  scan_ = std::make_unique<hal::LaserScan>();
  scanner_config_ = scanner;
  scanner_config_.backend = ScannerBackend::kSim;
  scan_max_age_ = static_cast<rt::Nanos>(scanner.max_age_s * 1e9);
}

void DepthSensor::addScanner(const ScannerConfig& scanner, std::unique_ptr<hal::LaserScanner> device) {
  if (!device) throw std::invalid_argument("DepthSensor: no laser scanner");
  scanner_ = std::move(device);
  scan_ = std::make_unique<hal::LaserScan>();
  scanner_config_ = scanner;
  if (scanner_config_.backend == ScannerBackend::kNone) scanner_config_.backend = ScannerBackend::kRos;
  scan_max_age_ = static_cast<rt::Nanos>(scanner.max_age_s * 1e9);
}

ScannerStatus DepthSensor::scannerStatus() const {
  ScannerStatus s;
  s.enabled = hasScanner();
  if (!s.enabled) return s;
  s.backend = toString(scanner_config_.backend).data();  // a literal: NUL-terminated
  s.scans_used = scansUsed();
  s.scans_too_old = scansTooOld();
  s.frames_without_scan = framesWithoutScan();
  s.scan_points = lastScanPoints();
  return s;
}

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
  prism_count_ = n;
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
  const ScanInput scan = scanFor(now, robot);
  stats_ = detector_.process(*frame_, robot, out, scan);
  if (scan.scan != nullptr) last_scan_points_.store(stats_.scan_points, std::memory_order_relaxed);
  ++frames_;
  return true;
}

ScanInput DepthSensor::scanFor(rt::Nanos now, const Pose2& robot) {
  if (!hasScanner()) return ScanInput{};
  if (scan_renderer_) {
    // The same movers and pose as the frame just rendered, at the same instant.
    scan_renderer_->render(robot, std::span<const hal::PrismView>(prisms_.data(), prism_count_), *scan_);
    scan_->stamp = frame_->stamp;
    scan_->sequence = frame_->sequence;
  } else {
    scanner_->read(now, *scan_);  // nothing new: the previous scan, judged by its age below
  }
  if (scan_->stamp < 0) {
    without_scan_.fetch_add(1, std::memory_order_relaxed);
    last_scan_points_.store(0, std::memory_order_relaxed);
    return ScanInput{};
  }
  // Either may be the newer: the camera's frames come with more latency than the scans.
  const rt::Nanos apart = scan_->stamp > frame_->stamp ? scan_->stamp - frame_->stamp : frame_->stamp - scan_->stamp;
  if (apart > scan_max_age_) {
    scans_too_old_.fetch_add(1, std::memory_order_relaxed);
    last_scan_points_.store(0, std::memory_order_relaxed);
    return ScanInput{};
  }
  scans_used_.fetch_add(1, std::memory_order_relaxed);
  return ScanInput{scan_.get(), scanner_config_.mount, robot};
}

namespace {

// The scanner of `config.scanner`, added to `sensor` (backend none: nothing).
void addScannerOf(const DaemonConfig& config, DepthSensor& sensor, std::unique_ptr<hal::LaserScanner> ros_scanner) {
  switch (config.scanner.backend) {
    case ScannerBackend::kNone: return;
    case ScannerBackend::kSim: sensor.addSimScanner(config.map, config.scanner, config.sim.seed); return;
    case ScannerBackend::kRos:
      // Without ROS built in, the daemon refused the config before (the ROS link it needs).
      if (ros_scanner == nullptr) throw std::logic_error("makeDepthSensor: scanner.backend ros needs the ROS link's scanner");
      sensor.addScanner(config.scanner, std::move(ros_scanner));
      return;
  }
}

std::unique_ptr<DepthSensor> makeCameraSensor(const DaemonConfig& config, hal::SimHal* sim, OdometrySlot& pose,
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

}  // namespace

std::unique_ptr<DepthSensor> makeDepthSensor(const DaemonConfig& config, hal::SimHal* sim, OdometrySlot& pose,
                                             std::unique_ptr<hal::DepthCamera> ros_camera,
                                             std::unique_ptr<hal::LaserScanner> ros_scanner) {
  std::unique_ptr<DepthSensor> sensor = makeCameraSensor(config, sim, pose, std::move(ros_camera));
  addScannerOf(config, *sensor, std::move(ros_scanner));
  return sensor;
}

}  // namespace staa::staad
