#include "robot/robot_profile.hpp"

#include "io/config_reader.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string_view>

namespace staa {
namespace {

constexpr std::string_view kFormat = "staa-robot/1";

Polygon readFootprint(const io::ConfigValue& node) {
  Polygon poly = node.polygon();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    if (std::abs(poly[i].x()) > RobotProfile::kMaxFootprintM || std::abs(poly[i].y()) > RobotProfile::kMaxFootprintM) {
      std::ostringstream problem;
      problem << "vertex " << i << " (" << poly[i].x() << ", " << poly[i].y() << ") is beyond "
              << RobotProfile::kMaxFootprintM << " m of the robot's origin in x or y";
      node[i].fail(problem.str());
    }
  }
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

// An optional number: the default when absent.
double optionalNumber(const io::ConfigValue& node, std::string_view key, double fallback, const io::Range& range) {
  const io::ConfigValue v = node.get(key);
  return v.present() ? v.number(range) : fallback;
}

DepthCameraProfile readCamera(const io::ConfigValue& node) {
  node.mapping({"mount", "fov_deg", "range_m", "rate_hz", "noise_mm_per_m2", "dropout", "grazing_deg", "frame_loss",
                "latency_s", "head"});
  DepthCameraProfile c;
  const io::ConfigValue m = node.required("mount", "{x, y, z, roll, pitch, yaw}: the camera on the base");
  m.mapping({"x", "y", "z", "roll", "pitch", "yaw"});
  const io::Range angle = io::Range::closed(-kPi, kPi, "rad");
  const io::Range offset = io::Range::closed(-DepthCameraProfile::kMaxMountOffsetM, DepthCameraProfile::kMaxMountOffsetM,
                                             "m", "on the base");
  c.x = optionalNumber(m, "x", 0.0, offset);
  c.y = optionalNumber(m, "y", 0.0, offset);
  c.z = m.required("z", "the camera's height above the floor").number(io::Range::above(0.0, "m", "above the floor"));
  c.roll = optionalNumber(m, "roll", 0.0, angle);
  c.pitch = optionalNumber(m, "pitch", 0.0, angle);
  c.yaw = optionalNumber(m, "yaw", 0.0, angle);
  const io::ConfigValue fov = node.required("fov_deg", "[horizontal, vertical] degrees");
  fov.numbers<2>("[horizontal, vertical] degrees");
  c.fov_h_deg = fov[0].number(io::Range::rightOpen(1.0, 170.0, "degrees"));
  c.fov_v_deg = fov[1].number(io::Range::rightOpen(1.0, 170.0, "degrees"));
  const io::ConfigValue range = node.required("range_m", "[min, max] depth in metres");
  range.numbers<2>("[min, max] depth in metres");
  c.min_range_m = range[0].number(io::Range::atLeast(0.0, "m"));
  c.max_range_m = range[1].number(io::Range::leftOpen(c.min_range_m, 65.535, "m", "above min, a depth image holds up to 65.535 m"));
  c.rate_hz = optionalNumber(node, "rate_hz", c.rate_hz, io::Range::leftOpen(0.0, 1000.0, "Hz"));
  c.noise_mm_per_m2 = optionalNumber(node, "noise_mm_per_m2", c.noise_mm_per_m2, io::Range::atLeast(0.0));
  c.dropout = optionalNumber(node, "dropout", c.dropout, io::Range::rightOpen(0.0, 1.0, {}, "a fraction of the pixels"));
  c.grazing_deg = optionalNumber(node, "grazing_deg", c.grazing_deg, io::Range::leftOpen(0.0, 90.0, "degrees"));
  c.frame_loss = optionalNumber(node, "frame_loss", c.frame_loss, io::Range::rightOpen(0.0, 1.0, {}, "a fraction of the frames"));
  c.latency_s = optionalNumber(node, "latency_s", c.latency_s,
                               io::Range::closed(0.0, std::min(1.0, DepthCameraProfile::kMaxLatencyFrames / c.rate_hz), "s",
                                                 "at most 1 s and 7 frames at rate_hz"));
  const io::ConfigValue head = node.section("head", {"pan_max", "pan_rate", "look_ahead_m", "scan"});
  if (head.present()) {
    c.pan_max = head.required("pan_max", "how far the head pans each way, rad").number(io::Range::closed(0.0, kPi, "rad"));
    c.pan_rate = optionalNumber(head, "pan_rate", c.pan_rate, io::Range::above(0.0, "rad/s"));
    c.look_ahead_m = optionalNumber(head, "look_ahead_m", c.look_ahead_m, io::Range::above(0.0, "m"));
    c.scan = optionalNumber(head, "scan", c.scan, io::Range::closed(0.0, kPi, "rad"));
  }
  return c;
}

ScannerProfile readScanner(const io::ConfigValue& node) {
  node.mapping({"mount", "fov_deg", "beams", "range_m", "noise_m", "dropout"});
  ScannerProfile c;
  const io::ConfigValue m = node.required("mount", "{x, y, z, yaw}: the scanner on the base");
  m.mapping({"x", "y", "z", "yaw"});
  const io::Range offset = io::Range::closed(-DepthCameraProfile::kMaxMountOffsetM, DepthCameraProfile::kMaxMountOffsetM,
                                             "m", "on the base");
  c.x = optionalNumber(m, "x", 0.0, offset);
  c.y = optionalNumber(m, "y", 0.0, offset);
  c.z = m.required("z", "the scan plane's height above the floor").number(io::Range::above(0.0, "m", "above the floor"));
  c.yaw = optionalNumber(m, "yaw", 0.0, io::Range::closed(-kPi, kPi, "rad"));
  c.fov_deg = optionalNumber(node, "fov_deg", c.fov_deg, io::Range::closed(1.0, 360.0, "degrees"));
  const io::ConfigValue beams = node.get("beams");
  if (beams.present()) {
    c.beams = static_cast<int>(beams.integer(2, ScannerProfile::kMaxBeams, "beams over the sweep"));
  }
  const io::ConfigValue range = node.get("range_m");
  if (range.present()) {
    range.numbers<2>("[min, max] range in metres");
    c.min_range_m = range[0].number(io::Range::atLeast(0.0, "m"));
    c.max_range_m = range[1].number(io::Range::leftOpen(c.min_range_m, 100.0, "m", "above min"));
  }
  c.noise_m = optionalNumber(node, "noise_m", c.noise_m, io::Range::closed(0.0, 1.0, "m"));
  c.dropout = optionalNumber(node, "dropout", c.dropout, io::Range::rightOpen(0.0, 1.0, {}, "a fraction of the beams"));
  return c;
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
    const io::ConfigValue& root = doc.root(kFormat, {"format", "name", "footprint", "limits", "height", "camera", "scanner"});
    RobotProfile profile;
    const io::ConfigValue name = root.get("name");
    profile.name = name.present() ? name.string("a string") : std::filesystem::path(source).stem().string();
    profile.footprint = readFootprint(root.required("footprint", "a list of [x, y] vertices in the robot frame"));
    profile.limits = readLimits(root.required("limits", "{v_max, v_min, w_max, a_max, b_max}"));
    profile.height_m = optionalNumber(root, "height", profile.height_m, io::Range::above(0.0, "m"));
    const io::ConfigValue camera = root.get("camera");
    if (camera.present()) {
      profile.camera = readCamera(camera);
      profile.has_camera = true;
    }
    const io::ConfigValue scanner = root.get("scanner");
    if (scanner.present()) {
      profile.scanner = readScanner(scanner);
      profile.has_scanner = true;
    }
    return profile;
  });
}

