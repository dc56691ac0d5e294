#pragma once
// The picture of a staad run (`staad --svg FILE`, config telemetry.svg; docs/staad.md, "Run
// picture"): the map, the path the robot drove, every goal it was sent (a marker with its
// id, filled once reached), the robot's footprint at its end pose, and a title with the run's
// duration, the distance driven and the goals reached.
//
// The service thread keeps the run (RunRecord) as it drains the telemetry ring and queues
// goals, and draws it when staad stops. Service thread only: it allocates freely.

#include "app/staad/status.hpp"
#include "geometry/types.hpp"
#include "map/polygon_map.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace staa::staad {

class RunRecord {
 public:
  // At most one path point per 5 cm of travel: a long run stays a small picture.
  static constexpr double kMinStepM = 0.05;
  // A step between two records longer than this, and faster than kMaxSpeed, is a pose
  // correction (`staactl pose`), not travel: the path breaks there and the distance skips it.
  static constexpr double kJumpM = 0.5;
  static constexpr double kMaxSpeed = 10.0;  // m/s

  struct Goal {
    std::uint64_t id = 0;
    Pose2 pose;
    bool reached = false;
  };

  // One telemetry record: the robot's pose at monotonic time t_s.
  void addPose(double t_s, const Pose2& pose);
  // A goal as the service thread queued it.
  void addGoal(std::uint64_t id, const Pose2& pose);
  // A status snapshot: a goal counts as reached once a status says reached for its id.
  void observe(const Status& status);

  // The path as polylines (a new one after each pose correction), decimated; the last one
  // ends at the end pose.
  std::vector<std::vector<Vec2>> path() const;
  const std::vector<Goal>& goals() const { return goals_; }
  bool hasPose() const { return records_ > 0; }
  const Pose2& endPose() const { return end_; }
  std::uint64_t records() const { return records_; }
  double durationS() const { return records_ > 0 ? t_end_ - t_start_ : 0.0; }
  double distanceM() const { return distance_m_; }
  std::size_t goalsReached() const { return goals_reached_; }

 private:
  std::vector<std::vector<Vec2>> segments_;
  std::vector<Goal> goals_;
  std::uint64_t records_ = 0;
  Pose2 end_;
  double t_start_ = 0.0, t_end_ = 0.0;
  double distance_m_ = 0.0;
  double travel_since_kept_m_ = 0.0;
  std::size_t goals_reached_ = 0;
  std::uint64_t last_reached_id_ = 0;
};

// The SVG document of `run` over `map` (its scenario goals left out: the run's goals are
// numbered by their ids), with the robot's `footprint` (robot frame) at the end pose.
std::string runSvg(const RunRecord& run, const PolygonMap& map, const Polygon& footprint);

// Writes `text` to PATH.tmp beside `path`, then renames it over `path`: a reader sees the old
// file or the complete new one, never a part. Throws std::runtime_error naming the path.
void writeFileAtomically(const std::filesystem::path& path, std::string_view text);

// At start-up: throws std::runtime_error naming the path when `path` cannot be written that
// way (its directory is missing or not writable), so a bad path stops staad before it runs.
void checkWritable(const std::filesystem::path& path);

}  // namespace staa::staad
