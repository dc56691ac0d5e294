#include "hal/base.hpp"

namespace staa::hal {

const char* toString(BaseFault fault) {
  switch (fault) {
    case BaseFault::kNone: return "none";
    case BaseFault::kEmergencyStop: return "emergency stop";
    case BaseFault::kHeartbeatLost: return "heartbeat lost";
    case BaseFault::kBusOff: return "bus off";
    case BaseFault::kWriteFailed: return "write failed";
    case BaseFault::kDriverFault: return "driver fault";
    case BaseFault::kOdometryInvalid: return "odometry invalid";
    case BaseFault::kOdometryStampBack: return "odometry stamp went back";
  }
  // A value cast in from a corrupted frame: say so instead of reading past a table.
  return "unknown";
}

}  // namespace staa::hal
