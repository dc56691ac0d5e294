// staa-depth-probe: opens the depth camera through OpenNI2 (the HSR's head Xtion), prints what
// the device reports and the statistics of a few frames. For checking a camera on the robot
// before staad uses it.
//
//   staa-depth-probe [--uri URI] [--frames N] [--timeout S]
// Exit status: 0 frames received; 2 bad arguments; 3 no device / cannot open (the reason on
// stderr); 4 the device sent no frame in time.

#include "hal/openni2/openni2_camera.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace {

struct FrameStats {
  std::size_t valid = 0;
  unsigned min_mm = 0;
  unsigned median_mm = 0;
};

FrameStats stats(const staa::hal::DepthFrame& frame, std::vector<std::uint16_t>& scratch) {
  scratch.clear();
  for (const std::uint16_t d : frame.depth_mm) {
    if (d != 0) scratch.push_back(d);
  }
  FrameStats s;
  s.valid = scratch.size();
  if (scratch.empty()) return s;
  s.min_mm = *std::min_element(scratch.begin(), scratch.end());
  auto mid = scratch.begin() + static_cast<std::ptrdiff_t>(scratch.size() / 2);
  std::nth_element(scratch.begin(), mid, scratch.end());
  s.median_mm = *mid;
  return s;
}

void printIntrinsics(const char* what, const staa::hal::CameraIntrinsics& k) {
  std::printf("%s: fx %.1f  fy %.1f  cx %.1f  cy %.1f (pixels)\n", what, k.fx, k.fy, k.cx, k.cy);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Opens the depth camera through OpenNI2 and prints its intrinsics and frame statistics"};
  std::string uri;
  int frames = 10;
  double timeout_s = 2.0;
  app.add_option("--uri", uri, "OpenNI2 device URI (default: the first device)");
  app.add_option("--frames", frames, "frames to read")->check(CLI::Range(1, 100000));
  app.add_option("--timeout", timeout_s, "seconds to wait for each frame")->check(CLI::Range(0.1, 60.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  staa::hal::OpenNI2Config config;
  config.uri = uri;
  config.timeout_s = timeout_s;
  std::unique_ptr<staa::hal::OpenNI2Camera> camera;
  try {
    camera = std::make_unique<staa::hal::OpenNI2Camera>(config);
  } catch (const staa::hal::OpenNI2Error& e) {
    std::cerr << "staa-depth-probe: " << e.what() << "\n";
    return 3;
  }
  std::printf("device: %s\n", camera->deviceDescription().c_str());
  printIntrinsics("device intrinsics (from its field of view, uncalibrated)", camera->deviceIntrinsics());
  printIntrinsics("configured intrinsics (OpenNI2Config defaults)", camera->intrinsics());

  auto frame = std::make_unique<staa::hal::DepthFrame>();
  std::vector<std::uint16_t> scratch;
  scratch.reserve(frame->depth_mm.size());
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < frames; ++i) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!camera->read(0, *frame)) {
      if (std::chrono::steady_clock::now() >= deadline) {
        std::cerr << "staa-depth-probe: no depth frame within " << timeout_s << " s after " << i << " frames ("
                  << camera->framesRejected() << " rejected)\n";
        return 4;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    const FrameStats s = stats(*frame, scratch);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("frame %d (seq %llu, t %.3f s): valid %zu / %zu (%.1f %%), min %u mm, median %u mm\n", i + 1,
                static_cast<unsigned long long>(frame->sequence), t, s.valid, frame->depth_mm.size(),
                100.0 * static_cast<double>(s.valid) / static_cast<double>(frame->depth_mm.size()), s.min_mm,
                s.median_mm);
  }
  std::printf("received %llu frames, rejected %llu\n", static_cast<unsigned long long>(camera->framesReceived()),
              static_cast<unsigned long long>(camera->framesRejected()));
  return 0;
}
