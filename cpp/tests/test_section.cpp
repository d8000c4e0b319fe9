#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "osteon/section.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::rectangle;
using osteon::testing::regular_polygon;

TEST(SectionProperties, SquareWeakestAlongTheDiagonal) {
  const double a = 10.0;
  SectionPolygon poly{rectangle(a, a), {}};
  const SectionProperties p = section_properties(poly);
  ASSERT_TRUE(p.valid);
  EXPECT_NEAR(p.area, a * a, 1e-12);
  EXPECT_NEAR(p.second_moment(0, 0), a * a * a * a / 12, 1e-9);
  EXPECT_NEAR(p.second_moment(0, 1), 0.0, 1e-9);
  EXPECT_NEAR(p.modulus, a * a * a / (6 * std::sqrt(2.0)), 1e-9);
}

TEST(SectionProperties, RectangleBelowThinDirectionValue) {
  const double b = 20, h = 5;
  const SectionProperties p = section_properties({rectangle(b, h), {}});
  EXPECT_NEAR(p.modulus, b * b * h * h / (6 * std::sqrt(b * b + h * h)), 1e-9);
  EXPECT_LT(p.modulus, b * h * h / 6);
}

TEST(SectionProperties, CircleAndTube) {
  const double ro = 6, ri = 4;
  const SectionProperties disc = section_properties({regular_polygon(ro, 4096), {}});
  EXPECT_NEAR(disc.modulus / (M_PI * ro * ro * ro / 4), 1.0, 1e-4);
  const SectionProperties tube =
      section_properties({regular_polygon(ro, 4096), {regular_polygon(ri, 4096)}});
  EXPECT_NEAR(tube.area / (M_PI * (ro * ro - ri * ri)), 1.0, 1e-5);
  EXPECT_NEAR(tube.modulus / (M_PI * (ro * ro * ro * ro - ri * ri * ri * ri) / (4 * ro)), 1.0,
              1e-4);
}

TEST(SectionProperties, OrientationAndPositionDoNotMatter) {
  std::vector<Vec2> r = rectangle(12, 4);
  const double w = section_properties({r, {}}).modulus;
  std::vector<Vec2> moved;
  for (auto it = r.rbegin(); it != r.rend(); ++it) moved.push_back(*it + Vec2(1e3, -2e3));
  EXPECT_NEAR(section_properties({moved, {}}).modulus / w, 1.0, 1e-9);
}

TEST(SectionProperties, DegenerateIsInvalid) {
  EXPECT_FALSE(section_properties({{{0, 0}, {1, 0}, {2, 0}}, {}}).valid);
  EXPECT_FALSE(section_properties({{{0, 0}, {1, 1}}, {}}).valid);
}

TEST(PointInLoop, EvenOdd) {
  const auto sq = rectangle(2, 2);
  EXPECT_TRUE(point_in_loop(sq, {0, 0}));
  EXPECT_FALSE(point_in_loop(sq, {3, 0}));
  EXPECT_NEAR(std::abs(signed_area(sq)), 4.0, 1e-12);
}

TEST(SignedArea, SameBitsAsAModuloPerEdge) {
  // The shoelace sum edge by edge with the closing edge last, as (i, (i + 1) % n) gives it.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-500.0, 500.0);
  for (int n = 0; n < 60; ++n) {
    std::vector<Vec2> loop;
    for (int i = 0; i < n; ++i) loop.emplace_back(coord(rng), coord(rng));
    double a = 0.0;
    for (int i = 0; i < n; ++i) {
      const Vec2& p = loop[i];
      const Vec2& q = loop[(i + 1) % n];
      a += p.x() * q.y() - q.x() * p.y();
    }
    EXPECT_EQ(signed_area(loop), a / 2) << n;
  }
}
