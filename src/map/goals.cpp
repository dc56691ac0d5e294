#include "map/goals.hpp"

#include "geometry/clipper_convert.hpp"
#include "geometry/clipper_ops.hpp"
#include "geometry/polygon.hpp"
#include "geometry/splitmix64.hpp"
#include "io/yaml_support.hpp"

#include <clipper.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace staa {
namespace {

namespace cl = ClipperLib;

// The obstacles are grown by the clearance plus this, with round corners whose chords stay
// within it of the true arc: the grown shapes then contain every point closer than the
// clearance, and the free space Clipper returns keeps at least the clearance.
constexpr double kArcTolerance_m = 0.01;
// Beyond this many lattice points (a 500 x 500 m map at 0.25 m) the lattice coarsens.
constexpr double kMaxLatticePoints = 4e6;

using yaml_support::formatNumber;
// Both built by appending: GCC 12 warns falsely (-Wrestrict) on "'" + s + "'" and the like.
std::string mapLabel(const PolygonMap& map) {
  if (map.name.empty()) return "map (unnamed)";
  std::string s = "map '";
  s.append(map.name);
  s.push_back('\'');
  return s;
}

std::string boxText(const Box& b) {
  std::string s = "[";
  for (const double v : {b.min.x(), b.min.y(), b.max.x(), b.max.y()}) {
    if (s.size() > 1) s.append(", ");
    s.append(formatNumber(v));
  }
  s.push_back(']');
  return s;
}

using clipper_convert::toPath;
using clipper_convert::toPolygon;

// One connected part of the free space: an outer ring and its holes (filled even-odd).
struct Component {
  std::vector<Polygon> rings;
  Box box;
};

void collectComponents(const cl::PolyNode& node, std::vector<Component>& out) {
  for (const cl::PolyNode* child : node.Childs) {
    // Children of the root (and of holes) are outer boundaries, their children holes.
    Component c;
    c.rings.push_back(toPolygon(child->Contour));
    for (const cl::PolyNode* hole : child->Childs) {
      c.rings.push_back(toPolygon(hole->Contour));
      collectComponents(*hole, out);  // islands of free space inside an obstacle's hole
    }
    if (c.rings.front().size() < 3) continue;
    c.box = boundingBox(c.rings.front());
    out.push_back(std::move(c));
  }
}

// The free space at `clearance` inside `region`: the region minus the obstacles grown by the
// clearance. Exact connectivity, independent of the lattice: a 1.35 m door is open at 0.6 m
// clearance wherever the lattice points fall.
std::vector<Component> freeComponents(const PolygonMap& map, const Box& region, double clearance) {
  cl::Clipper clipper;
  const Polygon box{region.min, {region.max.x(), region.min.y()}, region.max, {region.min.x(), region.max.y()}};
  clipper.AddPath(toPath(box), cl::ptSubject, true);
  if (!map.obstacles.empty()) {
    const double grow = clearance > 0.0 ? clearance + kArcTolerance_m : 0.0;
    // Outer rings counter-clockwise, holes clockwise: nonzero fill leaves the holes free.
    for (const PolygonWithHoles& r : inflatePolygons(map.obstacles, grow, kArcTolerance_m)) {
      clipper.AddPath(toPath(r.outer), cl::ptClip, true);
      for (const Polygon& h : r.holes) clipper.AddPath(toPath(h), cl::ptClip, true);
    }
  }
  cl::PolyTree tree;
  clipper.Execute(cl::ctDifference, tree, cl::pftNonZero, cl::pftNonZero);
  std::vector<Component> out;
  collectComponents(tree, out);
  return out;
}

// The exact test behind the Clipper region (which agrees up to its micrometre rounding).
class ClearanceCheck {
 public:
  ClearanceCheck(const PolygonMap& map, double clearance) : map_(map), clearance_(clearance) {
    boxes_.reserve(map.obstacles.size());
    for (const Polygon& poly : map.obstacles) {
      Box b = boundingBox(poly);
      b.min -= Vec2{clearance, clearance};
      b.max += Vec2{clearance, clearance};
      boxes_.push_back(b);
    }
  }

