#include "geometry/convex.hpp"

#include "geometry/predicates.hpp"

#include "geometry/polygon.hpp"

#include <ccd/ccd.h>

#include <algorithm>

namespace staa {

// ---- hulls ----

std::size_t convexHullInPlace(std::span<Vec2> points, std::span<Vec2> out) {
  if (points.empty() || out.size() < points.size() + 1) return 0;
  std::sort(points.begin(), points.end(), [](const Vec2& p, const Vec2& q) {
    return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y());
  });
  const std::size_t n = static_cast<std::size_t>(std::unique(points.begin(), points.end()) - points.begin());
  if (n <= 2) {
    std::copy_n(points.begin(), n, out.begin());
    return n;
  }
  // Popping on orient <= 0 drops collinear points; the chain never holds more than n + 1.
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && orientSign(out[k - 2], out[k - 1], points[i]) <= 0) --k;
    out[k++] = points[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {
    while (k >= t && orientSign(out[k - 2], out[k - 1], points[i]) <= 0) --k;
    out[k++] = points[i];
  }
  return k - 1;  // the last vertex repeats the first
}

Polygon convexHull(std::span<const Vec2> points) {
  Polygon sorted(points.begin(), points.end());
  Polygon hull(points.size() + 1);
  hull.resize(convexHullInPlace(sorted, hull));
  return hull;
}

namespace {
int sign(double v) { return (v > 0.0) - (v < 0.0); }
}  // namespace

bool isConvex(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return false;
  int turn = 0;  // the sign every non-zero turn must share
  int x_flips = 0, first_x = 0, last_x = 0;
  Vec2 first_edge{0.0, 0.0}, prev_edge{0.0, 0.0};
  bool have_prev = false;
  // A turn between consecutive non-zero edges: same sign as the others, or straight on.
  auto turnIsConvex = [&turn](const Vec2& e0, const Vec2& e1) {
    const int s = orientSign(Vec2::Zero(), e0, e1);  // the exact sign of cross(e0, e1)
    if (s == 0) return e0.dot(e1) > 0.0;  // a fold back along the same line is not convex
    if (turn == 0) turn = s;
    return s == turn;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 e = poly[(i + 1) % n] - poly[i];
    if (e.x() == 0.0 && e.y() == 0.0) continue;  // repeated vertex
    if (have_prev) {
      if (!turnIsConvex(prev_edge, e)) return false;
    } else {
      first_edge = e;
    }
    // Counting direction reversals in x rejects stars, whose turns all agree but which
    // wind more than once: a convex polygon reverses exactly twice.
    if (const int sx = sign(e.x()); sx != 0) {
      if (last_x != 0 && sx != last_x) ++x_flips;
      if (first_x == 0) first_x = sx;
      last_x = sx;
    }
    prev_edge = e;
    have_prev = true;
  }
  if (!have_prev || !turnIsConvex(prev_edge, first_edge)) return false;
  if (first_x != 0 && first_x != last_x) ++x_flips;
  return turn != 0 && x_flips <= 2;
}

// ---- SAT ----

namespace {

// Projections compared exactly: a shared boundary point gives equal ends, which is not a
// separation, so touching counts as intersecting.
bool separatedAlong(const Vec2& axis, PolygonView a, PolygonView b) {
  if (axis.x() == 0.0 && axis.y() == 0.0) return false;
  double a_lo = axis.dot(a[0]), a_hi = a_lo;
  for (const Vec2& p : a) {
    const double d = axis.dot(p);
    a_lo = std::min(a_lo, d);
    a_hi = std::max(a_hi, d);
  }
  double b_lo = axis.dot(b[0]), b_hi = b_lo;
  for (const Vec2& p : b) {
    const double d = axis.dot(p);
    b_lo = std::min(b_lo, d);
    b_hi = std::max(b_hi, d);
    if (b_lo <= a_hi && a_lo <= b_hi) return false;  // already overlapping on this axis
  }
  return a_hi < b_lo || b_hi < a_lo;
}

// Tries the normals (or, for flat shapes, the directions) of the edges of `edges_of`.
bool separatedByEdges(PolygonView edges_of, PolygonView a, PolygonView b, bool normals) {
  const std::size_t n = edges_of.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2 e = edges_of[i] - edges_of[j];
    if (separatedAlong(normals ? Vec2{-e.y(), e.x()} : e, a, b)) return true;
  }
  return false;
}

// A point or a segment (zero area relative to its size): its edge normals alone miss the
// axis along the segment, so SAT must also try the edge directions.
bool isFlat(PolygonView p) {
  double twice_area = 0.0, max_edge2 = 0.0;
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++) {
    twice_area += cross(p[j], p[i]);
    max_edge2 = std::max(max_edge2, (p[i] - p[j]).squaredNorm());
  }
  return std::abs(twice_area) <= 1e-12 * max_edge2 || max_edge2 == 0.0;
}

}  // namespace

