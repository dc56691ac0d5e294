#include "hal/ros/ros_base.hpp"

#include <cmath>

namespace staa::hal {

namespace {

bool finite(const OdometrySample& s) {
  return std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.yaw) && std::isfinite(s.v) && std::isfinite(s.w);
}

// a * b: b's frame mapped through a.
Pose2 compose(const Pose2& a, const Pose2& b) {
  const Vec2 p = a.transform(b.position());
  return {p.x(), p.y(), wrapAngle(a.theta + b.theta)};
}

Pose2 inverse(const Pose2& a) {
  const Vec2 p = Pose2{0.0, 0.0, -a.theta}.transform(-a.position());
  return {p.x(), p.y(), wrapAngle(-a.theta)};
}

// The measurement's time on the monotonic clock: arrival minus the age the transport saw.
// A negative age (clocks of two machines apart) or one beyond a second says nothing reliable
// about the age: then the arrival is the stamp, and staleness is judged from arrival alone.
rt::Nanos monotonicStamp(std::int64_t arrival, std::int64_t age) {
  if (age < 0 || age > rt::kNanosPerSecond) return arrival;
  return arrival - age;
}

}  // namespace

RosBase::RosBase(RosBaseOptions options) : options_(options) { status_.enabled = true; }

void RosBase::offerOdometry(const OdometrySample& sample) {
  BaseFault fault = BaseFault::kNone;
  if (!finite(sample)) {
    fault = BaseFault::kOdometryInvalid;
  } else if (offered_any_ && sample.stamp_ns <= last_offered_stamp_) {
    // The same stamp again is a repeat (dropped); an older one is a clock gone back.
    if (sample.stamp_ns < last_offered_stamp_) fault = BaseFault::kOdometryStampBack;
    bad_offered_.fetch_add(1, std::memory_order_relaxed);
    if (fault == BaseFault::kNone) return;
  }
  if (fault != BaseFault::kNone) {
    if (fault == BaseFault::kOdometryInvalid) bad_offered_.fetch_add(1, std::memory_order_relaxed);
    pending_fault_.store(static_cast<std::uint8_t>(fault), std::memory_order_release);
    return;
  }
  offered_any_ = true;
  last_offered_stamp_ = sample.stamp_ns;
  odometry_in_.writeBuffer() = sample;
  odometry_in_.publish();
}

void RosBase::offerPose(const PoseSample& sample) {
  fixes_in_.writeBuffer() = sample;
  fixes_in_.publish();
}

void RosBase::takeOdometry() {
  status_.bad_frames = bad_offered_.load(std::memory_order_relaxed);
  const auto fault = static_cast<BaseFault>(pending_fault_.exchange(0, std::memory_order_acq_rel));
  if (fault != BaseFault::kNone) {
    status_.fault = fault;
    fault_fresh_ = true;
  }
  if (!odometry_in_.update()) return;
  const OdometrySample& s = odometry_in_.readBuffer();
  if (fault_fresh_) {
    fault_fresh_ = false;  // this sample may predate the bad one: the next clears the fault
  } else {
    status_.fault = BaseFault::kNone;
  }
  have_odometry_ = true;
  odom_pose_ = Pose2{s.x, s.y, wrapAngle(s.yaw)};
  history_[history_next_] = Stamped{s.stamp_ns, odom_pose_};
  history_next_ = (history_next_ + 1) % kHistory;
  if (history_count_ < kHistory) ++history_count_;
  odometry_.stamp = monotonicStamp(s.arrival_ns, s.age_ns);
  odometry_.v = s.v;
  odometry_.w = s.w;
  status_.stamp = odometry_.stamp;
}

// The odometry pose at `ros_stamp`, interpolated between the two samples around it (the
// newest when the stamp is ahead of it by less than a sample period's worth of history).
bool RosBase::odometryAt(std::int64_t ros_stamp, Pose2& out) const {
  if (history_count_ == 0) return false;
  const std::size_t newest = (history_next_ + kHistory - 1) % kHistory;
  // Stamp 0 is ROS's "the latest" (tf's Time(0), an unstamped message).
  if (ros_stamp == 0 || ros_stamp >= history_[newest].ros_stamp) {
    out = history_[newest].pose;
    return true;
  }
  for (std::size_t k = 1; k < history_count_; ++k) {
    const Stamped& later = history_[(newest + kHistory - k + 1) % kHistory];
    const Stamped& earlier = history_[(newest + kHistory - k) % kHistory];
    if (ros_stamp < earlier.ros_stamp) continue;
    const double span = static_cast<double>(later.ros_stamp - earlier.ros_stamp);
    const double f = span > 0.0 ? static_cast<double>(ros_stamp - earlier.ros_stamp) / span : 1.0;
    out.x = earlier.pose.x + f * (later.pose.x - earlier.pose.x);
    out.y = earlier.pose.y + f * (later.pose.y - earlier.pose.y);
    out.theta = wrapAngle(earlier.pose.theta + f * wrapAngle(later.pose.theta - earlier.pose.theta));
    return true;
  }
  return false;  // older than the history kept
}

