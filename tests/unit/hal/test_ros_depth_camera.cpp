// camera.backend ros without ROS: RosDepthCamera fed through its port (hal/ros/depth_image.hpp)
// as a transport would, and the optical-frame pose converted to the project's mount.
//   - 16UC1 little and big endian, padded rows, 32FC1 metres with no-reading values;
//   - every bad frame dropped, counted under its reason, the last good frame kept;
//   - read() true once per accepted frame, allocating nothing;
//   - the stamp mapped to the monotonic clock;
//   - the pose of the HSR's head (tilted, panned) as tf gives its optical frame.
#include "hal/ros/ros_depth_camera.hpp"

#include "hal/camera_model.hpp"
#include "rt/alloc_count.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

namespace staa::hal {
namespace {

constexpr std::uint32_t kW = DepthFrame::kWidth;
constexpr std::uint32_t kH = DepthFrame::kHeight;
constexpr std::int64_t kSecond = 1'000'000'000;

// The HSR head's mount as the shipped config has it (pitch 0.3: looking down ahead).
constexpr CameraMount kHead{0.0, 0.0, 1.0, 0.0, 0.3, 0.0};

// A depth image message's bytes and the view onto them.
struct Image {
  std::vector<std::uint8_t> bytes;
  DepthImageView view;

