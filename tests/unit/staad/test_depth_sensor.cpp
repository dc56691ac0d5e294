// obstacles: depth (src/app/staad/depth_sensor.hpp): the camera and scanner sections of the
// config (every key read, every bad value named with its key, line and value); the depth
// sensor in lockstep with the simulated world (a mover walking in front of the robot is
// reported where it is and as fast as it walks, the walls are not reported, nothing is
// allocated; with the base's scanner a mover beside the robot, out of the camera's view, is
// seen, and a scan too far from the frame's stamp is not used). The staad binary with
// `obstacles: depth` is tests/integration/test_staad_depth.cpp's.
#include "app/staad/config.hpp"
#include "app/staad/depth_sensor.hpp"
#include "geometry/polygon.hpp"
#include "world/sim_depth_camera.hpp"
#include "world/sim_hal.hpp"
#include "world/sim_laser_scan.hpp"
#include "rt/alloc_count.hpp"
#include "world/world.hpp"

#if defined(STAA_HAVE_OPENNI2)
#include "hal/openni2/openni2_camera.hpp"
#endif

#include "shared_dir.hpp"

#include <gmock/gmock.h>
#include "child_process.hpp"
#include "read_file.hpp"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>


namespace staa::staad {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
constexpr rt::Nanos kMs = rt::kNanosPerMilli;

using staa::test::readFile;

// ---- the camera section ----

// A config with obstacles: depth and every camera key, one per line.
const std::string kDepth = R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
hal: sim
sim:
  start: [1.5, 4.5, 0.0]
obstacles: depth
camera:
  backend: sim
  uri: ""
  intrinsics: {fx: 570.3, fy: 570.3, cx: 319.5, cy: 239.5}
  mount: {x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: 0.0}
  sim_noise_mm_per_m2: 1.5
  perception:
    stride: 4
    min_depth_m: 0.45
    max_range_m: 4.5
    scan_range_m: 0
    min_height_m: 0.05
    max_height_m: 1.8
    cell_m: 0.1
    min_points_per_cell: 3
    min_cluster_points: 8
    cluster_gap_m: 0.3
    static_margin_m: 0.15
    max_vertices: 16
    gate_m: 0.5
    max_speed_mps: 2.5
    max_missed_frames: 5
)";

// `text` with `from` replaced by `to` (which must occur).
std::string edited(const std::string& from, const std::string& to, std::string text = kDepth) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

int lineOf(const std::string& text, const std::string& what) {
  const auto at = text.find(what);
  if (at == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// A temporary folder with the shipped robot profile and map beside the config.
class CameraConfigFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("staad-depth-config-" + std::to_string(::getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "robots");
    fs::create_directories(dir_ / "maps");
    fs::create_directories(dir_ / "can");
    fs::copy_file(test::sourceDir() / "config/robots/hsr.yaml", dir_ / "robots/hsr.yaml");
    fs::copy_file(test::sourceDir() / "config/maps/office.yaml", dir_ / "maps/office.yaml");
    fs::copy_file(test::sourceDir() / "config/can/hsr_base.yaml", dir_ / "can/hsr_base.yaml");
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  DaemonConfig load(const std::string& text, const std::string& name = "staad.yaml") const {
    return loadDaemonConfig(write(name, text));
  }
  // config/staad.yaml with its commented block from `header` to the next blank line
  // uncommented (`lines`: how many), `obstacles: sim` replaced by `obstacles`, and the files it
  // names copied beside it as "shipped/": load(text, "shipped/staad.yaml") reads it.
  std::string shippedWithBlock(const std::string& header, const std::string& obstacles, int& lines) const {
    std::istringstream in(readFile(test::sourceDir() / "config/staad.yaml"));
    std::string text, line;
    bool block = false;
    lines = 0;
    while (std::getline(in, line)) {
      if (line == header) block = true;
      if (block && line.empty()) block = false;
      if (block && (line == header || line.rfind("#   ", 0) == 0)) {
        line = line.substr(2);
        ++lines;
      }
      if (line == "obstacles: sim") line = obstacles;
      text += line + "\n";
    }
    for (const char* f : {"robots/hsr.yaml", "maps/office.yaml"}) {
      fs::create_directories((dir_ / "shipped" / f).parent_path());
      fs::copy_file(test::sourceDir() / "config" / f, dir_ / "shipped" / f);
    }
    return text;
  }
  std::string loadError(const std::string& text) const {
    try {
      load(text);
    } catch (const ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no ConfigError for:\n" << text;
    return "";
  }

  fs::path dir_;
};

TEST_F(CameraConfigFiles, ReadsEveryCameraKey) {
  std::string text = edited("fx: 570.3, fy: 570.3, cx: 319.5, cy: 239.5", "fx: 525.0, fy: 526.5, cx: 320.25, cy: 241.0");
  text = edited("{x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: 0.0}",
                "{x: 0.05, y: -0.02, z: 1.2, roll: 0.01, pitch: 0.4, yaw: -0.1}", text);
  text = edited("uri: \"\"", "uri: \"1d27/0601@3/7\"", text);
  text = edited("sim_noise_mm_per_m2: 1.5", "sim_noise_mm_per_m2: 0", text);
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"stride: 4", "stride: 2"},
           {"min_depth_m: 0.45", "min_depth_m: 0.6"},
           {"max_range_m: 4.5", "max_range_m: 3.5"},
           {"scan_range_m: 0", "scan_range_m: 8"},
           {"min_height_m: 0.05", "min_height_m: 0.08"},
           {"max_height_m: 1.8", "max_height_m: 1.5"},
           {"cell_m: 0.1", "cell_m: 0.08"},
           {"min_points_per_cell: 3", "min_points_per_cell: 4"},
           {"min_cluster_points: 8", "min_cluster_points: 12"},
           {"cluster_gap_m: 0.3", "cluster_gap_m: 0.2"},
           {"static_margin_m: 0.15", "static_margin_m: 0.2"},
           {"max_vertices: 16", "max_vertices: 8"},
           {"gate_m: 0.5", "gate_m: 0.7"},
           {"max_speed_mps: 2.5", "max_speed_mps: 2.0"},
           {"max_missed_frames: 5", "max_missed_frames: 0"},
       }) {
    text = edited(from, to, text);
  }
  const DaemonConfig c = load(text);
  EXPECT_EQ(c.obstacles, ObstacleSource::kDepth);
  const CameraConfig& k = c.camera;
  EXPECT_EQ(k.backend, CameraBackend::kSim);
  EXPECT_EQ(k.uri, "1d27/0601@3/7");
  EXPECT_DOUBLE_EQ(k.intrinsics.fx, 525.0);
  EXPECT_DOUBLE_EQ(k.intrinsics.fy, 526.5);
  EXPECT_DOUBLE_EQ(k.intrinsics.cx, 320.25);
  EXPECT_DOUBLE_EQ(k.intrinsics.cy, 241.0);
  EXPECT_DOUBLE_EQ(k.mount.x, 0.05);
  EXPECT_DOUBLE_EQ(k.mount.y, -0.02);
  EXPECT_DOUBLE_EQ(k.mount.z, 1.2);
  EXPECT_DOUBLE_EQ(k.mount.roll, 0.01);
  EXPECT_DOUBLE_EQ(k.mount.pitch, 0.4);
  EXPECT_DOUBLE_EQ(k.mount.yaw, -0.1);
  EXPECT_DOUBLE_EQ(k.sim_noise_mm_per_m2, 0.0);
  const DepthObstaclesConfig& p = k.perception;
  EXPECT_EQ(p.pixel_stride, 2);
  EXPECT_DOUBLE_EQ(p.min_depth_m, 0.6);
  EXPECT_DOUBLE_EQ(p.max_range_m, 3.5);
  EXPECT_DOUBLE_EQ(p.scan_range_m, 8.0);
  EXPECT_DOUBLE_EQ(p.min_height_m, 0.08);
  EXPECT_DOUBLE_EQ(p.max_height_m, 1.5);
  EXPECT_DOUBLE_EQ(p.cell_m, 0.08);
  EXPECT_EQ(p.min_points_per_cell, 4);
  EXPECT_EQ(p.min_cluster_points, 12);
  EXPECT_DOUBLE_EQ(p.cluster_gap_m, 0.2);
  EXPECT_DOUBLE_EQ(p.static_margin_m, 0.2);
  EXPECT_EQ(p.max_vertices, 8u);
  EXPECT_DOUBLE_EQ(p.gate_m, 0.7);
  EXPECT_DOUBLE_EQ(p.max_speed_mps, 2.0);
  EXPECT_EQ(p.max_missed_frames, 0);
  // Not exposed: the tracker's noise model keeps its defaults.
  EXPECT_DOUBLE_EQ(p.centroid_noise_m, DepthObstaclesConfig{}.centroid_noise_m);
  EXPECT_DOUBLE_EQ(p.acceleration_mps2, DepthObstaclesConfig{}.acceleration_mps2);
  // The rendered camera sees every mover (its own range decides, not sim.sensor_range_m).
  EXPECT_TRUE(std::isinf(c.sim.sensor_range_m));
  EXPECT_FALSE(c.sim.movers_only);
}

