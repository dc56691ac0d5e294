// The maps shipped in config/maps are the generator's output: they must load, validate and
// equal what `staa-map generate NAME` produces now, vertex for vertex (to the last bits).
#include "map/generate.hpp"

#include "shared_dir.hpp"

#include <gtest/gtest.h>

namespace staa {
namespace {

TEST(ConfigMaps, ShippedPaperMapsEqualTheGenerator) {
  for (const char* name : {"office", "apartment", "clutter"}) {
    const PolygonMap shipped = loadPolygonMap(test::sourceDir() / "config/maps" / (std::string(name) + ".yaml"));
    const PolygonMap fresh = generatePaperMap(name, 1);
    ASSERT_EQ(shipped.obstacles.size(), fresh.obstacles.size()) << name;
    for (std::size_t k = 0; k < fresh.obstacles.size(); ++k) {
      ASSERT_EQ(shipped.obstacles[k].size(), fresh.obstacles[k].size()) << name << " obstacles[" << k << "]";
      for (std::size_t i = 0; i < fresh.obstacles[k].size(); ++i) {
        // Clutter's octagons go through sin/cos: another libm may differ in the last bit.
        EXPECT_LT((shipped.obstacles[k][i] - fresh.obstacles[k][i]).norm(), 1e-12)
            << name << " obstacles[" << k << "][" << i << "]";
      }
    }
    ASSERT_EQ(shipped.goals.size(), fresh.goals.size()) << name;
    for (std::size_t g = 0; g < fresh.goals.size(); ++g) EXPECT_EQ(shipped.goals[g], fresh.goals[g]) << name;
    EXPECT_EQ(shipped.bounds.has_value(), fresh.bounds.has_value()) << name;
  }
}

}  // namespace
}  // namespace staa
