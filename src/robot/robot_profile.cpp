#include "robot/robot_profile.hpp"

#include "io/yaml_support.hpp"

#include "geometry/polygon.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>

namespace staa {
namespace {

constexpr std::string_view kFormat = "staa-robot/1";

using yaml_support::describe;
using yaml_support::lineOf;
using yaml_support::readNumber;
std::string number(double v) { return yaml_support::formatNumber(v); }
std::string point(const Vec2& p) { return yaml_support::formatPoint(p); }





[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& what) {
  throw ProfileError(source + ": " + key + ": " + what);
}


Polygon readFootprint(const YAML::Node& node, const std::string& source) {
  if (!node.IsDefined() || node.IsNull()) fail(source, "footprint", "missing (a list of [x, y] vertices in the robot frame)");
  if (!node.IsSequence()) fail(source, "footprint", "expected a list of [x, y] vertices, got " + describe(node) + lineOf(node));
  Polygon poly;
  for (std::size_t k = 0; k < node.size(); ++k) {
    const YAML::Node v = node[k];
    std::optional<double> x, y;
    if (v.IsSequence() && v.size() == 2) {
      x = readNumber(v[0]);
      y = readNumber(v[1]);
    }
    const std::string key = "footprint[" + std::to_string(k) + "]";
    if (!x || !y) fail(source, key, "expected a pair of numbers [x, y], got " + describe(v) + lineOf(v));
    if (!std::isfinite(*x) || !std::isfinite(*y)) fail(source, key, "vertex is not finite " + point({*x, *y}) + lineOf(v));
    poly.emplace_back(*x, *y);
  }
  const std::size_t n = poly.size();
  if (n < 3) fail(source, "footprint", "has " + std::to_string(n) + " vertices, needs at least 3" + lineOf(node));
  for (std::size_t i = 0; i < n; ++i) {
    if (poly[i] == poly[(i + 1) % n]) {
      fail(source, "footprint", "vertex " + std::to_string((i + 1) % n) + " repeats vertex " + std::to_string(i) + " " +
                                    point(poly[i]) + lineOf(node));
    }
  }
  if (const auto e = findSelfIntersection(poly)) {
    fail(source, "footprint", "self-intersecting (edges " + std::to_string(e->first) + " and " + std::to_string(e->second) +
                                  " meet)" + lineOf(node));
  }
  // The robot's reference point (its pose) must lie strictly inside its own body: the
  // planner's centroid/corner checks and the circumradius inflation assume it.
  if (locatePoint(Vec2::Zero(), poly) != Containment::kInside) {
    fail(source, "footprint", "does not contain the robot's origin (0, 0) strictly inside" + lineOf(node));
  }
  if (!isCounterClockwise(poly)) std::reverse(poly.begin(), poly.end());
  return poly;
}

MotionLimits readLimits(const YAML::Node& node, const std::string& source) {
  if (!node.IsDefined() || node.IsNull()) fail(source, "limits", "missing ({v_max, v_min, w_max, a_max, b_max})");
  if (!node.IsMap()) fail(source, "limits", "expected a mapping {v_max, v_min, w_max, a_max, b_max}, got " + describe(node) + lineOf(node));
  static constexpr std::string_view kKeys[] = {"v_max", "v_min", "w_max", "a_max", "b_max"};
  for (const auto& kv : node) {
    const std::string key = kv.first.Scalar();
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      fail(source, "limits." + key, "unknown key (expected v_max, v_min, w_max, a_max, b_max)" + lineOf(kv.first));
    }
  }
  auto read = [&](const char* key) {
    const YAML::Node v = node[key];
    const std::string where = std::string("limits.") + key;
    if (!v.IsDefined() || v.IsNull()) fail(source, where, "missing" + lineOf(node));
    const auto x = readNumber(v);
    if (!x) fail(source, where, "expected a number, got " + describe(v) + lineOf(v));
    if (!std::isfinite(*x)) fail(source, where, "must be finite, got " + v.Scalar() + lineOf(v));
    return *x;
  };
  MotionLimits lim;
  lim.v_max = read("v_max");
  lim.v_min = read("v_min");
  lim.w_max = read("w_max");
  lim.a_max = read("a_max");
  lim.b_max = read("b_max");
  auto positive = [&](const char* key, double v) {
    if (!(v > 0.0)) fail(source, std::string("limits.") + key, "must be > 0, got " + number(v) + lineOf(node[key]));
  };
  positive("v_max", lim.v_max);
  if (lim.v_min > 0.0) fail(source, "limits.v_min", "must be <= 0 (it is the backward limit), got " + number(lim.v_min) + lineOf(node["v_min"]));
  positive("w_max", lim.w_max);
  positive("a_max", lim.a_max);
  positive("b_max", lim.b_max);
  return lim;
}

}  // namespace

double RobotProfile::circumradius() const {
  // The origin is inside the footprint, so the farthest point of the polygon is a vertex.
  double r = 0.0;
  for (const Vec2& p : footprint) r = std::max(r, p.norm());
  return r;
}

RobotProfile parseRobotProfile(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ProfileError(source + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw ProfileError(source + ": expected a mapping with format, name, footprint, limits, got " + describe(root));
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key != "format" && key != "name" && key != "footprint" && key != "limits") {
      fail(source, key, "unknown key (expected format, name, footprint, limits)" + lineOf(kv.first));
    }
  }
  const YAML::Node format = root["format"];
  if (!format.IsDefined() || format.IsNull()) fail(source, "format", "missing (expected " + std::string(kFormat) + ")");
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    fail(source, "format", "unknown format " + describe(format) + ", expected " + std::string(kFormat) + lineOf(format));
  }
  RobotProfile profile;
  const YAML::Node name = root["name"];
  if (name.IsDefined() && !name.IsNull()) {
    if (!name.IsScalar()) fail(source, "name", "expected a string, got " + describe(name) + lineOf(name));
    profile.name = name.Scalar();
  } else {
    profile.name = std::filesystem::path(source).stem().string();
  }
  profile.footprint = readFootprint(root["footprint"], source);
  profile.limits = readLimits(root["limits"], source);
  return profile;
}

RobotProfile loadRobotProfile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ProfileError(path.string() + ": cannot open robot profile");
  std::ostringstream text;
  text << in.rdbuf();
  return parseRobotProfile(text.str(), path.string());
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
