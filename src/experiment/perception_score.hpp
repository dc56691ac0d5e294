#pragma once
// How well the agents' depth perception (AgentCamera) saw the others, against the
// simulation's ground truth, frame by frame (staa-sim --obstacles depth):
//   - an obstacle covers an agent when it lies within kMatchM of the agent's footprint; the
//     covering obstacle whose centroid is nearest the footprint's is that agent's track: its
//     position error is the distance between the two centroids (the camera sees the near
//     side: a visible face's centroid lies up to half the body off), its velocity error the
//     difference of the velocity vectors. Seen tracks (in this frame) and kept ones (out of
//     view, at their predicted place) are counted apart;
//   - missed within 2 m: another agent whose footprint is within kNearM of the observer's
//     and that no obstacle covers, per frame (and how often it was in the image then);
//   - false obstacles: obstacles that cover no agent;
//   - latency: from a moving agent entering the view (kEnterPixels sampled pixels of it in
//     the frame after at least kOutOfViewS with fewer) to the first frame with a track of it
//     whose velocity is within kSettledMps of the truth; an agent that leaves the view first
//     counts as not settled.
// The errors go into fixed-bin histograms so that runs add up (percentiles over an
// experiment, not means of percentiles).

#include "geometry/line_of_sight.hpp"
#include "geometry/types.hpp"
#include "hal/obstacles.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace staa {

class MultiWorld;

struct ErrorHistogram {
  static constexpr double kBin = 0.02;  // m or m/s
  static constexpr std::size_t kBins = 150;  // to 3 m; the last bin holds everything beyond
  std::array<std::uint64_t, kBins + 1> counts{};
  std::uint64_t n = 0;
  double sum = 0.0;
  double max = 0.0;

  void add(double value);
  void merge(const ErrorHistogram& other);
  double mean() const { return n > 0 ? sum / static_cast<double>(n) : 0.0; }
  // The upper edge of the bin holding the p-th fraction (0..1) of the values; 0 when empty.
  double percentile(double p) const;
};

struct PerceptionAccuracy {
  std::uint64_t frames = 0;       // frames perceived, all observers
  std::uint64_t frames_lost = 0;  // lost (frame_loss)
  ErrorHistogram position_m, velocity_mps;            // seen tracks
  ErrorHistogram kept_position_m, kept_velocity_mps;  // kept tracks (out of view)
  std::uint64_t near_samples = 0;         // (observer, other, frame) within kNearM
  std::uint64_t near_missed = 0;          // ... no obstacle covered the other
  std::uint64_t near_missed_in_view = 0;  // ... although some of it was in the image
  std::uint64_t obstacles = 0, kept_obstacles = 0;
  std::uint64_t false_obstacles = 0, false_kept = 0;
  std::uint64_t entries = 0;      // moving agents entering the view
  std::uint64_t unsettled = 0;    // ... that left it again before their velocity settled
  std::vector<double> latency_s;  // ... that settled: the time it took
  double render_us_sum = 0.0, perception_us_sum = 0.0;  // wall time over the frames

  void merge(const PerceptionAccuracy& other);
};

class PerceptionScorer {
 public:
  static constexpr double kMatchM = 0.3;
  static constexpr double kNearM = 2.0;
  static constexpr std::uint32_t kEnterPixels = 8;
  static constexpr double kOutOfViewS = 0.5;
  static constexpr double kSettledMps = 0.3;
  static constexpr double kMovingMps = 0.3;

  // `sight` (the map's line of sight; may be null) and `sight_range_m`: what Sighting's
  // in_sight fields measure, with --obstacles sight's rule (SightObstacles).
  explicit PerceptionScorer(std::size_t agents, const LineOfSight* sight = nullptr, double sight_range_m = 0.0);

  // One frame of observer `self`, taken at `time_s` with the world as it is now: its
  // obstacles, and the pixels each other agent had in it (`others[m]` is the agent index of
  // the m-th entry of mover_pixels).
  void score(const MultiWorld& world, std::size_t self, double time_s, const hal::ObstacleFrame& frame,
             std::span<const std::size_t> others, std::span<const std::uint32_t> mover_pixels);
  void addCost(double render_us, double perception_us) {
    accuracy_.render_us_sum += render_us;
    accuracy_.perception_us_sum += perception_us;
  }

  const PerceptionAccuracy& accuracy() const { return accuracy_; }

  // A sighting: from the first frame in which observer `self` saw agent `other` (a seen track
  // covering it) while it was covered at all (seen, or kept out of view) with gaps of at most
  // kSightingGapS. What the observer's perception knew of `other` at `time_s` (a contact).
  static constexpr double kSightingGapS = 1.0;
  struct Sighting {
    bool seen = false;           // a sighting was on (or ended at most kSightingGapS ago)
    double seen_before_s = 0.0;  // its first frame, this long before time_s
    double seen_at_m = 0.0;      // the distance between the two footprints then
    bool covered = false;        // some frame ever had an obstacle covering `other`
    double covered_before_s = 0.0;  // the last such frame, this long before time_s
    // The map's part: the observer's centre had a clear line to a vertex of `other` within
    // the sight range (gaps of at most kSightingGapS), from in_sight_before_s before time_s, at
    // this footprint distance. A contact seen about when it came into sight was hidden by a
    // wall, not missed by the sensors.
    bool in_sight = false;
    double in_sight_before_s = 0.0;
    double in_sight_at_m = 0.0;
  };
  Sighting sighting(std::size_t self, std::size_t other, double time_s) const;

 private:
  struct Pair {  // observer i watching agent j
    double last_in_view_s = -1e9;  // the last frame it had kEnterPixels or more in the image
    bool entering = false;         // an entry waits for its velocity to settle
    double entered_s = 0.0;
    double sighting_s = -1.0;      // the current sighting's first frame (-1: none yet)
    double sighting_m = 0.0;
    double covered_s = -1.0;       // the last frame with an obstacle covering it (-1: none)
    double in_sight_s = -1.0;      // the current spell in the line of sight: its first frame (-1: none)
    double in_sight_m = 0.0;
    double last_in_sight_s = -1e9;
  };
  std::size_t n_;
  const LineOfSight* sight_ = nullptr;
  double sight_range_m_ = 0.0;
  std::vector<Pair> pairs_;  // n x n
  PerceptionAccuracy accuracy_;
};

}  // namespace staa
