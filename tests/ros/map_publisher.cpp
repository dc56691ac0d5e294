// staa-test-map-publisher MAP.yaml [SECOND.yaml]: a map_server stand-in for the ROS tests
// (C++17: ROS 1 headers). Publishes MAP.yaml as a latched nav_msgs/OccupancyGrid on /map
// (~topic) in frame "map" (~frame_id); each SIGUSR1 swaps in the other map on the same
// publisher (with SECOND.yaml given), as a new map arriving while staad drives.
//
// The YAML and PGM are read here, by map_server's rules, rather than by the project's map
// library: that library is C++20 (its headers cannot share a translation unit with ROS 1's),
// and an independent reading lets the tests check the grid against staa_map's own import.
// A map that cannot be read is fatal: exit 2 with the file and the reason.

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <csignal>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct MapYaml {
  std::string image;  // resolved against the YAML file's folder
  double resolution = 0.0;
  double origin[3] = {0.0, 0.0, 0.0};
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  std::string mode = "trinary";
};

std::runtime_error mapError(const std::string& file, const std::string& what) {
  return std::runtime_error(file + ": " + what);
}

MapYaml readMapYaml(const std::string& path) {
  YAML::Node doc;
  try {
    doc = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw mapError(path, std::string("cannot read the map YAML: ") + e.what());
  }
  MapYaml m;
  try {
    for (const char* key : {"image", "resolution", "origin"}) {
      if (!doc[key]) throw mapError(path, std::string("missing key '") + key + "'");
    }
    m.image = doc["image"].as<std::string>();
    if (!m.image.empty() && m.image[0] != '/') {
      const std::size_t slash = path.rfind('/');
      if (slash != std::string::npos) m.image = path.substr(0, slash + 1) + m.image;
    }
    m.resolution = doc["resolution"].as<double>();
    const YAML::Node origin = doc["origin"];
    if (!origin.IsSequence() || origin.size() != 3) throw mapError(path, "'origin' must be [x, y, yaw]");
    for (std::size_t i = 0; i < 3; ++i) m.origin[i] = origin[i].as<double>();
    // map_server reads negate as an integer; 0/1 and false/true both occur in the wild.
    if (doc["negate"]) {
      const std::string negate = doc["negate"].as<std::string>();
      m.negate = negate == "1" || negate == "true" || negate == "True";
    }
    if (doc["occupied_thresh"]) m.occupied_thresh = doc["occupied_thresh"].as<double>();
    if (doc["free_thresh"]) m.free_thresh = doc["free_thresh"].as<double>();
    if (doc["mode"]) m.mode = doc["mode"].as<std::string>();
  } catch (const YAML::Exception& e) {
    throw mapError(path, std::string("bad value: ") + e.what());
  }
  if (!(m.resolution > 0.0) || !std::isfinite(m.resolution)) {
    throw mapError(path, "resolution " + std::to_string(m.resolution) + " must be positive");
  }
  if (m.mode != "trinary" && m.mode != "scale" && m.mode != "raw") {
    throw mapError(path, "mode '" + m.mode + "' is not trinary, scale or raw");
  }
  return m;
}

// A P5 (binary) or P2 (ASCII) greyscale image, each pixel scaled to 0..255; row 0 is the top.
struct Pgm {
  int width = 0, height = 0;
  std::vector<double> pixels;
};

Pgm readPgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw mapError(path, "cannot open the PGM image");
  std::string magic;
  in >> magic;
  if (magic != "P5" && magic != "P2") throw mapError(path, "not a PGM image (magic '" + magic + "')");
  long header[3];
  for (long& value : header) {
    in >> std::ws;
    while (in.peek() == '#') {  // comment lines between the header's numbers
      std::string comment;
      std::getline(in, comment);
      in >> std::ws;
    }
    if (!(in >> value) || value <= 0) throw mapError(path, "bad PGM header");
  }
  const long width = header[0], height = header[1], maxval = header[2];
  if (width > 100000 || height > 100000 || maxval > 65535) throw mapError(path, "PGM header out of range");
  in.get();  // the single whitespace byte before the pixels
  Pgm pgm;
  pgm.width = static_cast<int>(width);
  pgm.height = static_cast<int>(height);
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  pgm.pixels.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    long value = 0;
    if (magic == "P2") {
      in >> value;
    } else if (maxval < 256) {
      value = in.get();
    } else {
      const int hi = in.get();
      value = (hi << 8) | in.get();
    }
    if (!in || value < 0 || value > maxval) {
      throw mapError(path, "truncated or bad pixel data at pixel " + std::to_string(i) + " of " + std::to_string(count));
    }
    pgm.pixels[i] = 255.0 * static_cast<double>(value) / static_cast<double>(maxval);
  }
  return pgm;
}

