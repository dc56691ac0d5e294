#pragma once
// The paper's three evaluation worlds (docs/paper-worlds.md): office, apartment,
// clutter, each with its goal locations.

#include "map/polygon_map.hpp"

#include <cstdint>
#include <string_view>

namespace staa {

PolygonMap generateOfficeMap();
PolygonMap generateApartmentMap();
// Random from `seed`: the same seed gives the same map on every machine.
PolygonMap generateClutterMap(std::uint64_t seed);

// By name ("office", "apartment", "clutter"); throws MapError for an unknown name.
PolygonMap generatePaperMap(std::string_view name, std::uint64_t seed);

}  // namespace staa
