#include "app/staad/status.hpp"

namespace staa::staad {

// The spellings are part of the `staactl status --json` contract (docs/ARCHITECTURE.md section 6):
// scripts compare against them, so they never change with the enumerators' names.

const char* toString(DaemonState state) {
  switch (state) {
    case DaemonState::kIdle: return "idle";
    case DaemonState::kDriving: return "driving";
    case DaemonState::kReached: return "reached";
    case DaemonState::kUnreachable: return "unreachable";
    case DaemonState::kStopped: return "stopped";
    case DaemonState::kFault: return "fault";
  }
  return "unknown";  // a value cast from a corrupt byte: say so rather than crash
}

const char* toString(FaultKind fault) {
  switch (fault) {
    case FaultKind::kNone: return "none";
    case FaultKind::kStaleOdometry: return "stale_odometry";
    case FaultKind::kStaleObstacles: return "stale_obstacles";
    case FaultKind::kBase: return "base";
  }
  return "unknown";
}

const char* toString(RequestKind kind) {
  switch (kind) {
    case RequestKind::kGoal: return "goal";
    case RequestKind::kStop: return "stop";
    case RequestKind::kPose: return "pose";
    case RequestKind::kStatus: return "status";
    case RequestKind::kDebug: return "debug";
    case RequestKind::kHistograms: return "histograms";
    case RequestKind::kRecord: return "record";
  }
  return "unknown";
}

const char* toString(DebugKind kind) {
  switch (kind) {
    case DebugKind::kNone: return "none";
    case DebugKind::kOverrun: return "overrun";
    case DebugKind::kStallObstacles: return "stall_obstacles";
  }
  return "unknown";
}

}  // namespace staa::staad
