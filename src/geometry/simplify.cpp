#include "geometry/simplify.hpp"

#include "geometry/polygon.hpp"
#include "geometry/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

// How simplifyOutward keeps P ⊆ S ⊆ P ⊕ tolerance. S only ever grows, by regions outside
// it, each within a proven distance of P; every edge e of S carries a bound eps(e) on the
// distance to P of its points and of the region added behind it, and no step may raise a
// bound beyond the tolerance. The input must be simple (it is checked: O(n log n)).
//
// 1. Pockets of the convex hull. Between two consecutive hull vertices the boundary either
//    follows the hull edge (the lid) or dips into a pocket, a region of air that no other
//    part of P enters. A pocket is filled (the lid becomes an edge) when every point of it
//    lies within the tolerance of its chain: for a pocket of one vertex (a notch: a
//    triangle) within half the lid's length or its depth, for a longer one within its
//    depth. The notches of a toothed ring and the gaps of a spiky star go here.
// 2. A strictly convex outline (a circle, or the hull the pockets left) is circumscribed in
//    one pass: keep an edge, skip the next ones while the corner where the kept edge's line
//    meets the candidate's stays within the tolerance of the outline it replaces, and so
//    on. The result is the intersection of the kept edges' half-planes: convex and simple.
// 3. Local steps, smallest resulting bound first (a heap that keeps each step once):
//    - remove a reflex vertex v between u and w: S gains the triangle (u, v, w), whose
//      points lie within min(|uw| / 2, depth of v) of the edges uv and vw (and within |uw| / 2
//      of one of u, v, w when all three are P's and the angle at v is obtuse); allowed when
//      no other vertex lies in the closed triangle (then no edge enters it: it could only
//      cross uw, and it would have to end inside);
//    - replace a convex edge vw by the corner X where the lines of its neighbouring edges
//      uv and wz meet (both turns left, together less than a half turn): S gains the region
//      between u-v-w-z and u-X-z, whose points lie within the distance from X to vw of that
//      edge; allowed when no other vertex lies in the triangle (u, X, z) and no other edge
//      meets uX or Xz (no test at all while the outline is strictly convex: every other
//      vertex then lies strictly inside each edge's line).
//    Convex stretches of a non-convex outline become circumscribed, concave ones chords.
//    An edge grid (a linked list per cell) finds the vertices and edges near a step.
// New corners are computed in floating point and then moved out by a hair until the exact
// orientation tests put them outside both lines they lie on, so no sliver of P is cut off.

namespace staa {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double distanceToLine(const Vec2& p, const Vec2& a, const Vec2& b) {
  const double len = (b - a).norm();
  return len > 0.0 ? std::abs(orient(a, b, p)) / len : (p - a).norm();
}

// The convex hull's vertices (strictly convex corners only), counter-clockwise, by index:
// Andrew's monotone chain with exact orientation tests.
std::vector<std::uint32_t> convexHull(const std::vector<Vec2>& p) {
  std::vector<std::uint32_t> order(p.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return p[a].x() < p[b].x() || (p[a].x() == p[b].x() && (p[a].y() < p[b].y() || (p[a].y() == p[b].y() && a < b)));
  });
  std::vector<std::uint32_t> hull(2 * order.size());
  std::size_t k = 0;
  for (const std::uint32_t i : order) {
    while (k >= 2 && orientSign(p[hull[k - 2]], p[hull[k - 1]], p[i]) <= 0) --k;
    hull[k++] = i;
  }
  const std::size_t lower = k + 1;
  for (std::size_t j = order.size() - 1; j-- > 0;) {
    const std::uint32_t i = order[j];
    while (k >= lower && orientSign(p[hull[k - 2]], p[hull[k - 1]], p[i]) <= 0) --k;
    hull[k++] = i;
  }
  hull.resize(k > 0 ? k - 1 : 0);
  return hull;
}

