#pragma once
// hal: ros — the base driven over a ROS transport (the HSR-B: the supported way to command its
// base is ROS; docs/ros.md). The transport's callback thread offers odometry and localization
// fixes (BaseSink); the base I/O thread calls read() and write() as for every backend; a
// publisher thread of the transport takes the twist with takeTwist() after waitTwist().
// Nothing here includes ROS: a ROS 2 transport uses the same backend.
//
// Faults, each a named BaseFault that brakes (the control thread holds the robot):
//   kOdometryInvalid   an odometry message had a NaN or infinite value (dropped, counted)
//   kOdometryStampBack an odometry message's stamp went back (dropped, counted)
// Each clears with good odometry after it (at the next read() but one). Every message is
// judged as it is offered, so none slips by between two reads; a repeated stamp is dropped
// and counted without a fault. No odometry at all is the control thread's stale odometry
// fault (Odometry::stamp does not advance).
//
// The pose staad plans in is the map frame: odometry (the odometry frame) corrected by the
// latest localization fix, T_map_odom = fix * inverse(odometry at the fix's stamp); the
// odometry at that stamp is interpolated from the last kHistory samples (stamp 0, ROS's "the
// latest", takes the newest). A fix is applied by
// read(), between two control cycles; its jump (how far the corrected pose moved) is in
// status(). setPose() (staactl pose) re-anchors the same correction.
//
// read(), write() and the publisher's takeTwist() do not allocate, lock or block.

#include "hal/base.hpp"
#include "hal/ros/base_port.hpp"
#include "rt/triple_buffer.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <semaphore>

namespace staa::hal {

struct RosBaseOptions {
  rt::Nanos twist_period = 33'333'333;  // the control period: a twist at least this often
  bool localization = true;             // false: fixes are ignored (odometry is the map frame)
};

class RosBase final : public Base, public BaseSink {
 public:
  static constexpr std::size_t kHistory = 128;  // odometry samples kept (2.5 s at 50 Hz)

  explicit RosBase(RosBaseOptions options = {});

  // Base (the base I/O thread).
  void read(rt::Nanos now) override;
  void write(rt::Nanos now, const VelocityCommand& command) override;
  Odometry odometry() const override { return odometry_; }
  BaseStatus status() const override { return status_; }
  bool setPose(const Pose2& pose) override;
  CommandSent lastCommandSent() const override;

  // BaseSink (the transport's callback thread).
  void offerOdometry(const OdometrySample& sample) override;
  void offerPose(const PoseSample& sample) override;

  // The publisher thread: waits up to `timeout` for a twist to send; takes the latest.
  bool waitTwist(rt::Nanos timeout);
  bool takeTwist(TwistSample& out);
  // After publishing: when (monotonic) the twist carrying `command_stamp` went out.
  void twistSent(std::int64_t command_stamp, rt::Nanos sent_at);

 private:
  struct Stamped {
    std::int64_t ros_stamp;
    Pose2 pose;
  };
  void takeOdometry();
  void takeFix();
  bool odometryAt(std::int64_t ros_stamp, Pose2& out) const;
  Pose2 toMap(const Pose2& odom) const;

  RosBaseOptions options_;
  // transport -> base thread
  rt::TripleBuffer<OdometrySample> odometry_in_;
  std::int64_t last_offered_stamp_ = -1;  // the transport thread's
  bool offered_any_ = false;
  std::atomic<std::uint64_t> bad_offered_{0};
  std::atomic<std::uint8_t> pending_fault_{0};  // a BaseFault seen by offerOdometry, not yet read
  rt::TripleBuffer<PoseSample> fixes_in_;
  // base thread -> publisher thread
  rt::TripleBuffer<TwistSample> twist_out_;
  std::binary_semaphore twist_ready_{0};
  // Set while a release is outstanding: a binary semaphore must not be released twice.
  std::atomic<bool> twist_signalled_{false};
  std::atomic<std::int64_t> sent_command_stamp_{-1};
  std::atomic<std::int64_t> sent_at_{-1};

  // base thread only
  Odometry odometry_;
  BaseStatus status_;
  Pose2 odom_pose_;          // the newest good odometry, in the odometry frame
  bool have_odometry_ = false;
  bool fault_fresh_ = false;  // the fault came in this read: good odometry of the same read does not clear it
  bool have_pending_fix_ = false;
  PoseSample pending_fix_;
  Pose2 map_from_odom_;      // T_map_odom
  std::array<Stamped, kHistory> history_{};
  std::size_t history_count_ = 0;
  std::size_t history_next_ = 0;
  rt::Nanos last_twist_at_ = -1;
  rt::Nanos last_twist_command_ = -2;
};

}  // namespace staa::hal