TEST_F(CameraConfigFiles, OnlyTheBackendIsRequiredTheRestHasTheDocumentedDefaults) {
  const DaemonConfig c = load(R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
sim: {start: [1.5, 4.5, 0.0]}
obstacles: depth
camera: {backend: sim}
)");
  const CameraConfig& k = c.camera;
  EXPECT_EQ(k.backend, CameraBackend::kSim);
  EXPECT_EQ(k.uri, "");
  EXPECT_DOUBLE_EQ(k.intrinsics.fx, 570.3);
  EXPECT_DOUBLE_EQ(k.intrinsics.fy, 570.3);
  EXPECT_DOUBLE_EQ(k.intrinsics.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.intrinsics.cy, 239.5);
  EXPECT_DOUBLE_EQ(k.mount.z, 1.0);
  EXPECT_DOUBLE_EQ(k.mount.pitch, 0.3);  // the HSR's head, looking down ahead
  EXPECT_DOUBLE_EQ(k.mount.roll, 0.0);
  EXPECT_DOUBLE_EQ(k.sim_noise_mm_per_m2, 1.5);
  EXPECT_EQ(k.perception.pixel_stride, 4);
  EXPECT_DOUBLE_EQ(k.perception.max_range_m, 4.5);
  EXPECT_DOUBLE_EQ(k.perception.cell_m, 0.1);
  EXPECT_EQ(k.perception.max_vertices, 16u);

  // The backend is not defaulted: a robot must never silently run on a simulated camera.
  const std::string missing = loadError(edited("  backend: sim\n", ""));
  EXPECT_THAT(missing, HasSubstr("camera.backend: missing"));
  EXPECT_THAT(missing, HasSubstr("sim, openni2 or ros"));
  const std::string no_section = loadError(R"(format: staad-config/1
robot: robots/hsr.yaml
map: maps/office.yaml
sim: {start: [1.5, 4.5, 0.0]}
obstacles: depth
)");
  EXPECT_THAT(no_section, HasSubstr("staad.yaml:5: camera: missing (obstacles: depth needs camera.backend"));
}

TEST_F(CameraConfigFiles, ShippedConfigsCommentedCameraBlockLoadsWithItsValues) {
  // config/staad.yaml documents the section as comments ("# camera:" to the blank line).
  int lines = 0;
  const std::string text = shippedWithBlock("# camera:", "obstacles: depth", lines);
  ASSERT_GE(lines, 6) << "no commented camera block in config/staad.yaml";
  const DaemonConfig c = load(text, "shipped/staad.yaml");
  EXPECT_EQ(c.obstacles, ObstacleSource::kDepth);
  EXPECT_EQ(c.camera.backend, CameraBackend::kSim);
  EXPECT_EQ(c.camera.uri, "");
  EXPECT_DOUBLE_EQ(c.camera.intrinsics.fx, 570.3);
  EXPECT_DOUBLE_EQ(c.camera.mount.pitch, 0.3);
  EXPECT_DOUBLE_EQ(c.camera.mount.z, 1.0);
  EXPECT_EQ(c.camera.perception.pixel_stride, 4);
  EXPECT_DOUBLE_EQ(c.camera.perception.max_range_m, DepthObstaclesConfig{}.max_range_m);
  EXPECT_DOUBLE_EQ(c.camera.perception.static_margin_m, DepthObstaclesConfig{}.static_margin_m);
  EXPECT_EQ(c.camera.perception.max_missed_frames, DepthObstaclesConfig{}.max_missed_frames);
}

struct BadCase {
  std::string from;
  std::string to;
  std::vector<std::string> expected;  // substrings of the message
  bool check_line = true;             // the message names the line of `to`
};

