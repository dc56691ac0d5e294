#include "map/ros_import.hpp"

#include "geometry/predicates.hpp"

#include "geometry/clipper_ops.hpp"

#include "io/config_reader.hpp"
#include "io/yaml_support.hpp"

#include <clipper.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <utility>

namespace staa {

namespace {

// ---------------------------------------------------------------------------------------
// PGM reader

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }

// Walks a PGM byte buffer; every read is bounds-checked so a malformed file becomes an error.
class PgmCursor {
 public:
  PgmCursor(std::string_view bytes, const std::string& source) : bytes_(bytes), source_(source) {}

  [[noreturn]] void fail(const std::string& what) const { throw MapError(source_ + ": " + what); }

  void skipSpaceAndComments() {
    while (pos_ < bytes_.size()) {
      if (isSpace(bytes_[pos_])) {
        ++pos_;
      } else if (bytes_[pos_] == '#') {
        while (pos_ < bytes_.size() && bytes_[pos_] != '\n' && bytes_[pos_] != '\r') ++pos_;
      } else {
        break;
      }
    }
  }

  // A decimal number in [lo, hi], followed by whitespace, a comment or the end of the file.
  long readNumber(const std::string& what, long lo, long hi) {
    skipSpaceAndComments();
    if (pos_ >= bytes_.size()) fail("truncated PGM: missing " + what);
    if (!isDigit(bytes_[pos_])) {
      fail("malformed PGM: " + what + " is not a number (found '" + printable(bytes_[pos_]) + "')");
    }
    long value = 0;
    const std::size_t start = pos_;
    while (pos_ < bytes_.size() && isDigit(bytes_[pos_])) {
      value = std::min(value * 10 + (bytes_[pos_] - '0'), hi + 1);  // saturate: no overflow
      ++pos_;
    }
    if (pos_ < bytes_.size() && !isSpace(bytes_[pos_]) && bytes_[pos_] != '#') {
      fail("malformed PGM: " + what + " '" + std::string(bytes_.substr(start, pos_ - start + 1)) +
           "' is not a number");
    }
    if (value < lo || value > hi) {
      fail("malformed PGM: " + what + " " + std::string(bytes_.substr(start, pos_ - start)) + " out of range [" +
           std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return value;
  }

  std::size_t pos() const { return pos_; }
  void advance(std::size_t n) { pos_ += n; }
  std::size_t remaining() const { return bytes_.size() - pos_; }
  unsigned char byteAt(std::size_t i) const { return static_cast<unsigned char>(bytes_[i]); }

  static std::string printable(char c) {
    if (c >= 0x20 && c < 0x7f) return std::string(1, c);
    std::ostringstream s;
    s << "\\x" << std::hex << (static_cast<int>(c) & 0xff);
    return s.str();
  }

 private:
  std::string_view bytes_;
  const std::string& source_;
  std::size_t pos_ = 0;
};

std::string readFile(const std::filesystem::path& path, const char* what) {
  std::error_code ec;
  if (const auto size = std::filesystem::file_size(path, ec); !ec && size > kMaxPgmFileBytes) {
    throw MapError(path.string() + ": " + std::to_string(size) + " bytes, beyond the bound of " +
                   std::to_string(kMaxPgmFileBytes) + " bytes for a " + what);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path.string() + ": cannot open " + what);
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw MapError(path.string() + ": error reading " + what);
  return std::move(s).str();
}

// ---------------------------------------------------------------------------------------
// map_server YAML

constexpr io::Choice<RosMapInfo::Mode> kModes[] = {
    {"trinary", RosMapInfo::Mode::kTrinary}, {"scale", RosMapInfo::Mode::kScale}, {"raw", RosMapInfo::Mode::kRaw}};

// map_server's keys (its files are others': keys this reader does not know are left alone).
// With `image_must_exist` the image file is looked for, named at its key when it is not there.
RosMapInfo readRosMapInfo(const io::ConfigValue& root, bool image_must_exist) {
  if (!root.node().IsMap()) root.fail("expected a map_server YAML mapping (image, resolution, origin, ...), got " + root.described());
  root.anyMapping();
  RosMapInfo info;
  const io::ConfigValue image = root.required("image", "the PGM file");
  info.image = image.path("a file name");
  if (image_must_exist && !std::filesystem::is_regular_file(info.image)) image.fail("file " + info.image.string() + " not found");

  info.resolution = root.required("resolution", "metres per pixel").number(io::Range::above(0.0, "m per pixel"));
  const auto origin = root.required("origin", "[x, y, yaw] of the lower-left pixel").numbers<3>("3 numbers [x, y, yaw]");
  info.origin = Pose2{origin[0], origin[1], origin[2]};

  if (const io::ConfigValue negate = root.get("negate"); negate.present()) {
    // map_server writes 0/1; YAML booleans are accepted too.
    const std::optional<double> n = yaml_support::readNumber(negate.node());
    if (n && (*n == 0.0 || *n == 1.0)) {
      info.negate = *n == 1.0;
    } else if (bool on = false; negate.node().IsScalar() && io::decodeYamlBool(negate.node().Scalar(), on)) {
      info.negate = on;
    } else {
      negate.fail("must be 0 or 1, got " + negate.text());
    }
  }
  const io::Range fraction = io::Range::closed(0.0, 1.0);
  const io::ConfigValue occupied = root.get("occupied_thresh");
  const io::ConfigValue free = root.get("free_thresh");
  if (occupied.present()) info.occupied_thresh = occupied.number(fraction);
  if (free.present()) info.free_thresh = free.number(fraction);
  if (info.free_thresh >= info.occupied_thresh) {
    if (free.present()) free.failRule("below occupied_thresh (" + yaml_support::formatNumber(info.occupied_thresh) + ")");
    occupied.failRule("above free_thresh (" + yaml_support::formatNumber(info.free_thresh) + ")");
  }
  if (const io::ConfigValue mode = root.get("mode"); mode.present()) info.mode = mode.choice<RosMapInfo::Mode>(kModes);
  return info;
}

// ---------------------------------------------------------------------------------------
// Tracing the blocked cells. Clipper works on integers; in units of 1/kSub cell every pixel
// corner is exact and the crossings made by simplification round to 1/1024 of a cell.

namespace cl = ClipperLib;
constexpr cl::cInt kSub = 1024;

// The boundaries of the blocked cells, traced along pixel edges with the blocked side on the
// left: outer rings counter-clockwise, holes clockwise, one vertex per corner. Unlike a union
// of cell rectangles, no ring carries an edge with blocked cells on both sides, so simplifying
// rings one by one cannot open a seam inside a solid area. Outside the image counts as free.
cl::Paths traceBlockedBoundaries(const OccupancyGrid& grid) {
  const int w = grid.width, h = grid.height;
  const auto blocked = [&](int c, int r) { return c >= 0 && c < w && r >= 0 && r < h && grid.blocked(c, r); };
  // Directions 0: +x, 1: +y, 2: -x, 3: -y (counter-clockwise order, so d + 1 turns left).
  constexpr int kDx[4] = {1, 0, -1, 0};
  constexpr int kDy[4] = {0, 1, 0, -1};
  const std::size_t stride = static_cast<std::size_t>(w) + 1;
  // Unvisited outgoing boundary edges at each lattice vertex, one bit per direction.
  std::vector<std::uint8_t> out(stride * (static_cast<std::size_t>(h) + 1), 0);
  for (int y = 0; y <= h; ++y) {
    for (int x = 0; x <= w; ++x) {
      const bool ne = blocked(x, y), nw = blocked(x - 1, y), se = blocked(x, y - 1), sw = blocked(x - 1, y - 1);
      out[y * stride + x] = static_cast<std::uint8_t>((ne && !se ? 1 : 0) | (nw && !ne ? 2 : 0) |
                                                      (sw && !nw ? 4 : 0) | (se && !sw ? 8 : 0));
    }
  }
  cl::Paths rings;
  std::vector<cl::IntPoint> corners;
  for (int y0 = 0; y0 <= h; ++y0) {
    for (int x0 = 0; x0 <= w; ++x0) {
      while (out[y0 * stride + x0] != 0) {
        const std::uint8_t m0 = out[y0 * stride + x0];
        const int d0 = (m0 & 1) ? 0 : (m0 & 2) ? 1 : (m0 & 4) ? 2 : 3;
        corners.clear();
        int x = x0, y = y0, d = d0;
        while (true) {
          out[y * stride + x] &= static_cast<std::uint8_t>(~(1u << d));
          x += kDx[d];
          y += kDy[d];
          // At a pinch (two blocked cells meeting at a corner) prefer the left turn, which
          // keeps diagonal neighbours in separate rings; the final union joins them.
          const std::uint8_t m = out[y * stride + x] | (x == x0 && y == y0 ? (1u << d0) : 0u);
          int next = -1;
          for (const int turn : {1, 0, 3}) {
            if (m & (1u << ((d + turn) % 4))) {
              next = (d + turn) % 4;
              break;
            }
          }
          if (next != d) corners.emplace_back(static_cast<cl::cInt>(x) * kSub, static_cast<cl::cInt>(y) * kSub);
          if (x == x0 && y == y0 && next == d0) break;
          d = next;
        }
        rings.push_back(corners);
      }
    }
  }
  return rings;
}

// Squared: libm's hypot is not rounded alike on every platform (glibc uses fused
// multiply-adds where the hardware has them), and a last-bit difference against the
// tolerance keeps another vertex. Basic arithmetic rounds the same everywhere.
double pointSegmentDistance2(const cl::IntPoint& p, const cl::IntPoint& a, const cl::IntPoint& b) {
  const double abx = static_cast<double>(b.X - a.X), aby = static_cast<double>(b.Y - a.Y);
  const double apx = static_cast<double>(p.X - a.X), apy = static_cast<double>(p.Y - a.Y);
  const double len2 = abx * abx + aby * aby;
  const double t = len2 > 0.0 ? std::clamp((apx * abx + apy * aby) / len2, 0.0, 1.0) : 0.0;
  const double dx = apx - t * abx, dy = apy - t * aby;
  return dx * dx + dy * dy;
}

// Douglas-Peucker on a closed ring, anchored at vertex 0 and the vertex farthest from it.
cl::Path douglasPeucker(const cl::Path& ring, double tolerance) {
  const std::size_t n = ring.size();
  if (n <= 3) return ring;
  std::size_t far = 0;
  double far_d2 = -1.0;
  for (std::size_t i = 1; i < n; ++i) {
    const double dx = static_cast<double>(ring[i].X - ring[0].X), dy = static_cast<double>(ring[i].Y - ring[0].Y);
    if (dx * dx + dy * dy > far_d2) {
      far_d2 = dx * dx + dy * dy;
      far = i;
    }
  }
  std::vector<char> keep(n, 0);
  keep[0] = keep[far] = 1;
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, far}, {far, n}};  // index n is vertex 0
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    double worst = tolerance * tolerance;
    std::size_t worst_i = 0;
    for (std::size_t i = a + 1; i < b; ++i) {
      const double d = pointSegmentDistance2(ring[i], ring[a], ring[b % n]);
      if (d > worst) {
        worst = d;
        worst_i = i;
      }
    }
    if (worst_i != 0) {
      keep[worst_i] = 1;
      stack.emplace_back(a, worst_i);
      stack.emplace_back(worst_i, b);
    }
  }
  cl::Path out;
  for (std::size_t i = 0; i < n; ++i) {
    if (keep[i]) out.push_back(ring[i]);
  }
  return out;
}

