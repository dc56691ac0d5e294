// staa-test-ros-probe: the ROS client side of the tests (C++17: ROS 1 headers). The tests
// themselves are C++20 and include no ROS header; they run this program in the test's graph
// and parse the JSON line it prints on stdout per message or result (line-buffered).
//
//   odom-log SECONDS [--topic /hsrb/odom]          a line per nav_msgs/Odometry for SECONDS
//   pub-twist V W SECONDS [--topic /hsrb/command_velocity] [--rate 30] [--vy VY] [--brake]
//                                                  Twists for SECONDS, a zero one after with
//                                                  --brake; one summary line
//   map-watch COUNT [--topic /map] [--timeout 10]  a line per nav_msgs/OccupancyGrid, COUNT of them
//
// Exit codes: 0 done, 2 bad arguments, 3 timed out (waiting for a message or a subscriber).

#include <geometry_msgs/Twist.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

// Positional arguments and --name value options (--brake is a flag).
struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;
  std::string option(const std::string& name, const std::string& fallback) const {
    const auto it = options.find(name);
    return it == options.end() ? fallback : it->second;
  }
};

bool parseArgs(int argc, char** argv, Args& args) {
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--brake") {
      args.options[a] = "1";
    } else if (a.rfind("--", 0) == 0) {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "staa-test-ros-probe: %s needs a value\n", a.c_str());
        return false;
      }
      args.options[a] = argv[++i];
    } else {
      args.positional.push_back(a);
    }
  }
  return true;
}

bool toDouble(const std::string& text, const char* what, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(out)) {
    std::fprintf(stderr, "staa-test-ros-probe: %s '%s' is not a number\n", what, text.c_str());
    return false;
  }
  return true;
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

int odomLog(ros::NodeHandle& n, const Args& args) {
  double seconds = 0.0;
  if (args.positional.size() != 1 || !toDouble(args.positional[0], "SECONDS", seconds)) return 2;
  const auto onOdom = [](const nav_msgs::Odometry& m) {
    std::printf("{\"t\":%.6f,\"recv\":%.6f,\"frame\":\"%s\",\"child\":\"%s\",\"x\":%.9g,\"y\":%.9g,\"theta\":%.9g,"
                "\"v\":%.9g,\"vy\":%.9g,\"w\":%.9g}\n",
                m.header.stamp.toSec(), ros::Time::now().toSec(), m.header.frame_id.c_str(), m.child_frame_id.c_str(),
                m.pose.pose.position.x, m.pose.pose.position.y, yawOf(m.pose.pose.orientation), m.twist.twist.linear.x,
                m.twist.twist.linear.y, m.twist.twist.angular.z);
  };
  ros::Subscriber sub = n.subscribe<nav_msgs::Odometry>(args.option("--topic", "/hsrb/odom"), 100,
                                                        [&](const nav_msgs::Odometry::ConstPtr& m) { onOdom(*m); },
                                                        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) ros::spinOnce(), ros::WallDuration(0.001).sleep();
  return 0;
}

