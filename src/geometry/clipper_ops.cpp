#include "geometry/clipper_ops.hpp"

#include "geometry/clipper_convert.hpp"
#include "geometry/polygon.hpp"
#include "geometry/simplify.hpp"

#include <clipper.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {

namespace {

namespace cl = ClipperLib;

using clipper_convert::kScale;
using clipper_convert::toPath;
using clipper_convert::toPolygon;

cl::Paths toPaths(const std::vector<Polygon>& polygons) {
  cl::Paths paths;
  paths.reserve(polygons.size());
  for (const Polygon& p : polygons) {
    if (p.size() >= 3) paths.push_back(toPath(p));
  }
  return paths;
}

void collect(const cl::PolyNode& node, std::vector<PolygonWithHoles>& out) {
  for (const cl::PolyNode* child : node.Childs) {
    // Children of the root (and of holes) are outer boundaries; their children are holes.
    PolygonWithHoles region;
    region.outer = toPolygon(child->Contour);
    if (!isCounterClockwise(region.outer)) std::reverse(region.outer.begin(), region.outer.end());
    for (const cl::PolyNode* hole : child->Childs) {
      Polygon h = toPolygon(hole->Contour);
      if (isCounterClockwise(h)) std::reverse(h.begin(), h.end());
      region.holes.push_back(std::move(h));
      collect(*hole, out);  // islands inside the hole
    }
    out.push_back(std::move(region));
  }
}

std::vector<PolygonWithHoles> solve(cl::Clipper& clipper, cl::ClipType type, cl::PolyFillType fill) {
  cl::PolyTree tree;
  clipper.StrictlySimple(true);
  clipper.Execute(type, tree, fill, fill);
  std::vector<PolygonWithHoles> out;
  collect(tree, out);
  return out;
}

void addRegion(const PolygonWithHoles& r, cl::Clipper& clipper) {
  clipper.AddPath(toPath(r.outer), cl::ptSubject, true);
  for (const Polygon& h : r.holes) clipper.AddPath(toPath(h), cl::ptSubject, true);
}

void splitRegion(const PolygonWithHoles& region, double overlap, std::vector<Polygon>& out, int depth) {
  if (region.holes.empty() || depth > 64) {
    out.push_back(region.outer);
    return;
  }
  // Cut through the middle of the first hole's extent: the vertical line crosses that hole,
  // so neither half keeps it closed. Cutting never creates holes, so this terminates.
  const Box hb = boundingBox(region.holes.front());
  const double c = 0.5 * (hb.min.x() + hb.max.x());
  const double e = std::min(overlap, 0.25 * hb.width());
  const Box rb = boundingBox(region.outer);
  const double y0 = rb.min.y() - 1.0, y1 = rb.max.y() + 1.0;
  const Polygon left{{rb.min.x() - 1.0, y0}, {c + e, y0}, {c + e, y1}, {rb.min.x() - 1.0, y1}};
  const Polygon right{{c - e, y0}, {rb.max.x() + 1.0, y0}, {rb.max.x() + 1.0, y1}, {c - e, y1}};
  for (const Polygon* half : {&left, &right}) {
    cl::Clipper clipper;
    addRegion(region, clipper);
    clipper.AddPath(toPath(*half), cl::ptClip, true);
    for (const PolygonWithHoles& piece : solve(clipper, cl::ctIntersection, cl::pftEvenOdd)) {
      splitRegion(piece, overlap, out, depth + 1);
    }
  }
}

}  // namespace

std::vector<PolygonWithHoles> unitePolygons(const std::vector<Polygon>& polygons) {
  cl::Clipper clipper;
  cl::Paths paths = toPaths(polygons);
  // Nonzero fill needs a consistent winding: orient every input counter-clockwise.
  for (cl::Path& p : paths) {
    if (!cl::Orientation(p)) cl::ReversePath(p);
  }
  clipper.AddPaths(paths, cl::ptSubject, true);
  return solve(clipper, cl::ctUnion, cl::pftNonZero);
}