// A uniform grid over a box; per cell a singly linked list of vertex ids (an entry stands
// for the edge that starts at that vertex). Cells are found for convex shapes (a segment, a
// triangle) row by row, slightly widened so that a point two shapes share is in a cell of both.
// Every edge is listed where it runs when it is made; an entry whose vertex has since got
// another edge stays (that edge is tested there too: harmless), one whose vertex is gone is
// dropped when its cell is next visited.
class CellLists {
 public:
  CellLists(const Box& box, double cell, std::size_t entries_hint) : origin_(box.min), cell_(cell) {
    cols_ = std::max(1, static_cast<int>(std::ceil(box.width() / cell)) + 1);
    rows_ = std::max(1, static_cast<int>(std::ceil(box.height() / cell)) + 1);
    head_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_), -1);
    next_.reserve(entries_hint);
    item_.reserve(entries_hint);
  }

  void insert(const Vec2& a, const Vec2& b, std::int32_t item) {
    const Vec2 pts[2] = {a, b};
    forEachCell(pts, 2, [&](std::size_t c) {
      next_.push_back(head_[c]);
      item_.push_back(item);
      head_[c] = static_cast<std::int32_t>(item_.size() - 1);
      return false;
    });
  }

  // Calls visit(item) for every entry of every cell the convex shape touches (an item may
  // come more than once); stops and returns true when visit does. Entries of items that are
  // gone (alive[item] == 0) are unlinked on the way.
  template <typename Visit>
  bool visit(const Vec2* pts, int n, const std::vector<std::uint8_t>& alive, Visit&& visit_item) {
    return forEachCell(pts, n, [&](std::size_t c) {
      std::int32_t* link = &head_[c];
      while (*link >= 0) {
        const auto e = static_cast<std::size_t>(*link);
        if (!alive[static_cast<std::size_t>(item_[e])]) {
          *link = next_[e];
          continue;
        }
        if (visit_item(item_[e])) return true;
        link = &next_[e];
      }
      return false;
    });
  }

 private:
  template <typename F>
  bool forEachCell(const Vec2* pts, int n, F&& f) const {
    double y_lo = kInf, y_hi = -kInf;
    for (int i = 0; i < n; ++i) {
      y_lo = std::min(y_lo, pts[i].y());
      y_hi = std::max(y_hi, pts[i].y());
    }
    const double pad = 1e-9 + 1e-12 * (std::abs(origin_.x()) + std::abs(origin_.y()) + cell_ * (cols_ + rows_));
    const int r0 = clampRow(std::floor((y_lo - pad - origin_.y()) / cell_));
    const int r1 = clampRow(std::floor((y_hi + pad - origin_.y()) / cell_));
    for (int r = r0; r <= r1; ++r) {
      // The shape's x-range within this row's slab: its edges clipped to the slab.
      const double s0 = std::max(y_lo, origin_.y() + r * cell_ - pad);
      const double s1 = std::min(y_hi, origin_.y() + (r + 1) * cell_ + pad);
      double x_lo = kInf, x_hi = -kInf;
      for (int i = 0; i < n; ++i) {
        const Vec2& a = pts[i];
        const Vec2& b = pts[(i + 1) % n];
        const double ya = std::min(a.y(), b.y()), yb = std::max(a.y(), b.y());
        if (yb < s0 || ya > s1) continue;
        if (yb == ya) {
          x_lo = std::min({x_lo, a.x(), b.x()});
          x_hi = std::max({x_hi, a.x(), b.x()});
          continue;
        }
        for (const double y : {std::clamp(s0, ya, yb), std::clamp(s1, ya, yb)}) {
          const double x = a.x() + (b.x() - a.x()) * ((y - a.y()) / (b.y() - a.y()));
          x_lo = std::min(x_lo, x);
          x_hi = std::max(x_hi, x);
        }
      }
      if (!(x_lo <= x_hi)) continue;
      const int c0 = clampCol(std::floor((x_lo - pad - origin_.x()) / cell_));
      const int c1 = clampCol(std::floor((x_hi + pad - origin_.x()) / cell_));
      for (int c = c0; c <= c1; ++c) {
        if (f(static_cast<std::size_t>(r) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(c))) return true;
      }
    }
    return false;
  }
  int clampRow(double r) const { return static_cast<int>(std::clamp(r, 0.0, static_cast<double>(rows_ - 1))); }
  int clampCol(double c) const { return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(cols_ - 1))); }

  Vec2 origin_;
  double cell_;
  int cols_ = 1;
  int rows_ = 1;
  std::vector<std::int32_t> head_;
  std::vector<std::int32_t> next_;
  std::vector<std::int32_t> item_;
};