// Simplifies every ring. A ring that collapses (fewer than 3 vertices, or less than half its
// area left) was thinner than the tolerance: an obstacle ring is then kept exact, so no post
// or thin wall vanishes; a free pocket is closed (dropped), which errs on the blocked side.
cl::Paths simplifyRings(const cl::Paths& rings, double tolerance) {
  cl::Paths out;
  out.reserve(rings.size());
  for (const cl::Path& ring : rings) {
    const double area = cl::Area(ring);
    cl::Path simple = douglasPeucker(ring, tolerance);
    const double simple_area = simple.size() >= 3 ? cl::Area(simple) : 0.0;
    const bool collapsed = area > 0.0 ? simple_area < 0.5 * area : simple_area > 0.5 * area;
    if (!collapsed) {
      out.push_back(std::move(simple));
    } else if (area > 0.0) {
      out.push_back(ring);
    }
  }
  return out;
}

// Re-unites simplified rings, which may cross. Nonzero fill keeps every twisted lobe and every
// overlap blocked, so a crossing errs on the blocked side (a hole stays open where its winding
// cancels its outer ring's).
// Simplification also closes gaps of exactly one cell to zero width, leaving a vertex on
// another edge; Clipper's StrictlySimple splits rings only at shared vertices, so those
// touches would survive as non-simple polygons. Growing the region by kTouchGrow (2/1024 of
// a cell, a fraction of a millimetre) turns each such touch into solid overlap.
constexpr double kTouchGrow = 2.0;