TEST_F(CameraConfigFiles, EveryBadCameraValueIsNamedWithItsKeyLineAndValue) {
  const std::string k = "fx: 570.3, fy: 570.3, cx: 319.5, cy: 239.5";
  const std::string m = "x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: 0.0";
  const std::vector<BadCase> cases = {
      {"obstacles: depth", "obstacles: lidar", {"obstacles", "sim", "depth", "none", "'lidar'"}},
      {"backend: sim", "backend: kinect", {"camera.backend", "sim", "openni2", "'kinect'"}},
      {"backend: sim", "backend: [sim]", {"camera.backend", "a list of 1 items"}},
      {"uri: \"\"", "uri: [a, b]", {"camera.uri", "a list of 2 items"}},
      {"uri: \"\"", "url: \"\"", {"camera.url", "unknown key", "backend, uri, intrinsics"}},
      {k, "fx: 0, fy: 570.3, cx: 319.5, cy: 239.5", {"camera.intrinsics.fx", "> 0", "got 0"}},
      {k, "fx: 570.3, fy: .nan, cx: 319.5, cy: 239.5", {"camera.intrinsics.fy", "finite", ".nan"}},
      {k, "fx: 570.3, fy: 570.3, cx: 640, cy: 239.5", {"camera.intrinsics.cx", "[0, 640)", "got 640"}},
      {k, "fx: 570.3, fy: 570.3, cx: 319.5, cy: -1", {"camera.intrinsics.cy", "[0, 480)", "got -1"}},
      {k, k + ", k1: 0.1", {"camera.intrinsics.k1", "unknown key", "fx, fy, cx, cy"}},
      {m, "x: abc, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: 0.0", {"camera.mount.x", "expected a number", "'abc'"}},
      {m, "x: 0.0, y: 0.0, z: 0, roll: 0.0, pitch: 0.3, yaw: 0.0", {"camera.mount.z", "> 0 m", "got 0"}},
      {m, "x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 17, yaw: 0.0", {"camera.mount.pitch", "[-pi, pi]", "degrees", "got 17"}},
      {m, "x: 0.0, y: 0.0, z: 1.0, roll: 0.0, pitch: 0.3, yaw: -4", {"camera.mount.yaw", "got -4"}},
      {"sim_noise_mm_per_m2: 1.5", "sim_noise_mm_per_m2: -1", {"camera.sim_noise_mm_per_m2", ">= 0", "got -1"}},
      {"stride: 4", "stride: 0", {"camera.perception.stride", "1..16", "got 0"}},
      {"stride: 4", "stride: 2.5", {"camera.perception.stride", "integer", "2.5"}},
      {"stride: 4", "strides: 4", {"camera.perception.strides", "unknown key", "stride, min_depth_m"}},
      {"min_depth_m: 0.45", "min_depth_m: -0.1", {"camera.perception.min_depth_m", ">= 0", "got -0.1"}},
      {"max_range_m: 4.5", "max_range_m: 0", {"camera.perception.max_range_m", "> 0", "got 0"}},
      {"scan_range_m: 0", "scan_range_m: -2", {"camera.perception.scan_range_m", ">= 0", "got -2"}},
      {"min_height_m: 0.05", "min_height_m: low", {"camera.perception.min_height_m", "'low'"}},
      {"max_height_m: 1.8", "max_height_m: 0.01", {"camera.perception.max_height_m", "> min_height_m (0.05 m)", "got 0.01"}},
      {"cell_m: 0.1", "cell_m: -0.1", {"camera.perception.cell_m", "> 0", "got -0.1"}},
      {"min_points_per_cell: 3", "min_points_per_cell: 0", {"camera.perception.min_points_per_cell", "1..65535", "got 0"}},
      {"min_cluster_points: 8", "min_cluster_points: -3", {"camera.perception.min_cluster_points", "got -3"}},
      {"cluster_gap_m: 0.3", "cluster_gap_m: 0.05", {"camera.perception.cluster_gap_m", "[0.1, 0.5]", "got 0.05"}},
      {"static_margin_m: 0.15", "static_margin_m: -1", {"camera.perception.static_margin_m", ">= 0", "got -1"}},
      {"max_vertices: 16", "max_vertices: 3", {"camera.perception.max_vertices", "4..32", "got 3"}},
      {"max_vertices: 16", "max_vertices: 33", {"camera.perception.max_vertices", "got 33"}},
      {"gate_m: 0.5", "gate_m: 0", {"camera.perception.gate_m", "> 0", "got 0"}},
      {"max_speed_mps: 2.5", "max_speed_mps: .inf", {"camera.perception.max_speed_mps", "finite", ".inf"}},
      {"max_missed_frames: 5", "max_missed_frames: -1", {"camera.perception.max_missed_frames", "0..1000", "got -1"}},
      {"intrinsics: {" + k + "}", "intrinsics: 570.3", {"camera.intrinsics", "expected a mapping", "'570.3'"}},
      {"  backend: sim\n", "", {"camera.backend: missing"}, false},
  };
  for (const BadCase& c : cases) {
    const std::string text = edited(c.from, c.to);
    const std::string error = loadError(text);
    SCOPED_TRACE(c.to + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    EXPECT_THAT(error, HasSubstr((dir_ / "staad.yaml").string()));
    if (c.check_line) {
      EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(text, c.to)) + ": "));
    }
  }

  // The grid would exceed the detector's 2000 cells: named at cell_m.
  const std::string fine = edited("cluster_gap_m: 0.3", "cluster_gap_m: 0.004", edited("cell_m: 0.1", "cell_m: 0.004"));
  const std::string error = loadError(fine);
  EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(fine, "cell_m: 0.004")) + ": camera.perception.cell_m"));
  EXPECT_THAT(error, HasSubstr("998 cells"));
  EXPECT_THAT(error, HasSubstr("got 0.004"));
}

TEST_F(CameraConfigFiles, TheSimSectionIsNeededOnlyForTheRenderedCamera) {
  const std::string can = "hal: socketcan\nsocketcan: {interface: can0, profile: can/hsr_base.yaml}";
  const std::string no_sim = edited("sim:\n  start: [1.5, 4.5, 0.0]\n", "", edited("hal: sim", can));
  // openni2 with a real base: no simulated world at all.
  const DaemonConfig ni = load(edited("backend: sim", "backend: openni2", no_sim));
  EXPECT_EQ(ni.camera.backend, CameraBackend::kOpenNI2);
  EXPECT_EQ(ni.hal, HalBackend::kSocketCan);
  // The rendered camera with a real base: the world is anchored at sim.start, its movers walk.
  const std::string error = loadError(no_sim);
  EXPECT_THAT(error, HasSubstr("sim: missing (camera.backend: sim renders the simulated world"));
  const DaemonConfig movers_only = load(edited("hal: sim", can));
  EXPECT_TRUE(movers_only.sim.movers_only);
  EXPECT_TRUE(std::isinf(movers_only.sim.sensor_range_m)) << "not measured from sim.start";
}

TEST_F(CameraConfigFiles, WithOtherObstaclesTheCameraSectionIsOnlyCheckedForTypos) {
  const DaemonConfig c = load(edited("obstacles: depth", "obstacles: sim", edited("backend: sim", "backend: kinect")));
  EXPECT_EQ(c.obstacles, ObstacleSource::kSim);
  EXPECT_FALSE(std::isinf(c.sim.sensor_range_m));
  const std::string error = loadError(edited("obstacles: depth", "obstacles: none", edited("uri: \"\"", "ur: \"\"")));
  EXPECT_THAT(error, HasSubstr("camera.ur: unknown key"));
}

// ---- the scanner section ----

// kDepth with every scanner key, one per line.
const std::string kScanner = kDepth + R"(scanner:
  backend: sim
  mount: {x: 0.1675, y: 0.0, z: 0.1844, yaw: 0.0}
  max_age_s: 0.1
  fov_deg: 270
  beams: 1081
  range_m: [0.05, 20.0]
  noise_m: 0.01
)";

TEST_F(CameraConfigFiles, WithoutAScannerSectionTheCameraIsAloneAndTheDefaultsAreTheHsrsScanner) {
  const ScannerConfig s = load(kDepth).scanner;
  EXPECT_EQ(s.backend, ScannerBackend::kNone);
  EXPECT_DOUBLE_EQ(s.mount.x, 0.1675);  // the HSR-B's base_range_sensor_joint
  EXPECT_DOUBLE_EQ(s.mount.y, 0.0);
  EXPECT_DOUBLE_EQ(s.mount.z, 0.1844);
  EXPECT_DOUBLE_EQ(s.mount.yaw, 0.0);
  EXPECT_DOUBLE_EQ(s.max_age_s, 0.1);
  EXPECT_DOUBLE_EQ(s.fov_deg, 270.0);
  EXPECT_EQ(s.beams, 1081);
  EXPECT_DOUBLE_EQ(s.range_min_m, 0.05);
  EXPECT_DOUBLE_EQ(s.range_max_m, 20.0);
  EXPECT_DOUBLE_EQ(s.noise_m, 0.01);
  // Only the backend given: the rest as documented.
  const DaemonConfig sim = load(kDepth + "scanner: {backend: sim}\n");
  EXPECT_EQ(sim.scanner.backend, ScannerBackend::kSim);
  EXPECT_DOUBLE_EQ(sim.scanner.mount.z, 0.1844);
  EXPECT_FALSE(sim.ros.enabled);
  // The shipped values, written out, are the defaults.
  const ScannerConfig all = load(kScanner).scanner;
  EXPECT_EQ(all.backend, ScannerBackend::kSim);
  EXPECT_DOUBLE_EQ(all.mount.x, s.mount.x);
  EXPECT_DOUBLE_EQ(all.max_age_s, s.max_age_s);
  EXPECT_EQ(all.beams, s.beams);
}

