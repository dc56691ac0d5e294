#pragma once
// staad as a whole: wires the configuration, the HAL, the control task, the rings and
// buffers, the control socket and the threads, in the start-up order of docs/staad.md
// ("Start-up order"):
//
//   1. config loaded and validated (a bad value: exit 2, the key and the value named);
//   2. every workspace created: HAL (the base: sim or socketcan, whose bus is opened here,
//      exit 3 when it cannot be; the obstacles: sim or none), channels, control task,
//      control socket, telemetry file;
//   3. rt::lockMemory (mlockall, malloc tuned, heap and stack prefaulted);
//   4. the real-time threads started with their ThreadSpecs: base and perception first
//      (the control thread's first cycle then sees fresh inputs), then control;
//   5. after the control thread's first cycle: the allocation count reset, READY=1.
//
// The main thread then runs the service loop. SIGTERM/SIGINT: the control thread brakes and
// holds; once the robot stands (or 0.6 s passed) STOPPING=1, the threads are joined, the
// run's picture is written (with an SVG path), exit 0.

#include "app/staad/config.hpp"
#include "rt/clock.hpp"

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace staa::staad {

enum ExitCode : int {
  kExitOk = 0,         // stopped by SIGTERM/SIGINT
  kExitFailure = 1,    // run-time failure: socket busy, a thread could not start, ...
  kExitBadConfig = 2,  // bad config, bad arguments, bad environment
  kExitDevice = 3,     // the hardware cannot be opened at start-up (no such CAN interface, no
                       // socket at the unix: path): the message names it
};

// The base's bus or device cannot be opened at start-up: staad exits 3.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DaemonOptions {
  std::filesystem::path config_file;  // empty: defaultConfigPath()
  std::optional<HalBackend> hal;      // overrides the config's hal
  std::optional<std::string> socket_path;
  std::optional<std::filesystem::path> telemetry_path;
  std::optional<std::filesystem::path> svg_path;  // overrides telemetry.svg
  std::vector<std::string> ros_remappings;  // NAME:=VALUE from the command line (roslaunch)
};

// config/staad.yaml relative to the current directory if it exists, else
// /etc/staad/staad.yaml if it exists; empty when neither does.
std::filesystem::path defaultConfigPath();

// Loads the config and applies the command line's overrides. Throws ConfigError naming the
// file (or option), the key and the value.
DaemonConfig loadConfig(const DaemonOptions& options);

// Runs staad until SIGTERM/SIGINT on `clock` (the monotonic clock in production); every
// message goes to `log`. Returns the exit code; never throws.
int runDaemon(const DaemonOptions& options, rt::Clock& clock, std::ostream& log);

}  // namespace staa::staad
