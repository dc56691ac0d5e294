#pragma once
// The HSR's head Xtion (docs/ARCHITECTURE.md section 4, `openni2`) through OpenNI2
// (libopenni2-dev): 640 x 480 depth at 30 Hz in PIXEL_FORMAT_DEPTH_1_MM.
//
// OpenNI2 delivers frames on its own thread through a frame listener; the listener copies
// each into a preallocated triple buffer, and read() hands the latest one to the perception
// thread: it never allocates and never blocks. Opening fails fast with a clear message (no
// device, a wrong URI, an unsupported mode, no first frame within timeout_s); it never waits
// without a bound. This header does not include OpenNI's: users need only this library.

#include "hal/depth_camera.hpp"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa::hal {

struct OpenNI2Config {
  std::string uri;              // the device (OpenNI2's URI, e.g. "1d27/0601@3/7"); empty: any device
  CameraIntrinsics intrinsics;  // this camera's calibration (default: the Xtion's nominal values)
  CameraMount mount;            // the camera on the robot's base
  // How long opening waits for the first frame (s); 0: does not wait (the stream is started
  // and frames arrive later). A bound, never an open-ended wait.
  double timeout_s = 2.0;
};

// Every failure to open: what() says what is wrong and what to check.
class OpenNI2Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct OpenNI2DeviceInfo {
  std::string uri;
  std::string vendor;
  std::string name;
  int usb_vendor_id = 0;
  int usb_product_id = 0;
};

class OpenNI2Camera final : public DepthCamera {
 public:
  // Initialises OpenNI2, opens the device, sets 640 x 480 DEPTH_1_MM at 30 Hz (mirroring
  // off), starts the stream and waits up to config.timeout_s for a first frame. Throws
  // OpenNI2Error (no device: "openni2: no depth device found (is the Xtion connected? ...");
  // std::invalid_argument for a bad config value. Without a device it fails in well under a
  // second (most of it OpenNI2's shutdown joining its device-watch thread, 0.25-0.5 s).
  explicit OpenNI2Camera(const OpenNI2Config& config);
  ~OpenNI2Camera() override;
  OpenNI2Camera(const OpenNI2Camera&) = delete;
  OpenNI2Camera& operator=(const OpenNI2Camera&) = delete;

  // The newest frame when one arrived since the last call (stamped on CLOCK_MONOTONIC when
  // OpenNI2 handed it over). No allocation, no lock, no wait.
  bool read(rt::Nanos now, DepthFrame& out) override;
  CameraIntrinsics intrinsics() const override { return config_.intrinsics; }
  CameraMount mount() const override { return config_.mount; }

  // What the device itself reports: intrinsics from its fields of view (uncalibrated), and
  // "vendor name (uri)".
  CameraIntrinsics deviceIntrinsics() const;
  std::string deviceDescription() const;
  // Frames copied / rejected (wrong size or format) by the listener so far (any thread).
  std::uint64_t framesReceived() const;
  std::uint64_t framesRejected() const;

  // The devices OpenNI2 sees now (initialises OpenNI2 for the call). Throws OpenNI2Error
  // when OpenNI2 cannot be initialised.
  static std::vector<OpenNI2DeviceInfo> listDevices();

 private:
  class Impl;
  OpenNI2Config config_;
  std::unique_ptr<Impl> impl_;
};

// ---- pure helpers (tested without a device) ----

// Copies a 16-bit depth image of width x height pixels whose rows are stride_bytes apart into
// frame.depth_mm. False (the frame untouched) unless it is 640 x 480 with a stride of at least
// 1280 bytes and data is not null.
bool copyDepthImage(const void* data, int width, int height, int stride_bytes, DepthFrame& frame);

// The pinhole intrinsics of a width x height image with these fields of view (rad), the
// principal point in the centre: fx = (width / 2) / tan(hfov / 2).
CameraIntrinsics intrinsicsFromFieldOfView(double horizontal_fov, double vertical_fov, int width = DepthFrame::kWidth,
                                           int height = DepthFrame::kHeight);

// The first line of the error when no device is found (tests and tools match it).
inline constexpr const char* kNoDepthDeviceMessage = "openni2: no depth device found";

}  // namespace staa::hal
