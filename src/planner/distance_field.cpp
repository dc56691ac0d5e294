#include "planner/distance_field.hpp"

#include <algorithm>
#include <cmath>

namespace staa {

void conservativeDistanceField(std::span<const std::uint8_t> occupied, int w, int h, double cell_m,
                               std::span<float> out) {
  constexpr float kFar = 1e9f;
  // The chamfer length exceeds the Euclidean one by at most this factor.
  constexpr double kChamferOverestimate = 1.0824;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  for (std::size_t i = 0; i < n; ++i) out[i] = occupied[i] ? 0.0f : kFar;
  const float d1 = 1.0f, d2 = static_cast<float>(std::sqrt(2.0));
  auto at = [&](int i, int j) -> float& { return out[static_cast<std::size_t>(j) * static_cast<std::size_t>(w) + static_cast<std::size_t>(i)]; };
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      float& d = at(i, j);
      if (i > 0) d = std::min(d, at(i - 1, j) + d1);
      if (j > 0) {
        d = std::min(d, at(i, j - 1) + d1);
        if (i > 0) d = std::min(d, at(i - 1, j - 1) + d2);
        if (i + 1 < w) d = std::min(d, at(i + 1, j - 1) + d2);
      }
    }
  }
  for (int j = h - 1; j >= 0; --j) {
    for (int i = w - 1; i >= 0; --i) {
      float& d = at(i, j);
      if (i + 1 < w) d = std::min(d, at(i + 1, j) + d1);
      if (j + 1 < h) {
        d = std::min(d, at(i, j + 1) + d1);
        if (i + 1 < w) d = std::min(d, at(i + 1, j + 1) + d2);
        if (i > 0) d = std::min(d, at(i - 1, j + 1) + d2);
      }
    }
  }
  // Cells to metres, conservatively: the chamfer overestimate, and a cell's diagonal for the
  // query point's offset in its cell plus the occupied cell's own extent.
  const float scale = static_cast<float>(cell_m / kChamferOverestimate);
  const float margin = static_cast<float>(cell_m * std::sqrt(2.0));
  for (std::size_t i = 0; i < n; ++i) out[i] = out[i] >= kFar ? kFar : out[i] * scale - margin;
}

}  // namespace staa