  Image(const char* encoding, std::uint32_t step, bool big_endian, std::int64_t stamp_ns) {
    bytes.assign(static_cast<std::size_t>(step) * kH, 0);
    view.stamp_ns = stamp_ns;
    view.received_ns = stamp_ns + 20'000'000;  // 20 ms old on arrival
    view.encoding = encoding;
    view.width = kW;
    view.height = kH;
    view.step = step;
    view.big_endian = big_endian;
    sync();
  }
  void sync() {
    view.data = bytes.data();
    view.size = bytes.size();
  }
  std::uint8_t* pixel(std::uint32_t u, std::uint32_t v, std::size_t bytes_per_pixel) {
    return bytes.data() + static_cast<std::size_t>(v) * view.step + u * bytes_per_pixel;
  }
  void set16(std::uint32_t u, std::uint32_t v, std::uint16_t mm) {
    std::uint8_t* p = pixel(u, v, 2);
    p[view.big_endian ? 0 : 1] = static_cast<std::uint8_t>(mm >> 8);
    p[view.big_endian ? 1 : 0] = static_cast<std::uint8_t>(mm & 0xff);
  }
  void set32(std::uint32_t u, std::uint32_t v, float metres) {
    const auto bits = std::bit_cast<std::uint32_t>(metres);
    std::uint8_t* p = pixel(u, v, 4);
    for (int i = 0; i < 4; ++i) {
      const auto byte = static_cast<std::uint8_t>(bits >> (8 * i));
      p[view.big_endian ? 3 - i : i] = byte;
    }
  }
};

// A pattern every pixel of which differs from its neighbours' (both bytes vary).
std::uint16_t pattern(std::uint32_t u, std::uint32_t v) { return static_cast<std::uint16_t>(u * 37 + v * 1009 + 1); }

Image patterned16(bool big_endian, std::int64_t stamp_ns, std::uint32_t step = 2 * kW) {
  Image im("16UC1", step, big_endian, stamp_ns);
  for (std::uint32_t v = 0; v < kH; ++v) {
    for (std::uint32_t u = 0; u < kW; ++u) im.set16(u, v, pattern(u, v));
  }
  return im;
}

CameraInfoView info(const CameraIntrinsics& k = {}) {
  CameraInfoView i;
  i.width = kW;
  i.height = kH;
  const double K[9] = {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
  std::memcpy(i.K, K, sizeof K);
  return i;
}

CameraPoseSample pose(double yaw = 0.0) { return CameraPoseSample{true, 0.05, 0.0, 1.0, 0.0, 0.3, yaw}; }

RosDepthCameraConfig config() {
  RosDepthCameraConfig c;
  c.mount = kHead;
  return c;
}

void expectPattern(const DepthFrame& f) {
  for (std::uint32_t v = 0; v < kH; ++v) {
    for (std::uint32_t u = 0; u < kW; ++u) {
      ASSERT_EQ(f.depth_mm[static_cast<std::size_t>(v) * kW + u], pattern(u, v)) << "pixel " << u << ", " << v;
    }
  }
}

TEST(RosDepthCamera, Takes16UC1InBothByteOrdersAndPaddedRows) {
  RosDepthCamera camera(config());
  const CameraInfoView ci = info();
  auto frame = std::make_unique<DepthFrame>();
  std::int64_t stamp = 100 * kSecond;
  for (const bool big : {false, true}) {
    for (const std::uint32_t step : {2 * kW, 2 * kW + 64}) {
      SCOPED_TRACE(std::string(big ? "big" : "little") + " endian, step " + std::to_string(step));
      stamp += kSecond / 30;
      const Image im = patterned16(big, stamp, step);
      camera.offer(im.view, &ci, pose(0.25), 5 * kSecond);
      ASSERT_TRUE(camera.read(0, *frame));
      EXPECT_FALSE(camera.read(0, *frame));  // once per accepted frame
      expectPattern(*frame);
      EXPECT_TRUE(frame->has_mount);
      EXPECT_EQ(frame->mount.x, 0.05);
      EXPECT_EQ(frame->mount.pitch, 0.3);
      EXPECT_EQ(frame->mount.yaw, 0.25);
      EXPECT_EQ(frame->sequence, camera.accepted());
    }
  }
  EXPECT_EQ(camera.accepted(), 4u);
  EXPECT_EQ(camera.droppedTotal(), 0u);
  // The camera's own mount stays the configured one (perception sizes its grid from it).
  EXPECT_EQ(camera.mount().pitch, 0.3);
  EXPECT_EQ(camera.mount().yaw, 0.0);
}

TEST(RosDepthCamera, Takes32FC1MetresRoundedToMillimetresAndNoReadingsAsZero) {
  for (const bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    RosDepthCamera camera(config());
    const CameraInfoView ci = info();
    Image im("32FC1", 4 * kW, big, 7 * kSecond);
    const float inf = std::numeric_limits<float>::infinity();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    struct Case {
      std::uint32_t u;
      float metres;
      std::uint16_t mm;
    };
    const Case cases[] = {{0, 1.2345F, 1235},  {1, 0.45F, 450},   {2, 2.0004F, 2000}, {3, 65.535F, 65535},
                          {4, nan, 0},         {5, inf, 0},       {6, -inf, 0},       {7, -1.5F, 0},
                          {8, 0.0F, 0},        {9, 65.6F, 0},     {10, 1e30F, 0},     {11, 0.0004F, 0},
                          {12, 7.9996F, 8000}, {13, 0.0005F, 1}};
    for (const Case& c : cases) im.set32(c.u, 10, c.metres);
    im.set32(639, 479, 3.0F);  // the last byte of the image
    camera.offer(im.view, &ci, pose(), 9 * kSecond);
    auto frame = std::make_unique<DepthFrame>();
    ASSERT_TRUE(camera.read(0, *frame));
    for (const Case& c : cases) EXPECT_EQ(frame->depth_mm[10 * kW + c.u], c.mm) << "pixel " << c.u << ": " << c.metres;
    EXPECT_EQ(frame->depth_mm[479 * kW + 639], 3000);
    EXPECT_EQ(frame->depth_mm[0], 0);  // 0.0 m
  }
}

// Each bad frame: dropped under its reason, nothing new for read(), the last good frame kept.
TEST(RosDepthCamera, DropsBadFramesCountingEachReasonAndKeepsTheLastGoodOne) {
  RosDepthCamera camera(config());
  const CameraInfoView ci = info();
  auto frame = std::make_unique<DepthFrame>();
  const std::int64_t t0 = 50 * kSecond;
  camera.offer(patterned16(false, t0).view, &ci, pose(), kSecond);
  ASSERT_TRUE(camera.read(0, *frame));
  const rt::Nanos good_stamp = frame->stamp;

  std::int64_t stamp = t0;
  const auto next = [&stamp] { return stamp += kSecond / 30; };
  const auto expectDropped = [&](const char* what, RosDepthDrop reason, const DepthImageView& view,
                                 const CameraInfoView* i, const CameraPoseSample& p) {
    SCOPED_TRACE(what);
    const std::uint64_t before = camera.dropped(reason), total = camera.droppedTotal();
    camera.offer(view, i, p, 2 * kSecond);
    EXPECT_EQ(camera.dropped(reason), before + 1) << toString(reason);
    EXPECT_EQ(camera.droppedTotal(), total + 1);
    EXPECT_EQ(camera.accepted(), 1u);
    EXPECT_FALSE(camera.read(0, *frame));
    EXPECT_EQ(frame->stamp, good_stamp);
  };

  Image rgb = patterned16(false, next());
  rgb.view.encoding = "rgb8";
  expectDropped("rgb8", RosDepthDrop::kEncoding, rgb.view, &ci, pose());
  rgb.view.encoding = "mono16";
  expectDropped("mono16", RosDepthDrop::kEncoding, rgb.view, &ci, pose());
  rgb.view.encoding = nullptr;
  expectDropped("no encoding", RosDepthDrop::kEncoding, rgb.view, &ci, pose());

  Image small = patterned16(false, next());
  small.view.width = 320;
  small.view.height = 240;
  small.view.step = 640;
  small.bytes.resize(640 * 240);
  small.sync();
  expectDropped("320 x 240", RosDepthDrop::kSize, small.view, &ci, pose());
  Image wide = patterned16(false, next());
  wide.view.width = 641;
  expectDropped("641 x 480", RosDepthDrop::kSize, wide.view, &ci, pose());

  Image step = patterned16(false, next());
  step.view.step = 2 * kW - 2;  // shorter than a row
  expectDropped("step < row", RosDepthDrop::kLayout, step.view, &ci, pose());
  Image as32 = patterned16(false, next());
  as32.view.encoding = "32FC1";  // 1280-byte rows for 4-byte pixels
  expectDropped("32FC1 with a 16-bit step", RosDepthDrop::kLayout, as32.view, &ci, pose());
  Image truncated = patterned16(false, next());
  truncated.bytes.resize(truncated.bytes.size() - 1);
  truncated.sync();
  expectDropped("truncated", RosDepthDrop::kLayout, truncated.view, &ci, pose());
  Image longer = patterned16(false, next());
  longer.bytes.resize(longer.bytes.size() + 2);
  longer.sync();
  expectDropped("data beyond step * height", RosDepthDrop::kLayout, longer.view, &ci, pose());
  Image null = patterned16(false, next());
  null.view.data = nullptr;
  expectDropped("no data", RosDepthDrop::kLayout, null.view, &ci, pose());

  expectDropped("stamp equal", RosDepthDrop::kStamp, patterned16(false, t0).view, &ci, pose());
  expectDropped("stamp going back", RosDepthDrop::kStamp, patterned16(false, t0 - 1).view, &ci, pose());
  expectDropped("stamp unset", RosDepthDrop::kStamp, patterned16(false, 0).view, &ci, pose());

  expectDropped("no camera_info", RosDepthDrop::kNoCameraInfo, patterned16(false, next()).view, nullptr, pose());
  CameraIntrinsics other;
  other.fx += 1.5;
  const CameraInfoView off = info(other);
  expectDropped("fx 1.5 px off", RosDepthDrop::kIntrinsics, patterned16(false, next()).view, &off, pose());
  other = CameraIntrinsics{};
  other.cy -= 2.0;
  const CameraInfoView off_cy = info(other);
  expectDropped("cy 2 px off", RosDepthDrop::kIntrinsics, patterned16(false, next()).view, &off_cy, pose());
  CameraInfoView qvga = info();
  qvga.width = 320;
  expectDropped("camera_info of another size", RosDepthDrop::kIntrinsics, patterned16(false, next()).view, &qvga,
                pose());
  CameraInfoView nan_k = info();
  nan_k.K[0] = std::numeric_limits<double>::quiet_NaN();
  expectDropped("NaN in K", RosDepthDrop::kIntrinsics, patterned16(false, next()).view, &nan_k, pose());

  expectDropped("no pose", RosDepthDrop::kNoPose, patterned16(false, next()).view, &ci, CameraPoseSample{});
  CameraPoseSample below = pose();
  below.z = -0.1;
  expectDropped("pose below the floor", RosDepthDrop::kBadPose, patterned16(false, next()).view, &ci, below);
  CameraPoseSample nan_pose = pose();
  nan_pose.yaw = std::numeric_limits<double>::quiet_NaN();
  expectDropped("NaN pose", RosDepthDrop::kBadPose, patterned16(false, next()).view, &ci, nan_pose);

  EXPECT_EQ(camera.dropped(RosDepthDrop::kEncoding), 3u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kSize), 2u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kLayout), 5u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kStamp), 3u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kNoCameraInfo), 1u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kIntrinsics), 4u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kNoPose), 1u);
  EXPECT_EQ(camera.dropped(RosDepthDrop::kBadPose), 2u);
  EXPECT_EQ(camera.droppedTotal(), 21u);

  // Within a pixel of the calibration is the same camera; after the drops, frames flow again.
  other = CameraIntrinsics{};
  other.fx += 0.9;
  other.cx -= 0.5;
  const CameraInfoView close = info(other);
  camera.offer(patterned16(true, next()).view, &close, pose(), 3 * kSecond);
  ASSERT_TRUE(camera.read(0, *frame));
  expectPattern(*frame);
  EXPECT_EQ(camera.accepted(), 2u);
  EXPECT_EQ(frame->sequence, 2u);
  EXPECT_STREQ(toString(RosDepthDrop::kNoPose), "no_pose");
}