TEST_F(CameraConfigFiles, ShippedConfigsCommentedScannerBlockLoadsWithItsValues) {
  // config/staad.yaml documents the section as comments ("# scanner:" to the blank line).
  int lines = 0;
  const std::string text = shippedWithBlock("# scanner:", "obstacles: depth\ncamera: {backend: sim}", lines);
  ASSERT_GE(lines, 8) << "no commented scanner block in config/staad.yaml";
  const ScannerConfig s = load(text, "shipped/staad.yaml").scanner;
  // The defaults: the shipped robot profile's scanner (the HSR's).
  const ScannerConfig defaults = load(kDepth).scanner;
  EXPECT_EQ(s.backend, ScannerBackend::kSim);
  EXPECT_DOUBLE_EQ(s.mount.x, defaults.mount.x);
  EXPECT_DOUBLE_EQ(s.mount.z, defaults.mount.z);
  EXPECT_DOUBLE_EQ(s.max_age_s, defaults.max_age_s);
  EXPECT_DOUBLE_EQ(s.fov_deg, defaults.fov_deg);
  EXPECT_EQ(s.beams, defaults.beams);
  EXPECT_DOUBLE_EQ(s.range_max_m, defaults.range_max_m);
  EXPECT_DOUBLE_EQ(s.noise_m, defaults.noise_m);
}

TEST_F(CameraConfigFiles, ReadsEveryScannerKey) {
  std::string text = edited("{x: 0.1675, y: 0.0, z: 0.1844, yaw: 0.0}", "{x: 0.2, y: -0.05, z: 0.3, yaw: 3.0}", kScanner);
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"max_age_s: 0.1", "max_age_s: 0.25"},
           {"fov_deg: 270", "fov_deg: 360"},
           {"beams: 1081", "beams: 720"},
           {"range_m: [0.05, 20.0]", "range_m: [0.1, 12]"},
           {"noise_m: 0.01", "noise_m: 0"},
       }) {
    text = edited(from, to, text);
  }
  const ScannerConfig s = load(text).scanner;
  EXPECT_EQ(s.backend, ScannerBackend::kSim);
  EXPECT_DOUBLE_EQ(s.mount.x, 0.2);
  EXPECT_DOUBLE_EQ(s.mount.y, -0.05);
  EXPECT_DOUBLE_EQ(s.mount.z, 0.3);
  EXPECT_DOUBLE_EQ(s.mount.yaw, 3.0);
  EXPECT_DOUBLE_EQ(s.max_age_s, 0.25);
  EXPECT_DOUBLE_EQ(s.fov_deg, 360.0);
  EXPECT_EQ(s.beams, 720);
  EXPECT_DOUBLE_EQ(s.range_min_m, 0.1);
  EXPECT_DOUBLE_EQ(s.range_max_m, 12.0);
  EXPECT_DOUBLE_EQ(s.noise_m, 0.0);
  // A full turn: one increment short of 360 degrees, no beam twice.
  const hal::SimScanConfig sim = simScanConfig(s, 1);
  EXPECT_DOUBLE_EQ(sim.angle_min, -kPi);
  EXPECT_NEAR(sim.angle_max, kPi - 2.0 * kPi / 720, 1e-12);
  EXPECT_EQ(sim.beams, 720);
  EXPECT_DOUBLE_EQ(sim.mount.yaw, 3.0);
  EXPECT_DOUBLE_EQ(simScanConfig(ScannerConfig{}, 1).angle_max, 0.75 * kPi);

  // ros: the ROS link runs, the topic from ros.scanner (the HSR's by default).
  const DaemonConfig ros = load(edited("backend: sim\n  mount", "backend: ros\n  mount", kScanner));
  EXPECT_EQ(ros.scanner.backend, ScannerBackend::kRos);
  EXPECT_TRUE(ros.ros.enabled);
  EXPECT_EQ(ros.ros.transport.scan_topic, "/hsrb/base_scan");
  const DaemonConfig topic =
      load(edited("backend: sim\n  mount", "backend: ros\n  mount", kScanner) + "ros: {scanner: {topic: /base_scan}}\n");
  EXPECT_EQ(topic.ros.transport.scan_topic, "/base_scan");
}

// The robot profile's scanner is the one source of the scanner's mount and sweep: staad's
// section overrides it key by key, and with a profile that has none the mount must be given.
TEST_F(CameraConfigFiles, TheScannerDefaultsToTheRobotProfilesAndNeedsAMountWithoutOne) {
  std::string profile = readFile(dir_ / "robots/hsr.yaml");
  const std::string hsr_mount = "mount: {x: 0.1675, y: 0.0, z: 0.1844, yaw: 0.0}";
  ASSERT_NE(profile.find(hsr_mount), std::string::npos);
  profile.replace(profile.find(hsr_mount), hsr_mount.size(), "mount: {x: 0.21, y: 0.01, z: 0.3, yaw: 0.1}");
  profile.replace(profile.find("beams: 1081"), std::string("beams: 1081").size(), "beams: 541");
  write("robots/other.yaml", profile);
  auto withRobot = [&](const std::string& robot, const std::string& scanner) {
    std::string text = kDepth + scanner;
    text.replace(text.find("robots/hsr.yaml"), std::string("robots/hsr.yaml").size(), robot);
    return text;
  };
  const ScannerConfig from_profile = load(withRobot("robots/other.yaml", "scanner: {backend: sim}\n")).scanner;
  EXPECT_DOUBLE_EQ(from_profile.mount.x, 0.21);
  EXPECT_DOUBLE_EQ(from_profile.mount.y, 0.01);
  EXPECT_DOUBLE_EQ(from_profile.mount.z, 0.3);
  EXPECT_DOUBLE_EQ(from_profile.mount.yaw, 0.1);
  EXPECT_EQ(from_profile.beams, 541);
  const ScannerConfig overridden =
      load(withRobot("robots/other.yaml", "scanner: {backend: sim, mount: {z: 0.25}, beams: 361}\n")).scanner;
  EXPECT_DOUBLE_EQ(overridden.mount.x, 0.21);
  EXPECT_DOUBLE_EQ(overridden.mount.z, 0.25);
  EXPECT_EQ(overridden.beams, 361);

  // Without a scanner section in the profile: the mount's z is required, naming the profile.
  std::string bare = readFile(dir_ / "robots/hsr.yaml");
  bare.erase(bare.find("\nscanner:"));
  write("robots/bare.yaml", bare + "\n");
  const std::string error = loadError(withRobot("robots/bare.yaml", "scanner: {backend: sim}\n"));
  EXPECT_NE(error.find("scanner.mount.z"), std::string::npos) << error;
  EXPECT_NE(error.find("bare.yaml"), std::string::npos) << error;
  EXPECT_NE(error.find("no scanner section"), std::string::npos) << error;
  const ScannerConfig given =
      load(withRobot("robots/bare.yaml", "scanner: {backend: sim, mount: {x: 0.1, z: 0.2}}\n")).scanner;
  EXPECT_DOUBLE_EQ(given.mount.x, 0.1);
  EXPECT_DOUBLE_EQ(given.mount.z, 0.2);
  // The camera alone (backend none) needs no mount.
  EXPECT_EQ(load(withRobot("robots/bare.yaml", "")).scanner.backend, ScannerBackend::kNone);
}

