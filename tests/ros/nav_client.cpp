// staa-test-nav-client: what a ROS navigation user sends staad and reads back, for the tests
// of the ROS link (C++17: ROS 1 headers). One JSON line per result on stdout.
//
//   move-base X Y THETA [--frame map] [--timeout 60] [--cancel-after S] [--action move_base]
//       a move_base action goal; {"state":"SUCCEEDED"|"ABORTED"|"PREEMPTED"|...,"text":...,
//       "feedbacks":N,"last_feedback":[x,y,theta]} when it ends (exit 3 if it does not)
//   simple-goal X Y THETA [--frame map] [--topic /move_base_simple/goal]
//   pose X Y THETA [--topic /global_pose] [--frame map] [--covariance]
//       one localization fix, stamped now
//   bad-odom KIND COUNT [--topic /hsrb/odom]   KIND: nan | inf | back (stamps 10 s in the past)
//   markers [--topic /staad/markers] [--timeout 10] [--with NS]
//       the first MarkerArray (that has namespace NS): {"namespaces":{"ns":points,...}}
//   depth-images ENCODING WIDTH HEIGHT SECONDS [--rate 30]
//       depth images (all "no reading") with camera_info (the Xtion's nominal K) on the HSR's
//       topics, and the static tf base_footprint -> head_rgbd_sensor_rgb_frame (1 m up, an
//       optical frame looking ahead)
//   laser-scans KIND SECONDS [--rate 40] [--range 2.0]
//       the HSR-B's base scans (270 degrees in 1,081 beams, every beam returning at --range m)
//       on /hsrb/base_scan, stamped now; KIND good, or a bad one: empty (no ranges),
//       nan-increment, back (each stamp 10 s before the previous)
//   static-tf PARENT CHILD X Y YAW SECONDS    a static transform, kept up for SECONDS
//   diagnostics [--topic /diagnostics] [--timeout 10] [--until KEY=VALUE]
//       the first DiagnosticArray of staad (whose KEY is VALUE): {"level":L,"message":...,"values":{...}}
//
// Exit codes: 0 done, 2 bad arguments, 3 timed out.

#include <actionlib/client/simple_action_client.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <move_base_msgs/MoveBaseAction.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace {

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;
  std::string option(const std::string& name, const std::string& fallback) const {
    const auto it = options.find(name);
    return it == options.end() ? fallback : it->second;
  }
  double number(const std::string& name, double fallback) const {
    const auto it = options.find(name);
    return it == options.end() ? fallback : std::strtod(it->second.c_str(), nullptr);
  }
};

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

bool pose3(const Args& a, double& x, double& y, double& theta) {
  if (a.positional.size() < 3) return false;
  char* end = nullptr;
  x = std::strtod(a.positional[0].c_str(), &end);
  y = std::strtod(a.positional[1].c_str(), &end);
  theta = std::strtod(a.positional[2].c_str(), &end);
  return true;
}

geometry_msgs::PoseStamped stamped(double x, double y, double theta, const std::string& frame) {
  geometry_msgs::PoseStamped p;
  p.header.stamp = ros::Time::now();
  p.header.frame_id = frame;
  p.pose.position.x = x;
  p.pose.position.y = y;
  p.pose.orientation.z = std::sin(theta / 2.0);
  p.pose.orientation.w = std::cos(theta / 2.0);
  return p;
}

double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

// getNumSubscribers() counts a subscriber as soon as its link is accepted, a little before a
// message published on it is delivered: the publishers below are latched (the subscriber
// gets the last message when its link is up) and wait a moment more.
template <typename Publisher>
bool waitSubscriber(const Publisher& pub, double seconds) {
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(seconds);
  while (pub.getNumSubscribers() == 0) {
    if (!ros::ok() || ros::WallTime::now() > give_up) return false;
    ros::WallDuration(0.01).sleep();
  }
  ros::WallDuration(0.2).sleep();
  return true;
}