cl::Paths reuniteSimplified(const cl::Paths& rings) {
  cl::Paths united;
  {
    cl::Clipper clipper;
    clipper.AddPaths(rings, cl::ptSubject, true);
    clipper.Execute(cl::ctUnion, united, cl::pftNonZero, cl::pftNonZero);
  }
  cl::ClipperOffset offset(2.0);  // square pixel corners stay square under the mitre
  offset.AddPaths(united, cl::jtMiter, cl::etClosedPolygon);
  cl::Paths grown;
  offset.Execute(grown, kTouchGrow);
  return grown;
}

// Rings whose area is below 1% of a cell are slivers made where simplified rings cross, not
// map content: every traced ring encloses at least one whole cell.
constexpr double kSliverArea = 0.01 * static_cast<double>(kSub) * static_cast<double>(kSub);

Polygon toWorld(const cl::Path& path, const OccupancyGrid& grid) {
  Polygon poly;
  poly.reserve(path.size());
  const double scale = grid.resolution / static_cast<double>(kSub);
  for (const cl::IntPoint& p : path) {
    poly.push_back(grid.origin.transform(Vec2(static_cast<double>(p.X) * scale, static_cast<double>(p.Y) * scale)));
  }
  return poly;
}

void collectRegions(const cl::PolyNode& node, const OccupancyGrid& grid, std::vector<PolygonWithHoles>& out) {
  for (const cl::PolyNode* outer : node.Childs) {
    // Islands inside a hole are collected even when the outer is a sliver.
    for (const cl::PolyNode* hole : outer->Childs) collectRegions(*hole, grid, out);
    if (std::abs(cl::Area(outer->Contour)) < kSliverArea) continue;
    PolygonWithHoles region;
    region.outer = toWorld(outer->Contour, grid);
    for (const cl::PolyNode* hole : outer->Childs) {
      if (std::abs(cl::Area(hole->Contour)) >= kSliverArea) region.holes.push_back(toWorld(hole->Contour, grid));
    }
    out.push_back(std::move(region));
  }
}

