#include "local/local_map.hpp"

#include "geometry/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace staa {
namespace {

// Tolerance in cell units for the conservative raster: a polygon that reaches a cell's
// boundary to within this marks the cell (rounding must never drop a touched cell).
constexpr double kRasterEps = 1e-7;
// Tolerance for "on the box boundary", in metres times the edge length (cross products).
constexpr double kBoxEps = 1e-9;

// Rounding to int for grid indices; the argument is clamped first so that geometry far
// outside the box (or a non-finite value) cannot overflow the conversion.
constexpr double kIndexLimit = 1e8;
double clampIndex(double v) { return v >= -kIndexLimit ? std::min(v, kIndexLimit) : -kIndexLimit; }  // NaN -> low
int floorToInt(double v) { return static_cast<int>(std::floor(clampIndex(v))); }
int ceilToInt(double v) { return static_cast<int>(std::ceil(clampIndex(v))); }

// Inside or on the convex counter-clockwise quadrilateral.
bool insideConvex(std::span<const Vec2, 4> box, const Vec2& p) {
  for (std::size_t e = 0; e < 4; ++e) {
    const Vec2& a = box[e];
    const Vec2& b = box[(e + 1) % 4];
    if (cross(b - a, p - a) < -kBoxEps * (b - a).norm()) return false;
  }
  return true;
}

// Cyrus-Beck: the parameter range [t0, t1] of a + t (b - a), t in [0, 1], inside the convex
// counter-clockwise quadrilateral; false when the segment misses it.
bool clipToConvex(std::span<const Vec2, 4> box, const Vec2& a, const Vec2& b, double& t0, double& t1) {
  t0 = 0.0;
  t1 = 1.0;
  const Vec2 d = b - a;
  for (std::size_t e = 0; e < 4; ++e) {
    const Vec2& p = box[e];
    const Vec2 edge = box[(e + 1) % 4] - p;
    // Inside this edge's half-plane where f(t) = num + t den >= 0.
    const double num = cross(edge, a - p);
    const double den = cross(edge, d);
    if (den == 0.0) {
      if (num < 0.0) return false;
      continue;
    }
    const double t = -num / den;
    if (den > 0.0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  return true;
}

double headingOf(const Vec2& a, const Vec2& b) { return std::atan2(b.y() - a.y(), b.x() - a.x()); }

}  // namespace

// ---- G~ (paper, Sec. III-C; issue 16) ----

std::size_t pathPiecesInBox(std::span<const Vec2, 4> box_ccw, std::span<const Vec2> path, std::span<PathPiece> out) {
  const std::size_t n = path.size();
  if (n == 0 || out.empty()) return 0;
  std::size_t count = 0;
  PathPiece piece;
  // The first piece starts at the path's start, or, should that lie outside the box (a stale
  // path), where the path first enters the box.
  auto enterFrom = [&](std::size_t s0, PathPiece& p) {
    for (std::size_t s = s0; s + 1 < n; ++s) {
      double t0 = 0.0, t1 = 1.0;
      if (clipToConvex(box_ccw, path[s], path[s + 1], t0, t1)) {
        p.first = s;
        p.in = path[s] + t0 * (path[s + 1] - path[s]);
        return true;
      }
    }
    return false;
  };
  if (insideConvex(box_ccw, path[0])) {
    piece.first = 0;
    piece.in = path[0];
  } else if (!enterFrom(0, piece)) {
    return 0;
  }
  std::size_t s = piece.first;
  while (s + 1 < n) {
    const Vec2 a = s == piece.first ? piece.in : path[s];
    const Vec2& b = path[s + 1];
    if (insideConvex(box_ccw, b)) {  // both ends inside: the convex box holds the segment
      ++s;
      continue;
    }
    double t0 = 0.0, t1 = 0.0;
    const double t = clipToConvex(box_ccw, a, b, t0, t1) ? t1 : 0.0;
    piece.out = a + t * (b - a);
    piece.heading = headingOf(a, b);
    piece.last = s;
    piece.ends_path = false;
    out[count++] = piece;
    // The next piece: where the path enters the box again (a segment meets a convex box in one
    // interval, so not on this one).
    if (count == out.size() || !enterFrom(s + 1, piece)) return count;
    s = piece.first;
  }
  piece.out = path[n - 1];
  piece.last = n >= 2 ? n - 2 : 0;
  piece.ends_path = true;
  out[count++] = piece;
  return count;
}

IntermediateGoal intermediateGoalOf(std::span<const PathPiece> pieces, std::span<const bool> reached,
                                    std::span<const Vec2> path, double goal_theta) {
  IntermediateGoal g;
  if (path.empty()) {
    g.pose.theta = goal_theta;
    g.is_final = true;
    return g;
  }
  const std::size_t n = path.size();
  if (pieces.empty()) {
    // The path never touches the box: aim at its start (the caller should replan).
    g.pose = {path[0].x(), path[0].y(), n > 1 ? headingOf(path[0], path[1]) : goal_theta};
    g.is_final = n == 1;
    return g;
  }
  std::size_t k = pieces.size() - 1;
  while (k > 0 && !(k < reached.size() && reached[k])) --k;
  const PathPiece& p = pieces[k];
  if (p.ends_path) {
    g.pose = {p.out.x(), p.out.y(), goal_theta};
    g.is_final = true;
  } else {
    g.pose = {p.out.x(), p.out.y(), p.heading};
  }
  g.segment = p.last;
  return g;
}

IntermediateGoal findIntermediateGoal(std::span<const Vec2, 4> box_ccw, std::span<const Vec2> path, double goal_theta) {
  std::array<PathPiece, 64> pieces{};
  std::array<bool, 64> reached{};
  reached.fill(true);
  const std::size_t count = pathPiecesInBox(box_ccw, path, pieces);
  return intermediateGoalOf(std::span<const PathPiece>(pieces.data(), count), reached, path, goal_theta);
}

// ---- construction ----

GridSize boxGridSize(const LocalMapConfig& config, double cell_m) {
  GridSize g;
  g.width = std::max(1, ceilToInt((config.ahead_m + config.behind_m) / cell_m - 1e-9));
  g.height = std::max(1, ceilToInt(2.0 * config.side_m / cell_m - 1e-9));
  return g;
}

LocalMap::LocalMap(const LocalMapConfig& config) : config_(config) {
  const GridSize size = gridSize(config_);
  width_ = size.width;
  height_ = size.height;
  const std::size_t cells = size.cells();

  const double dilate_cells = std::max(0.0, config_.dilate_m / config_.cell_m);
  dilate_cells_ = floorToInt(dilate_cells + 1e-9);
  dilate_r2_ = dilate_cells * dilate_cells + 1e-9;

  const double sigma = config_.blur_sigma_m / config_.cell_m;
  if (sigma > 0.0) {
    blur_radius_ = std::max(1, ceilToInt(3.0 * sigma));
    kernel_.resize(static_cast<std::size_t>(blur_radius_) + 1);
    double sum = 0.0;
    for (int k = 0; k <= blur_radius_; ++k) {
      const double w = std::exp(-0.5 * k * k / (sigma * sigma));
      kernel_[static_cast<std::size_t>(k)] = static_cast<float>(w);
      sum += k == 0 ? w : 2.0 * w;
    }
    for (float& w : kernel_) w = static_cast<float>(w / sum);
  }

  const std::size_t padded_rows = static_cast<std::size_t>(height_ + 2 * blur_radius_);
  grid_.assign(cells, 0);
  costmap_.assign(cells, 0.0f);
  winding_.assign(cells, 0);
  row_winding_.assign(static_cast<std::size_t>(height_), 0);
  span_lo_.assign(static_cast<std::size_t>(height_), 0.0);
  span_hi_.assign(static_cast<std::size_t>(height_), 0.0);
  dilated8_.assign(cells, 0);
  scratch_.assign(padded_rows * static_cast<std::size_t>(width_), 0.0f);
  // K(x) = sum of the kernel over [-r, x], tabulated for x in [-width - r - 1, width + r] so
  // that every offset a run can ask for is in the table (0 left of -r, the full sum right of r).
  const int r = blur_radius_;
  cumulative_.assign(static_cast<std::size_t>(2 * (width_ + r + 1)), 0.0f);
  if (r > 0) {
    double acc = 0.0;
    for (int x = -(width_ + r + 1); x <= width_ + r; ++x) {
      if (std::abs(x) <= r) acc += kernel_[static_cast<std::size_t>(std::abs(x))];
      cumulative_[static_cast<std::size_t>(x + width_ + r + 1)] = static_cast<float>(acc);
    }
  }
  row_any_.assign(padded_rows, 0);
  reach_blocked_.assign(cells, 0);
  reach_seen_.assign(cells, 0);
  reach_queue_.assign(cells, 0);
  update(Pose2{}, PolygonSet{}, {}, 0.0);
  real_ = nullptr;  // that set was a temporary
}

// ---- the cycle's step ----

void LocalMap::update(const Pose2& robot, const PolygonSet& real, std::span<const Vec2> global_path,
                      double goal_theta, double clearance_m) {
  robot_ = robot;
  real_ = &real;
  exact_static_ = false;
  cos_ = std::cos(robot.theta);
  sin_ = std::sin(robot.theta);
  frame_ = frameAt(config_.cell_m);

  const auto toWorld = [&](double lx, double ly) {
    return Vec2{robot.x + cos_ * lx - sin_ * ly, robot.y + sin_ * lx + cos_ * ly};
  };
  box_world_[0] = toWorld(-config_.behind_m, -config_.side_m);
  box_world_[1] = toWorld(config_.ahead_m, -config_.side_m);
  box_world_[2] = toWorld(config_.ahead_m, config_.side_m);
  box_world_[3] = toWorld(-config_.behind_m, config_.side_m);
  Box aabb{box_world_[0], box_world_[0]};
  for (const Vec2& c : box_world_) {
    aabb.min = aabb.min.cwiseMin(c);
    aabb.max = aabb.max.cwiseMax(c);
  }

  drawObstacles(real, aabb);
  buildCostmap();

  const std::size_t pieces = pathPiecesInBox(boxCorners(), global_path, pieces_);
  reached_.fill(false);
  reached_[0] = true;
  // A path that leaves the box and comes back: which of its later pieces the robot reaches
  // without leaving the box (the grid, only then: most cycles have one piece).
  if (pieces > 1) reachPieces(pieces, global_path, clearance_m);
  goal_ = intermediateGoalOf(std::span<const PathPiece>(pieces_.data(), pieces), reached_, global_path, goal_theta);
  if (global_path.empty()) goal_.pose = {robot.x, robot.y, goal_theta};  // nothing to follow: stay
}

// Reached within the box: a flood over the cells whose centre lies farther than the clearance
// from every occupied cell's centre (less half a cell: C is drawn conservatively), 4-connected,
// from the cells along the first piece. A piece one of whose cells the flood reaches is
// reached, and the flood goes on along it (a piece of the route is a way in itself, also
// where it runs closer to C than the clearance).
void LocalMap::reachPieces(std::size_t count, std::span<const Vec2> path, double clearance_m) {
  const std::size_t w = static_cast<std::size_t>(width_);
  const double radius = std::max(0.0, clearance_m / config_.cell_m - 0.5);
  const int r = floorToInt(radius + 1e-9);
  const double r2 = radius * radius + 1e-9;
  dilateGrid(reach_blocked_, r, r2);  // C dilated by the clearance
  std::fill(reach_seen_.begin(), reach_seen_.end(), std::uint8_t{0});
  std::size_t head = 0, tail = 0;
  // Visits the cells along a piece, half a cell apart, until visit returns true.
  auto alongPiece = [&](const PathPiece& piece, auto&& visit) {
    for (std::size_t s = piece.first; s <= piece.last; ++s) {
      const Vec2 a = s == piece.first ? piece.in : path[s];
      const Vec2 b = s == piece.last ? piece.out : path[s + 1];
      const int steps = std::max(1, ceilToInt(2.0 * (b - a).norm() / config_.cell_m));
      for (int k = 0; k <= steps; ++k) {
        int i = 0, j = 0;
        nearestCell(a + (static_cast<double>(k) / steps) * (b - a), i, j);
        if (visit(static_cast<std::size_t>(j) * w + static_cast<std::size_t>(i))) return true;
      }
    }
    return false;
  };
  auto seed = [&](const PathPiece& piece) {
    alongPiece(piece, [&](std::size_t c) {
      if (reach_seen_[c] == 0) {
        reach_seen_[c] = 1;
        reach_queue_[tail++] = static_cast<std::uint32_t>(c);
      }
      return false;
    });
  };
  auto pieceSeen = [&](const PathPiece& piece) {
    return alongPiece(piece, [&](std::size_t c) { return reach_seen_[c] != 0; });
  };
  seed(pieces_[0]);
  for (bool grew = true; grew;) {
    // The flood: a cell's free 4-neighbours.
    while (head < tail) {
      const std::uint32_t c = reach_queue_[head++];
      const int ci = static_cast<int>(c % w), cj = static_cast<int>(c / w);
      const int ni[4] = {ci + 1, ci - 1, ci, ci};
      const int nj[4] = {cj, cj, cj + 1, cj - 1};
      for (int k = 0; k < 4; ++k) {
        if (ni[k] < 0 || nj[k] < 0 || ni[k] >= width_ || nj[k] >= height_) continue;
        const std::size_t nc = static_cast<std::size_t>(nj[k]) * w + static_cast<std::size_t>(ni[k]);
        if (reach_seen_[nc] != 0 || reach_blocked_[nc] != 0) continue;
        reach_seen_[nc] = 1;
        reach_queue_[tail++] = static_cast<std::uint32_t>(nc);
      }
    }
    grew = false;
    for (std::size_t k = 1; k < count; ++k) {
      if (reached_[k] || !pieceSeen(pieces_[k])) continue;
      reached_[k] = true;
      seed(pieces_[k]);
      grew = true;
    }
  }
}

// C: conservative rasterization. A cell meets a closed polygon iff an edge passes through
// the (closed) cell or the cell lies wholly inside, and then its centre is inside. So: mark
// every cell each edge touches (supercover) and fill the cells whose centre is inside, one
// scanline per row centre. A convex polygon (every wall and block of a typical map) crosses
// each row centre twice: its cells between the two crossings are filled directly. Other
// polygons add their crossings to a per-row winding count; PolygonSet stores polygons
// counter-clockwise, so overlapping ones add up and never cancel.
void LocalMap::drawObstacles(const PolygonSet& real, const Box& box_aabb) {
  std::fill(grid_.begin(), grid_.end(), std::uint8_t{0});
  std::fill(row_winding_.begin(), row_winding_.end(), std::uint8_t{0});
  for (std::size_t k = 0; k < real.polygonCount(); ++k) {
    if (!real.polygonBox(k).overlaps(box_aabb)) continue;
    const PolygonView poly = real.polygon(k);
    const std::size_t n = poly.size();
    bool convex = true;
    double ylo = std::numeric_limits<double>::infinity(), yhi = -ylo;
    for (std::size_t v = 0; v < n; ++v) {
      convex = convex && orientSign(poly[(v + n - 1) % n], poly[v], poly[(v + 1) % n]) >= 0;
      const double gy = frame_.gridY(poly[v].x(), poly[v].y());
      ylo = std::min(ylo, gy);
      yhi = std::max(yhi, gy);
    }
    // The rows whose centre the polygon spans (half-open, as in addEdgeCrossings).
    const int j0 = std::max(0, ceilToInt(ylo - 0.5));
    const int j1 = std::min(height_ - 1, ceilToInt(yhi - 0.5) - 1);
    if (convex) {
      for (int j = j0; j <= j1; ++j) {
        span_lo_[static_cast<std::size_t>(j)] = std::numeric_limits<double>::infinity();
        span_hi_[static_cast<std::size_t>(j)] = -std::numeric_limits<double>::infinity();
      }
    }
    Vec2 prev = toGrid(poly[n - 1]);
    for (const Vec2& w : poly) {
      const Vec2 cur = toGrid(w);
      markEdgeCells(prev, cur);
      addEdgeCrossings(prev, cur, convex);
      prev = cur;
    }
    if (!convex) continue;
    for (int j = j0; j <= j1; ++j) {
      const double lo = span_lo_[static_cast<std::size_t>(j)], hi = span_hi_[static_cast<std::size_t>(j)];
      if (!(lo <= hi)) continue;
      const int i0 = std::max(0, ceilToInt(lo - 0.5));
      const int i1 = std::min(width_, ceilToInt(hi - 0.5));
      std::uint8_t* row = grid_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      if (i0 < i1) std::fill(row + i0, row + i1, std::uint8_t{1});
    }
  }
  // Non-convex polygons: sum the winding along the rows that have crossings, clearing the
  // counts for the next update as we go.
  for (int j = 0; j < height_; ++j) {
    if (row_winding_[static_cast<std::size_t>(j)] == 0) continue;
    const std::size_t row = static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
    int winding = 0;
    for (int i = 0; i < width_; ++i) {
      winding += winding_[row + static_cast<std::size_t>(i)];
      winding_[row + static_cast<std::size_t>(i)] = 0;
      grid_[row + static_cast<std::size_t>(i)] |= static_cast<std::uint8_t>(winding != 0);
    }
  }
}

// Every cell the closed segment touches: row by row, the segment's x-extent inside the row's
// strip [j, j+1], widened by kRasterEps so a touch on a cell boundary marks both cells.
void LocalMap::markEdgeCells(const Vec2& a, const Vec2& b) {
  const double xlo = std::min(a.x(), b.x()), xhi = std::max(a.x(), b.x());
  const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
  if (xhi < -kRasterEps || xlo > width_ + kRasterEps || yhi < -kRasterEps || ylo > height_ + kRasterEps) return;
  const int j0 = std::max(0, floorToInt(ylo - kRasterEps));
  const int j1 = std::min(height_ - 1, floorToInt(yhi + kRasterEps));
  const double dy = b.y() - a.y();
  const bool flat = std::abs(dy) < 1e-12;
  const double x_per_y = flat ? 0.0 : (b.x() - a.x()) / dy;
  for (int j = j0; j <= j1; ++j) {
    double x0 = xlo, x1 = xhi;
    if (!flat) {
      const double xa = a.x() + (std::max(ylo, static_cast<double>(j)) - a.y()) * x_per_y;
      const double xb = a.x() + (std::min(yhi, static_cast<double>(j + 1)) - a.y()) * x_per_y;
      x0 = std::clamp(std::min(xa, xb), xlo, xhi);
      x1 = std::clamp(std::max(xa, xb), xlo, xhi);
    }
    const int i0 = std::max(0, floorToInt(x0 - kRasterEps));
    const int i1 = std::min(width_ - 1, floorToInt(x1 + kRasterEps));
    std::uint8_t* row = grid_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
    for (int i = i0; i <= i1; ++i) row[i] = 1;
  }
}

// Scanline fill: where the edge crosses a row's centre line y = j + 0.5 (half-open in y, so a
// vertex on the line counts once). A convex polygon's crossings widen the row's span; another
// polygon's change the winding number of every cell whose centre lies right of the crossing
// (crossings left of the grid apply to the whole row).
void LocalMap::addEdgeCrossings(const Vec2& a, const Vec2& b, bool convex) {
  const double dy = b.y() - a.y();
  if (dy == 0.0) return;
  const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
  const int j0 = std::max(0, ceilToInt(ylo - 0.5));
  const int j1 = std::min(height_ - 1, ceilToInt(yhi - 0.5) - 1);
  const double x_per_y = (b.x() - a.x()) / dy;
  if (convex) {
    for (int j = j0; j <= j1; ++j) {
      const double xc = a.x() + (j + 0.5 - a.y()) * x_per_y;
      double& lo = span_lo_[static_cast<std::size_t>(j)];
      double& hi = span_hi_[static_cast<std::size_t>(j)];
      lo = std::min(lo, xc);
      hi = std::max(hi, xc);
    }
    return;
  }
  const std::int16_t step = dy > 0.0 ? -1 : 1;  // counter-clockwise: +1 inside
  for (int j = j0; j <= j1; ++j) {
    const double xc = a.x() + (j + 0.5 - a.y()) * x_per_y;
    const int k = std::max(0, ceilToInt(xc - 0.5));  // first cell whose centre is right of xc
    if (k >= width_) continue;
    winding_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(k)] += step;
    row_winding_[static_cast<std::size_t>(j)] = 1;
  }
}

// C dilated by a disk of cell-centre distances (r2 in cells^2, r its whole part): row j + dj
// contributes its cells within reach(dj) = floor(sqrt(r2 - dj^2)) along the row. Byte ORs
// over shifted rows (the compiler vectorises them).
void LocalMap::dilateGrid(std::vector<std::uint8_t>& out_grid, int r, double r2) const {
  const std::size_t w = static_cast<std::size_t>(width_);
  std::fill(out_grid.begin(), out_grid.end(), std::uint8_t{0});
  for (int j = 0; j < height_; ++j) {
    std::uint8_t* out = out_grid.data() + static_cast<std::size_t>(j) * w;
    for (int dj = -r; dj <= r; ++dj) {
      const int jj = j + dj;
      if (jj < 0 || jj >= height_) continue;
      const std::uint8_t* g = grid_.data() + static_cast<std::size_t>(jj) * w;
      const double rest = r2 - static_cast<double>(dj * dj);
      if (rest < 0.0) continue;
      const int reach = std::min(floorToInt(std::sqrt(rest)), width_ - 1);
      for (std::size_t i = 0; i < w; ++i) out[i] |= g[i];
      for (int di = 1; di <= reach; ++di) {
        const std::size_t d = static_cast<std::size_t>(di);
        for (std::size_t i = 0; i + d < w; ++i) out[i] |= g[i + d];
        for (std::size_t i = d; i < w; ++i) out[i] |= g[i - d];
      }
    }
  }
}

// C': C dilated by a disk of dilate_m (cell centre distances), then a separable Gaussian
// blur (kernel sum 1, zero outside the box), and max(dilated, blurred) so that obstacles stay
// exactly 1 while the cost falls off with distance to 0.
void LocalMap::buildCostmap() {
  const std::size_t w = static_cast<std::size_t>(width_);

  dilateGrid(dilated8_, dilate_cells_, dilate_r2_);
  if (blur_radius_ == 0) {
    std::transform(dilated8_.begin(), dilated8_.end(), costmap_.begin(),
                   [](std::uint8_t d) { return static_cast<float>(d); });
    return;
  }

  // Horizontal pass into scratch_ (blur_radius_ zero rows above and below), run by run: a
  // run of occupied cells [s, e] adds K(i - s) - K(i - e - 1) at cell i, K the cumulative
  // kernel, so the cost follows the occupied runs, not the row length times the kernel.
  const int r = blur_radius_;
  const float* kw = kernel_.data();
  const float* k0 = cumulative_.data() + (width_ + r + 1);  // K at offset 0
  for (int j = 0; j < height_; ++j) {
    const std::uint8_t* in = dilated8_.data() + static_cast<std::size_t>(j) * w;
    float* out = scratch_.data() + static_cast<std::size_t>(j + r) * w;
    std::fill(out, out + w, 0.0f);
    bool any = false;
    for (int i = 0; i < width_;) {
      if (in[i] == 0) {
        ++i;
        continue;
      }
      const int s = i;
      while (i < width_ && in[i] != 0) ++i;
      const int e = i - 1;
      any = true;
      const float* ks = k0 - s;
      const float* ke = k0 - e - 1;
      const int lo = std::max(0, s - r), hi = std::min(width_ - 1, e + r);
      for (int x = lo; x <= hi; ++x) out[x] += ks[x] - ke[x];
    }
    row_any_[static_cast<std::size_t>(j + r)] = any;
  }

  // Vertical pass into costmap_, skipping source rows that are all zero.
  for (int j = 0; j < height_; ++j) {
    float* out = costmap_.data() + static_cast<std::size_t>(j) * w;
    const float* c = scratch_.data() + static_cast<std::size_t>(j + r) * w;
    for (std::size_t i = 0; i < w; ++i) out[i] = kw[0] * c[i];
    for (int k = 1; k <= r; ++k) {
      const bool up = row_any_[static_cast<std::size_t>(j + r - k)] != 0;
      const bool down = row_any_[static_cast<std::size_t>(j + r + k)] != 0;
      if (!up && !down) continue;
      const float wk = kw[k];
      const float* lo = c - static_cast<std::ptrdiff_t>(k) * static_cast<std::ptrdiff_t>(w);
      const float* hi = c + static_cast<std::size_t>(k) * w;
      for (std::size_t i = 0; i < w; ++i) out[i] += wk * (lo[i] + hi[i]);
    }
    const std::uint8_t* d = dilated8_.data() + static_cast<std::size_t>(j) * w;
    for (std::size_t i = 0; i < w; ++i) out[i] = std::min(1.0f, std::max(out[i], static_cast<float>(d[i])));
  }
}

// ---- queries ----

bool LocalMap::inBox(const Vec2& world) const {
  const Vec2 g = toGrid(world);
  return g.x() >= 0.0 && g.x() <= width_ && g.y() >= 0.0 && g.y() <= height_;
}

GridFrame LocalMap::frameAt(double cell_m) const {
  // World -> the box's frame (rear-right corner at the origin) -> cells.
  const double inv = 1.0 / cell_m;
  GridFrame f;
  f.xx = cos_ * inv;
  f.xy = sin_ * inv;
  f.x0 = (config_.behind_m - cos_ * robot_.x - sin_ * robot_.y) * inv;
  f.yx = -sin_ * inv;
  f.yy = cos_ * inv;
  f.y0 = (config_.side_m + sin_ * robot_.x - cos_ * robot_.y) * inv;
  return f;
}

void LocalMap::nearestCell(const Vec2& world, int& i, int& j) const {
  const Vec2 g = toGrid(world);
  i = std::clamp(floorToInt(g.x()), 0, width_ - 1);
  j = std::clamp(floorToInt(g.y()), 0, height_ - 1);
}

bool LocalMap::cellOf(const Vec2& world, int& i, int& j) const {
  const Vec2 g = toGrid(world);
  if (!(g.x() >= 0.0 && g.x() < width_ && g.y() >= 0.0 && g.y() < height_)) return false;
  i = static_cast<int>(g.x());
  j = static_cast<int>(g.y());
  return true;
}

bool LocalMap::occupied(const Vec2& world) const {
  int i = 0, j = 0;
  if (!cellOf(world, i, j)) return false;
  return grid_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i)] != 0;
}

float LocalMap::cost(const Vec2& world) const {
  int i = 0, j = 0;
  if (!cellOf(world, i, j)) return 0.0f;
  return costmap_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i)];
}

Vec2 LocalMap::cellCenter(int i, int j) const {
  const double lx = (i + 0.5) * config_.cell_m - config_.behind_m;
  const double ly = (j + 0.5) * config_.cell_m - config_.side_m;
  return {robot_.x + cos_ * lx - sin_ * ly, robot_.y + sin_ * lx + cos_ * ly};
}

}  // namespace staa
