#pragma once
// Import of a ROS map_server occupancy map (YAML + PGM) into a polygon map.

#include "map/polygon_map.hpp"

#include <cstdint>
#include <filesystem>
#include <vector>

namespace staa {

// The map_server metadata (http://wiki.ros.org/map_server, "YAML format").
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
};

RosMapInfo loadRosMapInfo(const std::filesystem::path& yaml_path);   // throws MapError
OccupancyGrid loadOccupancyGrid(const std::filesystem::path& yaml_path);  // YAML + PGM, throws MapError

struct ImportOptions {
  double simplify_m = 0.05;  // Douglas-Peucker tolerance in metres (0: keep every pixel corner)
};

// Occupied and unknown cells become obstacles; holes (free rooms inside walls) stay free.
PolygonMap importOccupancyGrid(const OccupancyGrid& grid, const ImportOptions& options, const std::string& name);
PolygonMap importRosMap(const std::filesystem::path& yaml_path, const ImportOptions& options);

}  // namespace staa
