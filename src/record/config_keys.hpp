#pragma once
// The control cycle's configuration as named keys: every field of ControlConfig (and of the
// structs in it) under a dotted name ("staa.dt", "staa.heuristic.kind", "local.cell_m"), so
// that a recording carries the exact configuration its cycles ran with, and `staa-replay
// --set KEY=VALUE` can change one. Doubles are written so that they read back bit for bit.
//
// A field added to ControlConfig, StaaConfig, HeuristicConfig, LocalMapConfig or
// GlobalPathOptions needs its key in visitControlConfig (config_keys.cpp); the unit test
// RecordConfigKeys.CoverEveryField fails until it has one.

#include "control/control_cycle.hpp"
#include "robot/robot_profile.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace staa::record {

class KeyError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// {"rate_hz": 30, "staa.dt": 0.3, ...}: every key, as a JSON object's text.
std::string controlConfigJson(const ControlConfig& config);
// Reads such an object; a missing key keeps `base`'s value, an unknown one is an error.
ControlConfig controlConfigFromJson(const std::string& json, const ControlConfig& base = {});
// Sets one key from its text ("staa.heuristic.kind" = "path-euclid"); KeyError names the key
// and the value, and lists the keys when it is unknown.
void setControlKey(ControlConfig& config, const std::string& key, const std::string& value);
// Every key with its value as text (for --help and error messages).
std::vector<std::pair<std::string, std::string>> controlConfigKeys(const ControlConfig& config);

// The robot profile the cycles ran with: {"name", "footprint": [[x, y], ...], "limits": {...}}.
std::string robotProfileJson(const RobotProfile& robot);
RobotProfile robotProfileFromJson(const std::string& json);

}  // namespace staa::record