// With a rotated origin the bounds are the image's bounding box; the four corner triangles
// between the box and the image are outside the image, hence blocked.
std::vector<Polygon> outsideCorners(const std::array<Vec2, 4>& image_corners) {
  std::vector<Polygon> out;
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec2& a = image_corners[i];
    const Vec2& b = image_corners[(i + 1) % 4];
    // The bounding-box corner beside edge a->b lies to its right (the image is counter-clockwise).
    Vec2 c(a.x(), b.y());
    if (orientSign(a, b, c) >= 0) c = Vec2(b.x(), a.y());
    if (std::abs(orient(a, b, c)) > 1e-9) out.push_back({a, c, b});
  }
  return out;
}

}  // namespace

// -----------------------------------------------------------------------------------------

PgmImage parsePgm(std::string_view bytes, const std::string& source) {
  PgmCursor in(bytes, source);
  if (bytes.size() < 2 || bytes[0] != 'P') in.fail("not a PGM image (no 'P2'/'P5' magic number)");
  const char kind = bytes[1];
  if (kind != '2' && kind != '5') {
    in.fail(std::string("unsupported image type 'P") + PgmCursor::printable(kind) +
            "' (only greyscale PGM, P2 or P5, is read)");
  }
  in.advance(2);
  if (in.remaining() > 0 && !isSpace(bytes[2]) && bytes[2] != '#') in.fail("malformed PGM: no whitespace after the magic number");

  PgmImage image;
  image.width = static_cast<int>(in.readNumber("width", 1, kMaxPgmSide));
  image.height = static_cast<int>(in.readNumber("height", 1, kMaxPgmSide));
  image.maxval = static_cast<int>(in.readNumber("maxval", 1, 65535));
  const std::size_t count = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);

  const auto checkValue = [&](long v, std::size_t i) {
    if (v > image.maxval) {
      in.fail("malformed PGM: pixel value " + std::to_string(v) + " at column " + std::to_string(i % image.width) +
              ", row " + std::to_string(i / image.width) + " exceeds maxval " + std::to_string(image.maxval));
    }
  };

  if (kind == '5') {
    // Exactly one whitespace byte separates maxval from the raster (which may start with '#').
    if (in.remaining() == 0) in.fail("truncated PGM: no pixel data after the header");
    in.advance(1);
    const std::size_t bytes_per_sample = image.maxval > 255 ? 2 : 1;
    const std::size_t needed = count * bytes_per_sample;
    if (in.remaining() < needed) {
      in.fail("truncated PGM: " + std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels need " +
              std::to_string(needed) + " bytes of pixel data, found " + std::to_string(in.remaining()));
    }
    image.pixels.resize(count);
    const std::size_t base = in.pos();
    for (std::size_t i = 0; i < count; ++i) {
      const long v = bytes_per_sample == 1 ? in.byteAt(base + i)
                                           : (in.byteAt(base + 2 * i) << 8) | in.byteAt(base + 2 * i + 1);
      checkValue(v, i);
      image.pixels[i] = static_cast<std::uint16_t>(v);
    }
  } else {
    // Every ASCII sample takes at least one byte: bounds the allocation by the file's size.
    if (in.remaining() < count) {
      in.fail("truncated PGM: " + std::to_string(image.width) + " x " + std::to_string(image.height) +
              " pixels cannot fit in the " + std::to_string(in.remaining()) + " bytes left");
    }
    image.pixels.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      const long v = in.readNumber("pixel " + std::to_string(i) + " of " + std::to_string(count), 0, 65535);
      checkValue(v, i);
      image.pixels[i] = static_cast<std::uint16_t>(v);
    }
  }
  return image;
}

