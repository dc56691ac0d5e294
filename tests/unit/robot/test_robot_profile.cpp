#include "robot/robot_profile.hpp"

#include "geometry/polygon.hpp"
#include "shared_dir.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <tuple>
#include <vector>
#include <string>

namespace staa {
namespace {

using ::testing::HasSubstr;

std::string errorOf(const std::string& text, const std::string& source = "robot.yaml") {
  try {
    parseRobotProfile(text, source);
  } catch (const ProfileError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ProfileError for:\n" << text;
  return "";
}

// A valid profile with one line replaced.
std::string withLine(const std::string& footprint, const std::string& limits) {
  return "format: staa-robot/1\nname: test\nfootprint: " + footprint + "\nlimits: " + limits + "\n";
}
const std::string kSquare = "[[0.3, 0.3], [-0.3, 0.3], [-0.3, -0.3], [0.3, -0.3]]";
const std::string kLimits = "{v_max: 1.0, v_min: -0.5, w_max: 2.0, a_max: 1.0, b_max: 3.0}";

TEST(RobotProfile, ShippedPaperAgentEqualsPaperAgentProfile) {
  const RobotProfile loaded = loadRobotProfile(test::sourceDir() / "config/robots/paper-agent.yaml");
  const RobotProfile paper = paperAgentProfile();
  EXPECT_EQ(loaded.name, "paper-agent");
  EXPECT_EQ(loaded.name, paper.name);
  ASSERT_EQ(loaded.footprint.size(), 4u);
  ASSERT_EQ(paper.footprint.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(loaded.footprint[k], paper.footprint[k]) << "vertex " << k;
  EXPECT_TRUE(isCounterClockwise(loaded.footprint));
  EXPECT_DOUBLE_EQ(loaded.limits.v_max, 2.0);
  EXPECT_DOUBLE_EQ(loaded.limits.v_min, -1.0);
  EXPECT_DOUBLE_EQ(loaded.limits.w_max, 3.0);
  EXPECT_DOUBLE_EQ(loaded.limits.a_max, 2.0);
  EXPECT_DOUBLE_EQ(loaded.limits.b_max, 6.0);
  // 0.8 m x 0.5 m, front 0.4 m wide: area = 0.8 * (0.4 + 0.5) / 2.
  EXPECT_NEAR(signedArea(loaded.footprint), 0.36, 1e-12);
  EXPECT_NEAR(loaded.circumradius(), std::hypot(0.4, 0.25), 1e-15);
  // The nearest edges are the slanted sides, from (0.4, +-0.2) to (-0.4, +-0.25): the origin
  // lies 0.225 / hypot(0.8, 0.05) * 0.8 from each.
  EXPECT_NEAR(loaded.inscribedRadius(), 0.225 * 0.8 / std::hypot(0.8, 0.05), 1e-12);
  // The body and camera staa-sim --obstacles depth gives it, the same in both.
  EXPECT_EQ(loaded.height_m, paper.height_m);
  ASSERT_TRUE(loaded.has_camera);
  ASSERT_TRUE(paper.has_camera);
  const DepthCameraProfile& a = loaded.camera;
  const DepthCameraProfile& b = paper.camera;
  for (const auto& [name, x, y] : std::vector<std::tuple<const char*, double, double>>{
           {"x", a.x, b.x}, {"y", a.y, b.y}, {"z", a.z, b.z}, {"roll", a.roll, b.roll}, {"pitch", a.pitch, b.pitch},
           {"yaw", a.yaw, b.yaw}, {"fov_h", a.fov_h_deg, b.fov_h_deg}, {"fov_v", a.fov_v_deg, b.fov_v_deg},
           {"min_range", a.min_range_m, b.min_range_m}, {"max_range", a.max_range_m, b.max_range_m},
           {"rate", a.rate_hz, b.rate_hz}, {"noise", a.noise_mm_per_m2, b.noise_mm_per_m2},
           {"dropout", a.dropout, b.dropout}, {"grazing", a.grazing_deg, b.grazing_deg},
           {"frame_loss", a.frame_loss, b.frame_loss}, {"latency", a.latency_s, b.latency_s},
           {"pan_max", a.pan_max, b.pan_max}, {"pan_rate", a.pan_rate, b.pan_rate},
           {"look_ahead", a.look_ahead_m, b.look_ahead_m}, {"scan", a.scan, b.scan}}) {
    EXPECT_EQ(x, y) << name;
  }
  // An Xtion: 58 x 45 degrees, 1 m up looking 0.3 rad down, one 30 Hz frame of latency.
  EXPECT_EQ(a.fov_h_deg, 58.0);
  EXPECT_EQ(a.fov_v_deg, 45.0);
  EXPECT_EQ(a.z, 1.0);
  EXPECT_EQ(a.pitch, 0.3);
  EXPECT_EQ(a.latency_s, 1.0 / 30.0);
}

TEST(RobotProfile, ShippedHsrHasItsHeadCamera) {
  const RobotProfile hsr = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  ASSERT_TRUE(hsr.has_camera);
  EXPECT_EQ(hsr.camera.z, 1.0);
  EXPECT_EQ(hsr.camera.pitch, 0.3);
  EXPECT_EQ(hsr.camera.fov_h_deg, 58.0);
  EXPECT_GT(hsr.camera.pan_max, 0.0);
  EXPECT_EQ(hsr.height_m, 1.0);
}

TEST(RobotProfile, CameraSectionIsOptionalAndItsDefaultsApply) {
  const RobotProfile none = parseRobotProfile(withLine(kSquare, kLimits), "r.yaml");
  EXPECT_FALSE(none.has_camera);
  EXPECT_EQ(none.height_m, 1.0);
  const RobotProfile some = parseRobotProfile(
      withLine(kSquare, kLimits) + "height: 1.4\ncamera:\n  mount: {z: 1.2, pitch: 0.4}\n  fov_deg: [60, 49.5]\n"
                                   "  range_m: [0.6, 5]\n",
      "r.yaml");
  EXPECT_EQ(some.height_m, 1.4);
  ASSERT_TRUE(some.has_camera);
  EXPECT_EQ(some.camera.z, 1.2);
  EXPECT_EQ(some.camera.pitch, 0.4);
  EXPECT_EQ(some.camera.x, 0.0);
  EXPECT_EQ(some.camera.fov_h_deg, 60.0);
  EXPECT_EQ(some.camera.fov_v_deg, 49.5);
  EXPECT_EQ(some.camera.min_range_m, 0.6);
  EXPECT_EQ(some.camera.max_range_m, 5.0);
  EXPECT_EQ(some.camera.pan_max, 0.0);  // no head section: a fixed camera
  const DepthCameraProfile defaults;
  EXPECT_EQ(some.camera.noise_mm_per_m2, defaults.noise_mm_per_m2);
  EXPECT_EQ(some.camera.dropout, defaults.dropout);
  EXPECT_EQ(some.camera.latency_s, defaults.latency_s);
}

TEST(RobotProfile, EachBadCameraValueNamesItsKeyLineAndValue) {
  const std::string base = withLine(kSquare, kLimits) + "camera:\n";
  const std::string fov = "  fov_deg: [58, 45]\n";
  const std::string range = "  range_m: [0.5, 4.5]\n";
  const std::string mount = "  mount: {z: 1.0}\n";
  EXPECT_THAT(errorOf(base + "  mount: {z: 0}\n" + fov + range), HasSubstr("robot.yaml:6: camera.mount.z: must be > 0 m"));
  EXPECT_THAT(errorOf(base + "  mount: {z: 1, pitch: 17}\n" + fov + range),
              HasSubstr("camera.mount.pitch: must be in [-3.14159"));
  EXPECT_THAT(errorOf(base + mount + "  fov_deg: [58]\n" + range), HasSubstr("camera.fov_deg: expected [horizontal, vertical] degrees"));
  EXPECT_THAT(errorOf(base + mount + "  fov_deg: [180, 45]\n" + range), HasSubstr("camera.fov_deg[0]: must be in [1, 170) degrees, got 180"));
  EXPECT_THAT(errorOf(base + mount + fov + "  range_m: [2, 1]\n"), HasSubstr("camera.range_m[1]: must be in (2, 65.535] m"));
  EXPECT_THAT(errorOf(base + mount + fov + range + "  dropout: 1\n"), HasSubstr("camera.dropout: must be in [0, 1)"));
  EXPECT_THAT(errorOf(base + mount + fov + range + "  grazing_deg: 95\n"), HasSubstr("camera.grazing_deg: must be in (0, 90] degrees, got 95"));
  EXPECT_THAT(errorOf(base + mount + fov + range + "  head: {pan_rate: 1}\n"), HasSubstr("camera.head.pan_max: missing"));
  EXPECT_THAT(errorOf(base + mount + fov + range + "  exposure: 3\n"), HasSubstr("camera.exposure: unknown key"));
  EXPECT_THAT(errorOf(base + fov + range), HasSubstr("camera.mount: missing"));
  // A mount far off the base would need a perception grid beyond its bound; a latency beyond
  // the frames staa-sim keeps in flight: both are the profile's errors, not a failed run.
  EXPECT_THAT(errorOf(base + "  mount: {x: 11, z: 1}\n" + fov + range),
              HasSubstr("robot.yaml:6: camera.mount.x: must be in [-10, 10] m (on the base), got 11"));
  EXPECT_EQ(parseRobotProfile(withLine(kSquare, kLimits) + "camera:\n  mount: {y: -10, z: 1}\n" + fov + range, "r.yaml")
                .camera.y,
            -10.0);
  const std::string latency = errorOf(base + mount + fov + range + "  rate_hz: 30\n  latency_s: 0.5\n");
  EXPECT_THAT(latency, HasSubstr("camera.latency_s: must be in [0, 0.23"));
  EXPECT_THAT(latency, HasSubstr("7 frames at rate_hz), got 0.5"));
  EXPECT_EQ(parseRobotProfile(withLine(kSquare, kLimits) + "camera:\n" + mount + fov + range + "  rate_hz: 10\n"
                                  "  latency_s: 0.7\n",
                              "r.yaml")
                .camera.latency_s,
            0.7);  // 7 frames at 10 Hz
  EXPECT_THAT(errorOf(withLine(kSquare, kLimits) + "height: -1\n"), HasSubstr("robot.yaml:5: height: must be > 0 m, got -1"));
}

TEST(RobotProfile, ShippedHsrIsARound16GonOfRadius0215) {
  const RobotProfile hsr = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  EXPECT_EQ(hsr.name, "hsr");
  ASSERT_EQ(hsr.footprint.size(), 16u);
  EXPECT_TRUE(isCounterClockwise(hsr.footprint));
  for (const Vec2& p : hsr.footprint) EXPECT_NEAR(p.norm(), 0.215, 1e-6);
  EXPECT_NEAR(hsr.circumradius(), 0.215, 1e-6);
  // A 16-gon's edges lie cos(pi / 16) of the way out: 0.2109 m, within 5 mm of round.
  EXPECT_NEAR(hsr.inscribedRadius(), 0.215 * std::cos(kPi / 16.0), 1e-6);
  EXPECT_NEAR(hsr.limits.v_max, 0.22, 1e-12);  // 0.8 km/h, rounded down
  EXPECT_NEAR(hsr.limits.v_min, -0.22, 1e-12);
  EXPECT_GT(hsr.limits.w_max, 0.0);
  EXPECT_GT(hsr.limits.a_max, 0.0);
  EXPECT_GT(hsr.limits.b_max, 0.0);
}

TEST(RobotProfile, ClockwiseFootprintIsStoredCounterClockwise) {
  const RobotProfile p = parseRobotProfile(withLine("[[0.3, 0.3], [0.3, -0.3], [-0.3, -0.3], [-0.3, 0.3]]", kLimits), "cw.yaml");
  EXPECT_TRUE(isCounterClockwise(p.footprint));
  EXPECT_EQ(p.name, "test");
  EXPECT_NEAR(p.circumradius(), std::hypot(0.3, 0.3), 1e-15);
  EXPECT_NEAR(p.inscribedRadius(), 0.3, 1e-15);
}

TEST(RobotProfile, NameDefaultsToTheFileStem) {
  const RobotProfile p = parseRobotProfile("format: staa-robot/1\nfootprint: " + kSquare + "\nlimits: " + kLimits, "/x/my-bot.yaml");
  EXPECT_EQ(p.name, "my-bot");
}

TEST(RobotProfile, UnknownFormatNamesFileKeyAndValue) {
  const std::string e = errorOf("format: staa-robot/2\nfootprint: " + kSquare + "\nlimits: " + kLimits, "bot.yaml");
  EXPECT_THAT(e, HasSubstr("bot.yaml"));
  EXPECT_THAT(e, HasSubstr("format"));
  EXPECT_THAT(e, HasSubstr("staa-robot/2"));
}

TEST(RobotProfile, FootprintWithTwoVerticesIsRejected) {
  const std::string e = errorOf(withLine("[[0.3, 0.3], [-0.3, -0.3]]", kLimits));
  EXPECT_THAT(e, HasSubstr("robot.yaml:3: footprint"));
  EXPECT_THAT(e, HasSubstr("has 2 vertices"));
}

TEST(RobotProfile, NonFiniteVertexIsRejected) {
  const std::string e = errorOf(withLine("[[0.3, 0.3], [-0.3, .nan], [-0.3, -0.3], [0.3, -0.3]]", kLimits));
  EXPECT_THAT(e, HasSubstr("footprint[1]"));
  EXPECT_THAT(e, HasSubstr("robot.yaml:3: footprint[1][1]: must be finite"));
  EXPECT_THAT(e, HasSubstr("nan"));
  const std::string e2 = errorOf(withLine("[[0.3, 0.3], [-0.3, abc], [-0.3, -0.3], [0.3, -0.3]]", kLimits));
  EXPECT_THAT(e2, HasSubstr("footprint[1]"));
  EXPECT_THAT(e2, HasSubstr("footprint[1][1]: expected a number, got 'abc'"));
}

TEST(RobotProfile, SelfIntersectingFootprintIsRejected) {
  // A bow tie through the origin.
  const std::string e = errorOf(withLine("[[0.3, 0.3], [-0.3, -0.3], [-0.3, 0.3], [0.3, -0.3]]", kLimits));
  EXPECT_THAT(e, HasSubstr("robot.yaml:3: footprint"));
  EXPECT_THAT(e, HasSubstr("self-intersecting"));
}

// Found by the robot_profile fuzzer: vertices near 1e307 m made a simple footprint whose area
// overflowed (not counter-clockwise by signedArea). A footprint is a base's: within 10 m.
TEST(RobotProfile, AFootprintVertexBeyond10mIsRejectedWithItsIndexAndValue) {
  const std::string far = errorOf(withLine("[[0.3, 0.3], [-10.5, 0.3], [-0.3, -0.3], [0.3, -0.3]]", kLimits));
  EXPECT_THAT(far, HasSubstr("robot.yaml:3: footprint[1]: vertex 1 (-10.5, 0.3) is beyond 10 m of the robot's origin"));
  // The fuzzer's input (tests/fuzz/regressions/robot_profile): simple, holds the origin.
  const std::string huge = errorOf(withLine(
      "[[0.215, 0.0], [0.198634, 720807.2], [0.15202, 82277], [-0.1521e308, 2028], [5.19864, -6666082277], "
      "[-0.1501e308, 28]]",
      kLimits));
  EXPECT_THAT(huge, HasSubstr("footprint[1]: vertex 1 (0.198634, 720807) is beyond 10 m"));
  // At the bound: a 20 m long vehicle loads, counter-clockwise.
  const RobotProfile p = parseRobotProfile(withLine("[[10, -1], [10, 1], [-10, 1], [-10, -1]]", kLimits), "robot.yaml");
  EXPECT_DOUBLE_EQ(p.circumradius(), std::hypot(10.0, 1.0));
  EXPECT_GT(signedArea(p.footprint), 0.0);
}

TEST(RobotProfile, FootprintNotContainingTheOriginIsRejected) {
  const std::string e = errorOf(withLine("[[1, 1], [2, 1], [2, 2], [1, 2]]", kLimits));
  EXPECT_THAT(e, HasSubstr("robot.yaml:3: footprint"));
  EXPECT_THAT(e, HasSubstr("origin"));
  // On the boundary is not inside either.
  EXPECT_THAT(errorOf(withLine("[[0, 0], [1, 0], [1, 1], [0, 1]]", kLimits)), HasSubstr("origin"));
}

TEST(RobotProfile, MissingLimitsAreRejected) {
  EXPECT_THAT(errorOf("format: staa-robot/1\nfootprint: " + kSquare + "\n"), HasSubstr("robot.yaml: limits: missing"));
  const std::string e = errorOf(withLine(kSquare, "{v_max: 1.0, v_min: -0.5, w_max: 2.0, a_max: 1.0}"));
  EXPECT_THAT(e, HasSubstr("limits.b_max: missing"));
}

TEST(RobotProfile, EachBadLimitNamesKeyAndValue) {
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: -1, v_min: -0.5, w_max: 2.0, a_max: 1.0, b_max: 3.0}")),
              HasSubstr("robot.yaml:4: limits.v_max: must be > 0, got -1"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 0, v_min: -0.5, w_max: 2.0, a_max: 1.0, b_max: 3.0}")),
              HasSubstr("limits.v_max: must be > 0, got 0"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 1, v_min: 0.25, w_max: 2.0, a_max: 1.0, b_max: 3.0}")),
              HasSubstr("limits.v_min: must be <= 0 (it is the backward limit), got 0.25"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 1, v_min: -0.5, w_max: 0, a_max: 1.0, b_max: 3.0}")),
              HasSubstr("limits.w_max: must be > 0, got 0"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 1, v_min: -0.5, w_max: 2, a_max: -2, b_max: 3.0}")),
              HasSubstr("limits.a_max: must be > 0, got -2"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 1, v_min: -0.5, w_max: 2, a_max: 1, b_max: -0.5}")),
              HasSubstr("limits.b_max: must be > 0, got -0.5"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: .inf, v_min: -0.5, w_max: 2, a_max: 1, b_max: 3}")),
              HasSubstr("limits.v_max: must be finite, got .inf"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: fast, v_min: -0.5, w_max: 2, a_max: 1, b_max: 3}")),
              HasSubstr("limits.v_max: expected a number, got 'fast'"));
  // A zero backward limit is allowed: a robot that cannot reverse.
  EXPECT_NO_THROW(parseRobotProfile(withLine(kSquare, "{v_max: 1, v_min: 0, w_max: 2, a_max: 1, b_max: 3}"), "r.yaml"));
}

TEST(RobotProfile, UnknownKeysAreRejected) {
  EXPECT_THAT(errorOf(withLine(kSquare, kLimits) + "wheelbase: 0.3\n"), HasSubstr("robot.yaml:5: wheelbase: unknown key"));
  EXPECT_THAT(errorOf(withLine(kSquare, "{v_max: 1, v_min: -0.5, w_max: 2, a_max: 1, b_max: 3, j_max: 9}")),
              HasSubstr("robot.yaml:4: limits.j_max: unknown key"));
}

TEST(RobotProfile, LoadNamesAMissingFile) {
  try {
    loadRobotProfile("/nonexistent/dir/robot.yaml");
    FAIL() << "no error";
  } catch (const ProfileError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("/nonexistent/dir/robot.yaml"));
  }
}

}  // namespace
}  // namespace staa

