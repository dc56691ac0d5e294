#pragma once
// Where a simulated robot's moving obstacles come from (staa-sim --obstacles): the
// simulation's ground truth (every other body's exact polygon, velocity and turn rate), or
// its depth camera through staad's perception (experiment/agent_camera.hpp), or the camera
// and the base's laser scanner together (the HSR has both), or the ground truth of what lies
// in the line of sight (experiment/sight_obstacles.hpp: what occlusion alone costs).

#include <cstdint>

namespace staa {

enum class ObstacleSource : std::uint8_t { kTruth, kDepth, kDepthScan, kSight };

// Whether the obstacles come through perception (a camera, and maybe a scanner).
inline bool perceived(ObstacleSource source) {
  return source == ObstacleSource::kDepth || source == ObstacleSource::kDepthScan;
}

inline const char* toString(ObstacleSource source) {
  switch (source) {
    case ObstacleSource::kTruth: return "truth";
    case ObstacleSource::kDepth: return "depth";
    case ObstacleSource::kDepthScan: return "depth+scan";
    case ObstacleSource::kSight: return "sight";
  }
  return "unknown";
}

}  // namespace staa