PgmImage loadPgm(const std::filesystem::path& path) { return parsePgm(readFile(path, "PGM image"), path.string()); }

RosMapInfo parseRosMapInfo(const std::string& yaml_text, const std::string& source,
                           const std::filesystem::path& base_dir) {
  return io::readAs<MapError>(source, [&] { return readRosMapInfo(io::ConfigDocument::parse(yaml_text, source, base_dir).root(), false); });
}

RosMapInfo loadRosMapInfo(const std::filesystem::path& yaml_path) {
  const std::string source = yaml_path.string();
  return io::readAs<MapError>(source, [&] {
    const std::string text = io::ConfigDocument::readFile(yaml_path, "map YAML");
    return readRosMapInfo(io::ConfigDocument::parse(text, source, yaml_path.parent_path()).root(), true);
  });
}

OccupancyGrid classifyImage(const PgmImage& image, const RosMapInfo& info) {
  OccupancyGrid grid;
  grid.width = image.width;
  grid.height = image.height;
  grid.resolution = info.resolution;
  grid.origin = info.origin;
  grid.cells.resize(image.pixels.size());
  const double maxval = image.maxval;
  for (int row = 0; row < image.height; ++row) {
    // Image row 0 is the top of the map; grid row 0 is the bottom.
    const std::uint16_t* src = image.pixels.data() + static_cast<std::size_t>(image.height - 1 - row) * image.width;
    std::uint8_t* dst = grid.cells.data() + static_cast<std::size_t>(row) * image.width;
    for (int col = 0; col < image.width; ++col) {
      const double value = info.negate ? maxval - src[col] : src[col];
      double occ;
      if (info.mode == RosMapInfo::Mode::kRaw) {
        if (value > 100.0) {
          dst[col] = OccupancyGrid::kUnknown;
          continue;
        }
        occ = value / 100.0;
      } else {
        occ = (maxval - value) / maxval;  // darker is more occupied
      }
      dst[col] = occ > info.occupied_thresh ? OccupancyGrid::kOccupied
                 : occ < info.free_thresh   ? OccupancyGrid::kFree
                                            : OccupancyGrid::kUnknown;
    }
  }
  return grid;
}