// A binary min-heap of slots (a step at a vertex: 2 v + kind) by cost, ties by slot, that
// keeps each slot once and updates its cost in place: the local steps re-cost a few slots
// after every step, and a heap of stale copies outgrew the outline (and the cache) tenfold.
class SlotHeap {
 public:
  explicit SlotHeap(std::size_t slots) : where_(slots, -1), cost_(slots, kInf) {}
  bool empty() const { return heap_.empty(); }
  std::int32_t top() const { return heap_.front(); }
  double cost(std::int32_t slot) const { return cost_[static_cast<std::size_t>(slot)]; }
  void grow(std::size_t slots) {
    where_.resize(slots, -1);
    cost_.resize(slots, kInf);
  }
  // Sets the slot's cost; infinity takes it out.
  void set(std::int32_t slot, double cost) {
    const auto s = static_cast<std::size_t>(slot);
    const std::int32_t at = where_[s];
    if (!(cost < kInf)) {
      if (at >= 0) removeAt(static_cast<std::size_t>(at));
      return;
    }
    cost_[s] = cost;
    if (at < 0) {
      heap_.push_back(slot);
      where_[s] = static_cast<std::int32_t>(heap_.size() - 1);
      up(heap_.size() - 1);
    } else {
      up(static_cast<std::size_t>(at));
      down(static_cast<std::size_t>(where_[s]));
    }
  }

 private:
  bool less(std::int32_t a, std::int32_t b) const {
    const double ca = cost_[static_cast<std::size_t>(a)], cb = cost_[static_cast<std::size_t>(b)];
    return ca < cb || (ca == cb && a < b);
  }
  void place(std::size_t i, std::int32_t slot) {
    heap_[i] = slot;
    where_[static_cast<std::size_t>(slot)] = static_cast<std::int32_t>(i);
  }
  void up(std::size_t i) {
    const std::int32_t slot = heap_[i];
    while (i > 0 && less(slot, heap_[(i - 1) / 2])) {
      place(i, heap_[(i - 1) / 2]);
      i = (i - 1) / 2;
    }
    place(i, slot);
  }
  void down(std::size_t i) {
    const std::int32_t slot = heap_[i];
    for (;;) {
      std::size_t c = 2 * i + 1;
      if (c >= heap_.size()) break;
      if (c + 1 < heap_.size() && less(heap_[c + 1], heap_[c])) ++c;
      if (!less(heap_[c], slot)) break;
      place(i, heap_[c]);
      i = c;
    }
    place(i, slot);
  }
  void removeAt(std::size_t i) {
    const std::int32_t slot = heap_[i];
    where_[static_cast<std::size_t>(slot)] = -1;
    cost_[static_cast<std::size_t>(slot)] = kInf;
    const std::int32_t last = heap_.back();
    heap_.pop_back();
    if (i == heap_.size()) return;
    place(i, last);
    up(i);
    down(static_cast<std::size_t>(where_[static_cast<std::size_t>(last)]));
  }

  std::vector<std::int32_t> heap_;
  std::vector<std::int32_t> where_;
  std::vector<double> cost_;
};

// The corner where the lines of edges (a0 -> a1) and (c0 -> c1) meet ahead of a1 and behind
// c0 (the turn between them under a half turn), moved out until both lines have it strictly
// outside (exact tests: the rounded corner may lie a hair inside one of them, which would
// cut a sliver off P). The move is added to `moved`. False when there is no such corner.
bool cornerAhead(const Vec2& a0, const Vec2& a1, const Vec2& c0, const Vec2& c1, Vec2& x, double& moved) {
  const Vec2 e1 = a1 - a0, e3 = c1 - c0;
  const double turn = cross(e1, e3);
  if (!(turn > 0.0)) return false;
  const double t = cross(c0 - a1, e3) / turn;
  if (!(t >= 0.0) || !std::isfinite(t)) return false;
  const Vec2 exact = a1 + t * e1;
  const Vec2 out = Vec2(e1.y(), -e1.x()).normalized() + Vec2(e3.y(), -e3.x()).normalized();
  double step = 1e-12 * (1.0 + maxAbsCoordinate(exact));
  x = exact;
  for (int i = 0; orientSign(a0, a1, x) >= 0 || orientSign(c0, c1, x) >= 0; ++i, step *= 2.0) {
    if (i == 40) return false;
    x = exact + step * out;
  }
  moved = (x - exact).norm();
  return true;
}

