#pragma once
// Telemetry: one record per control cycle, pushed by the control thread into a lock-free
// ring and written by the service thread to a CSV file (docs/staad.md, "Telemetry"):
//
//   t_s,x,y,theta,v,w,v_cmd,w_cmd,expansions,depth,budget_used_ms,overrun
//
// t_s is CLOCK_MONOTONIC in seconds (the journal's monotonic time), x/y/theta the robot's
// pose (m, rad), v/w its measured velocities, v_cmd/w_cmd the command sent for the next
// period, expansions the planner's queue pops, depth the depth of the state the plan leads
// to, budget_used_ms the planner's time, overrun 1 when the cycle ended past its next
// deadline.

#include "rt/clock.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace staa::staad {

struct TelemetryRecord {
  double t_s = 0.0;
  double x = 0.0, y = 0.0, theta = 0.0;
  double v = 0.0, w = 0.0;
  double v_cmd = 0.0, w_cmd = 0.0;
  std::uint32_t expansions = 0;
  std::int32_t depth = 0;
  double budget_used_ms = 0.0;
  bool overrun = false;
};

// A single-producer single-consumer ring like rt::SpscRing, with its capacity chosen at
// start-up (config telemetry.records, rounded up to a power of two): the slots are
// allocated by the constructor, push/pop never allocate, a full ring drops and counts.
class TelemetryRing {
 public:
  explicit TelemetryRing(std::size_t min_capacity);
  TelemetryRing(const TelemetryRing&) = delete;
  TelemetryRing& operator=(const TelemetryRing&) = delete;

  bool push(const TelemetryRecord& record);  // producer (control thread)
  bool pop(TelemetryRecord& out);            // consumer (service thread)
  std::size_t capacity() const { return mask_ + 1; }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::unique_ptr<TelemetryRecord[]> slots_;
  std::size_t mask_ = 0;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
};

// The CSV header line (without the newline).
const char* telemetryHeader();
// One CSV row (without the newline); fixed precision, no locale.
std::string formatTelemetryRow(const TelemetryRecord& record);

// The telemetry file (service thread). open() throws std::runtime_error naming the path.
class TelemetryWriter {
 public:
  TelemetryWriter() = default;
  ~TelemetryWriter();
  TelemetryWriter(const TelemetryWriter&) = delete;
  TelemetryWriter& operator=(const TelemetryWriter&) = delete;

  void open(const std::filesystem::path& path);  // truncates, writes the header
  bool isOpen() const { return file_ != nullptr; }
  void write(const TelemetryRecord& record);
  void flush();
  void close();
  std::uint64_t rows() const { return rows_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::FILE* file_ = nullptr;
  std::filesystem::path path_;
  std::uint64_t rows_ = 0;
};

}  // namespace staa::staad
