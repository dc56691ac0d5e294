#include "hal/openni2/openni2_camera.hpp"

#include "rt/clock.hpp"
#include "rt/triple_buffer.hpp"

#include <OpenNI.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <thread>

namespace staa::hal {
namespace {

constexpr int kFps = 30;
// Longest first-frame wait accepted in a config (s): beyond it, a stuck device looks like a
// hung daemon to systemd.
constexpr double kMaxTimeoutS = 60.0;

std::string lastError() {
  std::string e = openni::OpenNI::getExtendedError();
  while (!e.empty() && (e.back() == '\n' || e.back() == ' ')) e.pop_back();
  while (!e.empty() && (e.front() == '\t' || e.front() == ' ')) e.erase(e.begin());
  return e.empty() ? "no detail from OpenNI2" : e;
}

std::string noDeviceMessage(const std::string& detail) {
  return std::string(kNoDepthDeviceMessage) +
         " (is the Xtion connected? `lsusb` should list 1d27:0601 or 1d27:0600 (ASUS/PrimeSense); check its "
         "USB cable and power, and that /lib/udev/rules.d/60-libopenni2-0.rules gives you access): " +
         detail;
}

std::string describe(const openni::VideoMode& m) {
  std::ostringstream s;
  s << m.getResolutionX() << "x" << m.getResolutionY() << "@" << m.getFps() << " format " << m.getPixelFormat();
  return s.str();
}

std::string deviceList(const openni::Array<openni::DeviceInfo>& list) {
  if (list.getSize() == 0) return "none";
  std::string s;
  for (int i = 0; i < list.getSize(); ++i) {
    if (i > 0) s += ", ";
    s += std::string("'") + list[i].getUri() + "' (" + list[i].getVendor() + " " + list[i].getName() + ")";
  }
  return s;
}

}  // namespace

bool copyDepthImage(const void* data, int width, int height, int stride_bytes, DepthFrame& frame) {
  constexpr int kRowBytes = DepthFrame::kWidth * static_cast<int>(sizeof(std::uint16_t));
  if (data == nullptr || width != DepthFrame::kWidth || height != DepthFrame::kHeight || stride_bytes < kRowBytes) {
    return false;
  }
  const auto* src = static_cast<const unsigned char*>(data);
  auto* dst = reinterpret_cast<unsigned char*>(frame.depth_mm.data());
  if (stride_bytes == kRowBytes) {
    std::memcpy(dst, src, static_cast<std::size_t>(kRowBytes) * DepthFrame::kHeight);
    return true;
  }
  for (int v = 0; v < DepthFrame::kHeight; ++v) {
    std::memcpy(dst + static_cast<std::size_t>(v) * kRowBytes, src + static_cast<std::size_t>(v) * stride_bytes,
                kRowBytes);
  }
  return true;
}

CameraIntrinsics intrinsicsFromFieldOfView(double horizontal_fov, double vertical_fov, int width, int height) {
  CameraIntrinsics k;
  k.fx = 0.5 * width / std::tan(0.5 * horizontal_fov);
  k.fy = 0.5 * height / std::tan(0.5 * vertical_fov);
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  return k;
}

// ---- the device, its stream and the listener on OpenNI2's thread ----

class OpenNI2Camera::Impl final : public openni::VideoStream::NewFrameListener {
 public:
  ~Impl() override { close(); }

  void open(const OpenNI2Config& config) {
    if (openni::OpenNI::initialize() != openni::STATUS_OK) {
      throw OpenNI2Error("openni2: cannot initialise OpenNI2 (are its drivers installed, e.g. "
                         "/usr/lib/x86_64-linux-gnu/OpenNI2/Drivers/libPS1080.so?): " +
                         lastError());
    }
    initialized_ = true;
    openni::Array<openni::DeviceInfo> devices;
    openni::OpenNI::enumerateDevices(&devices);
    if (config.uri.empty()) {
      if (devices.getSize() == 0) throw OpenNI2Error(noDeviceMessage("OpenNI2 lists no device"));
      if (device_.open(openni::ANY_DEVICE) != openni::STATUS_OK) throw OpenNI2Error(noDeviceMessage(lastError()));
    } else if (device_.open(config.uri.c_str()) != openni::STATUS_OK) {
      const std::string detail = lastError();
      if (devices.getSize() == 0) throw OpenNI2Error(noDeviceMessage("cannot open '" + config.uri + "': " + detail));
      throw OpenNI2Error("openni2: cannot open device '" + config.uri + "': " + detail +
                         "; devices found: " + deviceList(devices));
    }
    const openni::DeviceInfo& info = device_.getDeviceInfo();
    description_ = std::string(info.getVendor()) + " " + info.getName() + " (" + info.getUri() + ")";
    if (!device_.hasSensor(openni::SENSOR_DEPTH)) throw OpenNI2Error("openni2: " + description_ + " has no depth sensor");
    if (stream_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      throw OpenNI2Error("openni2: cannot create the depth stream of " + description_ + ": " + lastError());
    }
    setMode();
    // The Xtion's firmware may mirror the image; the pinhole model here is not mirrored. A
    // device without the property is left as it is.
    stream_.setMirroringEnabled(false);
    if (stream_.addNewFrameListener(this) != openni::STATUS_OK) {
      throw OpenNI2Error("openni2: cannot listen to the depth stream of " + description_ + ": " + lastError());
    }
    listening_ = true;
    if (stream_.start() != openni::STATUS_OK) {
      throw OpenNI2Error("openni2: cannot start the depth stream of " + description_ + ": " + lastError());
    }
    started_ = true;
    device_intrinsics_ = intrinsicsFromFieldOfView(stream_.getHorizontalFieldOfView(), stream_.getVerticalFieldOfView());
    waitForFirstFrame(config.timeout_s);
  }

