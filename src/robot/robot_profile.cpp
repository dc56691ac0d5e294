#include "robot/robot_profile.hpp"

#include "io/config_reader.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <string_view>

namespace staa {
namespace {

constexpr std::string_view kFormat = "staa-robot/1";

Polygon readFootprint(const io::ConfigValue& node) {
  Polygon poly = node.polygon();
  // The robot's reference point (its pose) must lie strictly inside its own body: the
  // planner's centroid/corner checks and the circumradius inflation assume it.
  if (locatePoint(Vec2::Zero(), poly) != Containment::kInside) node.fail("does not contain the robot's origin (0, 0) strictly inside");
  if (!isCounterClockwise(poly)) std::reverse(poly.begin(), poly.end());
  return poly;
}

MotionLimits readLimits(const io::ConfigValue& node) {
  node.mapping({"v_max", "v_min", "w_max", "a_max", "b_max"});
  const io::Range positive = io::Range::above(0.0);
  MotionLimits lim;
  lim.v_max = node.required("v_max").number(positive);
  lim.v_min = node.required("v_min").number(io::Range::atMost(0.0, {}, "it is the backward limit"));
  lim.w_max = node.required("w_max").number(positive);
  lim.a_max = node.required("a_max").number(positive);
  lim.b_max = node.required("b_max").number(positive);
  return lim;
}

}  // namespace

double RobotProfile::circumradius() const {
  // The origin is inside the footprint, so the farthest point of the polygon is a vertex.
  double r = 0.0;
  for (const Vec2& p : footprint) r = std::max(r, p.norm());
  return r;
}

double RobotProfile::inscribedRadius() const { return distanceToEdges(Vec2::Zero(), footprint); }

RobotProfile parseRobotProfile(const std::string& yaml_text, const std::string& source) {
  return io::readAs<ProfileError>(source, [&] {
    const io::ConfigDocument doc = io::ConfigDocument::parse(yaml_text, source);
    const io::ConfigValue& root = doc.root(kFormat, {"format", "name", "footprint", "limits"});
    RobotProfile profile;
    const io::ConfigValue name = root.get("name");
    profile.name = name.present() ? name.string("a string") : std::filesystem::path(source).stem().string();
    profile.footprint = readFootprint(root.required("footprint", "a list of [x, y] vertices in the robot frame"));
    profile.limits = readLimits(root.required("limits", "{v_max, v_min, w_max, a_max, b_max}"));
    return profile;
  });
}

RobotProfile loadRobotProfile(const std::filesystem::path& path) {
  const std::string source = path.string();
  return io::readAs<ProfileError>(source, [&] { return parseRobotProfile(io::ConfigDocument::readFile(path, "robot profile"), source); });
}

RobotProfile paperAgentProfile() {
  RobotProfile p;
  p.name = "paper-agent";
  // docs/paper-worlds.md, "The agent", in the paper's (clockwise) order, stored counter-clockwise.
  p.footprint = {{0.4, 0.2}, {0.4, -0.2}, {-0.4, -0.25}, {-0.4, 0.25}};
  std::reverse(p.footprint.begin(), p.footprint.end());
  p.limits = MotionLimits{2.0, -1.0, 3.0, 2.0, 6.0};
  return p;
}

}  // namespace staa
