// The ROS depth image adapter (hal/ros): RosDepthCamera::offer on any sensor_msgs/Image-like
// view (encoding, size, step, byte order, data length, stamps), camera_info and camera pose
// (from a fuzzed optical-frame transform or given directly), then read(): a frame that comes
// out carries a finite mount above the floor and a stamp after the previous one; a bad image
// is dropped and counted, never read out of bounds. No exception.
#include "fuzz_support.hpp"
#include "hal/ros/ros_depth_camera.hpp"

#include <cmath>
#include <vector>

namespace {
using namespace staa::hal;

DepthImageView takeImage(staa::fuzz::Fields& in, std::vector<std::uint8_t>& bytes, char (&encoding)[9]) {
  DepthImageView image;
  const std::uint8_t shape = in.take<std::uint8_t>();
  switch (shape % 4) {
    case 0: std::snprintf(encoding, sizeof encoding, "16UC1"); break;
    case 1: std::snprintf(encoding, sizeof encoding, "32FC1"); break;
    default:
      for (int i = 0; i < 8; ++i) encoding[i] = static_cast<char>(in.take<std::uint8_t>());
      encoding[8] = '\0';
  }
  image.encoding = encoding;
  const std::uint32_t bpp = (shape % 4) == 1 ? 4 : 2;
  image.width = DepthFrame::kWidth;
  image.height = DepthFrame::kHeight;
  if ((shape & 4) != 0) {  // any size (mostly dropped)
    image.width = in.take<std::uint16_t>();
    image.height = in.take<std::uint16_t>();
  }
  image.step = image.width * bpp + ((shape & 8) != 0 ? in.take<std::uint8_t>() : 0u);
  if ((shape & 16) != 0) image.step = in.take<std::uint32_t>();
  image.big_endian = (shape & 32) != 0;
  std::size_t length = static_cast<std::size_t>(image.step) * image.height;
  if ((shape & 64) != 0) length += static_cast<std::size_t>(in.take<std::uint8_t>()) - 128;  // a size that lies
  image.size = std::min<std::size_t>(length, std::size_t{4} << 20);
  image.stamp_ns = in.take<std::int64_t>();
  image.received_ns = in.take<std::int64_t>();
  bytes.assign(image.size, 0);
  const std::uint8_t* rest = in.rest();
  const std::size_t n = in.restSize();
  for (std::size_t i = 0; n > 0 && i < bytes.size(); ++i) bytes[i] = rest[i % n];
  image.data = bytes.data();
  return image;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  staa::fuzz::Fields in(data, size);
  const std::uint8_t flags = in.take<std::uint8_t>();
  RosDepthCamera camera{RosDepthCameraConfig{}};
  const CameraIntrinsics k = camera.intrinsics();
  CameraInfoView info{DepthFrame::kWidth, DepthFrame::kHeight, {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1}};
  if ((flags & 1) != 0) {
    info.width = in.take<std::uint32_t>();
    info.height = in.take<std::uint32_t>();
    for (double& v : info.K) v = in.take<double>();
  }
  CameraPoseSample pose{true, 0.0, 0.0, 1.0, 0.0, 0.3, 0.0};
  if ((flags & 2) != 0) {  // the transform tf would give, optical frame in the base frame
    double t[7];
    for (double& v : t) v = in.take<double>();
    pose = cameraPoseFromOpticalFrame(t[0], t[1], t[2], t[3], t[4], t[5], t[6]);
    if (pose.valid) {
      for (const double v : {pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw}) {
        staa::fuzz::require(std::isfinite(v), "a valid pose from the optical frame is not finite");
      }
    }
  }
  if ((flags & 4) != 0) pose = {(in.take<std::uint8_t>() & 1) != 0, in.take<double>(), in.take<double>(), in.take<double>(),
                                in.take<double>(), in.take<double>(), in.take<double>()};

  std::vector<std::uint8_t> bytes;
  char encoding[9] = {};
  const DepthImageView image = takeImage(in, bytes, encoding);
  static const auto frame = std::make_unique<DepthFrame>();
  staa::rt::Nanos last = -1;
  for (int k = 0; k < 2; ++k) {
    DepthImageView shot = image;
    // Saturating: the input's stamps may sit at the int64 ends, and the harness's own shift
    // must not overflow (the adapter itself is what is under test).
    const auto later = [k](std::int64_t t) {
      std::int64_t out = 0;
      return __builtin_add_overflow(t, std::int64_t{k} * 33'000'000, &out) ? t : out;
    };
    shot.stamp_ns = later(shot.stamp_ns);
    shot.received_ns = later(shot.received_ns);
    const std::int64_t arrival = 5'000'000'000 + k * 33'000'000;
    camera.offer(shot, (flags & 8) != 0 ? nullptr : &info, pose, arrival);
    if (camera.read(arrival, *frame)) {
      staa::fuzz::require(frame->stamp > last, "a frame's stamp is not after the previous one");
      last = frame->stamp;
      const CameraMount& m = frame->mount;
      for (const double v : {m.x, m.y, m.z, m.roll, m.pitch, m.yaw}) staa::fuzz::require(std::isfinite(v), "a mount not finite");
      staa::fuzz::require(m.z > 0.0, "a mount not above the floor");
    }
  }
  return 0;
}