RobotProfile loadRobotProfile(const std::filesystem::path& path) {
  const std::string source = path.string();
  return io::readAs<ProfileError>(source, [&] { return parseRobotProfile(io::ConfigDocument::readFile(path, "robot profile"), source); });
}

DepthCameraProfile paperAgentCamera() {
  DepthCameraProfile c;
  c.x = 0.0;
  c.y = 0.0;
  c.z = 1.0;
  c.pitch = 0.3;
  c.fov_h_deg = 58.0;
  c.fov_v_deg = 45.0;
  c.min_range_m = 0.5;
  c.max_range_m = 4.5;
  c.rate_hz = 30.0;
  c.noise_mm_per_m2 = 1.5;
  c.dropout = 0.02;
  c.grazing_deg = 80.0;
  c.frame_loss = 0.01;
  c.latency_s = 1.0 / 30.0;
  c.pan_max = 2.8;
  c.pan_rate = 2.0;
  c.look_ahead_m = 1.5;
  c.scan = 0.6;
  return c;
}

RobotProfile paperAgentProfile() {
  RobotProfile p;
  p.name = "paper-agent";
  // docs/paper-worlds.md, "The agent", in the paper's (clockwise) order, stored counter-clockwise.
  p.footprint = {{0.4, 0.2}, {0.4, -0.2}, {-0.4, -0.25}, {-0.4, 0.25}};
  std::reverse(p.footprint.begin(), p.footprint.end());
  p.limits = MotionLimits{2.0, -1.0, 3.0, 2.0, 6.0};
  // Not in the paper: the body and camera config/robots/paper-agent.yaml gives it for
  // staa-sim --obstacles depth.
  p.height_m = 1.0;
  p.has_camera = true;
  p.camera = paperAgentCamera();
  // And a scanner in the base like the HSR's (config/robots/paper-agent.yaml).
  p.has_scanner = true;
  p.scanner.z = 0.2;
  p.scanner.dropout = 0.01;
  return p;
}

}  // namespace staa
