#pragma once
// A scripted base and obstacle sensor for tests: the test sets what the "hardware" reports
// (odometry, status, faults, obstacle frames) and reads back every command written. The
// odometry can integrate the commands (a perfect unicycle with the profile's limits) or be
// set by hand. Not real-time safe in the script calls (tests only); read()/write() allocate
// nothing once `max_commands` commands are recorded (the log is reserved up front).

#include "robot/robot_profile.hpp"
#include "hal/base.hpp"
#include "hal/obstacles.hpp"

#include <atomic>
#include <cstddef>
#include <mutex>
#include <vector>

namespace staa::hal {

class MockBase final : public Base {
 public:
  explicit MockBase(const RobotProfile& robot, const Pose2& start = {}, std::size_t max_commands = 100'000);

  void read(rt::Nanos now) override;
  void write(rt::Nanos now, const VelocityCommand& command) override;
  Odometry odometry() const override;
  BaseStatus status() const override;
  bool setPose(const Pose2& pose) override;
  // The last command written, "sent" at write()'s now plus the scripted send delay.
  CommandSent lastCommandSent() const override;

  // Script: integrate commands into the pose (default on), or hold the odometry as set.
  void setIntegrate(bool on);
  void setOdometry(const Odometry& odometry);
  // Stop advancing the odometry stamp (stale odometry), until unfrozen.
  void freezeOdometry(bool frozen);
  void setFault(BaseFault fault, std::uint32_t code = 0);
  void setEnabled(bool enabled);
  // A command written at `now` counts as sent at now + delay (a driver's send path), or not
  // at all with a delay < 0 (a driver that has not sent it yet).
  void setSendDelay(rt::Nanos delay);
  // Every command written, in order (copy; takes the lock).
  std::vector<VelocityCommand> commands() const;
  VelocityCommand lastCommand() const;

 private:
  RobotProfile robot_;
  mutable std::mutex mutex_;  // tests only: the script runs on the test's thread
  Odometry odometry_;
  Odometry reported_;  // what odometry() returns while frozen: the last report before
  BaseStatus status_;
  bool integrate_ = true;
  bool frozen_ = false;
  rt::Nanos last_read_ = -1;
  VelocityCommand last_command_;
  CommandSent sent_;
  rt::Nanos send_delay_ = 0;
  std::vector<VelocityCommand> log_;
  std::size_t max_commands_;
};

class MockObstacles final : public ObstacleSensor {
 public:
  bool read(rt::Nanos now, ObstacleFrame& out) override;
  // The next read() returns this frame (stamped with read()'s `now` when stamp < 0).
  void push(const ObstacleFrame& frame);
  // No frames at all until resumed (a depth stall).
  void stall(bool stalled);
  // Without a pushed frame, read() returns an empty frame stamped `now` every call (a
  // camera that sees nothing), unless stalled.

 private:
  mutable std::mutex mutex_;
  ObstacleFrame pending_;
  bool has_pending_ = false;
  bool stalled_ = false;
  std::uint64_t sequence_ = 0;
};

}  // namespace staa::hal
