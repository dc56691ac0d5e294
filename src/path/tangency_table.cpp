#include "path/tangency_table.hpp"

#include <bit>
#include <cstring>
#include <mutex>

namespace staa {

TangencyTable::TangencyTable(const PolygonSet& set) {
  const std::size_t n = set.vertexCount();
  vertices_.reserve(n);
  polygon_of_.reserve(n);
  corner_of_.assign(n, -1);
  std::vector<std::size_t> vertex_of;
  for (std::size_t v = 0; v < n; ++v) {
    vertices_.push_back(set.vertex(v));
    polygon_of_.push_back(set.polygonOfVertex(v));
    if (!set.isConvexCorner(v)) continue;
    corner_of_[v] = static_cast<std::int32_t>(vertex_of.size());
    vertex_of.push_back(v);
  }
  corners_ = vertex_of.size();
  words_ = (corners_ + 63) / 64;
  bits_.assign(corners_ * words_, 0);
  // Every coordinate of the set is within maxCoordinate: the static filter's bound for them.
  const double bound = orientStaticBound(set.maxCoordinate());
  std::vector<Vec2> pos(corners_), prev(corners_), next(corners_);
  for (std::size_t k = 0; k < corners_; ++k) {
    const std::size_t v = vertex_of[k];
    pos[k] = set.vertex(v);
    prev[k] = set.vertex(set.prevVertex(v));
    next[k] = set.vertex(set.nextVertex(v));
  }
  for (std::size_t a = 0; a < corners_; ++a) {
    for (std::size_t b = a; b < corners_; ++b) {
      if (!tangentAt(pos[a], pos[b], prev[a], next[a], bound) || !tangentAt(pos[b], pos[a], prev[b], next[b], bound)) {
        continue;
      }
      bits_[a * words_ + (b >> 6)] |= std::uint64_t{1} << (b & 63);
      bits_[b * words_ + (a >> 6)] |= std::uint64_t{1} << (a & 63);
    }
  }
  row_count_.assign(corners_, 0);
  for (std::size_t a = 0; a < corners_; ++a) {
    for (std::size_t w = 0; w < words_; ++w) row_count_[a] += static_cast<std::uint32_t>(std::popcount(bits_[a * words_ + w]));
  }
}

bool TangencyTable::sameVertices(const PolygonSet& set) const {
  if (set.vertexCount() != vertices_.size()) return false;
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (std::memcmp(vertices_[v].data(), set.vertex(v).data(), 2 * sizeof(double)) != 0) return false;
    if (polygon_of_[v] != set.polygonOfVertex(v)) return false;
  }
  return true;
}

std::shared_ptr<const TangencyTable> TangencyTable::forSet(const PolygonSet& set) {
  std::size_t corners = 0;
  for (std::size_t v = 0; v < set.vertexCount(); ++v) corners += set.isConvexCorner(v) ? 1 : 0;
  if (corners == 0 || corners > kMaxCorners) return nullptr;
  // The tables alive, for the searches of one map (several per cycle, one cycle per agent).
  static std::mutex mutex;
  static std::vector<std::weak_ptr<const TangencyTable>> alive;
  const std::lock_guard<std::mutex> lock(mutex);
  std::erase_if(alive, [](const std::weak_ptr<const TangencyTable>& w) { return w.expired(); });
  for (const std::weak_ptr<const TangencyTable>& w : alive) {
    std::shared_ptr<const TangencyTable> table = w.lock();
    if (table && table->sameVertices(set)) return table;
  }
  std::shared_ptr<const TangencyTable> table(new TangencyTable(set));
  alive.push_back(table);
  return table;
}

}  // namespace staa
