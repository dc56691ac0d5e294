#pragma once
// Where a depth pixel's ray goes: the pinhole model (intrinsics) and the camera's mount on the
// robot. Shared by perception (back-projection) and the simulated camera (ray casting), so
// both agree on one convention:
//   - optical frame (OpenNI, ROS *_optical_frame): x right, y down, z forward (the depth);
//   - camera body frame: x forward, y left, z up (REP-103);
//   - base frame: REP-103, origin on the floor under the base centre, z up;
//   - mount: body -> base is Rz(yaw) * Ry(pitch) * Rx(roll) then the mount's position, so
//     pitch > 0 tilts the view DOWN (the HSR head looking at the floor ahead: pitch ~ +0.3).

#include "hal/depth_camera.hpp"

#include <Eigen/Core>

namespace staa {

using Vec3 = Eigen::Vector3d;

// The camera's rules, the one check (the model's constructor and staad's config reader):
// focal lengths > 0, the principal point inside the 640 x 480 image, the mount finite, above
// the floor (z > 0) and its angles in [-pi, pi]. Throws io::FieldError (an
// std::invalid_argument) naming the field ("mount.z"), the rule and the value.
void validateCamera(const hal::CameraIntrinsics& intrinsics, const hal::CameraMount& mount);

class CameraModel {
 public:
  // Validates (see validateCamera).
  CameraModel(const hal::CameraIntrinsics& intrinsics, const hal::CameraMount& mount);

  const hal::CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const hal::CameraMount& mount() const { return mount_; }
  // base <- camera body rotation and the camera's position in the base frame.
  const Eigen::Matrix3d& rotation() const { return rotation_; }
  const Vec3& position() const { return position_; }

  // The ray of pixel (u, v) in the base frame, scaled so that its optical z is 1: the point
  // a pixel of depth d (metres, as a DepthFrame stores it) sees is position() + d * ray(u, v).
  Vec3 ray(double u, double v) const { return ray(intrinsics_, rotation_, u, v); }
  // The same for any rotation (a mount that changes per frame), without validating.
  static Vec3 ray(const hal::CameraIntrinsics& intrinsics, const Eigen::Matrix3d& rotation, double u, double v);
  // base <- camera body for a mount: Rz(yaw) * Ry(pitch) * Rx(roll), not validated.
  static Eigen::Matrix3d rotationOf(const hal::CameraMount& mount);
  // The reverse: the pixel (u, v) and the depth (optical z) of a point in the base frame;
  // depth <= 0 for a point behind the camera.
  Vec3 project(const Vec3& point_in_base) const;

 private:
  hal::CameraIntrinsics intrinsics_;
  hal::CameraMount mount_;
  Eigen::Matrix3d rotation_;
  Vec3 position_;
};

}  // namespace staa
