#include "map/ros_import.hpp"

namespace staa {}  // namespace staa