TEST_F(CameraConfigFiles, EveryBadScannerValueIsNamedWithItsKeyLineAndValue) {
  const std::string m = "x: 0.1675, y: 0.0, z: 0.1844, yaw: 0.0";
  const std::vector<BadCase> cases = {
      {"backend: sim\n  mount", "backend: lidar\n  mount", {"scanner.backend", "none", "sim", "ros", "'lidar'"}},
      {"backend: sim\n  mount", "backend: [ros]\n  mount", {"scanner.backend", "a list of 1 items"}},
      {m, "x: abc, y: 0.0, z: 0.1844, yaw: 0.0", {"scanner.mount.x", "expected a number", "'abc'"}},
      {m, "x: 0.1675, y: 11, z: 0.1844, yaw: 0.0", {"scanner.mount.y", "[-10, 10] m", "got 11"}},
      {m, "x: 0.1675, y: 0.0, z: 0, yaw: 0.0", {"scanner.mount.z", "> 0 m", "got 0"}},
      {m, "x: 0.1675, y: 0.0, z: .nan, yaw: 0.0", {"scanner.mount.z", ".nan"}},
      {m, "x: 0.1675, y: 0.0, z: 0.1844, yaw: 90", {"scanner.mount.yaw", "rad", "got 90"}},
      {m, m + ", pitch: 0.1", {"scanner.mount.pitch", "unknown key", "x, y, z, yaw"}},
      {"max_age_s: 0.1", "max_age_s: 0", {"scanner.max_age_s", "(0, 1] s", "got 0"}},
      {"max_age_s: 0.1", "max_age_s: 2", {"scanner.max_age_s", "got 2"}},
      {"fov_deg: 270", "fov_deg: 400", {"scanner.fov_deg", "[1, 360] degrees", "got 400"}},
      {"beams: 1081", "beams: 1", {"scanner.beams", "2..2048", "got 1"}},
      {"beams: 1081", "beams: 4096", {"scanner.beams", "got 4096"}},
      {"beams: 1081", "beams: 10.5", {"scanner.beams", "integer", "10.5"}},
      {"range_m: [0.05, 20.0]", "range_m: [0.05]", {"scanner.range_m", "[min, max]", "a list of 1 items"}},
      {"range_m: [0.05, 20.0]", "range_m: [-1, 20.0]", {"scanner.range_m[0]", ">= 0 m", "got -1"}},
      {"range_m: [0.05, 20.0]", "range_m: [5, 2]", {"scanner.range_m[1]", "above min", "got 2"}},
      {"noise_m: 0.01", "noise_m: -0.01", {"scanner.noise_m", "[0, 1] m", "got -0.01"}},
      {"noise_m: 0.01", "noise: 0.01", {"scanner.noise", "unknown key", "backend, mount, max_age_s"}},
  };
  for (const BadCase& c : cases) {
    const std::string text = edited(c.from, c.to, kScanner);
    const std::string error = loadError(text);
    SCOPED_TRACE(c.to + "  ->  " + error);
    for (const std::string& e : c.expected) EXPECT_THAT(error, HasSubstr(e));
    EXPECT_THAT(error, HasSubstr((dir_ / "staad.yaml").string()));
    if (c.check_line) {
      EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(text, c.to)) + ": "));
    }
  }
  // ros.scanner's topic: a ROS name.
  const std::string ros = kScanner + "ros: {scanner: {topic: \"base scan\"}}\n";
  const std::string topic = loadError(ros);
  EXPECT_THAT(topic, HasSubstr("ros.scanner.topic"));
  EXPECT_THAT(topic, HasSubstr("'base scan'"));
  EXPECT_THAT(loadError(kScanner + "ros: {scanner: {topics: /x}}\n"), HasSubstr("ros.scanner.topics: unknown key"));
}

TEST_F(CameraConfigFiles, TheSimScannerScansTheRenderedCamerasWorldOnly) {
  const std::string ni = edited("backend: sim\n  uri", "backend: openni2\n  uri", kScanner);
  const std::string error = loadError(ni);
  EXPECT_THAT(error, HasSubstr("staad.yaml:" + std::to_string(lineOf(ni, "backend: sim\n  mount")) +
                               ": scanner.backend: sim scans the simulated world the camera renders"));
  EXPECT_THAT(error, HasSubstr("got camera.backend openni2"));
  // A real camera with the real scanner is fine.
  const DaemonConfig c = load(edited("backend: sim\n  mount", "backend: ros\n  mount", ni));
  EXPECT_EQ(c.camera.backend, CameraBackend::kOpenNI2);
  EXPECT_EQ(c.scanner.backend, ScannerBackend::kRos);
}

TEST_F(CameraConfigFiles, WithOtherObstaclesTheScannerSectionIsOnlyCheckedForTypos) {
  const std::string sim = edited("obstacles: depth", "obstacles: sim", kScanner);
  const DaemonConfig c = load(edited("backend: sim\n  mount", "backend: ros\n  mount", edited("beams: 1081", "beams: 0", sim)));
  EXPECT_EQ(c.scanner.backend, ScannerBackend::kNone) << "not used: its values are not read";
  EXPECT_FALSE(c.ros.enabled) << "an unused ros scanner does not start the ROS link";
  EXPECT_THAT(loadError(edited("noise_m: 0.01", "noise_mm: 0.01", sim)), HasSubstr("scanner.noise_mm: unknown key"));
  EXPECT_THAT(loadError(edited("z: 0.1844, yaw: 0.0}", "z: 0.1844, yaw: 0.0, roll: 0}", sim)), HasSubstr("scanner.mount.roll: unknown key"));
}

// ---- the sensor ----

const PolygonMap& officeMap() {
  static const PolygonMap map = loadPolygonMap(test::sourceDir() / "config/maps/office.yaml");
  return map;
}
const RobotProfile& hsrProfile() {
  static const RobotProfile robot = loadRobotProfile(test::sourceDir() / "config/robots/hsr.yaml");
  return robot;
}
// staad's scanner defaults with the shipped HSR profile: its `scanner` section.
ScannerConfig hsrScanner() { return scannerConfigOf(hsrProfile().scanner); }

Polygon placed(const Polygon& shape, const Vec2& at) {
  Polygon p;
  for (const Vec2& v : shape) p.push_back(v + at);
  return p;
}

// 0 inside the polygon, else the distance to its edges.
double distanceTo(const Vec2& p, const Polygon& poly) {
  return locatePoint(p, poly) == Containment::kOutside ? distanceToEdges(p, poly) : 0.0;
}

Polygon polygonOf(const hal::ObstacleFrame::Obstacle& o) {
  return Polygon(o.vertices.begin(), o.vertices.begin() + static_cast<std::ptrdiff_t>(o.n));
}