// The working outline: a cyclic doubly linked list; eps[i] bounds the edge i -> next[i].
class Outline {
 public:
  Outline(std::vector<Vec2> points, double tolerance) : pos_(std::move(points)), tol_(tolerance) {
    const std::size_t n = pos_.size();
    prev_.resize(n);
    next_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      prev_[i] = static_cast<std::int32_t>((i + n - 1) % n);
      next_[i] = static_cast<std::int32_t>((i + 1) % n);
    }
    eps_.assign(n, 0.0);
    alive_.assign(n, 1);
    on_p_.assign(n, 1);
    live_ = n;
  }

  void fillHullPockets();
  bool circumscribe();
  void reduce();
  Polygon result() const;

 private:
  enum Kind : std::uint8_t { kRemoveReflex = 0, kCollapseEdge = 1 };
  struct Step {
    double cost;
    std::int32_t v;
    Kind kind;
  };

  std::size_t at(std::int32_t i) const { return static_cast<std::size_t>(i); }
  const Vec2& p(std::int32_t i) const { return pos_[at(i)]; }
  // The bound after the step, or infinity when it does not apply. X: the new corner.
  double removeCost(std::int32_t v) const;
  double collapseCost(std::int32_t v, Vec2* corner) const;
  bool removeAllowed(std::int32_t v);
  bool collapseAllowed(std::int32_t v, const Vec2& corner);
  void push(std::int32_t v);
  void buildGrid();
  bool strictlyConvexAt(std::int32_t v) const;
  std::int32_t first() const {
    std::int32_t i = 0;
    while (!alive_[at(i)]) ++i;
    return i;
  }
  void pushAround(std::int32_t v);

  std::vector<Vec2> pos_;
  std::vector<std::int32_t> prev_, next_;
  std::vector<double> eps_;
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint8_t> on_p_;  // a vertex of P (not a new corner)
  std::size_t live_ = 0;
  double tol_;
  std::optional<CellLists> grid_;  // built unless the outline is strictly convex
  bool convex_ = false;
  SlotHeap heap_{0};
};

void Outline::fillHullPockets() {
  const std::vector<std::uint32_t> hull = convexHull(pos_);
  const std::size_t n = pos_.size(), k = hull.size();
  if (k < 3) return;
  // For a simple counter-clockwise polygon the hull's vertices come in the polygon's order;
  // anything else (not simple after all) skips this step.
  const auto first = static_cast<std::size_t>(std::min_element(hull.begin(), hull.end()) - hull.begin());
  for (std::size_t j = 1; j < k; ++j) {
    if (hull[(first + j) % k] <= hull[(first + j - 1) % k]) return;
  }
  for (std::size_t j = 0; j < k; ++j) {
    const std::uint32_t a = hull[(first + j) % k], b = hull[(first + j + 1) % k];
    const std::size_t count = (b + n - a - 1) % n;
    if (count == 0) continue;
    const Vec2 &pa = pos_[a], &pb = pos_[b];
    double err = 0.0;
    for (std::size_t i = (a + 1) % n; i != b; i = (i + 1) % n) err = std::max(err, distanceToLine(pos_[i], pa, pb));
    if (count == 1) err = std::min(err, 0.5 * (pb - pa).norm());
    if (err > tol_ || live_ - count < 3) continue;
    for (std::size_t i = (a + 1) % n; i != b; i = (i + 1) % n) alive_[i] = 0;
    live_ -= count;
    next_[a] = static_cast<std::int32_t>(b);
    prev_[b] = static_cast<std::int32_t>(a);
    eps_[a] = err;
  }
}

double Outline::removeCost(std::int32_t v) const {
  if (live_ <= 3) return kInf;
  const std::int32_t u = prev_[at(v)], w = next_[at(v)];
  const int turn = orientSign(p(u), p(v), p(w));
  if (turn > 0) return kInf;
  const double sides = std::max(eps_[at(u)], eps_[at(v)]);
  if (turn == 0) {
    if ((p(v) - p(u)).dot(p(w) - p(v)) <= 0.0) return kInf;  // a spike folding back: not ours to remove
    return sides;
  }
  const double chord = (p(w) - p(u)).norm();
  double bound = sides + std::min(0.5 * chord, distanceToLine(p(v), p(u), p(w)));
  // Three corners of P with an obtuse angle at v: every point of the triangle lies within
  // half the chord of one of them, whatever lies behind the sides (no error adds up).
  if (on_p_[at(u)] && on_p_[at(v)] && on_p_[at(w)] && (p(u) - p(v)).dot(p(w) - p(v)) <= 0.0) {
    bound = std::min(bound, 0.5 * chord);
  }
  return bound;
}