OccupancyGrid loadOccupancyGrid(const std::filesystem::path& yaml_path) {
  const RosMapInfo info = loadRosMapInfo(yaml_path);
  return classifyImage(loadPgm(info.image), info);
}

PolygonMap importOccupancyGrid(const OccupancyGrid& grid, const ImportOptions& options, const std::string& name) {
  PolygonMap map;
  map.name = name;

  cl::Paths rings = traceBlockedBoundaries(grid);
  if (options.simplify_m > 0.0) {
    rings = simplifyRings(rings, options.simplify_m / grid.resolution * static_cast<double>(kSub));
    rings = reuniteSimplified(rings);
  }
  cl::PolyTree tree;
  {
    cl::Clipper clipper;
    clipper.StrictlySimple(true);
    clipper.AddPaths(rings, cl::ptSubject, true);
    clipper.Execute(cl::ctUnion, tree, cl::pftNonZero, cl::pftNonZero);
  }
  std::vector<PolygonWithHoles> regions;
  collectRegions(tree, grid, regions);
  map.obstacles = removeHoles(regions);

  const double w = grid.width * grid.resolution, h = grid.height * grid.resolution;
  const std::array<Vec2, 4> corners{grid.origin.transform({0.0, 0.0}), grid.origin.transform({w, 0.0}),
                                    grid.origin.transform({w, h}), grid.origin.transform({0.0, h})};
  Box bounds{corners[0], corners[0]};
  for (const Vec2& c : corners) {
    bounds.min = bounds.min.cwiseMin(c);
    bounds.max = bounds.max.cwiseMax(c);
  }
  map.bounds = bounds;
  for (Polygon& corner : outsideCorners(corners)) map.obstacles.push_back(std::move(corner));

  validatePolygonMap(map, "map '" + name + "' imported from an occupancy grid");
  return map;
}

PolygonMap importRosMap(const std::filesystem::path& yaml_path, const ImportOptions& options) {
  const OccupancyGrid grid = loadOccupancyGrid(yaml_path);
  try {
    return importOccupancyGrid(grid, options, yaml_path.stem().string());
  } catch (const MapError& e) {
    throw MapError(yaml_path.string() + ": " + e.what());
  }
}

int defaultBorderCells(double simplify_m, double resolution) {
  // The small slack keeps 0.05 / 0.05 at one cell despite rounding.
  return static_cast<int>(std::ceil(std::max(simplify_m, 0.0) / resolution - 1e-9)) + 1;
}