bool convexIntersectSat(PolygonView a, PolygonView b) {
  if (a.empty() || b.empty()) return false;
  // Both proper convex polygons: the edge normals of both are the complete set of axes.
  if (separatedByEdges(a, a, b, true) || separatedByEdges(b, a, b, true)) return false;
  if (isFlat(a) || isFlat(b)) {
    // Collinear segments need their common direction; two points need the axis through them.
    if (separatedByEdges(a, a, b, false) || separatedByEdges(b, a, b, false)) return false;
    if (separatedAlong(a[0] - b[0], a, b)) return false;
  }
  return true;
}

// ---- libccd ----

namespace {

// libccd works in millimetres: its GJK decides "origin on the simplex" by a squared distance
// below DBL_EPSILON, i.e. within 1.5e-8 of the unit. In metres that called pairs 15 nm apart
// intersecting and missed overlaps of 0.1 um on random tests; in millimetres both vanish.
constexpr double kCcdUnitsPerMetre = 1e3;
// Half-height of the prism a polygon is lifted to (in metres), of the order of the polygons'
// size; the answer does not depend on it because the origin lies at mid-height.
constexpr double kPrismHalfHeight = 0.5 * kCcdUnitsPerMetre;

void prismSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const PolygonView& poly = *static_cast<const PolygonView*>(obj);
  const double dx = ccdVec3X(dir), dy = ccdVec3Y(dir);
  std::size_t best = 0;
  double best_dot = dx * poly[0].x() + dy * poly[0].y();
  for (std::size_t i = 1; i < poly.size(); ++i) {
    const double d = dx * poly[i].x() + dy * poly[i].y();
    if (d > best_dot) {
      best_dot = d;
      best = i;
    }
  }
  ccdVec3Set(out, kCcdUnitsPerMetre * poly[best].x(), kCcdUnitsPerMetre * poly[best].y(), ccdVec3Z(dir) >= 0.0 ? kPrismHalfHeight : -kPrismHalfHeight);
}

// MPR needs an interior point; the vertex mean of a convex polygon is one (at z = 0).
void prismCenter(const void* obj, ccd_vec3_t* out) {
  const PolygonView& poly = *static_cast<const PolygonView*>(obj);
  Vec2 c{0.0, 0.0};
  for (const Vec2& p : poly) c += p;
  c /= static_cast<double>(poly.size());
  ccdVec3Set(out, kCcdUnitsPerMetre * c.x(), kCcdUnitsPerMetre * c.y(), 0.0);
}

ccd_t makeCcd() {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = prismSupport;
  ccd.support2 = prismSupport;
  ccd.center1 = prismCenter;
  ccd.center2 = prismCenter;
  // libccd's default is unbounded; a bounded loop keeps the cycle's worst case bounded.
  ccd.max_iterations = 100;
  // MPR stops refining when the portal moves less than this and then reports "separated":
  // the default 1e-4 (here mm) would miss shallow contacts.
  ccd.mpr_tolerance = 1e-9;
  return ccd;
}

const ccd_t kCcd = makeCcd();

}  // namespace

bool convexIntersectGjk(PolygonView a, PolygonView b) {
  if (a.empty() || b.empty()) return false;
  return ccdGJKIntersect(&a, &b, &kCcd) != 0;
}

bool convexIntersectMpr(PolygonView a, PolygonView b) {
  if (a.empty() || b.empty()) return false;
  return ccdMPRIntersect(&a, &b, &kCcd) != 0;
}

bool convexIntersect(PolygonView a, PolygonView b) { return convexIntersectSat(a, b); }

// ---- non-convex pairs ----

namespace {

constexpr double kOnBoundaryEps = 1e-9;  // locatePoint's default boundary tolerance

// "Inside or on": points and segments (fewer than 3 vertices) have only a boundary.
bool insideOrOn(const Vec2& p, PolygonView poly) {
  switch (poly.size()) {
    case 0:
      return false;
    case 1:
      return (p - poly[0]).norm() <= kOnBoundaryEps;
    case 2:
      return distancePointSegment(p, poly[0], poly[1]) <= kOnBoundaryEps;
    default:
      return locatePoint(p, poly, kOnBoundaryEps) != Containment::kOutside;
  }
}

}  // namespace

bool cornerContainment(PolygonView a, PolygonView b) {
  for (const Vec2& p : a)
    if (insideOrOn(p, b)) return true;
  for (const Vec2& p : b)
    if (insideOrOn(p, a)) return true;
  return false;
}

bool polygonsOverlap(PolygonView a, PolygonView b) {
  if (a.empty() || b.empty()) return false;
  for (std::size_t i = 0, j = a.size() - 1; i < a.size(); j = i++)
    for (std::size_t k = 0, l = b.size() - 1; k < b.size(); l = k++)
      if (segmentsIntersect(a[j], a[i], b[l], b[k])) return true;
  // No boundary contact: overlap only if one lies inside the other, then all its corners do.
  return cornerContainment(a, b);
}

}  // namespace staa