double Outline::collapseCost(std::int32_t v, Vec2* corner) const {
  if (live_ <= 4) return kInf;
  const std::int32_t u = prev_[at(v)], w = next_[at(v)], z = next_[at(w)];
  if (orientSign(p(u), p(v), p(w)) <= 0 || orientSign(p(v), p(w), p(z)) <= 0) return kInf;
  Vec2 x;
  double moved = 0.0;
  if (!cornerAhead(p(u), p(v), p(w), p(z), x, moved)) return kInf;
  if (corner != nullptr) *corner = x;
  const double d = eps_[at(v)] + distancePointSegment(x, p(v), p(w));
  return std::max({eps_[at(u)], eps_[at(w)], d}) + moved;
}

bool Outline::removeAllowed(std::int32_t v) {
  const std::int32_t u = prev_[at(v)], w = next_[at(v)];
  if (orientSign(p(u), p(v), p(w)) == 0) return true;  // a straight vertex: nothing is added
  const Vec2 tri[3] = {p(u), p(v), p(w)};  // clockwise: v is reflex
  return !grid_->visit(tri, 3, alive_, [&](std::int32_t a) {
    if (a == u || a == v || a == w) return false;
    return orientSign(tri[0], tri[1], p(a)) <= 0 && orientSign(tri[1], tri[2], p(a)) <= 0 &&
           orientSign(tri[2], tri[0], p(a)) <= 0;
  });
}

bool Outline::collapseAllowed(std::int32_t v, const Vec2& x) {
  const std::int32_t u = prev_[at(v)], w = next_[at(v)], z = next_[at(w)];
  // S gains the region between u -> v -> w -> z and u -> x -> z, which lies in the triangle
  // (u, x, z): no other vertex may be in it, no other edge may meet ux or xz.
  const Vec2 tri[3] = {p(u), x, p(z)};  // counter-clockwise
  return !grid_->visit(tri, 3, alive_, [&](std::int32_t a) {
    if (a == u || a == v || a == w) return false;
    const std::int32_t b = next_[at(a)];
    if (a != z && orientSign(tri[0], tri[1], p(a)) >= 0 && orientSign(tri[1], tri[2], p(a)) >= 0 &&
        orientSign(tri[2], tri[0], p(a)) >= 0) {
      return true;
    }
    // The edges into u and out of z touch the new sides at their own ends only.
    return (b != u && segmentsIntersect(p(a), p(b), tri[0], x)) || (a != z && segmentsIntersect(p(a), p(b), x, tri[2]));
  });
}

void Outline::push(std::int32_t v) {
  const bool live = alive_[at(v)] != 0;
  const double r = live ? removeCost(v) : kInf;
  heap_.set(2 * v + kRemoveReflex, r <= tol_ ? r : kInf);
  const double c = live ? collapseCost(v, nullptr) : kInf;
  heap_.set(2 * v + kCollapseEdge, c <= tol_ ? c : kInf);
}

void Outline::pushAround(std::int32_t v) {
  std::int32_t s = v;
  for (int i = 0; i < 2; ++i) s = prev_[at(s)];
  for (int i = 0; i < 5; ++i, s = next_[at(s)]) push(s);
}

void Outline::buildGrid() {
  // About four edges' lengths a cell, at most 1024 cells a side, over the box grown by the
  // tolerance (new corners lie within it of P).
  Box box{pos_[at(first())], pos_[at(first())]};
  double perimeter = 0.0;
  for (std::size_t i = 0; i < pos_.size(); ++i) {
    if (!alive_[i]) continue;
    box.min = box.min.cwiseMin(pos_[i]);
    box.max = box.max.cwiseMax(pos_[i]);
    perimeter += (pos_[at(next_[i])] - pos_[i]).norm();
  }
  box.min -= Vec2(2.0 * tol_, 2.0 * tol_);
  box.max += Vec2(2.0 * tol_, 2.0 * tol_);
  const double side = std::max(box.width(), box.height());
  const double cell = std::max({4.0 * perimeter / static_cast<double>(live_), side / 1024.0, 1e-9});
  grid_.emplace(box, cell, 4 * live_);
  for (std::size_t i = 0; i < pos_.size(); ++i) {
    if (alive_[i]) grid_->insert(pos_[i], pos_[at(next_[i])], static_cast<std::int32_t>(i));
  }
}