// map_server's rules: occ = (255 - value) / 255 (value negated first with negate), above
// occupied_thresh 100, below free_thresh 0, between -1 (trinary) or scaled 1..99 (scale);
// raw takes the value as the occupancy, above 100 unknown. Grid row 0 is the image's bottom.
nav_msgs::OccupancyGrid makeGrid(const std::string& yaml_path, const std::string& frame_id) {
  const MapYaml m = readMapYaml(yaml_path);
  const Pgm pgm = readPgm(m.image);
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = frame_id;
  grid.info.map_load_time = ros::Time::now();
  grid.info.resolution = static_cast<float>(m.resolution);
  grid.info.width = static_cast<std::uint32_t>(pgm.width);
  grid.info.height = static_cast<std::uint32_t>(pgm.height);
  grid.info.origin.position.x = m.origin[0];
  grid.info.origin.position.y = m.origin[1];
  grid.info.origin.orientation.z = std::sin(0.5 * m.origin[2]);
  grid.info.origin.orientation.w = std::cos(0.5 * m.origin[2]);
  grid.data.resize(pgm.pixels.size());
  for (int row = 0; row < pgm.height; ++row) {
    for (int col = 0; col < pgm.width; ++col) {
      double value = pgm.pixels[static_cast<std::size_t>(row) * pgm.width + col];
      if (m.negate) value = 255.0 - value;
      int cell;
      if (m.mode == "raw") {
        cell = value > 100.0 ? -1 : static_cast<int>(std::lround(value));
      } else {
        const double occ = (255.0 - value) / 255.0;
        if (occ > m.occupied_thresh) cell = 100;
        else if (occ < m.free_thresh) cell = 0;
        else if (m.mode == "trinary") cell = -1;
        else cell = 1 + static_cast<int>(98.0 * (occ - m.free_thresh) / (m.occupied_thresh - m.free_thresh));
      }
      grid.data[static_cast<std::size_t>(pgm.height - 1 - row) * pgm.width + col] = static_cast<std::int8_t>(cell);
    }
  }
  return grid;
}

volatile std::sig_atomic_t g_swap_requested = 0;

extern "C" void onSigusr1(int) { g_swap_requested = 1; }

extern "C" void onSigterm(int) { ros::requestShutdown(); }

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "map_publisher");  // removes the remapping arguments from argv
  // SIGTERM ends it as SIGINT does (roscpp's handler only sets the shutdown flag).
  std::signal(SIGTERM, onSigterm);
  if (argc < 2 || argc > 3) {
    ROS_FATAL("usage: %s MAP.yaml [SECOND.yaml] (SIGUSR1 swaps in the other map)", argv[0]);
    return 2;
  }
  ros::NodeHandle n;
  ros::NodeHandle pn("~");
  std::string topic, frame_id;
  pn.param<std::string>("topic", topic, "/map");
  pn.param<std::string>("frame_id", frame_id, "map");

  std::vector<std::string> paths(argv + 1, argv + argc);
  std::vector<nav_msgs::OccupancyGrid> grids;
  try {
    for (const std::string& path : paths) grids.push_back(makeGrid(path, frame_id));
  } catch (const std::exception& e) {
    ROS_FATAL("%s", e.what());
    return 2;
  }

  struct sigaction sa {};
  sa.sa_handler = onSigusr1;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGUSR1, &sa, nullptr);

  ros::Publisher pub = n.advertise<nav_msgs::OccupancyGrid>(topic, 1, /*latch=*/true);
  std::size_t current = 0;
  const auto publish = [&] {
    nav_msgs::OccupancyGrid& grid = grids[current];
    grid.header.stamp = ros::Time::now();
    pub.publish(grid);
    ROS_INFO("published %s on %s: %u x %u cells of %.3f m", paths[current].c_str(), topic.c_str(), grid.info.width,
             grid.info.height, grid.info.resolution);
  };
  publish();
  ros::Rate rate(50.0);
  while (ros::ok()) {
    if (g_swap_requested != 0) {
      g_swap_requested = 0;
      if (grids.size() > 1) {
        current = (current + 1) % grids.size();
        publish();
      } else {
        ROS_WARN("SIGUSR1 without a second map: nothing to swap in");
      }
    }
    ros::spinOnce();
    rate.sleep();
  }
  return 0;
}