void RosBase::takeFix() {
  if (fixes_in_.update()) {
    const PoseSample& f = fixes_in_.readBuffer();
    if (!options_.localization) return;
    if (!(std::isfinite(f.x) && std::isfinite(f.y) && std::isfinite(f.yaw))) {
      ++status_.localization_dropped;
      return;
    }
    pending_fix_ = f;
    have_pending_fix_ = true;
  }
  if (!have_pending_fix_ || !have_odometry_) return;
  Pose2 odom_at_fix;
  if (!odometryAt(pending_fix_.stamp_ns, odom_at_fix)) {
    ++status_.localization_dropped;
    have_pending_fix_ = false;
    return;
  }
  have_pending_fix_ = false;
  const Pose2 before = toMap(odom_pose_);
  map_from_odom_ = compose(Pose2{pending_fix_.x, pending_fix_.y, wrapAngle(pending_fix_.yaw)}, inverse(odom_at_fix));
  const Pose2 after = toMap(odom_pose_);
  ++status_.localization_fixes;
  status_.last_jump_m = std::hypot(after.x - before.x, after.y - before.y);
  status_.last_jump_rad = std::abs(wrapAngle(after.theta - before.theta));
}

Pose2 RosBase::toMap(const Pose2& odom) const { return compose(map_from_odom_, odom); }

void RosBase::read(rt::Nanos) {
  takeOdometry();
  takeFix();
  if (have_odometry_) odometry_.pose = toMap(odom_pose_);
}

void RosBase::write(rt::Nanos now, const VelocityCommand& command) {
  // A twist every control period, and at once for a new command; a brake is a zero twist,
  // sent at the same rate (the HSR zeroes its speed 0.5 s after the last one).
  const bool fresh = command.stamp != last_twist_command_;
  if (!fresh && last_twist_at_ >= 0 && now - last_twist_at_ < options_.twist_period) return;
  TwistSample& t = twist_out_.writeBuffer();
  t.v = command.brake ? 0.0 : command.v;
  t.w = command.brake ? 0.0 : command.w;
  t.brake = command.brake;
  t.command_stamp_ns = command.stamp;
  t.odometry_stamp_ns = command.odometry_stamp;
  twist_out_.publish();
  // Lock-free: an atomic and, with a waiter, one futex wake.
  if (!twist_signalled_.exchange(true, std::memory_order_acq_rel)) twist_ready_.release();
  last_twist_at_ = now;
  last_twist_command_ = command.stamp;
}

bool RosBase::setPose(const Pose2& pose) {
  if (!have_odometry_) return false;
  map_from_odom_ = compose(pose, inverse(odom_pose_));
  odometry_.pose = toMap(odom_pose_);
  return true;
}

CommandSent RosBase::lastCommandSent() const {
  CommandSent c;
  c.sent_at = sent_at_.load(std::memory_order_acquire);
  c.command_stamp = sent_command_stamp_.load(std::memory_order_acquire);
  return c;
}

bool RosBase::waitTwist(rt::Nanos timeout) {
  if (!twist_ready_.try_acquire_for(std::chrono::nanoseconds(timeout))) return false;
  twist_signalled_.store(false, std::memory_order_release);  // before takeTwist: a later write signals again
  return true;
}

bool RosBase::takeTwist(TwistSample& out) {
  if (!twist_out_.update()) return false;
  out = twist_out_.readBuffer();
  return true;
}

void RosBase::twistSent(std::int64_t command_stamp, rt::Nanos sent_at) {
  sent_command_stamp_.store(command_stamp, std::memory_order_release);
  sent_at_.store(sent_at, std::memory_order_release);
}

}  // namespace staa::hal
