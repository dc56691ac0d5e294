#include "hal/camera_model.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>
#include <string>

namespace staa {
namespace {

[[noreturn]] void bad(const std::string& field, double value, const char* rule) {
  throw std::invalid_argument("camera: " + field + " must be " + rule + ", got " + std::to_string(value));
}

}  // namespace

void validateCamera(const hal::CameraIntrinsics& k, const hal::CameraMount& m) {
  if (!(k.fx > 0.0) || !std::isfinite(k.fx)) bad("intrinsics.fx", k.fx, "finite and > 0 (pixels)");
  if (!(k.fy > 0.0) || !std::isfinite(k.fy)) bad("intrinsics.fy", k.fy, "finite and > 0 (pixels)");
  if (!(k.cx >= 0.0 && k.cx < hal::DepthFrame::kWidth)) bad("intrinsics.cx", k.cx, "in [0, 640) (pixels)");
  if (!(k.cy >= 0.0 && k.cy < hal::DepthFrame::kHeight)) bad("intrinsics.cy", k.cy, "in [0, 480) (pixels)");
  const double values[] = {m.x, m.y, m.z, m.roll, m.pitch, m.yaw};
  const char* names[] = {"mount.x", "mount.y", "mount.z", "mount.roll", "mount.pitch", "mount.yaw"};
  for (int i = 0; i < 6; ++i) {
    if (!std::isfinite(values[i])) bad(names[i], values[i], "finite");
  }
}

CameraModel::CameraModel(const hal::CameraIntrinsics& intrinsics, const hal::CameraMount& mount)
    : intrinsics_(intrinsics), mount_(mount) {
  validateCamera(intrinsics, mount);
  rotation_ = (Eigen::AngleAxisd(mount.yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(mount.pitch, Vec3::UnitY()) *
               Eigen::AngleAxisd(mount.roll, Vec3::UnitX()))
                  .toRotationMatrix();
  position_ = Vec3(mount.x, mount.y, mount.z);
}

Vec3 CameraModel::ray(double u, double v) const {
  // Optical (x right, y down, z forward) to body (x forward, y left, z up).
  const Vec3 body(1.0, -(u - intrinsics_.cx) / intrinsics_.fx, -(v - intrinsics_.cy) / intrinsics_.fy);
  return rotation_ * body;
}

Vec3 CameraModel::project(const Vec3& point_in_base) const {
  const Vec3 body = rotation_.transpose() * (point_in_base - position_);
  const double depth = body.x();
  if (!(depth > 0.0)) return {0.0, 0.0, depth};
  return {intrinsics_.cx - intrinsics_.fx * body.y() / depth, intrinsics_.cy - intrinsics_.fy * body.z() / depth, depth};
}

}  // namespace staa
