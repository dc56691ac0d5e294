#include "planner/distance_field.hpp"

#include <algorithm>
#include <cmath>

namespace staa {

namespace {

// One row's update from the row before it (up = the previous row in scan order): the three
// diagonal/straight neighbours there, then the running scan along the row. The first part
// has no dependency between cells (the compiler vectorizes it); the second is a short chain.
void relaxRow(float* row, const float* up, int w, bool forward) {
  constexpr float d1 = 1.0f, d2 = 1.41421356f;
  if (up != nullptr) {
    row[0] = std::min({row[0], up[0] + d1, (w > 1 ? up[1] : row[0]) + d2});
    for (int i = 1; i + 1 < w; ++i) row[i] = std::min({row[i], up[i] + d1, up[i - 1] + d2, up[i + 1] + d2});
    if (w > 1) row[w - 1] = std::min({row[w - 1], up[w - 1] + d1, up[w - 2] + d2});
  }
  if (forward) {
    for (int i = 1; i < w; ++i) row[i] = std::min(row[i], row[i - 1] + d1);
  } else {
    for (int i = w - 2; i >= 0; --i) row[i] = std::min(row[i], row[i + 1] + d1);
  }
}

}  // namespace

void conservativeDistanceField(std::span<const std::uint8_t> occupied, int w, int h, double cell_m,
                               std::span<float> out) {
  constexpr float kFar = 1e9f;
  // The 3x3 chamfer length exceeds the Euclidean one by at most this factor.
  constexpr double kChamferOverestimate = 1.0824;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  for (std::size_t i = 0; i < n; ++i) out[i] = occupied[i] ? 0.0f : kFar;
  float* d = out.data();
  // Forward pass (top-left to bottom-right), then backward; each row in two sweeps (left to
  // right and right to left) so both passes see all eight neighbours across the two passes.
  for (int j = 0; j < h; ++j) {
    float* row = d + static_cast<std::size_t>(j) * w;
    relaxRow(row, j > 0 ? row - w : nullptr, w, true);
    relaxRow(row, nullptr, w, false);
  }
  for (int j = h - 1; j >= 0; --j) {
    float* row = d + static_cast<std::size_t>(j) * w;
    relaxRow(row, j + 1 < h ? row + w : nullptr, w, false);
    relaxRow(row, nullptr, w, true);
  }
  // Cells to metres, conservatively: the chamfer overestimate, and a cell's diagonal for the
  // query point's offset in its cell plus the occupied cell's own extent.
  const float scale = static_cast<float>(cell_m / kChamferOverestimate);
  const float margin = static_cast<float>(cell_m * std::sqrt(2.0));
  for (std::size_t i = 0; i < n; ++i) out[i] = out[i] >= kFar ? kFar : out[i] * scale - margin;
}

}  // namespace staa