double unionArea(const std::vector<Polygon>& polygons) {
  // Groups of polygons linked by overlapping boxes (closed boxes: touching counts), by a sweep
  // over x with union-find.
  std::vector<std::size_t> order, parent(polygons.size());
  std::vector<Box> boxes(polygons.size());
  for (std::size_t i = 0; i < polygons.size(); ++i) {
    parent[i] = i;
    if (polygons[i].size() < 3) continue;
    boxes[i] = boundingBox(polygons[i]);
    order.push_back(i);
  }
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return boxes[a].min.x() < boxes[b].min.x() || (boxes[a].min.x() == boxes[b].min.x() && a < b);
  });
  std::vector<std::size_t> active;
  for (const std::size_t i : order) {
    std::erase_if(active, [&](std::size_t j) { return boxes[j].max.x() < boxes[i].min.x(); });
    for (const std::size_t j : active) {
      if (boxes[j].min.y() <= boxes[i].max.y() && boxes[i].min.y() <= boxes[j].max.y()) parent[find(i)] = find(j);
    }
    active.push_back(i);
  }
  std::vector<std::vector<Polygon>> groups(polygons.size());
  for (const std::size_t i : order) groups[find(i)].push_back(polygons[i]);
  double area = 0.0;
  for (const std::vector<Polygon>& group : groups) {
    if (group.size() == 1) {
      area += std::abs(signedArea(group.front()));
      continue;
    }
    for (const PolygonWithHoles& region : unitePolygons(group)) {
      area += std::abs(signedArea(region.outer));
      for (const Polygon& hole : region.holes) area -= std::abs(signedArea(hole));
    }
  }
  return area;
}

std::vector<PolygonWithHoles> inflatePolygons(const std::vector<Polygon>& polygons, double radius,
                                              double arc_tolerance) {
  cl::Paths paths;
  paths.reserve(polygons.size());
  for (const Polygon& p : polygons) {
    // A big polygon is simplified outwards first (geometry/simplify.hpp): Clipper's offset
    // and the path search grow faster than linearly in its vertices. (Not before shrinking:
    // outwards is not the safe side there.) Only a big one is copied: a normal map's
    // polygons allocate as before.
    if (p.size() < 3) continue;
    paths.push_back(radius >= 0.0 && isBigPolygon(p) ? toPath(simplifyIfBig(p)) : toPath(p));
  }
  for (cl::Path& p : paths) {
    if (!cl::Orientation(p)) cl::ReversePath(p);
  }
  // Union first so that overlapping inputs do not offset into each other's interior.
  cl::Paths united;
  {
    cl::Clipper clipper;
    clipper.AddPaths(paths, cl::ptSubject, true);
    clipper.Execute(cl::ctUnion, united, cl::pftNonZero, cl::pftNonZero);
  }
  cl::ClipperOffset offset(2.0, std::max(arc_tolerance, 1e-6) * kScale);
  offset.AddPaths(united, cl::jtRound, cl::etClosedPolygon);
  cl::Paths grown;
  offset.Execute(grown, radius * kScale);
  cl::Clipper clipper;
  clipper.AddPaths(grown, cl::ptSubject, true);
  return solve(clipper, cl::ctUnion, cl::pftNonZero);
}

std::vector<Polygon> removeHoles(const std::vector<PolygonWithHoles>& regions, double overlap) {
  std::vector<Polygon> out;
  for (const PolygonWithHoles& r : regions) splitRegion(r, overlap, out, 0);
  return out;
}

std::vector<Polygon> inflateToSimple(const std::vector<Polygon>& polygons, double radius, double arc_tolerance) {
  return removeHoles(inflatePolygons(polygons, radius, arc_tolerance));
}

std::vector<Polygon> inflateEachToSimple(const std::vector<Polygon>& polygons, double radius, double arc_tolerance) {
  std::vector<Polygon> out;
  out.reserve(polygons.size());
  std::vector<Polygon> one(1);
  for (const Polygon& p : polygons) {
    one[0] = p;
    for (Polygon& piece : removeHoles(inflatePolygons(one, radius, arc_tolerance))) out.push_back(std::move(piece));
  }
  return out;
}

}  // namespace staa