int moveBase(const Args& a) {
  double x, y, theta;
  if (!pose3(a, x, y, theta)) return 2;
  actionlib::SimpleActionClient<move_base_msgs::MoveBaseAction> client(a.option("--action", "move_base"), true);
  if (!client.waitForServer(ros::Duration(10.0))) {
    std::fprintf(stderr, "staa-test-nav-client: no action server within 10 s\n");
    return 3;
  }
  move_base_msgs::MoveBaseGoal goal;
  goal.target_pose = stamped(x, y, theta, a.option("--frame", "map"));
  int feedbacks = 0;
  double fx = 0, fy = 0, ft = 0;
  client.sendGoal(goal, {}, {}, [&](const move_base_msgs::MoveBaseFeedbackConstPtr& f) {
    ++feedbacks;
    fx = f->base_position.pose.position.x;
    fy = f->base_position.pose.position.y;
    ft = yawOf(f->base_position.pose.orientation);
  });
  const double cancel_after = a.number("--cancel-after", -1.0);
  const double timeout = a.number("--timeout", 60.0);
  if (cancel_after >= 0.0) {
    client.waitForResult(ros::Duration(cancel_after));
    if (!client.getState().isDone()) client.cancelGoal();
  }
  if (!client.waitForResult(ros::Duration(timeout))) {
    std::fprintf(stderr, "staa-test-nav-client: no result within %g s\n", timeout);
    return 3;
  }
  std::printf("{\"state\":%s,\"text\":%s,\"feedbacks\":%d,\"last_feedback\":[%.6f,%.6f,%.6f]}\n",
              quoted(client.getState().toString()).c_str(), quoted(client.getState().getText()).c_str(), feedbacks, fx,
              fy, ft);
  return 0;
}

int simpleGoal(ros::NodeHandle& n, const Args& a) {
  double x, y, theta;
  if (!pose3(a, x, y, theta)) return 2;
  ros::Publisher pub = n.advertise<geometry_msgs::PoseStamped>(a.option("--topic", "/move_base_simple/goal"), 1, true);
  if (!waitSubscriber(pub, 10.0)) return 3;
  pub.publish(stamped(x, y, theta, a.option("--frame", "map")));
  ros::WallDuration(0.3).sleep();
  std::printf("{\"sent\":true}\n");
  return 0;
}

int pose(ros::NodeHandle& n, const Args& a) {
  double x, y, theta;
  if (!pose3(a, x, y, theta)) return 2;
  const std::string topic = a.option("--topic", "/global_pose");
  const std::string frame = a.option("--frame", "map");
  if (a.options.count("--covariance") != 0) {
    ros::Publisher pub = n.advertise<geometry_msgs::PoseWithCovarianceStamped>(topic, 1, true);
    if (!waitSubscriber(pub, 10.0)) return 3;
    geometry_msgs::PoseWithCovarianceStamped m;
    const geometry_msgs::PoseStamped p = stamped(x, y, theta, frame);
    m.header = p.header;
    m.pose.pose = p.pose;
    pub.publish(m);
    ros::WallDuration(0.5).sleep();  // before the publisher goes out of scope
  } else {
    ros::Publisher pub = n.advertise<geometry_msgs::PoseStamped>(topic, 1, true);
    if (!waitSubscriber(pub, 10.0)) return 3;
    pub.publish(stamped(x, y, theta, frame));
    ros::WallDuration(0.5).sleep();
  }
  std::printf("{\"sent\":true}\n");
  return 0;
}

int badOdom(ros::NodeHandle& n, const Args& a) {
  if (a.positional.size() != 2) return 2;
  const std::string kind = a.positional[0];
  const int count = std::atoi(a.positional[1].c_str());
  ros::Publisher pub = n.advertise<nav_msgs::Odometry>(a.option("--topic", "/hsrb/odom"), 10);
  if (!waitSubscriber(pub, 10.0)) return 3;
  for (int i = 0; i < count; ++i) {
    nav_msgs::Odometry o;
    o.header.stamp = ros::Time::now();
    o.header.frame_id = "odom";
    o.pose.pose.orientation.w = 1.0;
    if (kind == "nan") o.pose.pose.position.x = std::numeric_limits<double>::quiet_NaN();
    else if (kind == "inf") o.twist.twist.linear.x = std::numeric_limits<double>::infinity();
    else if (kind == "back") o.header.stamp = ros::Time::now() - ros::Duration(10.0);
    else return 2;
    pub.publish(o);
    ros::WallDuration(0.02).sleep();
  }
  ros::WallDuration(0.2).sleep();
  std::printf("{\"sent\":%d}\n", count);
  return 0;
}

