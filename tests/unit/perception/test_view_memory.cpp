// Where the camera has looked lately (ViewMemory): the bins within the view are stamped, the
// others keep their last look; across +-pi too.
#include "perception/view_memory.hpp"

#include "geometry/types.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace staa {
namespace {

constexpr double kDeg = kPi / 180.0;

TEST(ViewMemory, RemembersWhenEachDirectionWasLastInView) {
  ViewMemory m;
  EXPECT_EQ(m.unseenFor(0.0, 0.0), std::numeric_limits<double>::infinity());
  m.look(1.0, 0.0, 29.0 * kDeg);  // looking along +x, 58 degrees wide
  EXPECT_EQ(m.unseenFor(1.5, 0.0), 0.5);
  EXPECT_EQ(m.unseenFor(1.5, 20.0 * kDeg), 0.5);
  EXPECT_EQ(m.unseenFor(1.5, -20.0 * kDeg), 0.5);
  EXPECT_EQ(m.unseenFor(1.5, 40.0 * kDeg), std::numeric_limits<double>::infinity());
  EXPECT_EQ(m.unseenFor(1.5, kPi), std::numeric_limits<double>::infinity());
  // Looking back across +-pi later: both sides of it, the front keeps its older look.
  m.look(2.0, kPi, 29.0 * kDeg);
  EXPECT_EQ(m.unseenFor(2.0, 175.0 * kDeg), 0.0);
  EXPECT_EQ(m.unseenFor(2.0, -175.0 * kDeg), 0.0);
  EXPECT_EQ(m.unseenFor(2.0, 0.0), 1.0);
  EXPECT_EQ(m.unseenFor(2.0, kPi / 2.0), std::numeric_limits<double>::infinity());
  m.clear();
  EXPECT_EQ(m.unseenFor(2.0, kPi), std::numeric_limits<double>::infinity());
}

TEST(ViewMemory, ABinCountsAsSeenWhenItsCentreIsInTheView) {
  ViewMemory m;
  // Bins are 5 degrees from -180: the bin [0, 5) has its centre at 2.5 degrees.
  m.look(1.0, 0.0, 2.4 * kDeg);
  EXPECT_EQ(m.unseenFor(1.0, 1.0 * kDeg), std::numeric_limits<double>::infinity());
  m.look(1.0, 0.0, 2.6 * kDeg);
  EXPECT_EQ(m.unseenFor(1.0, 1.0 * kDeg), 0.0);
  EXPECT_EQ(m.unseenFor(1.0, -1.0 * kDeg), 0.0);
  EXPECT_EQ(m.unseenFor(1.0, 6.0 * kDeg), std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace staa
