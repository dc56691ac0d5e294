#pragma once
// The socketcan backend as its users see it: a hal::Base opened by interface name ("can0",
// "vcan0", "unix:/run/base.sock"), without <linux/can.h> (the driver's own headers,
// socketcan_base.hpp and can_transport.hpp, carry the kernel's frame types).

#include "geometry/types.hpp"
#include "hal/base.hpp"
#include "rt/clock.hpp"

#include <memory>
#include <stdexcept>
#include <string>

namespace staa::hal {

struct CanProfile;

// The bus (or the socket of a "unix:" interface) cannot be opened: what() names it and why.
class CanTransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A SocketCanBase on openCanTransport(interface, profile); `clock` stamps its command frames'
// hand-over to the kernel (see SocketCanBase). Throws CanTransportError.
std::unique_ptr<Base> openSocketCanBase(const std::string& interface, const CanProfile& profile,
                                        const Pose2& start, const rt::Clock* clock);

}  // namespace staa::hal
