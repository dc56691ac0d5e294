// The daemon's side of the ROS link without a ROS master: OccupancyGrid values into the
// importer of `staa-map import`.
#include "app/staad/ros_bridge.hpp"

#include "map/ros_import.hpp"
#include "shared_dir.hpp"

#include <gtest/gtest.h>
#include <gmock/gmock.h>

#include <stdexcept>
#include <string>

namespace staa::staad {
namespace {

using ::testing::HasSubstr;

// map_server's message for a classified grid: 100 occupied, 0 free, -1 unknown.
ros::GridSample messageOf(const OccupancyGrid& grid) {
  ros::GridSample g;
  g.frame_id = "map";
  g.width = static_cast<std::uint32_t>(grid.width);
  g.height = static_cast<std::uint32_t>(grid.height);
  g.resolution = grid.resolution;
  g.origin_x = grid.origin.x;
  g.origin_y = grid.origin.y;
  g.origin_yaw = grid.origin.theta;
  for (std::uint8_t c : grid.cells) {
    g.data.push_back(c == OccupancyGrid::kOccupied ? 100 : c == OccupancyGrid::kFree ? 0 : -1);
  }
  return g;
}

std::string errorOf(const ros::GridSample& g) {
  try {
    occupancyGridFrom(g, 0.65, 0.196);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(RosMapGrid, ValuesAreClassifiedWithMapServersThresholds) {
  ros::GridSample g;
  g.width = 6;
  g.height = 1;
  g.resolution = 0.05;
  g.data = {-1, 0, 19, 20, 66, 100};
  const OccupancyGrid o = occupancyGridFrom(g, 0.65, 0.196);
  ASSERT_EQ(o.cells.size(), 6u);
  EXPECT_EQ(o.cells[0], OccupancyGrid::kUnknown);
  EXPECT_EQ(o.cells[1], OccupancyGrid::kFree);
  EXPECT_EQ(o.cells[2], OccupancyGrid::kFree);     // 0.19 < 0.196
  EXPECT_EQ(o.cells[3], OccupancyGrid::kUnknown);  // between the thresholds
  EXPECT_EQ(o.cells[4], OccupancyGrid::kOccupied);
  EXPECT_EQ(o.cells[5], OccupancyGrid::kOccupied);
  EXPECT_EQ(o.width, 6);
  EXPECT_DOUBLE_EQ(o.resolution, 0.05);
}

TEST(RosMapGrid, AMalformedGridIsRefusedWithWhatIsWrong) {
  ros::GridSample g;
  g.width = 3;
  g.height = 2;
  g.resolution = 0.05;
  g.data = {0, 0, 0, 0, 0};
  EXPECT_THAT(errorOf(g), HasSubstr("5 cells, its info says 3 x 2 = 6"));
  g.data.push_back(0);
  g.resolution = 0.0;
  EXPECT_THAT(errorOf(g), HasSubstr("resolution must be a positive number"));
  g.resolution = 0.05;
  g.origin_x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(errorOf(g), HasSubstr("origin is not finite"));
  g = ros::GridSample{};
  EXPECT_THAT(errorOf(g), HasSubstr("empty (0 x 0)"));
}

// The map staad plans on from /map is the one `staa-map import` makes of the same file.
TEST(RosMapGrid, TheDepotFromTheTopicImportsAsStaaMapImportsItsFile) {
  const std::filesystem::path yaml = test::sharedDir() / "maps/ros/depot.yaml";
  STAA_REQUIRE_SHARED_FILE(yaml);
  const OccupancyGrid file_grid = loadOccupancyGrid(yaml);
  const OccupancyGrid topic_grid = occupancyGridFrom(messageOf(file_grid), 0.65, 0.196);
  EXPECT_EQ(topic_grid.cells, file_grid.cells);
  const ImportOptions options;
  const PolygonMap from_file = importRosMap(yaml, options);
  const PolygonMap from_topic = importOccupancyGrid(topic_grid, options, "/map");
  ASSERT_EQ(from_topic.obstacles.size(), from_file.obstacles.size());
  for (std::size_t i = 0; i < from_file.obstacles.size(); ++i) {
    ASSERT_EQ(from_topic.obstacles[i], from_file.obstacles[i]) << "obstacle " << i;
  }
  ASSERT_TRUE(from_file.bounds.has_value());
  ASSERT_TRUE(from_topic.bounds.has_value());
  EXPECT_EQ(from_topic.bounds->min, from_file.bounds->min);
  EXPECT_EQ(from_topic.bounds->max, from_file.bounds->max);
  EXPECT_GT(from_file.obstacles.size(), 100u);
}

}  // namespace
}  // namespace staa::staad
