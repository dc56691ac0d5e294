#pragma once
// A recording file: an MCAP file (record/mcap.hpp) holding once the session (the exact
// control configuration, the robot profile, the map, the software that ran, for people the
// daemon's config text) and per control cycle one binary `x-staa-cycle` message (the exact
// inputs and outputs, record/cycle_record.hpp) and the JSON messages people plot in
// Foxglove or Lichtblick: pose, command, state, plan, obstacles, timing. Channels are per
// agent: `/staa/...` for one robot, `/agentN/...` for several. The layout is in
// docs/ARCHITECTURE.md, "Flight recorder".
//
// Outside the real-time threads only: it allocates and does file I/O.

#include "control/control_cycle.hpp"
#include "map/polygon_map.hpp"
#include "record/cycle_record.hpp"
#include "record/mcap.hpp"
#include "robot/robot_profile.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace staa::record {

inline constexpr const char* kRecordingFormat = "staa-recording/1";
inline constexpr const char* kSessionMetadata = "staa.session";

struct AgentInfo {
  std::uint16_t agent = 0;
  std::string controller = "staa";  // staa | dwa | pd
  bool ghost = false;  // a ghost (staa-sim --mode ghost): drives without the blind-corner limit
};

// What one recording ran with, once per file.
struct Session {
  std::string source;      // staad | staa-sim
  std::string software;    // "staa 0.1.0 (abc1234)"
  std::string build_type;  // Release, Debug, ...
  std::string recorded_at; // UTC, ISO 8601
  std::string budget;      // "19.00 ms", "1000 expansions"
  ControlConfig control;   // exactly as the cycles were built with (ControlCycle::config())
  RobotProfile robot;
  PolygonMap map;
  std::vector<AgentInfo> agents;
  std::string config_text;   // staad: the config file as read; staa-sim: its command line
  std::string robot_text;    // the robot profile file, when there is one
};

// This build's software and build type.
std::string softwareVersion();
std::string buildType();
std::string utcNow();

KeyValues sessionMetadata(const Session& session);
// Throws RecordError naming `source` and what is wrong (a key missing, another format, a map
// whose text does not match its checksum).
Session sessionFromMetadata(const McapMetadata& metadata, const std::string& source);

// The channel prefix of an agent: "/staa" for a single robot, "/agentN" for several.
std::string agentPrefix(std::uint16_t agent, bool several);

// One recording file being written. I/O errors never throw: ok() turns false and error()
// says why (the recorder logs it as a warning).
class RecordingFile {
 public:
  RecordingFile(const std::filesystem::path& path, const Session& session);
  ~RecordingFile();
  RecordingFile(const RecordingFile&) = delete;
  RecordingFile& operator=(const RecordingFile&) = delete;

  // One encoded cycle record (encodeCycle): the binary message and its JSON messages.
  void add(std::span<const std::byte> record);
  // An event (a contact of a multi-agent run) as a JSON message on `topic`.
  void event(const std::string& topic, std::int64_t time_ns, const std::string& json);
  void close();

  bool ok() const;
  const std::string& error() const { return error_; }
  std::uint64_t bytes() const { return writer_ ? writer_->bytesWritten() : 0; }
  std::uint64_t cycles() const { return cycles_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct Channels {
    std::uint16_t cycle, pose, command, state, plan, obstacles, timing;
  };
  Channels& channelsFor(std::uint16_t agent);

  std::filesystem::path path_;
  std::ofstream out_;
  std::unique_ptr<McapWriter> writer_;
  bool several_ = false;
  std::map<std::uint16_t, Channels> channels_;
  std::map<std::string, std::uint16_t> event_channels_;
  std::map<std::string, std::uint16_t> schemas_;
  std::uint64_t cycles_ = 0;
  std::string error_;
};

// The JSON messages of one cycle (topic suffix, text), as RecordingFile writes them.
std::vector<std::pair<std::string, std::string>> cycleJson(const CycleRecord& record);

}  // namespace staa::record