TEST(RosDepthCamera, StampsAreArrivalMinusASaneAgeAndAlwaysIncrease) {
  RosDepthCameraConfig c = config();
  c.max_age_s = 0.5;
  RosDepthCamera camera(c);
  const CameraInfoView ci = info();
  auto frame = std::make_unique<DepthFrame>();
  const auto stampOf = [&](std::int64_t ros_stamp, std::int64_t received, std::int64_t arrival) {
    Image im = patterned16(false, ros_stamp);
    im.view.received_ns = received;
    camera.offer(im.view, &ci, pose(), arrival);
    EXPECT_TRUE(camera.read(0, *frame));
    return frame->stamp;
  };
  const std::int64_t t = 1000 * kSecond;
  EXPECT_EQ(stampOf(t, t + 30'000'000, 10 * kSecond), 10 * kSecond - 30'000'000);        // 30 ms old
  EXPECT_EQ(stampOf(t + kSecond, t + 2 * kSecond, 11 * kSecond), 11 * kSecond);          // 1 s: not believed
  EXPECT_EQ(stampOf(t + 2 * kSecond, t + kSecond, 12 * kSecond), 12 * kSecond);          // from the future
  EXPECT_EQ(stampOf(t + 3 * kSecond, t + 3 * kSecond + kSecond / 2, 13 * kSecond), 13 * kSecond - kSecond / 2);
  // A mapped stamp at or before the previous one is moved just after it.
  EXPECT_EQ(stampOf(t + 4 * kSecond, t + 4 * kSecond + 400'000'000, 13 * kSecond - 300'000'000),
            13 * kSecond - kSecond / 2 + 1);
}

