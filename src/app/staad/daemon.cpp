#include "app/staad/daemon.hpp"

#include "app/staad/channels.hpp"
#include "app/staad/control_task.hpp"
#include "app/staad/depth_sensor.hpp"
#include "app/staad/io_tasks.hpp"
#ifdef STAA_HAVE_ROS1
#include "app/staad/ros_bridge.hpp"
#endif
#include "app/staad/service.hpp"
#include "world/sim_hal.hpp"
#include "hal/socketcan/socketcan.hpp"
#include "rt/activity.hpp"
#include "rt/alloc_count.hpp"
#include "rt/realtime.hpp"
#include "rt/sd_notify.hpp"
#include "rt/signals.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <system_error>

namespace staa::staad {

namespace {

constexpr rt::Nanos kInputWait = 1 * rt::kNanosPerSecond;         // first odometry / obstacle frame
constexpr rt::Nanos kFirstCycleWait = 5 * rt::kNanosPerSecond;    // the control thread's first cycle
constexpr rt::Nanos kStandstillWait = 600 * rt::kNanosPerMilli;   // braking before STOPPING=1
constexpr double kStandstillV = 0.02;                             // m/s
constexpr double kStandstillW = 0.02;                             // rad/s
constexpr int kServicePollMs = 10;

rt::Nanos periodOf(double hz) { return static_cast<rt::Nanos>(std::llround(1e9 / hz)); }

class Daemon {
 public:
  Daemon(DaemonConfig config, rt::Clock& clock, std::ostream& log)
      : config_(std::move(config)), clock_(clock), log_(log) {}
  ~Daemon() { stopThreads(); }

  int run();

 private:
  void createWorkspaces();
  void createRosLink();
  void startRosLink();
  hal::Base* rosBase();
  std::unique_ptr<hal::DepthCamera> rosCamera();
  std::unique_ptr<hal::LaserScanner> rosScanner();
  void startThreads();
  // Starts the thread that steps `runnable` at `hz`, as `activity`.
  void startActivity(std::unique_ptr<rt::PeriodicActivity>& activity, const char* name, rt::Runnable& runnable,
                     const rt::ThreadSpec& spec, double hz);
  bool waitFor(rt::Nanos timeout, bool (Daemon::*done)() const);
  bool inputsArrived() const { return channels_->base.published() > 0 && channels_->obstacles.published() > 0; }
  bool controlCycled() const { return channels_->heartbeat.load(std::memory_order_acquire) > 0; }
  void shutdown();
  void stopThreads();
  void reportTiming(const rt::PeriodicActivity* activity);
  void say(const std::string& line) { log_ << "staad: " << line << std::endl; }
  void createRecorder();

