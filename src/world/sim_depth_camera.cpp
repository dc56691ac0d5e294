#include "world/sim_depth_camera.hpp"

#include "geometry/polygon.hpp"
#include "world/world.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace staa::hal {
namespace {

// Azimuth intervals are padded by this much (rad), so a ray through an edge's end point,
// rounded to float, still finds the edge in its bin.
constexpr double kAzimuthPad = 1e-6;
// Largest depth a frame holds (mm).
constexpr double kMaxDepthMm = 65535.0;

[[noreturn]] void bad(const char* field, double value, const char* rule) {
  throw std::invalid_argument(std::string("sim depth camera: config.") + field + " must be " + rule + ", got " +
                              std::to_string(value));
}

const SimDepthConfig& validated(const SimDepthConfig& c) {
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(c.wall_height_m)) bad("wall_height_m", c.wall_height_m, "finite and > 0 (m)");
  if (!positive(c.mover_height_m)) bad("mover_height_m", c.mover_height_m, "finite and > 0 (m)");
  if (!(c.min_depth_m >= 0.0)) bad("min_depth_m", c.min_depth_m, ">= 0 (m)");
  if (!(c.max_depth_m > c.min_depth_m && c.max_depth_m <= kMaxDepthMm / 1000.0)) {
    bad("max_depth_m", c.max_depth_m, "> min_depth_m and <= 65.535 (m)");
  }
  if (!(c.noise_mm_per_m2 >= 0.0) || !std::isfinite(c.noise_mm_per_m2)) {
    bad("noise_mm_per_m2", c.noise_mm_per_m2, "finite and >= 0");
  }
  if (!(c.dropout >= 0.0 && c.dropout < 1.0)) bad("dropout", c.dropout, "in [0, 1) (a fraction of the pixels)");
  if (!(c.grazing_deg > 0.0 && c.grazing_deg <= 90.0)) bad("grazing_deg", c.grazing_deg, "in (0, 90] degrees");
  if (c.pixel_stride < 1 || c.pixel_stride > 16) bad("pixel_stride", c.pixel_stride, "in 1..16");
  if (!positive(c.rate_hz)) bad("rate_hz", c.rate_hz, "finite and > 0 (Hz)");
  return c;
}

// Distance from the origin to the segment [a, a + e].
double originDistance(const Vec2& a, const Vec2& e) {
  const double len2 = e.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp(-a.dot(e) / len2, 0.0, 1.0) : 0.0;
  return (a + t * e).norm();
}

}  // namespace

StaticPrisms::StaticPrisms(const PolygonMap& map) {
  for (const Polygon& o : map.obstacles) {
    entries.push_back(Entry{static_cast<std::uint32_t>(points.size()), static_cast<std::uint32_t>(o.size()), boundingBox(o), true});
    points.insert(points.end(), o.begin(), o.end());
  }
  if (map.bounds) {
    const Box& b = *map.bounds;
    entries.push_back(Entry{static_cast<std::uint32_t>(points.size()), 4, b, false});
    points.insert(points.end(), {b.min, Vec2(b.max.x(), b.min.y()), b.max, Vec2(b.min.x(), b.max.y())});
  }
}

DepthRenderer::DepthRenderer(const PolygonMap& map, const SimDepthConfig& config)
    : config_(validated(config)), camera_(config.intrinsics, config.mount), static_(map), rng_(config.seed) {
  // Every pixel's ray and its azimuth bin (from the camera's yaw, so the field of view does
  // not wrap around +-pi for a camera looking backwards).
  yaw0_ = config_.mount.yaw;
  rays_.resize(static_cast<std::size_t>(DepthFrame::kWidth) * DepthFrame::kHeight);
  std::vector<double> azimuth(rays_.size(), 0.0);
  double lo = kPi, hi = -kPi;
  for (int v = 0; v < DepthFrame::kHeight; ++v) {
    for (int u = 0; u < DepthFrame::kWidth; ++u) {
      const std::size_t k = static_cast<std::size_t>(v) * DepthFrame::kWidth + static_cast<std::size_t>(u);
      const Vec3 r = camera_.ray(u, v);
      const double horizontal = std::hypot(r.x(), r.y());
      rays_[k] = PixelRay{static_cast<float>(r.x()), static_cast<float>(r.y()), static_cast<float>(r.z()),
                          horizontal > 1e-9 ? static_cast<float>(1.0 / horizontal) : 0.0F,
                          static_cast<float>(1.0 / r.norm()), 0};
      if (horizontal <= 1e-9) continue;
      azimuth[k] = wrapAngle(std::atan2(r.y(), r.x()) - yaw0_);
      lo = std::min(lo, azimuth[k]);
      hi = std::max(hi, azimuth[k]);
    }
  }
  fov_min_ = lo - kAzimuthPad;
  bin_width_ = std::max(hi - lo + 2.0 * kAzimuthPad, 1e-9) / kBins;
  for (std::size_t k = 0; k < rays_.size(); ++k) {
    if (rays_[k].inv_horizontal > 0.0F) rays_[k].bin = static_cast<std::uint16_t>(binOf(azimuth[k]));
  }

  edges_.reserve(static_.points.size() + kMaxMoverEdges);
  prisms_.reserve(static_.entries.size() + kMaxMoverEdges / 3);
  low_prisms_.reserve(prisms_.capacity());
  prism_mover_.reserve(prisms_.capacity());
  bin_items_.resize(8 * edges_.capacity() + 16 * kBins);
}

