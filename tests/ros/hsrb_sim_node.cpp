// staa-test-hsrb-base: a simulated HSR-B base for the ROS tests (C++17: ROS 1 headers).
// Takes geometry_msgs/Twist on /hsrb/command_velocity as the robot's ROS 1 stack does,
// drives a unicycle (linear.x and angular.z; staad commands no sideways speed, so linear.y is
// only counted) toward the command within the HSR's speed and acceleration limits, zeroes the
// command 0.5 s after the last one as the real base does, and publishes nav_msgs/Odometry on
// /hsrb/odom and the tf odom -> base_footprint at 50 Hz.
//
// Private parameters (defaults): ~cmd_topic (/hsrb/command_velocity), ~odom_topic (/hsrb/odom),
// ~rate (50 Hz), ~max_v (0.34 m/s: 8.5 rad/s wheels of 0.04 m radius), ~max_w (1.8 rad/s),
// ~max_acc (1.67 m/s^2: 41.7 rad/s^2 at the wheel), ~max_alpha (5 rad/s^2), ~cmd_timeout
// (0.5 s), ~x ~y ~theta (the start pose, 0), ~publish_tf (true), ~odom_frame (odom),
// ~base_frame (base_footprint). A bad parameter is fatal: exit 2.

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cmath>
#include <string>

namespace {

struct Params {
  std::string cmd_topic = "/hsrb/command_velocity";
  std::string odom_topic = "/hsrb/odom";
  std::string odom_frame = "odom";
  std::string base_frame = "base_footprint";
  double rate = 50.0;
  double max_v = 0.34;
  double max_w = 1.8;
  double max_acc = 1.67;
  double max_alpha = 5.0;
  double cmd_timeout = 0.5;
  double x = 0.0, y = 0.0, theta = 0.0;
  bool publish_tf = true;
};

// Reads the parameters; false (after ROS_FATAL naming the parameter and its value) when one
// is out of range.
bool readParams(const ros::NodeHandle& pn, Params& p) {
  pn.param("cmd_topic", p.cmd_topic, p.cmd_topic);
  pn.param("odom_topic", p.odom_topic, p.odom_topic);
  pn.param("odom_frame", p.odom_frame, p.odom_frame);
  pn.param("base_frame", p.base_frame, p.base_frame);
  pn.param("publish_tf", p.publish_tf, p.publish_tf);
  struct Positive {
    const char* name;
    double* value;
  };
  for (const Positive& q : {Positive{"rate", &p.rate}, Positive{"max_v", &p.max_v}, Positive{"max_w", &p.max_w},
                            Positive{"max_acc", &p.max_acc}, Positive{"max_alpha", &p.max_alpha},
                            Positive{"cmd_timeout", &p.cmd_timeout}}) {
    pn.param(q.name, *q.value, *q.value);
    if (!std::isfinite(*q.value) || *q.value <= 0.0) {
      ROS_FATAL("parameter %s/%s = %g: must be a positive finite number", pn.getNamespace().c_str(), q.name, *q.value);
      return false;
    }
  }
  for (const Positive& q : {Positive{"x", &p.x}, Positive{"y", &p.y}, Positive{"theta", &p.theta}}) {
    pn.param(q.name, *q.value, *q.value);
    if (!std::isfinite(*q.value)) {
      ROS_FATAL("parameter %s/%s = %g: must be finite", pn.getNamespace().c_str(), q.name, *q.value);
      return false;
    }
  }
  for (const std::string* topic : {&p.cmd_topic, &p.odom_topic, &p.odom_frame, &p.base_frame}) {
    if (topic->empty()) {
      ROS_FATAL("parameters under %s: topic and frame names must not be empty", pn.getNamespace().c_str());
      return false;
    }
  }
  return true;
}

// `current` moved toward `target` by at most `step`.
double approach(double current, double target, double step) {
  return current + std::clamp(target - current, -step, step);
}

class SimBase {
 public:
  SimBase(ros::NodeHandle& n, const Params& p) : p_(p), x_(p.x), y_(p.y), theta_(p.theta) {
    odom_pub_ = n.advertise<nav_msgs::Odometry>(p.odom_topic, 10);
    cmd_sub_ = n.subscribe(p.cmd_topic, 10, &SimBase::onCommand, this, ros::TransportHints().tcpNoDelay());
  }