  DaemonConfig config_;
  rt::Clock& clock_;
  std::ostream& log_;
  std::optional<rt::Notifier> notifier_;
  std::unique_ptr<hal::SimHal> sim_;                // hal: sim, or obstacles: sim
  std::unique_ptr<hal::Base> can_base_;             // hal: socketcan
  std::unique_ptr<NoObstacles> no_obstacles_;       // obstacles: none
  std::unique_ptr<OdometrySlot> odometry_slot_;     // obstacles: depth: the pose for perception
  std::unique_ptr<OdometryTap> odometry_tap_;       // ... published by the base thread
  std::unique_ptr<DepthSensor> depth_;              // obstacles: depth
  std::unique_ptr<Channels> channels_;
#ifdef STAA_HAVE_ROS1
  std::unique_ptr<RosBridge> ros_;                  // the ROS link (config ros)
#endif
  std::unique_ptr<ControlTask> task_;
  std::unique_ptr<record::RecordingService> recording_;  // the flight recorder's files (service thread)
  std::unique_ptr<BaseTask> base_task_;
  std::unique_ptr<PerceptionTask> perception_task_;
  std::unique_ptr<Service> service_;
  // The threads that step the tasks (declared last: they end before the tasks go).
  std::unique_ptr<rt::PeriodicActivity> base_;
  std::unique_ptr<rt::PeriodicActivity> perception_;
  std::unique_ptr<rt::PeriodicActivity> control_;
};

void Daemon::createWorkspaces() {
  // sd_notify: a malformed environment is a configuration error.
  std::optional<rt::Nanos> watchdog;
  try {
    notifier_.emplace(rt::Notifier::fromEnvironment());
    watchdog = rt::Notifier::watchdogInterval();
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }

  channels_ = std::make_unique<Channels>(config_.telemetry_records,
                                         config_.recorder.enabled ? config_.recorder.ring_kb * 1024 : 0);
  createRosLink();
  startRosLink();  // before anything is built on the map

  const rt::Nanos now = clock_.now();
  // The simulated world: the base with hal: sim; the movers (the simulated camera) with
  // obstacles: sim, or rendered with camera.backend: sim (config.sim.movers_only with a real
  // base).
  if (config_.hal == HalBackend::kSim || config_.obstacles == ObstacleSource::kSim ||
      (config_.obstacles == ObstacleSource::kDepth && config_.camera.backend == CameraBackend::kSim)) {
    try {
      sim_ = std::make_unique<hal::SimHal>(config_.map, config_.robot, config_.sim, now);
    } catch (const std::invalid_argument& e) {
      std::string message = config_.file.string();
      message.append(": sim: ").append(e.what());
      throw ConfigError(message);
    }
  }
  hal::Base* base = nullptr;
  if (config_.hal == HalBackend::kSocketCan) {
    // The bus is opened before anything else runs: a missing interface or socket is named
    // at once (exit 3), not discovered as a stale robot later.
    try {
      // The clock stamps each command frame's hand-over to the kernel.
      can_base_ = hal::openSocketCanBase(config_.socketcan.interface, config_.socketcan.profile, Pose2{}, &clock_);
    } catch (const hal::CanTransportError& e) {
      // e.what() names the interface or the socket path, and why.
      std::string message = config_.file.string();
      message.append(": socketcan.interface: cannot open the base's bus: ").append(e.what());
      throw DeviceError(message);
    }
    base = can_base_.get();
  } else if (config_.hal == HalBackend::kRos) {
    base = rosBase();
  } else {
    base = &sim_->base();
  }
  hal::ObstacleSensor* obstacles = nullptr;
  if (config_.obstacles == ObstacleSource::kSim) {
    obstacles = &sim_->obstacles();
  } else if (config_.obstacles == ObstacleSource::kDepth) {
    // The camera is opened here, like the bus: no device is exit 3 at once. The base is
    // wrapped so that the perception thread gets the robot's pose (depth_sensor.hpp).
    odometry_slot_ = std::make_unique<OdometrySlot>();
    odometry_tap_ = std::make_unique<OdometryTap>(*base, *odometry_slot_);
    base = odometry_tap_.get();
    try {
      depth_ = makeDepthSensor(config_, sim_.get(), *odometry_slot_, rosCamera(), rosScanner());
    } catch (const DepthCameraError& e) {
      std::string message = config_.file.string();
      message.append(": camera.backend: ").append(e.what());
      throw DeviceError(message);
    } catch (const std::invalid_argument& e) {
      std::string message = config_.file.string();
      message.append(": camera: ").append(e.what());
      throw ConfigError(message);
    }
    obstacles = depth_.get();
  } else {
    no_obstacles_ = std::make_unique<NoObstacles>();
    obstacles = no_obstacles_.get();
  }
  task_ = std::make_unique<ControlTask>(config_, *channels_, clock_);
  createRecorder();
#ifdef STAA_HAVE_ROS1
  if (ros_) ros_->acceptMapsForControl();
#endif
  base_task_ = std::make_unique<BaseTask>(*base, *channels_, periodOf(config_.control_hz));
  perception_task_ = std::make_unique<PerceptionTask>(*obstacles, *channels_);

  ServiceOptions so;
  so.socket_path = config_.socket_path;
  so.socket_mode = config_.socket_mode;
  so.max_clients = config_.socket_max_clients;
  so.idle_timeout = static_cast<rt::Nanos>(config_.socket_idle_timeout_s * static_cast<double>(rt::kNanosPerSecond));
  so.telemetry_path = config_.telemetry_path;
  so.svg_path = config_.svg_path;
  so.watchdog_interval = watchdog;
  so.debug_faults = config_.debug_faults;
  so.recorder = recording_.get();
  service_ = std::make_unique<Service>(*channels_, *notifier_, so, log_);
  // The fields other parts own: the ROS link's counts, the scanner's.
  service_->completeStatusWith([this](Status& s) {
#ifdef STAA_HAVE_ROS1
    if (ros_) ros_->fillStatus(s);
#endif
    if (depth_) s.scanner = depth_->scannerStatus();
  });
  service_->open();
}

// The flight recorder's service half: the session every file carries (the control cycle's
// exact configuration, the robot, the map, this config's text), its files and history.
void Daemon::createRecorder() {
  if (!config_.recorder.enabled) return;
  record::Session session;
  session.source = "staad";
  session.software = record::softwareVersion();
  session.build_type = record::buildType();
  session.recorded_at = record::utcNow();
  session.budget = config_.budget.describe();
  session.control = task_->controlCycle().config();
  session.robot = config_.robot;
  session.map = config_.map;
  session.agents = {{0, "staa"}};
  session.config_text = config_.text;
  if (!config_.robot_file.empty()) {
    std::ifstream in(config_.robot_file);
    session.robot_text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  record::RecorderOptions o;
  o.path = config_.recorder.path;
  o.max_file_bytes = config_.recorder.max_file_mb << 20;
  o.max_files = config_.recorder.max_files;
  o.seconds = config_.recorder.seconds;
  o.fault_dir = config_.recorder.fault_dir;
  o.fault_after_s = config_.recorder.fault_after_s;
  recording_ = std::make_unique<record::RecordingService>(std::move(session), o, [this](const std::string& line) { say(line); });
}

// The ROS link's objects (the base backend of hal: ros among them); nothing starts yet.
void Daemon::createRosLink() {
  if (!config_.ros.enabled) return;
#ifdef STAA_HAVE_ROS1
  ros_ = std::make_unique<RosBridge>(config_, *channels_);
#else
  throw ConfigError(config_.file.string() +
                    ": this staad was built without ROS (hal: ros, map: ros, camera.backend: ros, scanner.backend: ros or a "
                    "ros section need the ROS 1 packages at build time: toolchain/install-deps.sh)");
#endif
}

std::unique_ptr<hal::DepthCamera> Daemon::rosCamera() {
#ifdef STAA_HAVE_ROS1
  if (ros_) return ros_->takeCamera();
#endif
  return nullptr;
}

std::unique_ptr<hal::LaserScanner> Daemon::rosScanner() {
#ifdef STAA_HAVE_ROS1
  if (ros_) return ros_->takeScanner();
#endif
  return nullptr;
}

hal::Base* Daemon::rosBase() {
#ifdef STAA_HAVE_ROS1
  return ros_->base();
#else
  return nullptr;
#endif
}

// The transport starts (no master: exit 3, like a missing bus); with map: ros the first map
// is waited for here, before the control task is built on it.
void Daemon::startRosLink() {
#ifdef STAA_HAVE_ROS1
  if (!ros_) return;
  try {
    ros_->start();
  } catch (const ros::TransportError& e) {
    throw DeviceError(config_.file.string() + ": ros: " + e.what());
  }
  if (config_.map_from_ros) {
    say("waiting for the map on " + config_.ros.transport.map_topic);
    std::optional<PolygonMap> map =
        ros_->waitFirstMap(static_cast<rt::Nanos>(config_.ros.map_wait_s * 1e9), log_);
    if (!map) {
      char wait[32];
      std::snprintf(wait, sizeof wait, "%.1f", config_.ros.map_wait_s);
      throw DeviceError(config_.file.string() + ": map: ros: no map that imports arrived on " +
                        config_.ros.transport.map_topic + " within " + wait +
                        " s (ros.map.wait_s; is map_server running and publishing it latched?)");
    }
    config_.map = std::move(*map);
  }
#endif
}

void Daemon::startActivity(std::unique_ptr<rt::PeriodicActivity>& activity, const char* name, rt::Runnable& runnable,
                           const rt::ThreadSpec& spec, double hz) {
  activity = std::make_unique<rt::PeriodicActivity>(name, runnable, clock_, periodOf(hz));
  activity->start(spec);
  if (!activity->warning().empty()) say(activity->warning());
}

bool Daemon::waitFor(rt::Nanos timeout, bool (Daemon::*done)() const) {
  const rt::Nanos deadline = clock_.now() + timeout;
  while (!(this->*done)()) {
    if (clock_.now() >= deadline) return false;
    clock_.sleepUntil(clock_.now() + rt::kNanosPerMilli);
  }
  return true;
}

void Daemon::startThreads() {
  startActivity(base_, "base", *base_task_, config_.base_thread, config_.base_hz);
  startActivity(perception_, "perception", *perception_task_, config_.perception_thread, config_.perception_hz);
  if (!waitFor(kInputWait, &Daemon::inputsArrived)) {
    say("warning: no odometry or obstacle frame within 1 s of start-up; the robot is held (fault) until they come");
  }
  startActivity(control_, "control", *task_, config_.control_thread, config_.control_hz);
  if (!waitFor(kFirstCycleWait, &Daemon::controlCycled)) {
    throw std::runtime_error("the control thread did not run its first cycle within 5 s");
  }
}

void Daemon::stopThreads() {
  // All at once, then each joined: the base thread's last command is a brake.
  for (rt::PeriodicActivity* a : {control_.get(), perception_.get(), base_.get()}) {
    if (a != nullptr) a->requestStop();
  }
  for (rt::PeriodicActivity* a : {control_.get(), perception_.get(), base_.get()}) {
    if (a != nullptr) a->stop();
  }
}

void Daemon::reportTiming(const rt::PeriodicActivity* activity) {
  if (activity == nullptr || !activity->started()) return;
  const rt::ActivityTiming t = activity->timing();
  const rt::PeriodicCounters& c = t.counters;
  const rt::TimingSummary& e = t.execution;
  const rt::TimingSummary& k = t.wake;
  char line[448];
  std::snprintf(line, sizeof line,
                "[%s] %llu cycles; execution p50 %.0f us, p99 %.0f us, max %.0f us; wake-up p99 %.0f us, max %.0f us; "
                "%llu overruns (%llu execution, %llu late wake-ups, %llu preempted, %llu stalls), %llu periods skipped, "
                "%llu cycles blocked, %llu faulted",
                activity->name().c_str(), static_cast<unsigned long long>(c.cycles), e.p50_us, e.p99_us, e.max_us,
                k.p99_us, k.max_us,
                static_cast<unsigned long long>(c.overruns), static_cast<unsigned long long>(c.execution_overruns),
                static_cast<unsigned long long>(c.late_wakeups), static_cast<unsigned long long>(c.preempted),
                static_cast<unsigned long long>(c.stalls), static_cast<unsigned long long>(c.skipped_periods),
                static_cast<unsigned long long>(c.blocked_cycles), static_cast<unsigned long long>(c.faulted_cycles));
  say(line);
}

void Daemon::shutdown() {
  // Brake to standstill (bounded), then STOPPING=1, then the threads end.
  const rt::Nanos t0 = clock_.now();
  channels_->shutdown.store(true, std::memory_order_release);
  bool standing = false;
  rt::Nanos now = t0;
  for (; !standing && now - t0 < kStandstillWait; now = clock_.now()) {
    service_->runOnce(now, 5);
    const Status& s = service_->latest();
    standing = s.time_s * 1e9 >= static_cast<double>(t0) && std::abs(s.v) < kStandstillV && std::abs(s.w) < kStandstillW;
  }
  char braked[96];
  std::snprintf(braked, sizeof braked, standing ? "braked to standstill in %.0f ms" : "still moving after %.0f ms of braking",
                static_cast<double>(now - t0) * 1e-6);
  say(braked);
  service_->stopping();
  stopThreads();
#ifdef STAA_HAVE_ROS1
  if (ros_) ros_->stop();  // after the base thread's last command, a brake, went out
#endif
  task_->releaseMap();  // the map swapped in last, freed now that no thread plans on it
  service_->drain();
  const Status& s = service_->latest();
  char line[160];
  std::snprintf(line, sizeof line, "stopped at (%.3f, %.3f, %.3f), v %.3f m/s, w %.3f rad/s; %llu rt allocations",
                s.pose.x, s.pose.y, s.pose.theta, s.v, s.w,
                static_cast<unsigned long long>(rt::realtimeAllocations()));
  say(line);
  for (const rt::PeriodicActivity* a : {control_.get(), base_.get(), perception_.get()}) reportTiming(a);
  if (depth_ && depth_->hasScanner()) {
    say("scanner: " + std::to_string(depth_->frames()) + " depth frames, " + std::to_string(depth_->scansUsed()) +
        " perceived with a scan, " + std::to_string(depth_->scansTooOld()) + " without (the newest scan older than " +
        "scanner.max_age_s), " + std::to_string(depth_->framesWithoutScan()) + " before the first scan");
  }
  service_->writeRunSvg(config_.map, config_.robot.footprint);
  service_->close();
  if (recording_) {
    recording_->close();
    const record::RecorderStats& r = recording_->stats();
    say("recorder: " + std::to_string(r.cycles) + " cycles recorded, " + std::to_string(r.files) + " files, " +
        std::to_string(r.fault_files) + " fault files" +
        (r.write_failures > 0 ? ", " + std::to_string(r.write_failures) + " write failures (" + r.last_error + ")" : std::string()));
  }
}

int Daemon::run() {
  try {
    createWorkspaces();
  } catch (const ConfigError& e) {
    say(e.what());
    return kExitBadConfig;
  } catch (const DeviceError& e) {
    say(e.what());
    return kExitDevice;
  }
  if (config_.debug_faults) say("warning: debug.faults is on: the control socket takes fault-injection requests (tests only)");

  const rt::MemoryReport memory = rt::lockMemory(config_.heap_prefault_bytes, config_.stack_prefault_bytes);
  for (const std::string& w : memory.warnings) say("warning: " + w);

  startThreads();
  // After the real-time threads started (they do not inherit it): the service thread only.
  if (const std::string refused = rt::setThisThreadNice(config_.service_nice); !refused.empty()) {
    say("warning: threads.service: " + refused + " (the control socket answers at normal priority)");
  }
  rt::resetRealtimeAllocations();
  service_->watchTiming(control_.get(), base_->started() ? base_.get() : nullptr,
                        base_->started() ? base_task_.get() : nullptr,
                        perception_ && perception_->started() ? perception_.get() : nullptr);
  service_->ready(clock_.now());
  {
    std::string hal(toString(config_.hal));
    if (config_.hal == HalBackend::kSocketCan) hal.append(" on ").append(config_.socketcan.interface);
    if (config_.ros.enabled) hal.append(", ROS master ").append(config_.ros.transport.master_uri.empty() ? "$ROS_MASTER_URI" : config_.ros.transport.master_uri);
    hal.append(", obstacles ").append(toString(config_.obstacles));
    char line[512];
    std::snprintf(line, sizeof line, "ready: hal %s, control %.0f Hz (%s), base %.0f Hz, perception %.0f Hz, socket %s",
                  hal.c_str(), config_.control_hz,
                  control_->realtime() ? "SCHED_FIFO" : "normal scheduling", config_.base_hz,
                  config_.perception_hz, config_.socket_path.c_str());
    say(line);
  }

  while (!service_->runOnce(clock_.now(), kServicePollMs)) {
#ifdef STAA_HAVE_ROS1
    if (ros_) ros_->poll(clock_.now(), *service_, log_);
#endif
  }
  shutdown();
  return kExitOk;
}

}  // namespace

std::filesystem::path defaultConfigPath() {
  for (const char* candidate : {"config/staad.yaml", "/etc/staad/staad.yaml"}) {
    std::error_code ec;
    if (std::filesystem::exists(candidate, ec)) return candidate;
  }
  return {};
}

DaemonConfig loadConfig(const DaemonOptions& options) {
  std::filesystem::path file = options.config_file;
  if (file.empty()) {
    file = defaultConfigPath();
    if (file.empty()) {
      throw ConfigError("no config file: neither config/staad.yaml nor /etc/staad/staad.yaml exists (use --config FILE)");
    }
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    std::string message = "config file '";
    message.append(file.string()).append("': ").append(std::filesystem::exists(file, ec) ? "not a regular file" : "not found");
    throw ConfigError(message);
  }
  // --hal is applied while parsing: the sections it needs (sim, socketcan) are checked then.
  DaemonConfig config = loadDaemonConfig(file, options.hal);
  if (options.socket_path) config.socket_path = *options.socket_path;
  if (options.telemetry_path) config.telemetry_path = *options.telemetry_path;
  if (options.svg_path) config.svg_path = *options.svg_path;
  for (const std::string& r : options.ros_remappings) {
    const std::size_t at = r.find(":=");
    if (at == 0 || at + 2 >= r.size()) {
      throw ConfigError("command line: a ROS remapping is NAME:=VALUE, got '" + r + "'");
    }
    config.ros.transport.remappings.emplace_back(r.substr(0, at), r.substr(at + 2));
  }
  return config;
}

int runDaemon(const DaemonOptions& options, rt::Clock& clock, std::ostream& log) {
  try {
    DaemonConfig config;
    try {
      config = loadConfig(options);
    } catch (const ConfigError& e) {
      log << "staad: " << e.what() << std::endl;
      return kExitBadConfig;
    }
    // Before any thread exists: SIGTERM/SIGINT arrive only through the service's descriptor.
    rt::blockTerminationSignals();
    Daemon daemon(std::move(config), clock, log);
    return daemon.run();
  } catch (const ServiceError& e) {
    log << "staad: " << e.what() << std::endl;
    return kExitFailure;
  } catch (const std::system_error& e) {
    log << "staad: " << e.what() << std::endl;
    return kExitFailure;
  } catch (const std::exception& e) {
    log << "staad: " << e.what() << std::endl;
    return kExitFailure;
  } catch (...) {
    log << "staad: unknown error" << std::endl;
    return kExitFailure;
  }
}

}  // namespace staa::staad
