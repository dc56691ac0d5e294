#include "map/generate.hpp"

namespace staa {}  // namespace staa