int pubTwist(ros::NodeHandle& n, const Args& args) {
  double v = 0.0, w = 0.0, seconds = 0.0, rate_hz = 30.0, vy = 0.0;
  if (args.positional.size() != 3 || !toDouble(args.positional[0], "V", v) || !toDouble(args.positional[1], "W", w) ||
      !toDouble(args.positional[2], "SECONDS", seconds) || !toDouble(args.option("--rate", "30"), "--rate", rate_hz) ||
      !toDouble(args.option("--vy", "0"), "--vy", vy) || rate_hz <= 0.0) {
    return 2;
  }
  const std::string topic = args.option("--topic", "/hsrb/command_velocity");
  ros::Publisher pub = n.advertise<geometry_msgs::Twist>(topic, 10);
  // A message published before the subscriber's connection is up is lost.
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(10.0);
  while (pub.getNumSubscribers() == 0) {
    if (!ros::ok() || ros::WallTime::now() > give_up) {
      std::fprintf(stderr, "staa-test-ros-probe: no subscriber on %s within 10 s\n", topic.c_str());
      return 3;
    }
    ros::WallDuration(0.005).sleep();
  }
  geometry_msgs::Twist cmd;
  cmd.linear.x = v;
  cmd.linear.y = vy;
  cmd.angular.z = w;
  const ros::Time first = ros::Time::now();
  ros::Time last = first;
  int sent = 0;
  // The last one goes out at the end of the interval: the command covers all of SECONDS.
  while (ros::ok()) {
    last = ros::Time::now();
    pub.publish(cmd);
    ++sent;
    const double left = seconds - (ros::Time::now() - first).toSec();
    if (left <= 0.0) break;
    ros::WallDuration(std::min(left, 1.0 / rate_hz)).sleep();
  }
  double brake_at = 0.0;
  if (args.options.count("--brake") != 0) {
    pub.publish(geometry_msgs::Twist());
    brake_at = ros::Time::now().toSec();
  }
  // Let the transport flush before the publisher goes away.
  ros::WallDuration(0.2).sleep();
  std::printf("{\"first\":%.6f,\"last\":%.6f,\"sent\":%d,\"brake_at\":%.6f}\n", first.toSec(), last.toSec(), sent,
              brake_at);
  return 0;
}

std::uint64_t fnv1a(const std::vector<std::int8_t>& data) {
  std::uint64_t h = 14695981039346656037ull;
  for (const std::int8_t c : data) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 1099511628211ull;
  }
  return h;
}

int mapWatch(ros::NodeHandle& n, const Args& args) {
  double count = 0.0, timeout = 10.0;
  if (args.positional.size() != 1 || !toDouble(args.positional[0], "COUNT", count) || count < 1.0 ||
      !toDouble(args.option("--timeout", "10"), "--timeout", timeout)) {
    return 2;
  }
  int received = 0;
  const auto onMap = [&](const nav_msgs::OccupancyGrid::ConstPtr& m) {
    long occupied = 0, free = 0, unknown = 0, other = 0;
    for (const std::int8_t c : m->data) {
      if (c == 100) ++occupied;
      else if (c == 0) ++free;
      else if (c == -1) ++unknown;
      else ++other;
    }
    const auto& o = m->info.origin;
    std::printf("{\"frame\":\"%s\",\"t\":%.6f,\"load_time\":%.6f,\"width\":%u,\"height\":%u,\"resolution\":%.9g,"
                "\"origin\":[%.9g,%.9g,%.9g],\"cells\":%zu,\"occupied\":%ld,\"free\":%ld,\"unknown\":%ld,"
                "\"other\":%ld,\"fnv1a\":\"%016llx\"}\n",
                m->header.frame_id.c_str(), m->header.stamp.toSec(), m->info.map_load_time.toSec(), m->info.width,
                m->info.height, m->info.resolution, o.position.x, o.position.y, yawOf(o.orientation), m->data.size(),
                occupied, free, unknown, other, static_cast<unsigned long long>(fnv1a(m->data)));
    ++received;
  };
  const std::string topic = args.option("--topic", "/map");
  ros::Subscriber sub = n.subscribe<nav_msgs::OccupancyGrid>(topic, 2, onMap);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && received < static_cast<int>(count)) {
    if (ros::WallTime::now() > end) {
      std::fprintf(stderr, "staa-test-ros-probe: %d of %d maps on %s within %g s\n", received, static_cast<int>(count),
                   topic.c_str(), timeout);
      return 3;
    }
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "staa_test_probe", ros::init_options::AnonymousName);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  Args args;
  if (argc < 2 || !parseArgs(argc, argv, args)) {
    std::fprintf(stderr, "usage: staa-test-ros-probe odom-log|pub-twist|map-watch ARGS... (see the source)\n");
    return 2;
  }
  ros::NodeHandle n;
  const std::string command = argv[1];
  if (command == "odom-log") return odomLog(n, args);
  if (command == "pub-twist") return pubTwist(n, args);
  if (command == "map-watch") return mapWatch(n, args);
  std::fprintf(stderr, "staa-test-ros-probe: unknown command '%s' (odom-log, pub-twist, map-watch)\n", command.c_str());
  return 2;
}
