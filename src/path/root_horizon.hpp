#pragma once
// How far, in every direction from one point (the root of a backward shortest-path search: its
// goal), no obstacle boundary comes: a table over a fixed number of direction sectors.
//
// The heuristic's tree asks "is the edge from the root to this robot state free?" for every
// state STAA* evaluates: thousands of times per cycle for one root, and almost always yes. The
// collision grid cannot vouch for those edges (the intermediate goal lies on its border, which
// counts as an obstacle), so the exact test walked every one. One table per root answers the
// free ones with a pseudo-angle and a load. A yes is exact: the segment from the root to p
// stays within its direction's sector and closer than any boundary point there, so it crosses
// no edge, and the exact test would list no blocker (the root itself is free). A no decides
// nothing: the caller runs the exact test.
//
// Building allocates nothing (the table is sized at construction); it visits the edges in the
// box of the region and the root once (no other edge can meet a segment from the root to a
// point of the region).

#include "geometry/types.hpp"

#include <cstddef>
#include <vector>

namespace staa {

class PolygonSet;

class RootHorizon {
 public:
  static constexpr std::size_t kSectors = 1024;  // a multiple of 4 (the pseudo-angle's quadrants)

  RootHorizon() : bound_(kSectors, 0.0) {}

  // The table for `root` among the polygons of `set`, for segments to points of `region`
  // (the root need not lie in it).
  void build(const PolygonSet& set, const Vec2& root, const Box& region);
  // Forgets the table (the polygons or the region changed).
  void clear() { built_ = false; }
  bool builtFor(const Vec2& root) const { return built_ && root == root_; }

  // True when p lies in the region and the closed segment from the root to p meets no
  // polygon boundary (and so, the root being free, no interior). False says nothing.
  bool certifiesFree(const Vec2& p) const;

 private:
  static std::size_t sectorOf(const Vec2& d);
  // The unit-free direction at the start of sector s (pseudo-angle s * 4 / kSectors).
  static Vec2 sectorStart(std::size_t s);
  // Lowers the bounds of the sectors the edge (c, d) (relative to the root) passes through.
  void addEdge(const Vec2& c, const Vec2& d);

  std::vector<double> bound_;
  Vec2 root_{0.0, 0.0};
  Box region_;     // the region and the root: every segment asked about lies in it
  double reach_ = 0.0;
  bool built_ = false;
};

}  // namespace staa
