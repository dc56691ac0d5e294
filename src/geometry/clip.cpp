#include "geometry/clip.hpp"

#include <cmath>

namespace staa {

namespace {

// One of the box's four half-planes: coordinate `axis` (0 = x, 1 = y) >= bound when
// keep_above, else <= bound.
struct HalfPlane {
  int axis;
  double bound;
  bool keep_above;

  bool inside(const Vec2& p) const { return keep_above ? p[axis] >= bound : p[axis] <= bound; }
  // Only called for an edge with one end strictly outside and one inside, so the two ends
  // differ in `axis` and the division is safe.
  Vec2 crossing(const Vec2& a, const Vec2& b) const {
    const double t = (bound - a[axis]) / (b[axis] - a[axis]);
    Vec2 p = a + t * (b - a);
    p[axis] = bound;  // exactly on the box edge despite rounding
    return p;
  }
};

// One Sutherland-Hodgman stage. Returns the vertex count, or nothing when `out` is full.
FixedResult clipStage(PolygonView in, const HalfPlane& h, std::span<Vec2> out) {
  std::size_t k = 0;
  auto emit = [&](const Vec2& p) {
    if (k == out.size()) return false;
    out[k++] = p;
    return true;
  };
  const std::size_t n = in.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2& prev = in[j];
    const Vec2& cur = in[i];
    const bool prev_in = h.inside(prev), cur_in = h.inside(cur);
    if (prev_in != cur_in && !emit(h.crossing(prev, cur))) return {false, 0};
    if (cur_in && !emit(cur)) return {false, 0};
  }
  return {true, k};
}

}  // namespace

FixedResult clipToBox(PolygonView in, const Box& box, std::span<Vec2> out, std::span<Vec2> scratch) {
  if (in.empty()) return {true, 0};
  const HalfPlane planes[4] = {{0, box.min.x(), true}, {0, box.max.x(), false},
                               {1, box.min.y(), true}, {1, box.max.y(), false}};
  // Stages alternate scratch, out, scratch, out so the last one lands in `out`.
  PolygonView current = in;
  for (int s = 0; s < 4; ++s) {
    const std::span<Vec2> target = (s % 2 == 0) ? scratch : out;
    const FixedResult r = clipStage(current, planes[s], target);
    if (!r.ok) return r;
    if (r.size == 0) return {true, 0};
    current = PolygonView(target.data(), r.size);
  }
  return {true, current.size()};
}

FixedResult transformPolygon(PolygonView in, const Pose2& pose, std::span<Vec2> out) {
  if (out.size() < in.size()) return {false, 0};
  // One sin/cos for all vertices instead of one per Pose2::transform call.
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (std::size_t i = 0; i < in.size(); ++i) {
    const double x = in[i].x(), y = in[i].y();  // read before writing: out may alias in
    out[i] = Vec2{pose.x + c * x - s * y, pose.y + s * x + c * y};
  }
  return {true, in.size()};
}

}  // namespace staa