int DepthRenderer::binOf(double relative_azimuth) const {
  const auto b = static_cast<int>(std::floor((relative_azimuth - fov_min_) / bin_width_));
  return std::clamp(b, 0, kBins - 1);
}

// The bins an edge's azimuth interval (as seen from the camera) overlaps: up to two ranges
// (an interval across +-pi), none for an edge out of range or out of the field of view.
void DepthRenderer::binEdge(Edge& edge) const {
  std::fill(std::begin(edge.bins), std::end(edge.bins), -1);
  edge.near = originDistance(edge.p, edge.e);
  if (edge.near > config_.max_depth_m) return;
  const double fov_max = fov_min_ + bin_width_ * kBins;
  const auto range = [&](double a, double b, int slot) {
    a = std::max(a, fov_min_);
    b = std::min(b, fov_max);
    if (a > b) return;
    edge.bins[slot] = binOf(a);
    edge.bins[slot + 1] = binOf(b);
  };
  if (edge.near < 1e-9) {  // through the camera: every direction
    range(fov_min_, fov_max, 0);
    return;
  }
  const Vec2 q = edge.p + edge.e;
  const double ap = wrapAngle(std::atan2(edge.p.y(), edge.p.x()) - yaw0_);
  const double aq = wrapAngle(std::atan2(q.y(), q.x()) - yaw0_);
  const double turn = wrapAngle(aq - ap);
  const double start = (turn >= 0.0 ? ap : aq) - kAzimuthPad;
  const double end = start + std::abs(turn) + 2.0 * kAzimuthPad;
  range(start, std::min(end, kPi), 0);
  if (end > kPi) range(-kPi, end - 2.0 * kPi, 2);
  if (start < -kPi) range(start + 2.0 * kPi, kPi, 2);
}

