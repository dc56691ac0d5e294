// parsePgm on any bytes, then classifyImage and importOccupancyGrid on what parses: the
// pixels are width * height values <= maxval, the grid has a cell per pixel, and the
// imported map validates. Errors: MapError from the parser only (an image that parses imports).
#include "fuzz_support.hpp"
#include "map/ros_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace staa;
  PgmImage image;
  try {
    image = parsePgm(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.pgm");
  } catch (const MapError&) {
    return 0;
  }
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  fuzz::require(image.width > 0 && image.height > 0 && image.pixels.size() == pixels, "pixel count != width * height");
  fuzz::require(image.maxval >= 1 && image.maxval <= 65535, "maxval out of 1..65535");
  for (const std::uint16_t p : image.pixels) fuzz::require(p <= image.maxval, "a pixel above maxval");

  // Each mode in turn; the last byte picks negate.
  for (const RosMapInfo::Mode mode : {RosMapInfo::Mode::kTrinary, RosMapInfo::Mode::kScale, RosMapInfo::Mode::kRaw}) {
    RosMapInfo info;
    info.image = "fuzz.pgm";
    info.mode = mode;
    info.negate = size > 0 && (data[size - 1] & 1) != 0;
    const OccupancyGrid grid = classifyImage(image, info);
    fuzz::require(grid.width == image.width && grid.height == image.height && grid.cells.size() == pixels,
                  "grid size != image size");
    for (const std::uint8_t c : grid.cells) fuzz::require(c <= OccupancyGrid::kUnknown, "a cell of no class");
    // Tracing is quadratic in the worst case: only small images (the parser is the target).
    if (pixels > 64 * 64) continue;
    for (const double simplify_m : {0.0, 0.05}) {
      try {
        const PolygonMap map = importOccupancyGrid(grid, ImportOptions{simplify_m}, "fuzz");
        validatePolygonMap(map, "fuzz import");
      } catch (const MapError& e) {
        fuzz::violated("a parsed image does not import to a valid map", e.what());
      }
    }
  }
  return 0;
}
