#include "map/polygon_map.hpp"

namespace staa {}  // namespace staa