ImportAgreement measureAgreement(const OccupancyGrid& grid, const PolygonMap& map, int border_cells) {
  const int w = grid.width, h = grid.height;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);

  // Scanline rasterization at the cell centres (even-odd per simple polygon, OR over polygons).
  std::vector<std::uint8_t> inside(n, 0);
  std::vector<std::pair<int, double>> crossings;  // (row, x in cells)
  std::vector<Vec2> q;
  for (const Polygon& poly : map.obstacles) {
    q.clear();
    for (const Vec2& p : poly) q.push_back(grid.origin.inverseTransform(p) / grid.resolution);
    crossings.clear();
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Vec2& a = q[i];
      const Vec2& b = q[(i + 1) % q.size()];
      if (a.y() == b.y()) continue;
      const double ylo = std::min(a.y(), b.y()), yhi = std::max(a.y(), b.y());
      // Rows whose centre r + 0.5 lies in [ylo, yhi): half-open, so a vertex counts once.
      const int r0 = std::max(0, static_cast<int>(std::ceil(ylo - 0.5)));
      const int r1 = std::min(h - 1, static_cast<int>(std::ceil(yhi - 0.5)) - 1);
      for (int r = r0; r <= r1; ++r) {
        const double yc = r + 0.5;
        crossings.emplace_back(r, a.x() + (yc - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
      }
    }
    std::sort(crossings.begin(), crossings.end());
    for (std::size_t i = 0; i + 1 < crossings.size(); i += 2) {
      const int r = crossings[i].first;
      // Cells whose centre c + 0.5 lies in [x0, x1).
      const int c0 = std::max(0, static_cast<int>(std::ceil(crossings[i].second - 0.5)));
      const int c1 = std::min(w - 1, static_cast<int>(std::ceil(crossings[i + 1].second - 0.5)) - 1);
      std::uint8_t* row = inside.data() + static_cast<std::size_t>(r) * w;
      for (int c = c0; c <= c1; ++c) row[c] = 1;
    }
  }

  // Chebyshev distance to the nearest cell of the other class (blocked vs free), found by a
  // breadth-first search from the cells that touch the other class; 0 means farther than any.
  std::vector<int> dist(n, 0);
  std::vector<std::size_t> frontier, next;
  const auto blocked = [&](int c, int r) { return grid.blocked(c, r); };
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      bool touches = false;
      for (int dr = -1; dr <= 1 && !touches; ++dr) {
        for (int dc = -1; dc <= 1 && !touches; ++dc) {
          const int cc = c + dc, rr = r + dr;
          touches = cc >= 0 && cc < w && rr >= 0 && rr < h && blocked(cc, rr) != blocked(c, r);
        }
      }
      if (touches) {
        const std::size_t i = static_cast<std::size_t>(r) * w + c;
        dist[i] = 1;
        frontier.push_back(i);
      }
    }
  }
  for (int d = 2; d <= border_cells && !frontier.empty(); ++d) {
    next.clear();
    for (const std::size_t i : frontier) {
      const int c = static_cast<int>(i % w), r = static_cast<int>(i / w);
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int cc = c + dc, rr = r + dr;
          if (cc < 0 || cc >= w || rr < 0 || rr >= h) continue;
          const std::size_t j = static_cast<std::size_t>(rr) * w + cc;
          if (dist[j] == 0) {
            dist[j] = d;
            next.push_back(j);
          }
        }
      }
    }
    std::swap(frontier, next);
  }

  ImportAgreement result;
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * w + c;
      if (dist[i] != 0 && dist[i] <= border_cells) continue;
      ++result.cells_compared;
      const bool is_blocked = grid.blocked(c, r);
      if (is_blocked == (inside[i] != 0)) {
        ++result.cells_agreeing;
      } else if (is_blocked) {
        ++result.blocked_as_free;
      } else {
        ++result.free_as_blocked;
      }
    }
  }
  if (result.cells_compared > 0) {
    result.fraction = static_cast<double>(result.cells_agreeing) / static_cast<double>(result.cells_compared);
  }
  return result;
}

}  // namespace staa
