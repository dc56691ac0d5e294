#pragma once
// Logging from real-time threads without formatting or I/O: a thread pushes a record (a
// static message and up to three numbers) into its own ring; the service thread pops and
// formats them. A full ring drops the record and counts it.

#include "rt/clock.hpp"
#include "rt/spsc_ring.hpp"

#include <cstdint>

namespace staa::rt {

enum class LogLevel : std::uint8_t { kInfo, kWarning, kError };

struct LogRecord {
  Nanos time = 0;
  LogLevel level = LogLevel::kInfo;
  const char* message = "";  // a string literal (static storage): never freed
  double values[3] = {0.0, 0.0, 0.0};
  std::uint8_t value_count = 0;
};

using LogRing = SpscRing<LogRecord, 256>;

// Pushes one record (no formatting, no allocation); a full ring drops and counts it.
inline void pushLog(LogRing& ring, Nanos now, LogLevel level, const char* message, double a = 0.0, double b = 0.0,
                    double c = 0.0, std::uint8_t count = 0) {
  LogRecord r;
  r.time = now;
  r.level = level;
  r.message = message;
  r.values[0] = a;
  r.values[1] = b;
  r.values[2] = c;
  r.value_count = count;
  ring.push(r);
}

}  // namespace staa::rt
