#include "hal/camera_model.hpp"

#include "geometry/types.hpp"
#include "io/config_rules.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace staa {
namespace {

constexpr const char* kOwner = "camera";

void require(const char* field, double value, const io::Range& range) { io::requireField(kOwner, field, value, range); }

// Radians: a value beyond pi is most likely degrees.
void requireAngle(const char* field, double value) {
  if (!(std::abs(value) <= kPi)) throw io::FieldError(kOwner, field, "in [-pi, pi] rad (degrees? 17 deg is 0.297 rad)", value);
}

}  // namespace

void validateCamera(const hal::CameraIntrinsics& k, const hal::CameraMount& m) {
  using io::Range;
  require("intrinsics.fx", k.fx, Range::above(0.0, "pixels"));
  require("intrinsics.fy", k.fy, Range::above(0.0, "pixels"));
  require("intrinsics.cx", k.cx, Range::rightOpen(0.0, hal::DepthFrame::kWidth, "pixels", "inside the image"));
  require("intrinsics.cy", k.cy, Range::rightOpen(0.0, hal::DepthFrame::kHeight, "pixels", "inside the image"));
  require("mount.x", m.x, Range{});
  require("mount.y", m.y, Range{});
  require("mount.z", m.z, Range::above(0.0, "m", "above the floor"));
  requireAngle("mount.roll", m.roll);
  requireAngle("mount.pitch", m.pitch);
  requireAngle("mount.yaw", m.yaw);
}

CameraModel::CameraModel(const hal::CameraIntrinsics& intrinsics, const hal::CameraMount& mount)
    : intrinsics_(intrinsics), mount_(mount) {
  validateCamera(intrinsics, mount);
  rotation_ = rotationOf(mount);
  position_ = Vec3(mount.x, mount.y, mount.z);
}

Eigen::Matrix3d CameraModel::rotationOf(const hal::CameraMount& mount) {
  return (Eigen::AngleAxisd(mount.yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(mount.pitch, Vec3::UnitY()) *
          Eigen::AngleAxisd(mount.roll, Vec3::UnitX()))
      .toRotationMatrix();
}

Vec3 CameraModel::ray(const hal::CameraIntrinsics& k, const Eigen::Matrix3d& rotation, double u, double v) {
  // Optical (x right, y down, z forward) to body (x forward, y left, z up).
  const Vec3 body(1.0, -(u - k.cx) / k.fx, -(v - k.cy) / k.fy);
  return rotation * body;
}

Vec3 CameraModel::project(const Vec3& point_in_base) const {
  const Vec3 body = rotation_.transpose() * (point_in_base - position_);
  const double depth = body.x();
  if (!(depth > 0.0)) return {0.0, 0.0, depth};
  return {intrinsics_.cx - intrinsics_.fx * body.y() / depth, intrinsics_.cy - intrinsics_.fy * body.z() / depth, depth};
}

}  // namespace staa