  void close() {
    if (listening_) stream_.removeNewFrameListener(this);
    listening_ = false;
    if (started_) stream_.stop();
    started_ = false;
    if (stream_.isValid()) stream_.destroy();
    if (device_.isValid()) device_.close();
    if (initialized_) openni::OpenNI::shutdown();
    initialized_ = false;
  }

  // OpenNI2's thread: copy the frame into the triple buffer's write slot and publish it.
  void onNewFrame(openni::VideoStream& stream) override {
    openni::VideoFrameRef ref;
    if (stream.readFrame(&ref) != openni::STATUS_OK || !ref.isValid() ||
        ref.getVideoMode().getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM) {
      rejected_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    DepthFrame& f = frames_.writeBuffer();
    if (!copyDepthImage(ref.getData(), ref.getWidth(), ref.getHeight(), ref.getStrideInBytes(), f)) {
      rejected_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    // Arrival time on the daemon's clock (the device's own timestamps run on another clock).
    f.stamp = clock_.now();
    f.sequence = received_.fetch_add(1, std::memory_order_relaxed) + 1;
    frames_.publish();
  }

  rt::TripleBuffer<DepthFrame>& frames() { return frames_; }
  const std::string& description() const { return description_; }
  const CameraIntrinsics& deviceIntrinsics() const { return device_intrinsics_; }
  std::uint64_t received() const { return received_.load(std::memory_order_relaxed); }
  std::uint64_t rejected() const { return rejected_.load(std::memory_order_relaxed); }

 private:
  void setMode() {
    const openni::SensorInfo& sensor = stream_.getSensorInfo();
    const openni::Array<openni::VideoMode>& modes = sensor.getSupportedVideoModes();
    openni::VideoMode wanted;
    wanted.setResolution(DepthFrame::kWidth, DepthFrame::kHeight);
    wanted.setFps(kFps);
    wanted.setPixelFormat(openni::PIXEL_FORMAT_DEPTH_1_MM);
    if (stream_.setVideoMode(wanted) == openni::STATUS_OK) return;
    std::string supported;
    for (int i = 0; i < modes.getSize(); ++i) supported += (i > 0 ? ", " : "") + describe(modes[i]);
    throw OpenNI2Error("openni2: " + description_ + " does not accept depth mode " + describe(wanted) + " (" +
                       lastError() + "); it supports: " + (supported.empty() ? "none listed" : supported));
  }

  void waitForFirstFrame(double timeout_s) {
    if (timeout_s <= 0.0) return;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (frames_.published() == 0) {
      if (std::chrono::steady_clock::now() >= deadline) {
        std::ostringstream s;
        s << "openni2: " << description_ << " opened but sent no depth frame within " << timeout_s
          << " s (rejected frames: " << rejected() << "; a USB 3 port or hub can starve the Xtion: try a USB 2 port)";
        throw OpenNI2Error(s.str());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  openni::Device device_;
  openni::VideoStream stream_;
  bool initialized_ = false;
  bool listening_ = false;
  bool started_ = false;
  std::string description_;
  CameraIntrinsics device_intrinsics_;
  rt::MonotonicClock clock_;
  rt::TripleBuffer<DepthFrame> frames_;
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> rejected_{0};
};

OpenNI2Camera::OpenNI2Camera(const OpenNI2Config& config) : config_(config) {
  const CameraIntrinsics& k = config.intrinsics;
  if (!(k.fx > 0.0 && std::isfinite(k.fx) && k.fy > 0.0 && std::isfinite(k.fy) && std::isfinite(k.cx) &&
        std::isfinite(k.cy))) {
    throw std::invalid_argument("openni2: config.intrinsics must have finite fx, fy > 0 and a finite centre, got fx " +
                                std::to_string(k.fx) + ", fy " + std::to_string(k.fy));
  }
  if (!(config.timeout_s >= 0.0 && config.timeout_s <= kMaxTimeoutS)) {
    throw std::invalid_argument("openni2: config.timeout_s must be in [0, 60] (s), got " +
                                std::to_string(config.timeout_s));
  }
  impl_ = std::make_unique<Impl>();
  impl_->open(config);  // on a throw, impl_'s destructor closes what was opened
}

OpenNI2Camera::~OpenNI2Camera() = default;

bool OpenNI2Camera::read(rt::Nanos /*now*/, DepthFrame& out) {
  if (!impl_->frames().update()) return false;
  out = impl_->frames().readBuffer();
  return true;
}

CameraIntrinsics OpenNI2Camera::deviceIntrinsics() const { return impl_->deviceIntrinsics(); }
std::string OpenNI2Camera::deviceDescription() const { return impl_->description(); }
std::uint64_t OpenNI2Camera::framesReceived() const { return impl_->received(); }
std::uint64_t OpenNI2Camera::framesRejected() const { return impl_->rejected(); }

std::vector<OpenNI2DeviceInfo> OpenNI2Camera::listDevices() {
  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    throw OpenNI2Error("openni2: cannot initialise OpenNI2: " + lastError());
  }
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<OpenNI2DeviceInfo> out;
  for (int i = 0; i < devices.getSize(); ++i) {
    out.push_back(OpenNI2DeviceInfo{devices[i].getUri(), devices[i].getVendor(), devices[i].getName(),
                                    devices[i].getUsbVendorId(), devices[i].getUsbProductId()});
  }
  openni::OpenNI::shutdown();
  return out;
}

}  // namespace staa::hal