int depthImages(ros::NodeHandle& n, const Args& a) {
  if (a.positional.size() != 4) return 2;
  const std::string encoding = a.positional[0];
  const auto width = static_cast<std::uint32_t>(std::atoi(a.positional[1].c_str()));
  const auto height = static_cast<std::uint32_t>(std::atoi(a.positional[2].c_str()));
  const double seconds = std::strtod(a.positional[3].c_str(), nullptr);
  const std::string frame = "head_rgbd_sensor_rgb_frame";
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "base_footprint";
  t.child_frame_id = frame;
  t.transform.translation.z = 1.0;
  // The optical frame (z ahead, x right, y down) in the base frame (x ahead, z up).
  t.transform.rotation.x = -0.5;
  t.transform.rotation.y = 0.5;
  t.transform.rotation.z = -0.5;
  t.transform.rotation.w = 0.5;
  tf.sendTransform(t);
  ros::Publisher images = n.advertise<sensor_msgs::Image>("/hsrb/head_rgbd_sensor/depth_registered/image_rect_raw", 2);
  ros::Publisher infos = n.advertise<sensor_msgs::CameraInfo>("/hsrb/head_rgbd_sensor/depth_registered/camera_info", 2);
  if (!waitSubscriber(images, 10.0) || !waitSubscriber(infos, 10.0)) return 3;
  const std::uint32_t bytes = encoding == "32FC1" ? 4 : encoding == "16UC1" ? 2 : 3;
  sensor_msgs::Image image;
  image.header.frame_id = frame;
  image.encoding = encoding;
  image.width = width;
  image.height = height;
  image.step = width * bytes;
  image.data.assign(static_cast<std::size_t>(image.step) * height, 0);
  sensor_msgs::CameraInfo info;
  info.header.frame_id = frame;
  info.width = 640;
  info.height = 480;
  info.K = {570.3, 0.0, 319.5, 0.0, 570.3, 239.5, 0.0, 0.0, 1.0};
  const double rate = a.number("--rate", 30.0);
  // The camera_info and the static tf first, for 0.3 s: the two topics arrive over separate
  // connections, and a first image ahead of any camera_info (or of the camera's pose) is
  // rightly dropped by the daemon; the test counts drops of frames that had both.
  for (int k = 0; k < 9 && ros::ok(); ++k) {
    info.header.stamp = ros::Time::now();
    infos.publish(info);
    ros::WallDuration(1.0 / 30.0).sleep();
  }
  int sent = 0;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    info.header.stamp = image.header.stamp = ros::Time::now();
    infos.publish(info);
    images.publish(image);
    ++sent;
    ros::WallDuration(1.0 / rate).sleep();
  }
  ros::WallDuration(0.3).sleep();
  std::printf("{\"sent\":%d}\n", sent);
  return 0;
}

int laserScans(ros::NodeHandle& n, const Args& a) {
  if (a.positional.size() != 2) return 2;
  const std::string kind = a.positional[0];
  if (kind != "good" && kind != "empty" && kind != "nan-increment" && kind != "back") return 2;
  const double seconds = std::strtod(a.positional[1].c_str(), nullptr);
  ros::Publisher scans = n.advertise<sensor_msgs::LaserScan>("/hsrb/base_scan", 2);
  if (!waitSubscriber(scans, 10.0)) return 3;
  sensor_msgs::LaserScan scan;
  scan.header.frame_id = "base_range_sensor_link";
  scan.angle_min = -2.356194f;
  scan.angle_max = 2.356194f;
  scan.angle_increment = 0.004363323f;
  scan.scan_time = 0.025f;
  scan.range_min = 0.05f;
  scan.range_max = 20.0f;
  scan.ranges.assign(kind == "empty" ? 0 : 1081, static_cast<float>(a.number("--range", 2.0)));
  if (kind == "nan-increment") scan.angle_increment = std::numeric_limits<float>::quiet_NaN();
  const double rate = a.number("--rate", 40.0);
  int sent = 0;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  ros::Time back = ros::Time::now();
  while (ros::ok() && ros::WallTime::now() < end) {
    back -= ros::Duration(10.0);
    scan.header.stamp = kind == "back" ? back : ros::Time::now();
    scans.publish(scan);
    ++sent;
    ros::WallDuration(1.0 / rate).sleep();
  }
  ros::WallDuration(0.3).sleep();
  std::printf("{\"sent\":%d}\n", sent);
  return 0;
}

