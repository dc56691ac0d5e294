// The pinhole model and the mount convention shared by perception and the simulated camera.
#include "hal/camera_model.hpp"

#include "geometry/types.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace staa {
namespace {

hal::CameraIntrinsics centred() { return hal::CameraIntrinsics{570.0, 570.0, 320.0, 240.0}; }

TEST(CameraModel, LevelCameraCentrePixelLooksStraightAheadAndRightPixelsLookRight) {
  const CameraModel cam(centred(), hal::CameraMount{0.1, 0.0, 1.0, 0.0, 0.0, 0.0});
  const Vec3 r = cam.ray(320.0, 240.0);
  EXPECT_NEAR(r.x(), 1.0, 1e-12);
  EXPECT_NEAR(r.y(), 0.0, 1e-12);
  EXPECT_NEAR(r.z(), 0.0, 1e-12);
  // 57 pixels right of centre at 570 px focal length: y = -0.1 per metre of depth (REP-103:
  // y is left); 57 pixels down: z = -0.1.
  const Vec3 right = cam.ray(377.0, 297.0);
  EXPECT_NEAR(right.y(), -0.1, 1e-12);
  EXPECT_NEAR(right.z(), -0.1, 1e-12);
  EXPECT_NEAR(cam.position().x(), 0.1, 1e-12);
}

TEST(CameraModel, PitchDownPutsTheCentreRayOnTheFloorWhereTrigonometrySays) {
  // The HSR head: 1 m up, pitched 0.3 rad down. The centre ray meets the floor
  // 1 / tan(0.3) = 3.236 m ahead, at a depth (optical z) of 1 / sin(0.3) = 3.384 m.
  const CameraModel cam(centred(), hal::CameraMount{0.0, 0.0, 1.0, 0.0, 0.3, 0.0});
  const double depth = 1.0 / std::sin(0.3);
  const Vec3 floor = cam.position() + depth * cam.ray(320.0, 240.0);
  EXPECT_NEAR(floor.z(), 0.0, 1e-12);
  EXPECT_NEAR(floor.x(), 1.0 / std::tan(0.3), 1e-12);
  EXPECT_NEAR(floor.y(), 0.0, 1e-12);
}

TEST(CameraModel, YawTurnsTheViewLeftAndRollTurnsItAboutTheOpticalAxis) {
  const CameraModel left(centred(), hal::CameraMount{0.0, 0.0, 1.0, 0.0, 0.0, kPi / 2});
  const Vec3 r = left.ray(320.0, 240.0);
  EXPECT_NEAR(r.x(), 0.0, 1e-12);
  EXPECT_NEAR(r.y(), 1.0, 1e-12);
  // Rolled by +90 degrees about the forward axis: the image's "right" now points down.
  const CameraModel rolled(centred(), hal::CameraMount{0.0, 0.0, 1.0, kPi / 2, 0.0, 0.0});
  const Vec3 right = rolled.ray(377.0, 240.0);
  EXPECT_NEAR(right.y(), 0.0, 1e-12);
  EXPECT_NEAR(right.z(), -0.1, 1e-12);
}

TEST(CameraModel, ProjectInvertsTheRay) {
  const CameraModel cam(hal::CameraIntrinsics{575.8, 572.1, 314.5, 235.5},
                        hal::CameraMount{0.05, -0.02, 1.05, 0.02, 0.35, -0.1});
  for (double u : {0.0, 100.5, 319.5, 639.0}) {
    for (double v : {0.0, 240.0, 479.0}) {
      for (double d : {0.5, 2.0, 7.9}) {
        const Vec3 p = cam.position() + d * cam.ray(u, v);
        const Vec3 back = cam.project(p);
        EXPECT_NEAR(back.x(), u, 1e-9);
        EXPECT_NEAR(back.y(), v, 1e-9);
        EXPECT_NEAR(back.z(), d, 1e-12);
      }
    }
  }
  EXPECT_LE(cam.project(cam.position() - 2.0 * cam.ray(320.0, 240.0)).z(), 0.0);
}

TEST(CameraModel, RejectsBadIntrinsicsAndMountsNamingTheField) {
  try {
    CameraModel(hal::CameraIntrinsics{0.0, 570.0, 320.0, 240.0}, hal::CameraMount{});
    FAIL() << "fx = 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("intrinsics.fx"), std::string::npos) << e.what();
  }
  try {
    CameraModel(centred(), hal::CameraMount{0.0, 0.0, 1.0, 0.0, NAN, 0.0});
    FAIL() << "NaN pitch accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mount.pitch"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CameraModel(hal::CameraIntrinsics{570.0, 570.0, 700.0, 240.0}, hal::CameraMount{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace staa
