#pragma once
// camera.backend ros (docs/ARCHITECTURE.md, "Hardware"): depth images from a ROS transport
// (src/app/staad/ros/ros1_camera.hpp for ROS 1) as a DepthCamera, each frame with the
// camera's pose at its stamp (the HSR's head pans and tilts).
//
// offer() runs in the transport's thread: it checks the image, converts it into the write
// slot of a preallocated triple buffer (16UC1 millimetres as they are, in the host's byte
// order; 32FC1 metres rounded to millimetres, no reading (NaN, inf, <= 0, beyond 65.535 m)
// as 0) and publishes it. read() runs in the real-time perception thread: it takes the
// newest frame, allocating nothing, taking no lock, never waiting. A frame that fails a check
// is dropped, counted under its first failed check (RosDepthDrop, in the order below), and
// read() keeps returning nothing new: perception keeps the last good frame's obstacles until
// they go stale.
//
// The frame's stamp (for staleness, on CLOCK_MONOTONIC): the arrival time minus the message's
// age (received_ns - stamp_ns on the transport's clock) when that age is in [0, max_age_s];
// otherwise (the publisher's clock is another machine's and disagrees, or simulated time) the
// arrival time itself. Stamps handed to read() always increase.

#include "hal/depth_camera.hpp"
#include "hal/ros/depth_image.hpp"
#include "rt/triple_buffer.hpp"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace staa::hal {

struct RosDepthCameraConfig {
  // The configured calibration (camera.intrinsics): camera_info must agree with it.
  CameraIntrinsics intrinsics;
  // The nominal mount (camera.mount): mount(), which perception sizes its grid from; each
  // frame carries the pose tf gave for it.
  CameraMount mount;
  // Longest believable message age (s): more, or negative, and the clocks disagree.
  double max_age_s = 0.5;
};

// Why a frame was dropped: the checks in the order offer() makes them.
enum class RosDepthDrop : std::size_t {
  kEncoding,       // not 16UC1 or 32FC1
  kSize,           // not 640 x 480 (DepthFrame::kWidth x kHeight, the Xtion's VGA depth mode)
  kLayout,         // step < width * bytes per pixel, or data size != step * height
  kStamp,          // stamp 0 (unset), or not after the previous accepted frame's
  kNoCameraInfo,   // no camera_info received yet
  kIntrinsics,     // camera_info's size or K disagrees with the configured intrinsics
  kNoPose,         // the transport had no camera pose (tf failed)
  kBadPose,        // the pose is not a valid mount (not finite, not above the floor)
  kCount
};
const char* toString(RosDepthDrop reason);

class RosDepthCamera final : public DepthCamera, public DepthImageSink {
 public:
  // camera_info's fx, fy, cx, cy may differ from the configured ones by this much (pixels): a
  // pixel of fx moves a point at the image's edge by 0.3 % of its range (1 cm at 4 m, a tenth
  // of a grid cell); more is another calibration or another resolution.
  static constexpr double kIntrinsicsTolerancePx = 1.0;

  // Throws io::FieldError (std::invalid_argument) for bad intrinsics or mount (validateCamera)
  // and std::invalid_argument for max_age_s outside [0, 10] s.
  explicit RosDepthCamera(const RosDepthCameraConfig& config);
  RosDepthCamera(const RosDepthCamera&) = delete;
  RosDepthCamera& operator=(const RosDepthCamera&) = delete;

  // DepthImageSink: the transport's thread, one at a time.
  void offer(const DepthImageView& image, const CameraInfoView* info, const CameraPoseSample& pose,
             std::int64_t arrival_mono_ns) override;

  // DepthCamera: the perception thread. The newest accepted frame (with its mount) when one
  // was accepted since the last call.
  bool read(rt::Nanos now, DepthFrame& out) override;
  CameraIntrinsics intrinsics() const override { return config_.intrinsics; }
  CameraMount mount() const override { return config_.mount; }

  // Any thread.
  std::uint64_t accepted() const { return accepted_.load(std::memory_order_relaxed); }
  std::uint64_t dropped(RosDepthDrop reason) const;
  std::uint64_t droppedTotal() const;

 private:
  bool check(const DepthImageView& image, const CameraInfoView* info, const CameraPoseSample& pose);
  void drop(RosDepthDrop reason);
  rt::Nanos monotonicStamp(const DepthImageView& image, std::int64_t arrival_mono_ns);

  RosDepthCameraConfig config_;
  std::unique_ptr<rt::TripleBuffer<DepthFrame>> frames_;  // 3 x 600 KB, allocated once
  // The transport's thread only.
  std::int64_t last_stamp_ns_ = 0;
  rt::Nanos last_mono_ = -1;
  std::atomic<std::uint64_t> accepted_{0};
  std::array<std::atomic<std::uint64_t>, static_cast<std::size_t>(RosDepthDrop::kCount)> dropped_{};
};

// Converts a checked 640 x 480 image (16UC1 or 32FC1, rows `step` bytes apart) into depth_mm
// (no other field). Exposed for tests.
void convertDepthImage(const DepthImageView& image, DepthFrame& frame);

}  // namespace staa::hal