TEST(RosDepthCamera, ReadAndOfferAllocateNothing) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_ros_depth_camera must link staa_rt_alloc_hook";
  RosDepthCamera camera(config());
  const CameraInfoView ci = info();
  Image im16 = patterned16(false, kSecond);
  Image im32("32FC1", 4 * kW, false, kSecond);
  auto frame = std::make_unique<DepthFrame>();
  std::uint64_t offer_allocations = 0, read_allocations = 0;
  int reads = 0;
  for (int k = 1; k <= 300; ++k) {
    Image& im = (k % 2 == 0) ? im16 : im32;
    im.view.stamp_ns = k * kSecond / 30;
    {
      rt::AllocationScope scope;
      camera.offer(im.view, &ci, pose(0.01 * k), k * kSecond / 30);
      offer_allocations += scope.count();
    }
    rt::AllocationScope scope;
    reads += camera.read(0, *frame) ? 1 : 0;
    reads += camera.read(0, *frame) ? 1 : 0;
    read_allocations += scope.count();
  }
  EXPECT_EQ(reads, 300);
  EXPECT_EQ(read_allocations, 0u);
  EXPECT_EQ(offer_allocations, 0u);
}

TEST(RosDepthCamera, RejectsABadConfig) {
  RosDepthCameraConfig c = config();
  c.mount.z = 0.0;
  EXPECT_THROW(RosDepthCamera{c}, std::invalid_argument);
  c = config();
  c.max_age_s = -1.0;
  EXPECT_THROW(RosDepthCamera{c}, std::invalid_argument);
}

// ---- the pose: tf's base <- optical frame to the mount ----

// A camera's optical frame on its body: x right, y down, z forward, i.e. rpy (-pi/2, 0, -pi/2)
// from the body (x forward, y left, z up), as every ROS *_optical_frame is attached.
Eigen::Quaterniond bodyToOptical() {
  return Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX());
}