bool Outline::strictlyConvexAt(std::int32_t v) const { return orientSign(p(prev_[at(v)]), p(v), p(next_[at(v)])) > 0; }

bool Outline::circumscribe() {
  // A strictly convex outline in one pass: keep an edge, skip the following ones while the
  // corner where the kept edge's line meets the next candidate's stays within the
  // tolerance, keep that candidate, and so on round to the first edge. The corners' errors
  // do not add up (each is measured against the outline it replaces), and the result is the
  // intersection of the kept edges' half-planes: convex, no checks needed.
  std::vector<std::int32_t> ids;
  ids.reserve(live_);
  const std::int32_t s0 = first();
  std::int32_t i = s0;
  do {
    if (!strictlyConvexAt(i)) return false;
    ids.push_back(i);
    i = next_[at(i)];
  } while (i != s0);
  const std::size_t m = ids.size();
  auto pt = [&](std::size_t k) -> const Vec2& { return pos_[at(ids[k % m])]; };
  auto edgeEps = [&](std::size_t k) { return eps_[at(ids[k % m])]; };  // edge k: pt(k) -> pt(k + 1)
  std::vector<Vec2> corners;
  std::vector<double> corner_err;
  std::vector<std::size_t> kept;  // the kept edge before each corner
  std::vector<std::uint8_t> same;  // the corner is the old vertex (nothing skipped)
  for (std::size_t a = 0; a < m;) {
    std::size_t b = a + 1;
    Vec2 x_ok = pt(a + 1);
    double err_ok = 0.0, inner = 0.0;
    std::size_t q = a + 1;  // the old vertex nearest the corner, as far as a forward walk finds
    for (std::size_t c = a + 2; c <= m; ++c) {
      inner = std::max(inner, edgeEps(c - 1));
      Vec2 x;
      double moved = 0.0;
      if (!cornerAhead(pt(a), pt(a + 1), pt(c), pt(c + 1), x, moved)) break;
      // The region the corner adds lies between the old outline and x, all within the
      // distance from x to the old outline (the distance to a convex set is greatest at x):
      // bounded by the chord and by the old edges at the nearest vertex found.
      while (q < c && (x - pt(q + 1)).squaredNorm() <= (x - pt(q)).squaredNorm()) ++q;
      double to_old = std::min(distancePointSegment(x, pt(a + 1), pt(c)), distancePointSegment(x, pt(q), pt(q + 1)));
      if (q > a + 1) to_old = std::min(to_old, distancePointSegment(x, pt(q - 1), pt(q)));
      const double err = inner + to_old + moved;
      if (!(err <= tol_)) break;
      b = c;
      x_ok = x;
      err_ok = err;
    }
    kept.push_back(a);
    same.push_back(b == a + 1);
    corners.push_back(x_ok);
    corner_err.push_back(err_ok);
    a = b;
  }
  const std::size_t k = corners.size();
  if (k < 3 || k == m) return false;
  for (std::size_t j = 0; j < k; ++j) {
    if (orientSign(corners[(j + k - 1) % k], corners[j], corners[(j + 1) % k]) <= 0) return false;
  }
  // Corner j ends kept edge j; the edge from corner j - 1 to corner j lies on its line: on
  // the old edge or in the regions the two corners added.
  std::vector<double> eps(k);
  for (std::size_t j = 0; j < k; ++j) eps[j] = std::max({edgeEps(kept[(j + 1) % k]), corner_err[j], corner_err[(j + 1) % k]});
  std::vector<std::uint8_t> on_p(k);
  for (std::size_t j = 0; j < k; ++j) on_p[j] = same[j] && on_p_[at(ids[(kept[j] + 1) % m])];
  pos_ = std::move(corners);
  eps_ = std::move(eps);
  on_p_ = std::move(on_p);
  alive_.assign(k, 1);
  prev_.resize(k);
  next_.resize(k);
  for (std::size_t j = 0; j < k; ++j) {
    prev_[j] = static_cast<std::int32_t>((j + k - 1) % k);
    next_[j] = static_cast<std::int32_t>((j + 1) % k);
  }
  live_ = k;
  return true;
}

