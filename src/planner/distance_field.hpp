#pragma once
// Distance from every cell of a grid to the nearest occupied cell, by a two-pass 3x3 chamfer
// (steps 1 and sqrt 2), scaled to be conservative: never more than the true Euclidean
// distance from any point of the cell to any point of an occupied cell. No allocation: the
// caller owns `out` (width * height).

#include <cstdint>
#include <span>

namespace staa {

// out[j * width + i] in metres; a huge value where nothing is occupied.
void conservativeDistanceField(std::span<const std::uint8_t> occupied, int width, int height, double cell_m,
                               std::span<float> out);

}  // namespace staa