// The HSR's head as tf chains it: base -> head pan (about z) -> head tilt (about y, positive
// down in REP-103; the HSR's head_tilt_joint is negative looking down) -> the optical frame.
Eigen::Quaterniond headOptical(double pan, double tilt_down) {
  return Eigen::AngleAxisd(pan, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(tilt_down, Eigen::Vector3d::UnitY()) *
         bodyToOptical();
}

CameraPoseSample convert(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  return cameraPoseFromOpticalFrame(t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
}

// The mount's rays are the optical frame's: pixel (u, v) looks along base <- optical applied to
// ((u - cx) / fx, (v - cy) / fy, 1).
void expectRaysMatch(const CameraPoseSample& p, const Eigen::Quaterniond& q) {
  ASSERT_TRUE(p.valid);
  const CameraIntrinsics k;
  const CameraModel model(k, CameraMount{p.x, p.y, p.z, p.roll, p.pitch, p.yaw});
  for (const auto& [u, v] : {std::pair{319.5, 239.5}, {0.0, 0.0}, {639.0, 0.0}, {0.0, 479.0}, {500.0, 100.0}}) {
    const Eigen::Vector3d expected = q * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
    EXPECT_LE((model.ray(u, v) - expected).norm(), 1e-12) << "pixel " << u << ", " << v;
  }
}

TEST(RosCameraPose, TheHeadTiltedDownIsTheConfigsLookingDownMount) {
  // The head 1 m up tilted 0.3 rad down: the shipped config's mount {pitch: 0.3}.
  const Eigen::Quaterniond q = headOptical(0.0, 0.3);
  const CameraPoseSample p = convert({0.0, 0.0, 1.0}, q);
  ASSERT_TRUE(p.valid);
  EXPECT_NEAR(p.roll, kHead.roll, 1e-12);
  EXPECT_NEAR(p.pitch, kHead.pitch, 1e-12);
  EXPECT_NEAR(p.yaw, kHead.yaw, 1e-12);
  EXPECT_EQ(p.z, 1.0);
  expectRaysMatch(p, q);
  // The image centre looks ahead and down; the image's top right corner is to the right.
  const CameraModel model(CameraIntrinsics{}, CameraMount{p.x, p.y, p.z, p.roll, p.pitch, p.yaw});
  const Vec3 centre = model.ray(319.5, 239.5);
  EXPECT_GT(centre.x(), 0.0);
  EXPECT_NEAR(std::atan2(-centre.z(), centre.x()), 0.3, 1e-12);
  EXPECT_LT(model.ray(639.0, 239.5).y(), 0.0);
}

TEST(RosCameraPose, PannedTiltedAndRolledHeadsKeepTheirRays) {
  const Eigen::Quaterniond panned = headOptical(0.5, 0.3);
  const CameraPoseSample p = convert({0.02, -0.01, 1.05}, panned);
  EXPECT_NEAR(p.yaw, 0.5, 1e-12);
  EXPECT_NEAR(p.pitch, 0.3, 1e-12);
  EXPECT_NEAR(p.roll, 0.0, 1e-12);
  EXPECT_EQ(p.x, 0.02);
  EXPECT_EQ(p.y, -0.01);
  expectRaysMatch(p, panned);
  // Any orientation: a roll, a head looking backwards, one looking straight down.
  const Eigen::Quaterniond rolled = Eigen::AngleAxisd(-2.0, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()) * bodyToOptical();
  const CameraPoseSample r = convert({0.0, 0.0, 1.0}, rolled);
  EXPECT_NEAR(r.roll, 0.2, 1e-12);
  EXPECT_NEAR(r.pitch, 0.7, 1e-12);
  EXPECT_NEAR(r.yaw, -2.0, 1e-12);
  expectRaysMatch(r, rolled);
  expectRaysMatch(convert({0.0, 0.0, 1.0}, headOptical(0.4, M_PI / 2)), headOptical(0.4, M_PI / 2));
  // tf's quaternions need not be unit: scaled, the same pose.
  const Eigen::Quaterniond q = headOptical(0.5, 0.3);
  const CameraPoseSample s = cameraPoseFromOpticalFrame(0, 0, 1, 2 * q.x(), 2 * q.y(), 2 * q.z(), 2 * q.w());
  EXPECT_NEAR(s.yaw, 0.5, 1e-12);
  EXPECT_NEAR(s.pitch, 0.3, 1e-12);
  // No rotation at all, or not finite: not a pose.
  EXPECT_FALSE(cameraPoseFromOpticalFrame(0, 0, 1, 0, 0, 0, 0).valid);
  EXPECT_FALSE(cameraPoseFromOpticalFrame(0, std::nan(""), 1, 0, 0, 0, 1).valid);
}

}  // namespace
}  // namespace staa::hal