  bool ok(const Vec2& p) const {
    if (map_.bounds) {
      const Box& b = *map_.bounds;
      if (std::min({p.x() - b.min.x(), b.max.x() - p.x(), p.y() - b.min.y(), b.max.y() - p.y()}) < clearance_) {
        return false;
      }
    }
    for (std::size_t i = 0; i < boxes_.size(); ++i) {
      if (!boxes_[i].contains(p)) continue;
      const Polygon& poly = map_.obstacles[i];
      if (locatePoint(p, poly) != Containment::kOutside) return false;
      if (distanceToEdges(p, poly) < clearance_) return false;
    }
    return true;
  }

 private:
  const PolygonMap& map_;
  double clearance_;
  std::vector<Box> boxes_;
};

void validate(const GoalPlacement& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("placeGoals: " + what); };
  if (o.count < 1) fail("count must be >= 1, got " + std::to_string(o.count));
  if (!std::isfinite(o.clearance_m) || o.clearance_m < 0.0) {
    fail("clearance_m must be a finite number >= 0, got " + formatNumber(o.clearance_m));
  }
  if (!std::isfinite(o.min_spacing_m) || o.min_spacing_m <= 0.0) {
    fail("min_spacing_m must be a finite number > 0, got " + formatNumber(o.min_spacing_m));
  }
  if (!std::isfinite(o.lattice_m) || o.lattice_m <= 0.0) {
    fail("lattice_m must be a finite number > 0, got " + formatNumber(o.lattice_m));
  }
}

}  // namespace

