#pragma once
// Which pairs of a polygon set's convex corners pass Minimal Construct's two tangency tests
// (an edge between corners a and b must touch a's polygon at a and b's at b without cutting
// into either). Both tests are exact and the pair's answer is symmetric, so a table computed
// once for the static obstacles answers them for every search over those obstacles: the
// searches' expansions then visit only the corners that pass both. Built at start-up (it
// allocates and takes O(corners^2)); searches over equal polygon sets share one table.

#include "geometry/predicates.hpp"
#include "path/polygon_set.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace staa {

// The segment from corner `at` (neighbours prev and next on its polygon) towards `other`
// touches the polygon at `at` without cutting into it: both neighbours lie on the same side of
// the line. Exact (orientSignProduct with any bound valid for the points).
inline bool tangentAt(const Vec2& at, const Vec2& other, const Vec2& prev, const Vec2& next, double bound) {
  return orientSignProduct(at, other, prev, next, bound) >= 0;
}

class TangencyTable {
 public:
  // More corners than this get no table (4,096 corners: 2 MiB, about 8 M pair tests).
  static constexpr std::size_t kMaxCorners = 4096;

  // The table of `set`'s convex corners, shared with every earlier call for a set of the same
  // vertices (bit for bit, in the same order and polygons) that is still alive; nullptr when
  // the set has no convex corner or more than kMaxCorners. Thread-safe (a lock, at
  // construction only).
  static std::shared_ptr<const TangencyTable> forSet(const PolygonSet& set);

  // The corner index of a vertex, or -1 when it is no convex corner.
  std::int32_t cornerOf(std::size_t vertex) const { return corner_of_[vertex]; }
  std::size_t corners() const { return corners_; }
  // Whether corners a and b pass both tangency tests.
  bool joinable(std::int32_t a, std::int32_t b) const {
    const auto ub = static_cast<std::size_t>(b);
    return ((bits_[static_cast<std::size_t>(a) * words_ + (ub >> 6)] >> (ub & 63)) & 1U) != 0;
  }
  // How many corners corner a is joinable with (its row's bits).
  std::uint32_t rowCount(std::int32_t a) const { return row_count_[static_cast<std::size_t>(a)]; }
  // Corner a's row: bit b of word b / 64 is joinable(a, b).
  std::span<const std::uint64_t> row(std::int32_t a) const {
    return {bits_.data() + static_cast<std::size_t>(a) * words_, words_};
  }

 private:
  explicit TangencyTable(const PolygonSet& set);
  bool sameVertices(const PolygonSet& set) const;

  // The set's vertices and their polygons, for the sharing's exact comparison.
  std::vector<Vec2> vertices_;
  std::vector<std::uint32_t> polygon_of_;
  std::vector<std::int32_t> corner_of_;
  std::size_t corners_ = 0;
  std::size_t words_ = 0;
  std::vector<std::uint64_t> bits_;
  std::vector<std::uint32_t> row_count_;
};

}  // namespace staa
