#include "visibility_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa::test {

bool referenceSegmentFree(const Vec2& a, const Vec2& b, const std::vector<Polygon>& polys) {
  std::vector<double> ts{0.0, 1.0};
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  for (const Polygon& poly : polys) {
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Vec2& c = poly[j];
      const Vec2& d = poly[i];
      if (auto t = segmentIntersectionParam(a, b, c, d)) ts.push_back(*t);
      // Vertices on the segment and collinear overlaps.
      for (const Vec2* q : {&c, &d}) {
        if (len2 > 0.0 && orient(a, b, *q) == 0.0) {
          const double t = (*q - a).dot(ab) / len2;
          if (t > 0.0 && t < 1.0) ts.push_back(t);
        }
      }
    }
  }
  std::sort(ts.begin(), ts.end());
  for (std::size_t k = 0; k + 1 < ts.size(); ++k) {
    if (ts[k + 1] - ts[k] < 1e-12) continue;
    const Vec2 mid = a + 0.5 * (ts[k] + ts[k + 1]) * ab;
    for (const Polygon& poly : polys) {
      if (locatePoint(mid, poly, 1e-12) == Containment::kInside) return false;
    }
  }
  return true;
}

bool referencePointFree(const Vec2& p, const std::vector<Polygon>& polys) {
  for (const Polygon& poly : polys) {
    if (locatePoint(p, poly, 1e-12) == Containment::kInside) return false;
  }
  return true;
}

std::optional<double> referenceShortestPath(const Vec2& start, const Vec2& goal, const std::vector<Polygon>& polys) {
  std::vector<Vec2> nodes{start, goal};
  for (std::size_t k = 0; k < polys.size(); ++k) {
    const Polygon& poly = polys[k];
    const double s = signedArea(poly) > 0.0 ? 1.0 : -1.0;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& p = poly[(i + n - 1) % n];
      const Vec2& c = poly[i];
      const Vec2& q = poly[(i + 1) % n];
      if (s * orient(p, c, q) <= 0.0) continue;  // reflex or straight
      bool free = true;
      for (std::size_t m = 0; m < polys.size() && free; ++m) {
        if (m != k && locatePoint(c, polys[m], 1e-12) == Containment::kInside) free = false;
      }
      if (free) nodes.push_back(c);
    }
  }
  const std::size_t n = nodes.size();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<char> done(n, 0);
  dist[0] = 0.0;
  for (;;) {
    std::size_t u = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (!done[i] && (u == n || dist[i] < dist[u])) u = i;
    }
    if (u == n || !std::isfinite(dist[u])) return std::nullopt;
    if (u == 1) return dist[1];
    done[u] = 1;
    for (std::size_t w = 0; w < n; ++w) {
      if (done[w]) continue;
      const double nd = dist[u] + (nodes[w] - nodes[u]).norm();
      if (nd < dist[w] && referenceSegmentFree(nodes[u], nodes[w], polys)) dist[w] = nd;
    }
  }
}

}  // namespace staa::test