void DepthRenderer::addPrism(std::span<const Vec2> points_map, double height, bool solid, const Vec2& camera,
                             double c, double s) {
  // Map frame -> camera-relative, base-aligned: rotate by -theta about the camera.
  const auto relative = [&](const Vec2& p) {
    const Vec2 d = p - camera;
    return Vec2(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  };
  Prism prism;
  prism.first = static_cast<std::uint32_t>(edges_.size());
  prism.count = static_cast<std::uint32_t>(points_map.size());
  prism.height = height;
  const Vec2 first = relative(points_map[0]);
  prism.box = Box{first, first};
  for (std::size_t k = 0; k < points_map.size(); ++k) {
    const Vec2 a = relative(points_map[k]);
    const Vec2 b = relative(points_map[(k + 1) % points_map.size()]);
    Edge edge;
    edge.p = a;
    edge.e = b - a;
    edge.height = height;
    const double length = edge.e.norm();
    edge.inv_length = length > 0.0 ? 1.0 / length : 0.0;
    edge.prism = static_cast<std::uint32_t>(prisms_.size());
    binEdge(edge);
    edges_.push_back(edge);
    prism.box.min = prism.box.min.cwiseMin(a);
    prism.box.max = prism.box.max.cwiseMax(a);
  }
  if (solid && height < camera_.position().z()) low_prisms_.push_back(static_cast<std::uint32_t>(prisms_.size()));
  prisms_.push_back(prism);
}

void DepthRenderer::render(const Pose2& robot, std::span<const PrismView> movers, DepthFrame& out,
                           std::span<std::uint32_t> mover_pixels) {
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const Vec2 camera = robot.transform(camera_.position().head<2>());
  const double cz = camera_.position().z();
  const double range = config_.max_depth_m;

  // This frame's prisms: static ones near enough, then the movers.
  edges_.clear();
  prisms_.clear();
  low_prisms_.clear();
  prism_mover_.clear();
  for (const StaticPrisms::Entry& sp : static_.entries) {
    const double dx = std::max({sp.box.min.x() - camera.x(), 0.0, camera.x() - sp.box.max.x()});
    const double dy = std::max({sp.box.min.y() - camera.y(), 0.0, camera.y() - sp.box.max.y()});
    // The bounds are seen from inside: near whenever the camera is within range of a side.
    const bool near = sp.solid ? dx * dx + dy * dy <= range * range : true;
    if (!near) continue;
    prism_mover_.push_back(kNoMover);
    addPrism(static_.pointsOf(sp), config_.wall_height_m, sp.solid, camera, c, s);
  }
  for (std::size_t i = 0; i < movers.size(); ++i) {
    const PrismView& m = movers[i];
    if (m.shape.size() < 3 || edges_.size() + m.shape.size() > edges_.capacity() ||
        prisms_.size() == prisms_.capacity()) {
      continue;  // beyond the fixed capacity: unseen
    }
    if (m.shape.size() > kMaxMoverVertices) continue;
    std::array<Vec2, kMaxMoverVertices> placed{};
    for (std::size_t k = 0; k < m.shape.size(); ++k) placed[k] = m.shape[k] + m.position;
    prism_mover_.push_back(static_cast<std::uint32_t>(i));
    addPrism(std::span<const Vec2>(placed.data(), m.shape.size()), m.height_m, true, camera, c, s);
  }
  const bool count_movers = !mover_pixels.empty() && mover_pixels.size() == movers.size();
  if (count_movers) std::fill(mover_pixels.begin(), mover_pixels.end(), 0u);

  // Azimuth bins: counts, prefix sums, then the items.
  std::array<std::uint32_t, kBins> cursor{};
  for (const Edge& e : edges_) {
    for (int r = 0; r < 4; r += 2) {
      if (e.bins[r] < 0) continue;
      for (int b = e.bins[r]; b <= e.bins[r + 1]; ++b) ++cursor[static_cast<std::size_t>(b)];
    }
  }
  std::uint32_t total = 0;
  for (int b = 0; b < kBins; ++b) {
    bin_start_[static_cast<std::size_t>(b)] = total;
    total += cursor[static_cast<std::size_t>(b)];
    cursor[static_cast<std::size_t>(b)] = bin_start_[static_cast<std::size_t>(b)];
  }
  bin_start_[kBins] = total;
  if (bin_items_.size() < total) bin_items_.resize(total);  // grows only past every earlier frame
  for (std::uint32_t i = 0; i < edges_.size(); ++i) {
    const Edge& e = edges_[i];
    for (int r = 0; r < 4; r += 2) {
      if (e.bins[r] < 0) continue;
      for (int b = e.bins[r]; b <= e.bins[r + 1]; ++b) bin_items_[cursor[static_cast<std::size_t>(b)]++] = i;
    }
  }
  // Nearest first in every bin: a pixel stops at the first edge beyond its nearest hit.
  for (int b = 0; b < kBins; ++b) {
    std::sort(bin_items_.begin() + bin_start_[static_cast<std::size_t>(b)],
              bin_items_.begin() + bin_start_[static_cast<std::size_t>(b) + 1],
              [this](std::uint32_t x, std::uint32_t y) { return edges_[x].near < edges_[y].near; });
  }

  // Every pixel: the nearest of the floor, a prism's side and a low prism's top.
  const int stride = config_.pixel_stride;
  if (stride > 1) std::fill(out.depth_mm.begin(), out.depth_mm.end(), std::uint16_t{0});
  const double noise = config_.noise_mm_per_m2 * 1e-3;
  const double dropout = config_.dropout;
  // A reading needs the surface within grazing_deg of facing the ray: cos(incidence) >= this.
  const double min_cos = config_.grazing_deg < 90.0 ? std::cos(config_.grazing_deg * kPi / 180.0) : -1.0;
  for (int v = stride / 2; v < DepthFrame::kHeight; v += stride) {
    for (int u = stride / 2; u < DepthFrame::kWidth; u += stride) {
      const std::size_t k = static_cast<std::size_t>(v) * DepthFrame::kWidth + static_cast<std::size_t>(u);
      const PixelRay& ray = rays_[k];
      const double rx = ray.x, ry = ray.y, rz = ray.z;
      double best = range;  // depth (optical z): the point is depth * (rx, ry, rz) from the camera
      bool hit = false;
      std::uint32_t hit_prism = kNoMover;  // the prism whose side or top was hit (none: the floor)
      double hit_cos = 1.0;                // cos(incidence) times |ray|: the surface's normal . ray
      if (config_.floor && rz < 0.0 && -cz / rz < best) {
        best = -cz / rz;
        hit = true;
        hit_cos = -rz;
      }
      if (ray.inv_horizontal > 0.0F) {
        const double inv_h = ray.inv_horizontal;
        const std::uint32_t end = bin_start_[ray.bin + 1u];
        for (std::uint32_t j = bin_start_[ray.bin]; j < end; ++j) {
          const Edge& e = edges_[bin_items_[j]];
          if (e.near * inv_h >= best) break;  // this edge and the rest are farther than the hit
          // Solve depth * r = p + w * e (2-D): depth = cross(p, e) / cross(r, e).
          const double den = rx * e.e.y() - ry * e.e.x();
          if (den == 0.0) continue;
          const double depth = (e.p.x() * e.e.y() - e.p.y() * e.e.x()) / den;
          if (!(depth > 0.0 && depth < best)) continue;
          const double w = (e.p.x() * ry - e.p.y() * rx) / den;
          if (w < 0.0 || w > 1.0) continue;
          const double z = cz + depth * rz;
          if (z < 0.0 || z > e.height) continue;
          best = depth;
          hit = true;
          hit_prism = e.prism;
          hit_cos = std::abs(den) * e.inv_length;  // |cross(r, e)| / |e|: the ray along the edge's normal
        }
        if (rz < 0.0) {
          for (const std::uint32_t pi : low_prisms_) {
            const Prism& p = prisms_[pi];
            const double depth = (p.height - cz) / rz;
            if (!(depth > 0.0 && depth < best)) continue;
            const Vec2 at(depth * rx, depth * ry);
            if (!p.box.contains(at)) continue;
            bool inside = false;  // crossing number over the prism's edges
            for (std::uint32_t q = p.first; q < p.first + p.count; ++q) {
              const Vec2& a = edges_[q].p;
              const Vec2 b = a + edges_[q].e;
              if ((a.y() > at.y()) != (b.y() > at.y()) &&
                  at.x() < a.x() + (at.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) {
                inside = !inside;
              }
            }
            if (inside) {
              best = depth;
              hit = true;
              hit_prism = pi;
              hit_cos = -rz;
            }
          }
        }
      }
      std::uint16_t mm = 0;
      if (hit && best >= config_.min_depth_m && hit_cos * ray.inv_norm >= min_cos &&
          !(dropout > 0.0 && rng_.uniform() < dropout)) {
        double d = best;
        if (noise > 0.0) d += noise * best * best * rng_.normal();
        mm = static_cast<std::uint16_t>(std::clamp(std::round(d * 1000.0), 1.0, kMaxDepthMm));
        if (count_movers && hit_prism != kNoMover && prism_mover_[hit_prism] != kNoMover) {
          ++mover_pixels[prism_mover_[hit_prism]];
        }
      }
      out.depth_mm[k] = mm;
    }
  }
}

// ---- SimDepthCamera ----

SimDepthCamera::SimDepthCamera(const World& world, const SimDepthConfig& config)
    : world_(world),
      renderer_(world.map(), config),
      period_(std::max<rt::Nanos>(1, std::llround(1e9 / config.rate_hz))) {
  movers_.resize(world.moverCount());
  for (std::size_t i = 0; i < movers_.size(); ++i) {
    movers_[i].shape = PolygonView(world.mover(i).polygon);
    movers_[i].height_m = config.mover_height_m;
  }
}

bool SimDepthCamera::read(rt::Nanos now, DepthFrame& out) {
  // A fixed schedule of due times a period apart (a poll a little early still counts).
  if (next_due_ >= 0 && now < next_due_ - period_ / 20) return false;
  for (std::size_t i = 0; i < movers_.size(); ++i) movers_[i].position = world_.moverPosition(i);
  renderer_.render(world_.robot().pose, movers_, out);
  out.stamp = now;
  out.sequence = ++sequence_;
  next_due_ = (next_due_ < 0 ? now : next_due_) + period_;
  if (next_due_ <= now) next_due_ = now + period_;  // fell behind: skip, do not burst
  return true;
}

}  // namespace staa::hal