std::vector<Vec2> placeGoals(const PolygonMap& map, const GoalPlacement& options) {
  validate(options);
  const double clearance = options.clearance_m;

  // The area the goals lie in and the region whose free space decides connectivity. Without
  // bounds the region reaches beyond the obstacles' box, so that two places joined around
  // the outside of the obstacles count as connected.
  Box area;
  Box region;
  std::string where;
  if (map.bounds) {
    area = *map.bounds;
    region = Box{area.min + Vec2{clearance, clearance}, area.max - Vec2{clearance, clearance}};
    where = "inside the bounds " + boxText(area);
  } else if (!map.obstacles.empty()) {
    area = boundingBox(map.obstacles.front());
    for (const Polygon& poly : map.obstacles) {
      const Box b = boundingBox(poly);
      area.min = area.min.cwiseMin(b.min);
      area.max = area.max.cwiseMax(b.max);
    }
    const double margin = clearance + 2.0 * options.lattice_m;
    region = Box{area.min - Vec2{margin, margin}, area.max + Vec2{margin, margin}};
    where = "inside the obstacles' extent " + boxText(area) + " (the map has no bounds)";
  } else {
    throw MapError(mapLabel(map) + ": no place for goals: the map has neither bounds nor obstacles, so no area "
                   "to place them in");
  }

  const std::string none = mapLabel(map) + ": no free place for goals: no point of a " +
                           formatNumber(options.lattice_m) + " m lattice " + where + " has " +
                           formatNumber(clearance) + " m clearance from every obstacle" +
                           (map.bounds ? " and the bounds" : "");
  if (!(region.min.x() < region.max.x()) || !(region.min.y() < region.max.y())) throw MapError(none);

  // Lattice points are integer multiples of the step: round coordinates in the written map,
  // and the same points on every platform.
  double step = options.lattice_m;
  const double points = (area.width() / step + 1.0) * (area.height() / step + 1.0);
  if (points > kMaxLatticePoints) step *= std::sqrt(points / kMaxLatticePoints);
  const auto kx0 = static_cast<long long>(std::ceil(area.min.x() / step));
  const auto kx1 = static_cast<long long>(std::floor(area.max.x() / step));
  const auto ky0 = static_cast<long long>(std::ceil(area.min.y() / step));
  const auto ky1 = static_cast<long long>(std::floor(area.max.y() / step));
  if (kx1 < kx0 || ky1 < ky0) throw MapError(none);
  const auto nx = static_cast<std::size_t>(kx1 - kx0 + 1);
  const auto ny = static_cast<std::size_t>(ky1 - ky0 + 1);
  auto xAt = [&](std::size_t i) { return static_cast<double>(kx0 + static_cast<long long>(i)) * step; };
  auto yAt = [&](std::size_t j) { return static_cast<double>(ky0 + static_cast<long long>(j)) * step; };

  // Which component each lattice point lies strictly inside: per component and lattice row,
  // the crossings of its rings with the row, filled even-odd.
  const std::vector<Component> components = freeComponents(map, region, clearance);
  std::vector<int> label(nx * ny, -1);
  std::vector<double> crossings;
  for (std::size_t c = 0; c < components.size(); ++c) {
    const Component& comp = components[c];
    const auto j0 = static_cast<long long>(std::ceil(comp.box.min.y() / step)) - ky0;
    const auto j1 = static_cast<long long>(std::floor(comp.box.max.y() / step)) - ky0;
    for (long long jj = std::max(j0, 0LL); jj <= std::min(j1, static_cast<long long>(ny) - 1); ++jj) {
      const auto j = static_cast<std::size_t>(jj);
      const double y = yAt(j);
      crossings.clear();
      for (const Polygon& ring : comp.rings) {
        for (std::size_t k = 0; k < ring.size(); ++k) {
          const Vec2& a = ring[k];
          const Vec2& b = ring[(k + 1) % ring.size()];
          if ((a.y() <= y) == (b.y() <= y)) continue;  // half-open: a vertex on the row counts once
          crossings.push_back(a.x() + (y - a.y()) / (b.y() - a.y()) * (b.x() - a.x()));
        }
      }
      std::sort(crossings.begin(), crossings.end());
      for (std::size_t m = 0; m + 1 < crossings.size(); m += 2) {
        const auto i0 = std::max(static_cast<long long>(std::floor(crossings[m] / step)) + 1 - kx0, 0LL);
        const auto i1 = std::min(static_cast<long long>(std::ceil(crossings[m + 1] / step)) - 1 - kx0,
                                 static_cast<long long>(nx) - 1);
        for (long long i = i0; i <= i1; ++i) label[j * nx + static_cast<std::size_t>(i)] = static_cast<int>(c);
      }
    }
  }

  // Keep the candidates that pass the exact test; the component with the most is the largest
  // connected region.
  const ClearanceCheck check(map, clearance);
  std::vector<std::size_t> per_component(components.size(), 0);
  for (std::size_t k = 0; k < label.size(); ++k) {
    if (label[k] < 0) continue;
    if (!check.ok({xAt(k % nx), yAt(k / nx)})) {
      label[k] = -1;
      continue;
    }
    ++per_component[static_cast<std::size_t>(label[k])];
  }
  const auto largest = std::max_element(per_component.begin(), per_component.end());
  if (largest == per_component.end() || *largest == 0) throw MapError(none);
  const int keep = static_cast<int>(largest - per_component.begin());
  std::vector<Vec2> candidates;
  candidates.reserve(*largest);
  for (std::size_t k = 0; k < label.size(); ++k) {
    if (label[k] == keep) candidates.emplace_back(xAt(k % nx), yAt(k / nx));
  }

  // Farthest-point sampling: each goal is the candidate farthest from those chosen (the
  // first of equals in lattice order), which spreads them evenly over the region.
  SplitMix64 rng(options.seed);
  std::vector<Vec2> goals;
  std::vector<double> nearest_sq(candidates.size(), std::numeric_limits<double>::infinity());
  std::size_t pick = static_cast<std::size_t>(rng.next() % candidates.size());
  const double spacing_sq = options.min_spacing_m * options.min_spacing_m;
  while (true) {
    const Vec2 g = candidates[pick];
    goals.push_back(g);
    if (goals.size() >= static_cast<std::size_t>(options.count)) break;
    double best = -1.0;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      nearest_sq[k] = std::min(nearest_sq[k], (candidates[k] - g).squaredNorm());
      if (nearest_sq[k] > best) {
        best = nearest_sq[k];
        pick = k;
      }
    }
    if (best < spacing_sq) break;
  }
  return goals;
}

}  // namespace staa
