#include "hal/ros/depth_image.hpp"

#include <cmath>

namespace staa::hal {

CameraPoseSample cameraPoseFromOpticalFrame(double tx, double ty, double tz, double qx, double qy, double qz,
                                            double qw) {
  CameraPoseSample pose;
  const double norm = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
  if (!std::isfinite(tx) || !std::isfinite(ty) || !std::isfinite(tz) || !std::isfinite(norm) || !(norm > 1e-9)) {
    return pose;
  }
  qx /= norm;
  qy /= norm;
  qz /= norm;
  qw /= norm;
  // base <- optical, its columns the optical axes in the base frame.
  const double o[3][3] = {
      {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)},
      {2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)},
      {2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)},
  };
  // base <- body: body x (forward) is optical z, body y (left) optical -x, body z (up) optical -y.
  double r[3][3];
  for (int i = 0; i < 3; ++i) {
    r[i][0] = o[i][2];
    r[i][1] = -o[i][0];
    r[i][2] = -o[i][1];
  }
  // r = Rz(yaw) * Ry(pitch) * Rx(roll); looking straight up or down, yaw is taken as 0.
  const double cos_pitch = std::hypot(r[0][0], r[1][0]);
  pose.pitch = std::atan2(-r[2][0], cos_pitch);
  if (cos_pitch > 1e-9) {
    pose.yaw = std::atan2(r[1][0], r[0][0]);
    pose.roll = std::atan2(r[2][1], r[2][2]);
  } else {
    pose.yaw = 0.0;
    pose.roll = std::atan2(-r[1][2], r[1][1]);
  }
  pose.x = tx;
  pose.y = ty;
  pose.z = tz;
  pose.valid = true;
  return pose;
}

}  // namespace staa::hal