TEST(DepthSensor, TakesNoFrameBeforeTheFirstOdometryThenFindsTheBoxInFrontOfTheRobot) {
  // Any DepthCamera: here SimDepthCamera over a world with one box standing 2.5 m ahead.
  const Pose2 robot{4.5, 4.5, 0.0};
  const Polygon box{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}};
  World world(officeMap(), hsrProfile(), robot, {Mover{box, {Vec2(7.0, 4.6)}, 0.0}});
  CameraConfig camera;
  hal::SimDepthConfig rendered = simDepthConfig(camera, 1);
  rendered.pixel_stride = 1;  // a whole frame, as a real camera sends
  OdometrySlot slot;
  DepthSensor sensor(officeMap(), camera, std::make_unique<hal::SimDepthCamera>(world, rendered), slot);

  hal::ObstacleFrame out;
  EXPECT_FALSE(sensor.read(0, out));
  EXPECT_EQ(sensor.framesWithoutPose(), 1u);
  EXPECT_EQ(sensor.frames(), 0u);

  hal::Odometry odometry;
  odometry.stamp = 0;
  odometry.pose = robot;
  slot.publish(odometry);
  ASSERT_TRUE(sensor.read(40 * kMs, out));
  EXPECT_EQ(sensor.frames(), 1u);
  EXPECT_EQ(out.stamp, 40 * kMs);
  ASSERT_EQ(out.count, 1u) << "the box, and no wall of the corridor";
  const Polygon seen = polygonOf(out.obstacles[0]);
  const Polygon truth = placed(box, Vec2(7.0, 4.6));
  for (const Vec2& v : seen) EXPECT_LE(distanceTo(v, truth), 0.2) << v.transpose();
  EXPECT_LE(distanceTo(Vec2(6.8, 4.6), seen), 0.2) << "its face towards the robot is covered";
  EXPECT_GT(sensor.lastStats().map_cells, 0u) << "the corridor's walls were in view";
  EXPECT_FALSE(sensor.read(41 * kMs, out)) << "the camera's next frame is not due yet";
}

// The daemon's wiring in one thread: SimHal's base (through the OdometryTap) stepped at
// 100 Hz, the depth sensor read at 30 Hz, the robot turning to keep the walker in view.
class DepthLockstep {
 public:
  DepthLockstep(const Pose2& start, std::uint64_t seed, bool scanner = false)
      : sim_(officeMap(), hsrProfile(), simConfig(start, seed), 0),
        tap_(sim_.base(), slot_),
        sensor_(officeMap(), CameraConfig{}, seed, sim_.obstacles(), slot_) {
    if (scanner) sensor_.addSimScanner(officeMap(), hsrScanner(), seed);  // the HSR's, as staad's defaults
  }

  static hal::SimHalConfig simConfig(const Pose2& start, std::uint64_t seed) {
    hal::SimHalConfig c;
    c.start = start;
    c.movers = 1;
    c.mover_speed = 0.8;
    c.mover_radius = 0.25;
    c.seed = seed;
    c.sensor_range_m = std::numeric_limits<double>::infinity();
    return c;
  }

  // Advances to the next perception period; true when the sensor took a frame. The tap's and
  // the sensor's calls run marked real-time (the allocation hook counts there); the sensor's
  // read (render + detect) is timed.
  bool step() {
    const rt::Nanos target = next_perception_;
    while (next_base_ <= target) {
      steer(next_base_);
      rt::markRealtimeThread(true);
      tap_.read(next_base_);
      tap_.write(next_base_, command_);
      rt::markRealtimeThread(false);
      next_base_ += 10 * kMs;
    }
    const auto t0 = std::chrono::steady_clock::now();
    rt::markRealtimeThread(true);
    const bool taken = sensor_.read(target, frame_);
    rt::markRealtimeThread(false);
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    if (taken) costs_us_.push_back(us);
    next_perception_ += 33'333'333;
    return taken;
  }

  // Turn towards the walker (and rock back and forth a little, so the robot moves as well).
  void steer(rt::Nanos now) {
    const World& w = sim_.world();
    const Pose2& p = w.robot().pose;
    const Vec2 d = w.moverPosition(0) - p.position();
    const double error = wrapAngle(std::atan2(d.y(), d.x()) - p.theta);
    command_.stamp = now;
    command_.v = 0.15 * std::sin(static_cast<double>(now) * 1e-9);
    command_.w = std::clamp(2.0 * error, -0.8, 0.8);
  }

  const World& world() const { return sim_.world(); }
  const hal::ObstacleFrame& frame() const { return frame_; }
  const DepthSensor& sensor() const { return sensor_; }
  const std::vector<double>& costsUs() const { return costs_us_; }

 private:
  hal::SimHal sim_;
  OdometrySlot slot_;
  OdometryTap tap_;
  DepthSensor sensor_;
  hal::ObstacleFrame frame_;
  hal::VelocityCommand command_;
  rt::Nanos next_base_ = 0;
  rt::Nanos next_perception_ = 0;
  std::vector<double> costs_us_;
};

// Whether the walker is plainly in view: 1..4 m ahead of the camera, inside the field of view
// with a margin, clear of the walls (the static margin hides what stands at a wall), with no
// wall between them.
bool plainlyVisible(const World& world, const Vec2& centre) {
  const Pose2& robot = world.robot().pose;
  const Vec2 d = centre - robot.position();
  const double range = d.norm();
  if (range < 1.0 || range > 4.0) return false;
  if (std::abs(wrapAngle(std::atan2(d.y(), d.x()) - robot.theta)) > 0.35) return false;
  for (const Polygon& wall : world.map().obstacles) {
    if (distanceTo(centre, wall) < 0.6) return false;
    for (std::size_t i = 0; i < wall.size(); ++i) {
      if (segmentsIntersect(robot.position(), centre, wall[i], wall[(i + 1) % wall.size()])) return false;
    }
  }
  return true;
}

// What the depth sensor reported about the walker over a run (see walkerRun).
struct WalkerRun {
  int frames = 0;
  int visible = 0;    // frames with the walker in plain view
  int reported = 0;   // ... of which it was reported
  int compared = 0;   // ... and its velocity compared (settled)
  int phantoms = 0;   // obstacles reported away from the walker (walls, noise)
  int kept = 0;       // obstacles reported out of view (the walker's track, kept)
  int frames_with_walls = 0;
  double worst_position = 0.0, worst_velocity = 0.0;  // m, m/s
  std::uint64_t allocations = 0;                      // by the real-time reads
  std::vector<double> costs_us;                       // render + detect per frame
};

