// The OpenNI2 backend without a camera (this machine has none): opening fails quickly with a
// message that says what to check, and the frame copy and intrinsics helpers are exact.
#include "hal/openni2/openni2_camera.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <sys/wait.h>

// OpenNI2 leaks in its drivers, which it unloads at shutdown (so LeakSanitizer cannot even
// name them): a program of nothing but OpenNI::initialize/shutdown "leaks" 330 KB under ASan.
// Leak checking is off for this test program and the probe it runs (the sanitizers' hook;
// inert in a build without them). Address and UB checking stay on.
extern "C" const char* __lsan_default_options() { return "detect_leaks=0"; }

namespace staa::hal {
namespace {

// Skips when a depth camera is attached (the tests below are about its absence).
#define SKIP_IF_A_CAMERA_IS_ATTACHED()                                                           \
  do {                                                                                           \
    if (!OpenNI2Camera::listDevices().empty()) GTEST_SKIP() << "a depth camera is attached";     \
  } while (0)

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(OpenNI2Camera, WithoutADeviceOpeningFailsFastWithAClearMessage) {
  SKIP_IF_A_CAMERA_IS_ATTACHED();
  OpenNI2Config config;
  config.timeout_s = 5.0;  // the wait for a first frame must not even start
  const auto t0 = std::chrono::steady_clock::now();
  try {
    OpenNI2Camera camera(config);
    FAIL() << "opened a camera that is not there";
  } catch (const OpenNI2Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(kNoDepthDeviceMessage, 0), 0u) << what;
    EXPECT_NE(what.find("is the Xtion connected?"), std::string::npos) << what;
    EXPECT_NE(what.find("lsusb"), std::string::npos) << what;
  }
  EXPECT_LT(secondsSince(t0), 2.0);
  // OpenNI2 was shut down cleanly: a second attempt fails the same way.
  EXPECT_THROW(OpenNI2Camera{config}, OpenNI2Error);
}

TEST(OpenNI2Camera, AnUnknownUriFailsFastNamingIt) {
  SKIP_IF_A_CAMERA_IS_ATTACHED();
  OpenNI2Config config;
  config.uri = "1d27/0601@9/99";
  const auto t0 = std::chrono::steady_clock::now();
  try {
    OpenNI2Camera camera(config);
    FAIL() << "opened " << config.uri;
  } catch (const OpenNI2Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(kNoDepthDeviceMessage), std::string::npos) << what;
    EXPECT_NE(what.find("'1d27/0601@9/99'"), std::string::npos) << what;
  }
  EXPECT_LT(secondsSince(t0), 2.0);
}

TEST(OpenNI2Camera, RejectsABadTimeoutBeforeTouchingTheDevice) {
  OpenNI2Config config;
  config.timeout_s = -1.0;
  try {
    OpenNI2Camera camera(config);
    FAIL() << "negative timeout accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("timeout_s"), std::string::npos) << e.what();
  }
}

TEST(OpenNI2Camera, ProbeExitsWith3AndTheMessageWithoutADevice) {
  SKIP_IF_A_CAMERA_IS_ATTACHED();
  const std::string command =
      "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" " + std::string(STAA_DEPTH_PROBE_EXE) + " --frames 2 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) output += buf;
  const int status = pclose(pipe);
  EXPECT_LT(secondsSince(t0), 2.0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << output;
  EXPECT_NE(output.find("staa-depth-probe: openni2: no depth device found (is the Xtion connected?"),
            std::string::npos)
      << output;
}

TEST(OpenNI2Helpers, CopyDepthImageHonoursTheRowStrideAndRejectsOtherSizes) {
  // A 640 x 480 image whose rows are padded to 1300 bytes, pixel (u, v) = v * 640 + u (mod 2^16).
  const int stride = 1300;
  std::vector<unsigned char> image(static_cast<std::size_t>(stride) * DepthFrame::kHeight, 0xAB);
  for (int v = 0; v < DepthFrame::kHeight; ++v) {
    for (int u = 0; u < DepthFrame::kWidth; ++u) {
      const auto value = static_cast<std::uint16_t>(v * DepthFrame::kWidth + u);
      std::memcpy(&image[static_cast<std::size_t>(v) * stride + 2 * static_cast<std::size_t>(u)], &value, 2);
    }
  }
  auto frame = std::make_unique<DepthFrame>();
  ASSERT_TRUE(copyDepthImage(image.data(), 640, 480, stride, *frame));
  for (const std::size_t k : {std::size_t{0}, std::size_t{641}, std::size_t{307199}}) {
    EXPECT_EQ(frame->depth_mm[k], static_cast<std::uint16_t>(k)) << k;
  }
  frame->depth_mm[5] = 77;
  EXPECT_FALSE(copyDepthImage(image.data(), 320, 240, stride, *frame));
  EXPECT_FALSE(copyDepthImage(image.data(), 640, 480, 1000, *frame));
  EXPECT_FALSE(copyDepthImage(nullptr, 640, 480, 1280, *frame));
  EXPECT_EQ(frame->depth_mm[5], 77);  // untouched by the rejected copies
}

TEST(OpenNI2Helpers, IntrinsicsFromTheXtionsFieldOfView) {
  // The Xtion's depth field of view (OpenNI2 reports 58 x 45 degrees): fx = 320 / tan(29 deg).
  const CameraIntrinsics k = intrinsicsFromFieldOfView(58.0 * M_PI / 180.0, 45.0 * M_PI / 180.0);
  EXPECT_NEAR(k.fx, 577.29, 0.01);
  EXPECT_NEAR(k.fy, 579.41, 0.01);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
}

}  // namespace
}  // namespace staa::hal
