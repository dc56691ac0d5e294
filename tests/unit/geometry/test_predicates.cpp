#include "geometry/predicates.hpp"

#include "geometry/polygon.hpp"
#include "geometry/splitmix64.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

namespace staa {
namespace {

// The reference: coordinates that are whole multiples of 2^-53 below 32 in magnitude are
// integers of at most 59 bits in that unit, so the determinant is an integer of at most 120
// bits, exact in __int128.
constexpr double kUnit = 0x1p-53;
__extension__ typedef __int128 Int128;  // GCC and clang; -Wpedantic would flag the bare type

Int128 units(double v) {
  const double k = v / kUnit;  // exact: a power-of-two scaling
  EXPECT_EQ(k, std::trunc(k)) << v << " is not a multiple of 2^-53";
  EXPECT_LT(std::abs(k), 0x1p59);
  return static_cast<Int128>(k);
}

int referenceSign(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Int128 ax = units(a.x()), ay = units(a.y()), bx = units(b.x()), by = units(b.y());
  const Int128 cx = units(c.x()), cy = units(c.y());
  const Int128 det = (ax - cx) * (by - cy) - (ay - cy) * (bx - cx);
  return (det > 0) - (det < 0);
}

int naiveSign(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double o = orient(a, b, c);
  return (o > 0.0) - (o < 0.0);
}

// Kettner, Mehlhorn, Pion, Schirra and Yap's "classroom example" of a failing orientation:
// the points p + (i, j) ulps around p = (0.5, 0.5) against the line from (12, 12) to
// (24, 24). Rounding the plain evaluation calls many of them on the wrong side.
TEST(Predicates, OrientSignIsExactOnTheClassroomGridWhereThePlainEvaluationFails) {
  const Vec2 q(12.0, 12.0), r(24.0, 24.0);
  int wrong_plain = 0, cells = 0;
  for (int i = 0; i < 64; ++i) {
    for (int j = 0; j < 64; ++j) {
      const Vec2 p(0.5 + i * kUnit, 0.5 + j * kUnit);
      const int ref = referenceSign(p, q, r);
      ASSERT_EQ(orientSign(p, q, r), ref) << "i " << i << " j " << j;
      // The same triangle in every order: a rotation keeps the sign, a swap flips it.
      ASSERT_EQ(orientSign(q, r, p), ref);
      ASSERT_EQ(orientSign(r, p, q), ref);
      ASSERT_EQ(orientSign(q, p, r), -ref);
      // The static filter, with the bound for the grid's coordinates, decides the same.
      ASSERT_EQ(orientSign(p, q, r, orientStaticBound(24.0)), ref);
      wrong_plain += naiveSign(p, q, r) != ref;
      ++cells;
    }
  }
  // The test would not prove anything if the plain evaluation were right here.
  EXPECT_GT(wrong_plain, cells / 10) << "the plain orientation was wrong in " << wrong_plain << " of " << cells;
}

TEST(Predicates, OrientSignIsExactOnRandomNearlyCollinearTriples) {
  SplitMix64 rng(7);
  auto coordinate = [&rng] {
    // A multiple of 2^-53 in [-4, 4): 56 random bits (c below stays under 20 in magnitude).
    const auto k = static_cast<std::int64_t>(rng.next() >> 8) - (std::int64_t{1} << 55);
    return static_cast<double>(k) * kUnit;
  };
  int collinear = 0;
  for (int n = 0; n < 20000; ++n) {
    const Vec2 a(coordinate(), coordinate()), b(coordinate(), coordinate());
    // c on the line through a and b, rounded to the grid, then nudged by a few units.
    const double t = static_cast<double>(rng.next() >> 11) * 0x1p-53 * 3.0 - 1.0;
    Vec2 c = a + t * (b - a);
    c = Vec2(std::round(c.x() / kUnit) * kUnit, std::round(c.y() / kUnit) * kUnit);
    c += Vec2(static_cast<double>(static_cast<int>(rng.next() % 5) - 2) * kUnit,
              static_cast<double>(static_cast<int>(rng.next() % 5) - 2) * kUnit);
    const int ref = referenceSign(a, b, c);
    ASSERT_EQ(orientSign(a, b, c), ref) << n;
    ASSERT_EQ(orientSign(b, a, c), -ref) << n;
    ASSERT_EQ(orientSign(a, b, c, orientStaticBound(20.0)), ref) << n;
    collinear += ref == 0;
  }
  // Exactly collinear by construction (coarse coordinates: every sum is exact), then one
  // hair (2^-40) off the line.
  auto coarse = [&rng] { return static_cast<double>(static_cast<int>(rng.next() % 4001) - 2000) * 0x1p-10; };
  for (int n = 0; n < 5000; ++n) {
    const Vec2 a(coarse(), coarse()), d(coarse(), coarse());
    const Vec2 b = a + 3.0 * d, c = a - 2.0 * d;
    ASSERT_EQ(referenceSign(a, b, c), 0);
    ASSERT_EQ(orientSign(a, b, c), 0) << n;
    ASSERT_EQ(orientSign(c, a, b), 0) << n;
    const Vec2 c_off(c.x() + 0x1p-40, c.y());  // exact: c is below 8 in magnitude
    ASSERT_EQ(orientSign(a, b, c_off), referenceSign(a, b, c_off)) << n;
    collinear += 1;
  }
  EXPECT_GE(collinear, 5000);
}

// Coordinates of 33 bits (multiples of 2^-30 in [-4, 4)): every difference is exact, the
// products are not, and nearly collinear triples give products that round alike, the case
// the exact stage decides by the rounded products' order or, when equal, their errors.
// The paired tests (orientSignProduct, strictlySameSideFiltered) agree with the signs.
TEST(Predicates, OrientSignIsExactWhenTheDifferencesAreExactAndThePairedTestsAgree) {
  SplitMix64 rng(11);
  auto coordinate = [&rng] {
    const auto k = static_cast<std::int64_t>(rng.next() >> 31) - (std::int64_t{1} << 32);
    return static_cast<double>(k) * 0x1p-30;
  };
  const double bound = orientStaticBound(8.0);
  int zeros = 0, same_side = 0;
  for (int n = 0; n < 20000; ++n) {
    const Vec2 a(coordinate(), coordinate()), b(coordinate(), coordinate());
    const double t = static_cast<double>(rng.next() >> 11) * 0x1p-53;  // c and d between a and b
    auto nearLine = [&](double u) {
      const Vec2 p = a + u * (b - a);
      return Vec2(std::round(p.x() * 0x1p30) * 0x1p-30 + static_cast<double>(static_cast<int>(rng.next() % 3) - 1) * 0x1p-30,
                  std::round(p.y() * 0x1p30) * 0x1p-30 + static_cast<double>(static_cast<int>(rng.next() % 3) - 1) * 0x1p-30);
    };
    const Vec2 c = nearLine(t), d = nearLine(1.0 - t);
    const int rc = referenceSign(a, b, c), rd = referenceSign(a, b, d);
    ASSERT_EQ(orientSign(a, b, c), rc) << n;
    ASSERT_EQ(orientSign(b, c, a), rc) << n;
    ASSERT_EQ(orientSign(a, b, c, bound), rc) << n;
    ASSERT_EQ(orientSignProduct(a, b, c, d, bound), rc * rd) << n;
    const bool filtered = strictlySameSideFiltered(a, b, c, d, bound);
    if (filtered) {
      ASSERT_GT(rc * rd, 0) << n;  // never claims more than the exact signs say
    }
    // Off the line (by a quarter of |b - a|, the coordinates staying within the bound's 8)
    // the filter decides.
    const Vec2 off = c + 0.25 * Vec2(-(b - a).y(), (b - a).x());
    if (a != b) {
      ASSERT_TRUE(strictlySameSideFiltered(a, b, off, off, bound)) << n;
    }
    // The midpoint (exact: 34 bits) is exactly on the line, a hair beside it is not.
    const Vec2 m = 0.5 * (a + b), m_off(m.x() + 0x1p-31, m.y());
    ASSERT_EQ(referenceSign(a, b, m), 0);
    ASSERT_EQ(orientSign(a, b, m), 0) << n;
    ASSERT_EQ(orientSignProduct(a, b, m, c, bound), 0) << n;
    ASSERT_EQ(orientSign(a, b, m_off, bound), referenceSign(a, b, m_off)) << n;
    zeros += referenceSign(a, b, m_off) == 0;
    same_side += filtered;
  }
  // Beside the line is off it whenever b - a is not horizontal, and the filter decides
  // some of the near-line pairs alone.
  EXPECT_EQ(zeros, 0);
  EXPECT_GT(same_side, 100);
}

TEST(Predicates, TheStaticBoundCoversEveryCoordinateUpToItsMagnitude) {
  // Rounded up to a power of two: 24 -> 32, 8 * 32^2 * the filter's constant.
  EXPECT_EQ(orientStaticBound(24.0), detail::kOrientErrorBound * 8.0 * 32.0 * 32.0);
  EXPECT_EQ(orientStaticBound(32.0), detail::kOrientErrorBound * 8.0 * 64.0 * 64.0);
  EXPECT_GT(orientStaticBound(0.0), 0.0);  // raised to 2^-400: no underflow to 0
  EXPECT_TRUE(std::isinf(orientStaticBound(std::numeric_limits<double>::infinity())));
  EXPECT_TRUE(std::isinf(orientStaticBound(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_TRUE(std::isinf(orientStaticBound(1e300)));
  // An infinite bound never decides: the dynamic filter and the exact sum do.
  EXPECT_EQ(orientSign({0, 0}, {1, 0}, {0, 1}, orientStaticBound(1e300)), 1);
}

TEST(Predicates, OrientSignOnEasyInputsAgreesWithThePlainOrientation) {
  EXPECT_EQ(orientSign({0, 0}, {1, 0}, {0, 1}), 1);
  EXPECT_EQ(orientSign({0, 0}, {0, 1}, {1, 0}), -1);
  EXPECT_EQ(orientSign({0, 0}, {1, 1}, {3, 3}), 0);
  EXPECT_EQ(orientSign({1.5, 4.5}, {1.5, 9.0}, {1.5, -2.0}), 0);  // a wall's vertical line
  // Decimal coordinates that are not collinear in binary: 0.1, 0.2, 0.3 on the diagonal.
  const Vec2 a(0.1, 0.1), b(0.2, 0.2), c(0.3, 0.3);
  EXPECT_EQ(orientSign(a, b, c), -orientSign(b, a, c));
  EXPECT_EQ(orientSign(a, b, c), orientSign(b, c, a));
}

// The polygon predicates built on it agree with each other on a near-degenerate crossing:
// a segment through a vertex of the grid example touches, never "crosses a hair".
TEST(Predicates, SegmentTestsAgreeAtAnExactlyCollinearTouch) {
  const Vec2 q(12.0, 12.0), r(24.0, 24.0);
  const Vec2 p(0.5, 0.5);  // exactly on the line through q and r
  EXPECT_EQ(orientSign(p, q, r), 0);
  EXPECT_TRUE(segmentsIntersect(p, r, q, Vec2(12.0, 30.0)));
  EXPECT_FALSE(segmentsCrossProperly(p, r, q, Vec2(12.0, 30.0)));
  const Vec2 off(0.5 + kUnit, 0.5);  // one unit to the right of it: clockwise
  EXPECT_EQ(orientSign(off, q, r), referenceSign(off, q, r));
  EXPECT_EQ(orientSign(off, q, r), -1);
}

}  // namespace
}  // namespace staa
