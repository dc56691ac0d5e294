#include "hal/ros/ros_depth_camera.hpp"

#include "hal/camera_model.hpp"
#include "geometry/types.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace staa::hal {
namespace {

constexpr std::uint32_t kWidth = DepthFrame::kWidth;
constexpr std::uint32_t kHeight = DepthFrame::kHeight;
constexpr double kMaxAgeLimitS = 10.0;

bool is16UC1(const char* encoding) { return encoding != nullptr && std::strcmp(encoding, "16UC1") == 0; }
bool is32FC1(const char* encoding) { return encoding != nullptr && std::strcmp(encoding, "32FC1") == 0; }

// Metres to millimetres, rounded; no reading (NaN, inf, <= 0, more than 16 bits) is 0.
std::uint16_t millimetres(float metres) {
  const double mm = std::round(static_cast<double>(metres) * 1000.0);
  return (mm >= 1.0 && mm <= 65535.0) ? static_cast<std::uint16_t>(mm) : std::uint16_t{0};
}

bool near(double a, double b) { return std::abs(a - b) <= RosDepthCamera::kIntrinsicsTolerancePx; }

bool validMount(const CameraPoseSample& p) {
  const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.roll) &&
                      std::isfinite(p.pitch) && std::isfinite(p.yaw);
  return finite && p.z > 0.0 && std::abs(p.roll) <= kPi && std::abs(p.pitch) <= kPi && std::abs(p.yaw) <= kPi;
}

}  // namespace

const char* toString(RosDepthDrop reason) {
  switch (reason) {
    case RosDepthDrop::kEncoding: return "encoding";
    case RosDepthDrop::kSize: return "size";
    case RosDepthDrop::kLayout: return "layout";
    case RosDepthDrop::kStamp: return "stamp";
    case RosDepthDrop::kNoCameraInfo: return "no_camera_info";
    case RosDepthDrop::kIntrinsics: return "intrinsics";
    case RosDepthDrop::kNoPose: return "no_pose";
    case RosDepthDrop::kBadPose: return "bad_pose";
    case RosDepthDrop::kCount: break;
  }
  return "unknown";
}

void convertDepthImage(const DepthImageView& image, DepthFrame& frame) {
  const bool wide = is32FC1(image.encoding);
  for (std::uint32_t v = 0; v < kHeight; ++v) {
    const std::uint8_t* row = image.data + static_cast<std::size_t>(v) * image.step;
    std::uint16_t* out = frame.depth_mm.data() + static_cast<std::size_t>(v) * kWidth;
    if (!wide && image.big_endian == (std::endian::native == std::endian::big)) {
      std::memcpy(out, row, kWidth * sizeof(std::uint16_t));
      continue;
    }
    for (std::uint32_t u = 0; u < kWidth; ++u) {
      if (!wide) {
        const std::uint8_t* b = row + 2 * static_cast<std::size_t>(u);
        out[u] = image.big_endian ? static_cast<std::uint16_t>((b[0] << 8) | b[1])
                                  : static_cast<std::uint16_t>((b[1] << 8) | b[0]);
        continue;
      }
      const std::uint8_t* b = row + 4 * static_cast<std::size_t>(u);
      const std::uint32_t bits =
          image.big_endian ? (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) | (std::uint32_t{b[2]} << 8) | b[3]
                           : (std::uint32_t{b[3]} << 24) | (std::uint32_t{b[2]} << 16) | (std::uint32_t{b[1]} << 8) | b[0];
      out[u] = millimetres(std::bit_cast<float>(bits));
    }
  }
}

RosDepthCamera::RosDepthCamera(const RosDepthCameraConfig& config)
    : config_(config), frames_(std::make_unique<rt::TripleBuffer<DepthFrame>>()) {
  validateCamera(config.intrinsics, config.mount);
  if (!(config.max_age_s >= 0.0 && config.max_age_s <= kMaxAgeLimitS)) {
    throw std::invalid_argument("ros camera: max_age_s must be in [0, 10] s, got " + std::to_string(config.max_age_s));
  }
}

