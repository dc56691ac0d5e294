#pragma once
// Import of a ROS map_server occupancy map (YAML + PGM) into a polygon map.

#include "map/polygon_map.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace staa {

// The map_server metadata (http://wiki.ros.org/map_server, "YAML format").
// image, resolution and origin are required; negate, the thresholds and mode take
// map_server's usual values when absent.
struct RosMapInfo {
  std::filesystem::path image;          // resolved against the YAML file's folder
  double resolution = 0.05;             // metres per pixel
  Pose2 origin;                         // pose of the lower-left pixel in the map frame
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  enum class Mode { kTrinary, kScale, kRaw } mode = Mode::kTrinary;
};

// The image classified per cell, row 0 at the BOTTOM (map frame y grows with the row).
struct OccupancyGrid {
  int width = 0;
  int height = 0;
  double resolution = 0.05;
  Pose2 origin;
  enum Cell : std::uint8_t { kFree = 0, kOccupied = 1, kUnknown = 2 };
  std::vector<std::uint8_t> cells;  // width * height
  std::uint8_t at(int col, int row) const { return cells[static_cast<std::size_t>(row) * width + col]; }
  // Occupied and unknown cells are both obstacles for the planner.
  bool blocked(int col, int row) const { return at(col, row) != kFree; }
};

// A greyscale PGM image as stored: row 0 is the TOP row.
struct PgmImage {
  int width = 0;
  int height = 0;
  int maxval = 255;
  std::vector<std::uint16_t> pixels;  // width * height, row-major
};

// Parses P5 (binary; 8-bit, or 16-bit big-endian when maxval > 255) and P2 (ASCII) images.
// `source` names the file for errors; malformed or truncated input throws MapError.
// Bounds (docs/ARCHITECTURE.md, "Input bounds"): a PGM file of at most kMaxPgmFileBytes, a
// side of at most kMaxPgmSide pixels, and no more pixels than the file's bytes hold.
inline constexpr std::size_t kMaxPgmFileBytes = 256u << 20;
inline constexpr long kMaxPgmSide = 1 << 16;
PgmImage parsePgm(std::string_view bytes, const std::string& source);
PgmImage loadPgm(const std::filesystem::path& path);  // throws MapError

// Parses map_server YAML text; `image` is resolved against `base_dir` (not checked to exist).
RosMapInfo parseRosMapInfo(const std::string& yaml_text, const std::string& source,
                           const std::filesystem::path& base_dir);
RosMapInfo loadRosMapInfo(const std::filesystem::path& yaml_path);   // throws MapError
// Classifies every pixel per map_server: p = value / maxval, occ = negate ? p : 1 - p;
// occ > occupied_thresh is occupied, occ < free_thresh is free, anything between unknown.
// kScale classifies like kTrinary (the in-between values are unknown for a planner).
// kRaw takes the (negated) value as an occupancy percentage: 0..100 -> occ = value / 100,
// classified with the same thresholds; above 100 (255 is map_server's -1) is unknown.
OccupancyGrid classifyImage(const PgmImage& image, const RosMapInfo& info);
OccupancyGrid loadOccupancyGrid(const std::filesystem::path& yaml_path);  // YAML + PGM, throws MapError

struct ImportOptions {
  double simplify_m = 0.05;  // Douglas-Peucker tolerance in metres (0: keep every pixel corner)
};

// Occupied and unknown cells become obstacles; holes (free rooms inside walls) stay free.
// With simplify_m = 0 the obstacles cover exactly the blocked cells. Otherwise every ring is
// simplified, errs to the blocked side where simplified rings cross, and grows by 2/1024 of a
// cell (turns zero-width touches into overlap). A ring that collapses under simplification
// (under 3 vertices or half its area) is kept exact if it is an obstacle (no post vanishes)
// and closed if it is a free pocket; slivers under 1% of a cell are dropped.
// The result's bounds are the image extent (its bounding box when the origin is rotated,
// with the corners outside the image added as obstacles). The result is validated.
PolygonMap importOccupancyGrid(const OccupancyGrid& grid, const ImportOptions& options, const std::string& name);
PolygonMap importRosMap(const std::filesystem::path& yaml_path, const ImportOptions& options);

// How well the polygons reproduce the grid: every cell centre is rasterized against the
// obstacles (inside any one = blocked) and compared with the cell's blocked/free class,
// over the cells more than `border_cells` (Chebyshev) from a blocked/free transition.
struct ImportAgreement {
  double fraction = 1.0;           // agreeing / compared (1 when nothing is compared)
  std::size_t cells_compared = 0;
  std::size_t cells_agreeing = 0;
  std::size_t blocked_as_free = 0;  // blocked in the grid, outside every polygon
  std::size_t free_as_blocked = 0;  // free in the grid, inside some polygon
};
ImportAgreement measureAgreement(const OccupancyGrid& grid, const PolygonMap& map, int border_cells);
// The border the simplification may move: ceil(simplify_m / resolution) + 1 cells.
int defaultBorderCells(double simplify_m, double resolution);

}  // namespace staa