void Outline::reduce() {
  // A strictly convex outline (a circle, a hull after the pockets) stays one under the
  // corner step, and no other part of it can lie beyond an edge: no checks, no grid.
  convex_ = circumscribe();
  if (!convex_) {
    convex_ = true;
    for (std::size_t i = 0; i < pos_.size() && convex_; ++i) convex_ = !alive_[i] || strictlyConvexAt(static_cast<std::int32_t>(i));
  }
  if (!convex_) buildGrid();
  pos_.reserve(2 * pos_.size());
  heap_ = SlotHeap(2 * pos_.size());
  for (std::size_t i = 0; i < pos_.size(); ++i) push(static_cast<std::int32_t>(i));
  while (!heap_.empty()) {
    const std::int32_t slot = heap_.top();
    const Step s{heap_.cost(slot), slot / 2, static_cast<Kind>(slot % 2)};
    Vec2 x;
    const double cost = s.kind == kRemoveReflex ? removeCost(s.v) : collapseCost(s.v, &x);
    if (cost != s.cost) {  // every change re-costs the steps around it: only a safeguard
      heap_.set(slot, cost <= tol_ ? cost : kInf);
      continue;
    }
    const std::int32_t u = prev_[at(s.v)], w = next_[at(s.v)];
    if (s.kind == kRemoveReflex) {
      if (!grid_) buildGrid();  // (a reflex corner: the outline is not convex)
      convex_ = false;
      if (!removeAllowed(s.v)) {
        heap_.set(slot, kInf);  // until something around it changes
        continue;
      }
      alive_[at(s.v)] = 0;
      next_[at(u)] = w;
      prev_[at(w)] = u;
      eps_[at(u)] = cost;
      --live_;
      grid_->insert(p(u), p(w), u);
      push(s.v);  // out of the heap
      pushAround(u);
    } else {
      if (!convex_ && !collapseAllowed(s.v, x)) {
        heap_.set(slot, kInf);
        continue;
      }
      const std::int32_t z = next_[at(w)];
      const double d = cost;  // bounds both new edges (the corner's move included)
      const auto id = static_cast<std::int32_t>(pos_.size());
      pos_.push_back(x);
      prev_.push_back(u);
      next_.push_back(z);
      eps_.push_back(d);
      alive_.push_back(1);
      on_p_.push_back(0);
      heap_.grow(2 * pos_.size());
      alive_[at(s.v)] = 0;
      alive_[at(w)] = 0;
      next_[at(u)] = id;
      prev_[at(z)] = id;
      eps_[at(u)] = d;
      --live_;
      if (grid_) {
        grid_->insert(p(u), x, u);
        grid_->insert(x, p(z), id);
      }
      // The corner moved out by a hair can leave a straight neighbour a hair reflex.
      if (convex_ && !(strictlyConvexAt(u) && strictlyConvexAt(id) && strictlyConvexAt(z))) {
        convex_ = false;
        buildGrid();
      }
      push(s.v);
      push(w);
      pushAround(id);
    }
  }
  grid_.reset();
}

Polygon Outline::result() const {
  Polygon out;
  out.reserve(live_);
  const std::int32_t start = first();
  std::int32_t i = start;
  do {
    out.push_back(p(i));
    i = next_[at(i)];
  } while (i != start);
  return out;
}

}  // namespace

Polygon simplifyOutward(PolygonView poly, double tolerance) {
  Polygon points(poly.begin(), poly.end());
  // Every step below relies on the outline being simple (pockets, empty triangles).
  if (points.size() < 4 || !(tolerance > 0.0) || findSelfIntersection(points)) return points;
  if (!isCounterClockwise(points)) std::reverse(points.begin(), points.end());
  Outline outline(std::move(points), tolerance);
  outline.fillHullPockets();
  outline.reduce();
  return outline.result();
}

Polygon simplifyIfBig(PolygonView poly) {
  if (!isBigPolygon(poly)) return Polygon(poly.begin(), poly.end());
  return simplifyOutward(poly, kSimplifyTolerance_m);
}

}  // namespace staa