void RosDepthCamera::drop(RosDepthDrop reason) {
  dropped_[static_cast<std::size_t>(reason)].fetch_add(1, std::memory_order_relaxed);
}

bool RosDepthCamera::check(const DepthImageView& image, const CameraInfoView* info, const CameraPoseSample& pose) {
  const bool u16 = is16UC1(image.encoding);
  if (!u16 && !is32FC1(image.encoding)) {
    drop(RosDepthDrop::kEncoding);
    return false;
  }
  if (image.width != kWidth || image.height != kHeight) {
    drop(RosDepthDrop::kSize);
    return false;
  }
  const std::size_t row_bytes = static_cast<std::size_t>(kWidth) * (u16 ? 2 : 4);
  if (image.data == nullptr || image.step < row_bytes ||
      image.size != static_cast<std::size_t>(image.step) * image.height) {
    drop(RosDepthDrop::kLayout);
    return false;
  }
  if (image.stamp_ns <= 0 || image.stamp_ns <= last_stamp_ns_) {
    drop(RosDepthDrop::kStamp);
    return false;
  }
  if (info == nullptr) {
    drop(RosDepthDrop::kNoCameraInfo);
    return false;
  }
  const CameraIntrinsics& k = config_.intrinsics;
  if (info->width != kWidth || info->height != kHeight || !near(info->K[0], k.fx) || !near(info->K[4], k.fy) ||
      !near(info->K[2], k.cx) || !near(info->K[5], k.cy)) {
    drop(RosDepthDrop::kIntrinsics);
    return false;
  }
  if (!pose.valid) {
    drop(RosDepthDrop::kNoPose);
    return false;
  }
  if (!validMount(pose)) {
    drop(RosDepthDrop::kBadPose);
    return false;
  }
  return true;
}

rt::Nanos RosDepthCamera::monotonicStamp(const DepthImageView& image, std::int64_t arrival_mono_ns) {
  rt::Nanos stamp = arrival_mono_ns;
  const auto max_age = static_cast<std::int64_t>(config_.max_age_s * 1e9);
  if (image.received_ns >= 0) {  // stamp_ns > 0 (checked): no overflow
    const std::int64_t age = image.received_ns - image.stamp_ns;
    if (age >= 0 && age <= max_age) stamp = arrival_mono_ns - age;
  }
  if (last_mono_ >= 0 && stamp <= last_mono_) stamp = last_mono_ + 1;
  return stamp;
}

void RosDepthCamera::offer(const DepthImageView& image, const CameraInfoView* info, const CameraPoseSample& pose,
                           std::int64_t arrival_mono_ns) {
  if (!check(image, info, pose)) return;
  DepthFrame& f = frames_->writeBuffer();
  convertDepthImage(image, f);
  f.stamp = monotonicStamp(image, arrival_mono_ns);
  f.sequence = accepted() + 1;
  f.has_mount = true;
  f.mount = CameraMount{pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw};
  last_stamp_ns_ = image.stamp_ns;
  last_mono_ = f.stamp;
  frames_->publish();
  accepted_.fetch_add(1, std::memory_order_relaxed);
}

bool RosDepthCamera::read(rt::Nanos /*now*/, DepthFrame& out) {
  if (!frames_->update()) return false;
  out = frames_->readBuffer();
  return true;
}

std::uint64_t RosDepthCamera::dropped(RosDepthDrop reason) const {
  if (reason == RosDepthDrop::kCount) return 0;
  return dropped_[static_cast<std::size_t>(reason)].load(std::memory_order_relaxed);
}

std::uint64_t RosDepthCamera::droppedTotal() const {
  std::uint64_t total = 0;
  for (const auto& d : dropped_) total += d.load(std::memory_order_relaxed);
  return total;
}

}  // namespace staa::hal
