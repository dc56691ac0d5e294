#pragma once
// What the one-robot World and the MultiWorld share when they decide contacts: the sampling
// of a swept motion, the contact point's bisection and the box prefilter.

#include "geometry/types.hpp"

namespace staa::contact {

// The largest travel of any footprint point between two swept-motion samples.
constexpr double kSampleSpacing = 0.01;  // m
// Bisection steps for the contact point: the free fraction of the step to 2^-40.
constexpr int kContactBisections = 40;
// polygonsOverlap counts points within 1e-9 m of an edge as touching; the bounding-box
// prefilter is widened by more than that so it never skips a pair the exact test would call
// touching.
constexpr double kTouchMargin = 1e-8;  // m

inline bool strictlyInside(const Box& b, const Vec2& p) {
  return p.x() > b.min.x() && p.x() < b.max.x() && p.y() > b.min.y() && p.y() < b.max.y();
}

}  // namespace staa::contact
