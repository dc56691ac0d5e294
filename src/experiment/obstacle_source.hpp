#pragma once
// Where a simulated robot's moving obstacles come from (staa-sim --obstacles): the
// simulation's ground truth (every other body's exact polygon, velocity and turn rate), or
// its depth camera through staad's perception (experiment/agent_camera.hpp), or the camera
// and the base's laser scanner together (the HSR has both).

#include <cstdint>

namespace staa {

enum class ObstacleSource : std::uint8_t { kTruth, kDepth, kDepthScan };

// Whether the obstacles come through perception (a camera, and maybe a scanner).
inline bool perceived(ObstacleSource source) { return source != ObstacleSource::kTruth; }

inline const char* toString(ObstacleSource source) {
  switch (source) {
    case ObstacleSource::kTruth: return "truth";
    case ObstacleSource::kDepth: return "depth";
    case ObstacleSource::kDepthScan: return "depth+scan";
  }
  return "unknown";
}

}  // namespace staa
