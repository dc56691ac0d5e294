#include "planner/distance_field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace staa {
namespace {

// The field must never exceed the true distance from any point of a cell to any point of an
// occupied cell (it clears circles for collision checks), and should not be far below it.
TEST(DistanceField, IsConservativeAndTightOnRandomGrids) {
  std::mt19937 rng(3);
  const int w = 40, h = 30;
  const double cell = 0.05;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::uint8_t> occ(static_cast<std::size_t>(w * h), 0);
    std::bernoulli_distribution bit(0.01 + 0.01 * trial);
    for (auto& o : occ) o = bit(rng) ? 1 : 0;
    occ[static_cast<std::size_t>(w * h / 2 + 7)] = 1;  // at least one
    std::vector<float> field(occ.size());
    conservativeDistanceField(occ, w, h, cell, field);
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        // True minimum distance between the two cell squares, over all occupied cells.
        double best = 1e9;
        for (int q = 0; q < h; ++q) {
          for (int p = 0; p < w; ++p) {
            if (!occ[static_cast<std::size_t>(q * w + p)]) continue;
            const double dx = std::max(0, std::abs(p - i) - 1) * cell, dy = std::max(0, std::abs(q - j) - 1) * cell;
            best = std::min(best, std::hypot(dx, dy));
          }
        }
        const float f = field[static_cast<std::size_t>(j * w + i)];
        ASSERT_LE(f, best + 1e-6) << "cell " << i << "," << j;
        ASSERT_GE(f, best - 0.12 * best - 3.0 * cell) << "cell " << i << "," << j;
      }
    }
  }
}

}  // namespace
}  // namespace staa