// Runs `frames` perception periods from `start` with the walker of `seed`, checking every
// frame (EXPECTs name the frame): nothing but the walker is reported (what the camera sees
// lies at it; a track kept out of view lies no farther from it than the walker and the
// prediction can have drifted apart since it was last seen, and for at most keep_unseen_s);
// in plain view it is reported, within 0.2 m of where it is, and, settled, within 0.2 m/s of
// its velocity.
WalkerRun walkerRun(const Pose2& start, std::uint64_t seed, int frames, bool scanner = false) {
  constexpr int kSettled = 30;  // frames in view, and at one velocity, before it is compared
  DepthLockstep ls(start, seed, scanner);
  WalkerRun run;
  run.frames = frames;
  rt::resetRealtimeAllocations();
  int in_view_run = 0;
  std::deque<Vec2> velocities;
  double walker_speed = 0.0;  // the fastest the walker has walked so far
  const double keep_unseen_s = DepthObstaclesConfig{}.keep_unseen_s;  // staad's default
  for (int k = 0; k < frames; ++k) {
    const bool taken = ls.step();
    EXPECT_TRUE(taken) << "frame " << k;
    if (!taken) continue;
    const World& w = ls.world();
    const Vec2 centre = w.moverPosition(0);
    const Vec2 velocity = w.moverVelocity(0);
    const Polygon truth = placed(w.mover(0).polygon, centre);
    const hal::ObstacleFrame& f = ls.frame();
    run.frames_with_walls += ls.sensor().lastStats().map_cells > 0;

    // Nothing but the walker is ever reported: every vertex of every obstacle seen in this
    // frame lies at it. A kept track (out of view) was within 0.3 m when last seen; since then
    // its prediction moved at its velocity and the walker at its own, so its outline (which
    // only grows) lies within 0.3 m + (both speeds) x the time unseen of the walker.
    walker_speed = std::max(walker_speed, velocity.norm());
    int best = -1;
    double best_distance = 1e9;
    for (std::size_t i = 0; i < f.count; ++i) {
      const hal::ObstacleFrame::Obstacle& o = f.obstacles[i];
      const Polygon seen = polygonOf(o);
      if (o.unseen_s > 0.0) {
        ++run.kept;
        const double drift = 0.3 + (o.velocity.norm() + walker_speed) * o.unseen_s;
        const double off = distanceTo(centre, seen);
        if (off > drift || o.unseen_s > keep_unseen_s + 1e-6) {
          ++run.phantoms;
          ADD_FAILURE() << "frame " << k << ": a track kept " << o.unseen_s << " s out of view is " << off
                        << " m from the walker (at most " << drift << ") at " << seen[0].transpose();
        }
        continue;
      }
      double farthest = 0.0;
      for (const Vec2& v : seen) farthest = std::max(farthest, distanceTo(v, truth));
      if (farthest > 0.3) {
        ++run.phantoms;
        ADD_FAILURE() << "frame " << k << ": an obstacle " << farthest << " m away from the walker (a wall?) at "
                      << seen[0].transpose();
      } else if (farthest < best_distance) {
        best_distance = farthest;
        best = static_cast<int>(i);
      }
    }

    velocities.push_back(velocity);
    if (velocities.size() > kSettled) velocities.pop_front();
    if (!plainlyVisible(w, centre)) {
      in_view_run = 0;
      continue;
    }
    ++run.visible;
    ++in_view_run;
    EXPECT_GE(best, 0) << "frame " << k << ": the walker in plain view at " << centre.transpose() << " is not reported";
    if (best < 0) continue;
    ++run.reported;
    const hal::ObstacleFrame::Obstacle& o = f.obstacles[static_cast<std::size_t>(best)];

    // Where it is: no part of the report more than 0.2 m off the walker, and the walker's
    // point nearest the robot (what the robot would meet first) within 0.2 m of the report.
    const Polygon seen = polygonOf(o);
    const Vec2 camera = w.robot().pose.position();
    Vec2 nearest = truth[0];
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const Vec2 q = closestPointOnSegment(camera, truth[i], truth[(i + 1) % truth.size()]);
      if ((q - camera).norm() < (nearest - camera).norm()) nearest = q;
    }
    const double position_error = std::max(best_distance, distanceTo(nearest, seen));
    EXPECT_LE(position_error, 0.2) << "frame " << k;
    run.worst_position = std::max(run.worst_position, position_error);

    // As fast as it walks, once its track has settled: in view, and at one velocity, for a second.
    const bool steady = velocities.size() == kSettled &&
                        std::all_of(velocities.begin(), velocities.end(),
                                    [&](const Vec2& v) { return (v - velocity).norm() < 1e-9; });
    if (in_view_run < kSettled || !steady) continue;
    ++run.compared;
    const double velocity_error = (o.velocity - velocity).norm();
    EXPECT_LE(velocity_error, 0.2) << "frame " << k << ": reported " << o.velocity.transpose() << ", true "
                                   << velocity.transpose();
    run.worst_velocity = std::max(run.worst_velocity, velocity_error);
  }
  run.allocations = rt::realtimeAllocations();
  run.costs_us = ls.costsUs();
  std::sort(run.costs_us.begin(), run.costs_us.end());
  std::printf("walker in plain view in %d of %d frames, reported in %d, velocity compared in %d, kept out of view "
              "%d times; worst position error %.3f m, worst velocity error %.3f m/s; render+detect per frame: median "
              "%.0f us, p99 %.0f us, max %.0f us\n",
              run.visible, frames, run.reported, run.compared, run.kept, run.worst_position, run.worst_velocity,
              run.costs_us[run.costs_us.size() / 2], run.costs_us[run.costs_us.size() * 99 / 100], run.costs_us.back());
  return run;
}

TEST(DepthSensor, WalkerIsReportedWhereItIsAndAsFastAsItWalksWallsAreNotAndNothingAllocates) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_depth_sensor must link staa_rt_alloc_hook";
  // The office corridor (3 m wide, walls on both sides), the walker's walks from seed 1:
  // it comes along the corridor towards the robot, turns into a room and comes back out.
  // 30 s: the HSR turns after the walker at up to 0.5 rad/s (its profile's limit; the base
  // clamps the steering's 0.8), so the walker is often out of view for a while.
  const WalkerRun run = walkerRun(Pose2{4.5, 4.5, 0.0}, 1, 900);
  EXPECT_EQ(run.allocations, 0u) << "the base's and the depth sensor's reads allocate nothing, the first frame included";
  EXPECT_EQ(run.phantoms, 0);
  EXPECT_GE(run.visible, 60) << "the scene must show the walker for at least 2 s";
  EXPECT_EQ(run.reported, run.visible);
  EXPECT_GE(run.compared, 20) << "too few settled frames to judge the velocity";
  EXPECT_GT(run.frames_with_walls, run.frames / 2) << "the walls were in view (and explained by the map)";
}

TEST(DepthSensor, WalkersElsewhereInTheOfficeAreReportedAsWell) {
  // The corridor's middle and east end, other walks: the same bounds, other geometry.
  for (const auto& [start, seed] : {std::pair{Pose2{13.5, 4.5, 0.0}, 20}, std::pair{Pose2{19.5, 4.5, 0.0}, 7}}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const WalkerRun run = walkerRun(start, static_cast<std::uint64_t>(seed), 300);
    EXPECT_EQ(run.allocations, 0u);
    EXPECT_EQ(run.phantoms, 0);
    EXPECT_GE(run.visible, 60);
    EXPECT_EQ(run.reported, run.visible);
    EXPECT_GE(run.compared, 20);
  }
}

// ---- the base's scanner beside the camera ----

// A mover frame that never changes (one box standing where it is), every perception period:
// the sim camera's movers for a scene set by hand.
class StandingMovers final : public hal::ObstacleSensor {
 public:
  explicit StandingMovers(const Polygon& box) {
    frame_.count = 1;
    hal::ObstacleFrame::Obstacle& o = frame_.obstacles[0];
    o.n = box.size();
    std::copy(box.begin(), box.end(), o.vertices.begin());
  }
  bool read(rt::Nanos now, hal::ObstacleFrame& out) override {
    frame_.stamp = now;
    out = frame_;
    return true;
  }

 private:
  hal::ObstacleFrame frame_;
};

// The robot in the office corridor facing +x, a person-sized box 0.9 m to its left: out of the
// head camera's 58 degrees, in the base scanner's 270.
struct BesideTheRobot {
  static constexpr Pose2 kRobot{4.5, 4.5, 0.0};
  const Polygon box = placed(Polygon{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}}, Vec2(4.5, 5.4));
  StandingMovers movers{box};
  OdometrySlot slot;
  DepthSensor sensor{officeMap(), CameraConfig{}, 1, movers, slot};
  hal::ObstacleFrame out;

  BesideTheRobot() {
    hal::Odometry odometry;
    odometry.stamp = 0;
    odometry.pose = kRobot;
    slot.publish(odometry);
  }
  // `frames` perception periods; the obstacles of the last, seen in it, that touch the box.
  int run(int frames) {
    for (int k = 0; k < frames; ++k) EXPECT_TRUE(sensor.read(k * 33'333'333LL, out)) << "frame " << k;
    int at_box = 0;
    for (std::size_t i = 0; i < out.count; ++i) {
      const Polygon seen = polygonOf(out.obstacles[i]);
      double farthest = 0.0;
      for (const Vec2& v : seen) farthest = std::max(farthest, distanceTo(v, box));
      EXPECT_LE(farthest, 0.2) << "an obstacle away from the box at " << seen[0].transpose();
      at_box += (out.obstacles[i].unseen_s == 0.0 && farthest <= 0.2) ? 1 : 0;
    }
    return at_box;
  }
};

