#pragma once
// Where a simulated robot's moving obstacles come from (staa-sim --obstacles): the
// simulation's ground truth (every other body's exact polygon, velocity and turn rate), or
// its depth camera through staad's perception (experiment/agent_camera.hpp).

#include <cstdint>

namespace staa {

enum class ObstacleSource : std::uint8_t { kTruth, kDepth };

inline const char* toString(ObstacleSource source) {
  switch (source) {
    case ObstacleSource::kTruth: return "truth";
    case ObstacleSource::kDepth: return "depth";
  }
  return "unknown";
}

}  // namespace staa