int staticTf(const Args& a) {
  if (a.positional.size() != 6) return 2;
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = a.positional[0];
  t.child_frame_id = a.positional[1];
  t.transform.translation.x = std::strtod(a.positional[2].c_str(), nullptr);
  t.transform.translation.y = std::strtod(a.positional[3].c_str(), nullptr);
  const double yaw = std::strtod(a.positional[4].c_str(), nullptr);
  t.transform.rotation.z = std::sin(yaw / 2.0);
  t.transform.rotation.w = std::cos(yaw / 2.0);
  tf.sendTransform(t);
  std::printf("{\"sent\":true}\n");
  ros::WallDuration(std::strtod(a.positional[5].c_str(), nullptr)).sleep();
  return 0;
}

int markers(ros::NodeHandle& n, const Args& a) {
  const std::string with = a.option("--with", "");
  bool done = false;
  ros::Subscriber sub = n.subscribe<visualization_msgs::MarkerArray>(
      a.option("--topic", "/staad/markers"), 4, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        if (done) return;
        std::map<std::string, std::size_t> points;
        for (const auto& marker : m->markers) {
          if (marker.action != visualization_msgs::Marker::ADD) continue;
          points[marker.ns] += marker.points.empty() ? 1 : marker.points.size();
          if (marker.header.frame_id.empty()) points["<no frame>"] += 1;
        }
        if (!with.empty() && points.count(with) == 0) return;
        std::string out = "{\"namespaces\":{";
        bool first = true;
        for (const auto& p : points) {
          out += (first ? "" : ",") + quoted(p.first) + ":" + std::to_string(p.second);
          first = false;
        }
        std::printf("%s},\"markers\":%zu}\n", out.c_str(), m->markers.size());
        done = true;
      });
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(a.number("--timeout", 10.0));
  while (ros::ok() && !done && ros::WallTime::now() < end) ros::spinOnce(), ros::WallDuration(0.005).sleep();
  return done ? 0 : 3;
}

int diagnostics(ros::NodeHandle& n, const Args& a) {
  const std::string until = a.option("--until", "");
  const std::size_t eq = until.find('=');
  bool done = false;
  ros::Subscriber sub = n.subscribe<diagnostic_msgs::DiagnosticArray>(
      a.option("--topic", "/diagnostics"), 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) {
          if (done || s.name.find("staad") == std::string::npos) continue;
          bool match = until.empty();
          std::string values;
          for (const auto& kv : s.values) {
            values += (values.empty() ? "" : ",") + quoted(kv.key) + ":" + quoted(kv.value);
            if (eq != std::string::npos && kv.key == until.substr(0, eq) && kv.value == until.substr(eq + 1)) match = true;
          }
          if (!match) continue;
          std::printf("{\"name\":%s,\"level\":%d,\"message\":%s,\"values\":{%s}}\n", quoted(s.name).c_str(), s.level,
                      quoted(s.message).c_str(), values.c_str());
          done = true;
        }
      });
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(a.number("--timeout", 10.0));
  while (ros::ok() && !done && ros::WallTime::now() < end) ros::spinOnce(), ros::WallDuration(0.005).sleep();
  return done ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "staa_test_nav_client", ros::init_options::AnonymousName);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  if (argc < 2) {
    std::fprintf(stderr, "usage: staa-test-nav-client move-base|simple-goal|pose|bad-odom|markers|diagnostics ...\n");
    return 2;
  }
  Args args;
  for (int i = 2; i < argc; ++i) {
    const std::string s = argv[i];
    const bool flag = s == "--covariance";
    if (s.rfind("--", 0) == 0 && !flag && i + 1 < argc) {
      args.options[s] = argv[++i];
    } else if (flag) {
      args.options[s] = "1";
    } else {
      args.positional.push_back(s);
    }
  }
  ros::NodeHandle n;
  // The action client and the callbacks need spinning while moveBase waits.
  ros::AsyncSpinner spinner(1);
  const std::string c = argv[1];
  if (c == "move-base") {
    spinner.start();
    return moveBase(args);
  }
  if (c == "simple-goal") return simpleGoal(n, args);
  if (c == "pose") return pose(n, args);
  if (c == "bad-odom") return badOdom(n, args);
  if (c == "markers") return markers(n, args);
  if (c == "diagnostics") return diagnostics(n, args);
  if (c == "depth-images") return depthImages(n, args);
  if (c == "laser-scans") return laserScans(n, args);
  if (c == "static-tf") return staticTf(args);
  std::fprintf(stderr, "staa-test-nav-client: unknown command '%s'\n", c.c_str());
  return 2;
}