TEST(DepthSensorScanner, AMoverBesideTheRobotIsAnObstacleWithTheSimScannerAndNotWithout) {
  BesideTheRobot camera_alone;
  EXPECT_EQ(camera_alone.run(10), 0) << "the box is out of the camera's view";
  EXPECT_EQ(camera_alone.out.count, 0u);
  EXPECT_FALSE(camera_alone.sensor.hasScanner());
  EXPECT_FALSE(camera_alone.sensor.scannerStatus().enabled);

  BesideTheRobot with_scanner;
  with_scanner.sensor.addSimScanner(officeMap(), hsrScanner(), 1);
  EXPECT_EQ(with_scanner.run(10), 1) << "the scan sees it";
  const Polygon seen = polygonOf(with_scanner.out.obstacles[0]);
  EXPECT_LE(distanceTo(Vec2(4.5, 5.2), seen), 0.2) << "its face towards the robot is covered";
  EXPECT_GT(with_scanner.sensor.lastStats().scan_points, 0u);
  EXPECT_EQ(with_scanner.sensor.lastScanPoints(), with_scanner.sensor.lastStats().scan_points);
  EXPECT_EQ(with_scanner.sensor.scansUsed(), 10u) << "the sim scan is taken with each frame";
  EXPECT_EQ(with_scanner.sensor.scansTooOld(), 0u);
  EXPECT_EQ(with_scanner.sensor.framesWithoutScan(), 0u);
  const ScannerStatus status = with_scanner.sensor.scannerStatus();
  EXPECT_TRUE(status.enabled);
  EXPECT_STREQ(status.backend, "sim");
  EXPECT_EQ(status.scans_used, 10u);
  EXPECT_EQ(status.scan_points, with_scanner.sensor.lastScanPoints());
}

// A scanner whose next scan the test sets (read once, as a transport's newest scan).
class ScriptedScanner final : public hal::LaserScanner {
 public:
  void set(const hal::LaserScan& scan) {
    scan_ = scan;
    fresh_ = true;
  }
  bool read(rt::Nanos /*now*/, hal::LaserScan& out) override {
    if (!fresh_) return false;
    out = scan_;
    fresh_ = false;
    return true;
  }

 private:
  hal::LaserScan scan_;
  bool fresh_ = false;
};

TEST(DepthSensorScanner, TheNewestScanIsUsedOnlyWithinMaxAgeOfTheFramesStamp) {
  BesideTheRobot scene;
  auto owned = std::make_unique<ScriptedScanner>();
  ScriptedScanner& scripted = *owned;
  ScannerConfig config = hsrScanner();
  config.backend = ScannerBackend::kRos;
  config.max_age_s = 0.1;
  scene.sensor.addScanner(config, std::move(owned));
  // What the HSR's scanner would see of the scene.
  hal::ScanRenderer renderer(officeMap(), simScanConfig(config, 3));
  const hal::PrismView prism{PolygonView(scene.box.data(), scene.box.size()), Vec2(0.0, 0.0), 1.7};
  auto scan = std::make_unique<hal::LaserScan>();
  renderer.render(BesideTheRobot::kRobot, std::span<const hal::PrismView>(&prism, 1), *scan);

  constexpr rt::Nanos kPeriod = 33'333'333;
  rt::Nanos t = rt::kNanosPerSecond;  // scan stamps before it are still >= 0 (< 0: no scan)
  auto frame = [&] {
    EXPECT_TRUE(scene.sensor.read(t, scene.out));
    t += kPeriod;
  };
  frame();  // no scan yet: the frame alone
  EXPECT_EQ(scene.sensor.framesWithoutScan(), 1u);
  EXPECT_EQ(scene.sensor.lastStats().scan_points, 0u);

  // A scan 50 ms before the frame (within 0.1 s): used, and kept for the next frames while
  // it is recent enough (the sim camera's frames are stamped with their period's time).
  scan->stamp = t - 50 * kMs;
  scripted.set(*scan);
  frame();
  EXPECT_EQ(scene.sensor.scansUsed(), 1u);
  EXPECT_GT(scene.sensor.lastStats().scan_points, 0u);
  frame();  // 83 ms after the scan: still used
  EXPECT_EQ(scene.sensor.scansUsed(), 2u);
  frame();  // 117 ms: too old
  EXPECT_EQ(scene.sensor.scansTooOld(), 1u);
  EXPECT_EQ(scene.sensor.lastStats().scan_points, 0u);
  EXPECT_EQ(scene.sensor.lastScanPoints(), 0u);

  // A scan stamped well after the frame (a camera's frames lag): beyond 0.1 s is not used either.
  scan->stamp = t + 150 * kMs;
  scripted.set(*scan);
  frame();
  EXPECT_EQ(scene.sensor.scansTooOld(), 2u);
  scan->stamp = t + 20 * kMs;
  scripted.set(*scan);
  frame();
  EXPECT_EQ(scene.sensor.scansUsed(), 3u);
  const ScannerStatus status = scene.sensor.scannerStatus();
  EXPECT_STREQ(status.backend, "ros");
  EXPECT_EQ(status.scans_used, 3u);
  EXPECT_EQ(status.scans_too_old, 2u);
  EXPECT_EQ(status.frames_without_scan, 1u);
  EXPECT_GT(status.scan_points, 0u);
  EXPECT_EQ(scene.sensor.frames(), 6u);
}

TEST(DepthSensorScanner, TheSimScannerNeedsTheSimCamerasWorld) {
  const Polygon box{{-0.2, -0.2}, {0.2, -0.2}, {0.2, 0.2}, {-0.2, 0.2}};
  World world(officeMap(), hsrProfile(), Pose2{4.5, 4.5, 0.0}, {Mover{box, {Vec2(7.0, 4.6)}, 0.0}});
  OdometrySlot slot;
  DepthSensor sensor(officeMap(), CameraConfig{}, std::make_unique<hal::SimDepthCamera>(world, simDepthConfig(CameraConfig{}, 1)),
                     slot);
  EXPECT_THROW(sensor.addSimScanner(officeMap(), hsrScanner(), 1), std::logic_error);
  EXPECT_THROW(sensor.addScanner(ScannerConfig{}, nullptr), std::invalid_argument);
  EXPECT_FALSE(sensor.hasScanner());
}

TEST(DepthSensorScanner, WithTheSimScannerTheWalkerIsReportedAndNothingAllocates) {
  ASSERT_TRUE(rt::hookInstalled()) << "test_depth_sensor must link staa_rt_alloc_hook";
  // The corridor's walker of the camera test, with the base's scanner: what the camera sees
  // is still reported where the walker is, and the scanner's render and perception allocate
  // nothing (900 frames, the first included).
  const WalkerRun run = walkerRun(Pose2{4.5, 4.5, 0.0}, 1, 900, true);
  EXPECT_EQ(run.allocations, 0u);
  EXPECT_EQ(run.phantoms, 0);
  EXPECT_GE(run.visible, 60);
  EXPECT_EQ(run.reported, run.visible);
}

}  // namespace
}  // namespace staa::staad