namespace staa {
namespace {

TEST(RobotProfile, ShippedProfilesHaveTheirBaseScanner) {
  const RobotProfile hsr = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  ASSERT_TRUE(hsr.has_scanner);
  EXPECT_EQ(hsr.scanner.x, 0.1675);  // base_range_sensor_joint
  EXPECT_EQ(hsr.scanner.z, 0.1844);
  EXPECT_EQ(hsr.scanner.fov_deg, 270.0);
  EXPECT_EQ(hsr.scanner.beams, 1081);
  // The paper agent's, the same from its file and from code.
  const RobotProfile loaded = loadRobotProfile(test::sourceDir() / "config/robots/paper-agent.yaml");
  const RobotProfile paper = paperAgentProfile();
  ASSERT_TRUE(loaded.has_scanner);
  ASSERT_TRUE(paper.has_scanner);
  const ScannerProfile& a = loaded.scanner;
  const ScannerProfile& b = paper.scanner;
  for (const auto& [name, x, y] : std::vector<std::tuple<const char*, double, double>>{
           {"x", a.x, b.x}, {"y", a.y, b.y}, {"z", a.z, b.z}, {"yaw", a.yaw, b.yaw}, {"fov", a.fov_deg, b.fov_deg},
           {"beams", a.beams, b.beams}, {"min_range", a.min_range_m, b.min_range_m},
           {"max_range", a.max_range_m, b.max_range_m}, {"noise", a.noise_m, b.noise_m}, {"dropout", a.dropout, b.dropout}}) {
    EXPECT_EQ(x, y) << name;
  }
  EXPECT_EQ(a.z, 0.2);
  EXPECT_EQ(a.dropout, 0.01);
}

TEST(RobotProfile, EachBadScannerValueNamesItsKeyLineAndValue) {
  const std::string base = withLine(kSquare, kLimits) + "scanner:\n";
  const std::string mount = "  mount: {z: 0.2}\n";
  const RobotProfile none = parseRobotProfile(withLine(kSquare, kLimits), "r.yaml");
  EXPECT_FALSE(none.has_scanner);
  const RobotProfile some = parseRobotProfile(base + mount + "  fov_deg: 180\n  beams: 721\n", "r.yaml");
  ASSERT_TRUE(some.has_scanner);
  EXPECT_EQ(some.scanner.fov_deg, 180.0);
  EXPECT_EQ(some.scanner.beams, 721);
  EXPECT_EQ(some.scanner.max_range_m, ScannerProfile{}.max_range_m);
  EXPECT_THAT(errorOf(base + "  mount: {z: 0}\n"), HasSubstr("robot.yaml:6: scanner.mount.z: must be > 0 m"));
  EXPECT_THAT(errorOf(base + "  mount: {x: 0.1}\n"), HasSubstr("scanner.mount.z: missing"));
  EXPECT_THAT(errorOf(base + mount + "  fov_deg: 400\n"), HasSubstr("scanner.fov_deg: must be in [1, 360] degrees, got 400"));
  EXPECT_THAT(errorOf(base + mount + "  beams: 5000\n"), HasSubstr("scanner.beams: must be an integer in 2..2048"));
  EXPECT_THAT(errorOf(base + mount + "  beams: 10.5\n"), HasSubstr("scanner.beams"));
  EXPECT_THAT(errorOf(base + mount + "  range_m: [2, 1]\n"), HasSubstr("scanner.range_m[1]: must be in (2, 100] m"));
  EXPECT_THAT(errorOf(base + mount + "  noise_m: -1\n"), HasSubstr("scanner.noise_m: must be in [0, 1] m"));
  EXPECT_THAT(errorOf(base + mount + "  dropout: 1\n"), HasSubstr("scanner.dropout: must be in [0, 1)"));
  EXPECT_THAT(errorOf(base + mount + "  rate: 40\n"), HasSubstr("scanner.rate: unknown key"));
}

}  // namespace
}  // namespace staa