  void run() {
    ros::Rate rate(p_.rate);
    ros::Time last = ros::Time::now();
    while (ros::ok()) {
      ros::spinOnce();
      const ros::Time now = ros::Time::now();
      // The time actually passed (a late cycle integrates its whole interval), capped so a
      // stall does not teleport the base.
      const double dt = std::min((now - last).toSec(), 0.1);
      last = now;
      step(now, dt);
      publish(now);
      rate.sleep();
    }
    // After the shutdown rosconsole prints nothing: plain stdout.
    std::printf("commands received: %lu (%lu with a sideways speed, %lu not finite, ignored)\n", commands_, sideways_,
                rejected_);
  }

 private:
  void onCommand(const geometry_msgs::Twist& cmd) {
    ++commands_;
    if (cmd.linear.y != 0.0) ++sideways_;
    if (!std::isfinite(cmd.linear.x) || !std::isfinite(cmd.angular.z)) {
      ++rejected_;
      return;
    }
    cmd_v_ = std::clamp(cmd.linear.x, -p_.max_v, p_.max_v);
    cmd_w_ = std::clamp(cmd.angular.z, -p_.max_w, p_.max_w);
    last_cmd_ = ros::Time::now();
  }

  void step(const ros::Time& now, double dt) {
    const bool timed_out = last_cmd_.isZero() || (now - last_cmd_).toSec() > p_.cmd_timeout;
    const double target_v = timed_out ? 0.0 : cmd_v_;
    const double target_w = timed_out ? 0.0 : cmd_w_;
    v_ = approach(v_, target_v, p_.max_acc * dt);
    w_ = approach(w_, target_w, p_.max_alpha * dt);
    // Midpoint heading: exact for a constant speed along the step's arc to second order.
    const double mid = theta_ + 0.5 * w_ * dt;
    x_ += v_ * dt * std::cos(mid);
    y_ += v_ * dt * std::sin(mid);
    theta_ = std::remainder(theta_ + w_ * dt, 2.0 * M_PI);
  }

  void publish(const ros::Time& now) {
    nav_msgs::Odometry odom;
    odom.header.stamp = now;
    odom.header.frame_id = p_.odom_frame;
    odom.child_frame_id = p_.base_frame;
    odom.pose.pose.position.x = x_;
    odom.pose.pose.position.y = y_;
    odom.pose.pose.orientation.z = std::sin(0.5 * theta_);
    odom.pose.pose.orientation.w = std::cos(0.5 * theta_);
    odom.twist.twist.linear.x = v_;
    odom.twist.twist.angular.z = w_;
    // Small, fixed covariances (x, y, yaw) so consumers that check them see a valid matrix.
    for (const int i : {0, 7, 35}) {
      odom.pose.covariance[i] = 1e-4;
      odom.twist.covariance[i] = 1e-4;
    }
    odom_pub_.publish(odom);
    if (p_.publish_tf) {
      geometry_msgs::TransformStamped t;
      t.header = odom.header;
      t.child_frame_id = p_.base_frame;
      t.transform.translation.x = x_;
      t.transform.translation.y = y_;
      t.transform.rotation = odom.pose.pose.orientation;
      tf_.sendTransform(t);
    }
  }

  Params p_;
  ros::Publisher odom_pub_;
  ros::Subscriber cmd_sub_;
  tf2_ros::TransformBroadcaster tf_;
  double x_, y_, theta_;
  double v_ = 0.0, w_ = 0.0;
  double cmd_v_ = 0.0, cmd_w_ = 0.0;
  ros::Time last_cmd_;
  unsigned long commands_ = 0, sideways_ = 0, rejected_ = 0;
};

extern "C" void onSigterm(int) { ros::requestShutdown(); }

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "hsrb_sim_base");
  // SIGTERM ends it as SIGINT does (roscpp's handler only sets the shutdown flag).
  std::signal(SIGTERM, onSigterm);
  ros::NodeHandle n;
  ros::NodeHandle pn("~");
  Params p;
  if (!readParams(pn, p)) return 2;
  SimBase base(n, p);
  ROS_INFO("simulated HSR-B base: %s -> %s at %.0f Hz, from (%.3f, %.3f, %.3f)", p.cmd_topic.c_str(),
           p.odom_topic.c_str(), p.rate, p.x, p.y, p.theta);
  base.run();
  return 0;
}
