// winding_region (cpp/src/winding_region.hpp) against Clipper2's boolean passes: the region of
// positive winding of self-crossing paths (its union), and an inset cut by two shifted outlines
// (its intersection), the same up to the rounding of crossing points.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "clipper2/clipper.h"
#include "winding_region.hpp"

namespace {

using Clipper2Lib::FillRule;
using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using osteon::detail::Windings;

// A star-like path around (cx, cy) with random radii: it crosses itself where `wild`.
Path64 random_loop(std::mt19937& rng, int n, double cx, double cy, double r, bool wild) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Path64 p;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i + (wild ? 3.0 * u(rng) : 0.5 * u(rng))) / n;
    const double rr = r * (0.4 + 0.6 * u(rng));
    p.emplace_back(std::llround(cx + rr * std::cos(a)), std::llround(cy + rr * std::sin(a)));
  }
  return p;
}

double perimeter(const Paths64& paths) {
  double len = 0;
  for (const Path64& p : paths)
    for (std::size_t k = 0; k < p.size(); ++k)
      len += std::hypot(static_cast<double>(p[(k + 1) % p.size()].x - p[k].x),
                        static_cast<double>(p[(k + 1) % p.size()].y - p[k].y));
  return len;
}

void expect_same(const Paths64& ours, const Paths64& theirs) {
  // Crossing points rounded by both (half a unit each): the areas within a unit per length.
  const double slack = perimeter(theirs) + 1.0;
  EXPECT_NEAR(Clipper2Lib::Area(ours), Clipper2Lib::Area(theirs), slack);
  EXPECT_LE(std::abs(Clipper2Lib::Area(Clipper2Lib::Xor(ours, theirs, FillRule::NonZero))), slack);
}

bool positive(const Windings& w) { return w[0] > 0; }
bool both_shifted(const Windings& w) { return w[0] > 0 && w[1] + w[2] - 1 > 0; }

}  // namespace

TEST(WindingRegion, PositiveWindingOfSelfCrossingPaths) {
  std::mt19937 rng(11);
  int accepted = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Paths64 paths{random_loop(rng, 30 + trial, 0, 0, 1e6, true)};
    if (trial % 3 == 0) paths.push_back(random_loop(rng, 20, 3e5, 1e5, 5e5, true));
    if (trial % 4 == 1) {  // a clockwise loop: negative windings cancel positive ones
      Path64 hole = random_loop(rng, 25, -2e5, 0, 4e5, false);
      std::reverse(hole.begin(), hole.end());
      paths.push_back(hole);
    }
    Paths64 ours;
    if (!osteon::detail::winding_region({&paths}, positive, ours)) continue;
    ++accepted;
    expect_same(ours, Clipper2Lib::Union(paths, FillRule::Positive));
  }
  EXPECT_GE(accepted, 38);  // random coordinates are in general position
}

TEST(WindingRegion, InsetCutByShiftedOutlines) {
  std::mt19937 rng(5);
  int accepted = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Paths64 section{random_loop(rng, 60, 0, 0, 1e6, false)};
    const Paths64 inset = Clipper2Lib::InflatePaths(section, -8e4, Clipper2Lib::JoinType::Round,
                                                    Clipper2Lib::EndType::Polygon);
    const std::int64_t shift = 20000 + 7919 * trial;
    const Paths64 up = Clipper2Lib::TranslatePaths(section, shift, 0);
    const Paths64 down = Clipper2Lib::TranslatePaths(section, -shift, 0);
    Paths64 ours;
    if (!osteon::detail::winding_region({&inset, &up, &down}, both_shifted, ours)) continue;
    ++accepted;
    const Paths64 shifted = Clipper2Lib::Intersect(up, down, FillRule::NonZero);
    expect_same(ours, Clipper2Lib::Intersect(inset, shifted, FillRule::NonZero));
  }
  EXPECT_GE(accepted, 28);
}

TEST(WindingRegion, DeclinesTouchingPaths) {
  // Two squares sharing an edge: not in general position, so Clipper2 is asked instead.
  const Paths64 paths{{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {{10, 0}, {20, 0}, {20, 10}, {10, 10}}};
  Paths64 out;
  EXPECT_FALSE(osteon::detail::winding_region({&paths}, positive, out));
  EXPECT_TRUE(out.empty());
}

TEST(WindingRegion, CoarseGridPathsDeclineOrAgree) {
  // Paths on a 40-unit grid touch, overlap and cross at vertices all the time: each is either
  // declined (Clipper2 is used) or the same region as Clipper2's, never something else.
  std::mt19937 rng(23);
  std::uniform_int_distribution<int> coord(0, 40);
  int accepted = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Paths64 paths(1 + trial % 2);
    for (Path64& p : paths)
      for (int i = 0; i < 5 + trial % 7; ++i) p.emplace_back(coord(rng) * 1000, coord(rng) * 1000);
    Paths64 ours;
    if (!osteon::detail::winding_region({&paths}, positive, ours)) continue;
    ++accepted;
    expect_same(ours, Clipper2Lib::Union(paths, FillRule::Positive));
  }
  EXPECT_GT(accepted, 200);
}

TEST(WindingRegion, DeclinesAStarOfManyLongSpikes) {
  // Every edge runs from near the centre to the rim: the edges' grid boxes would hold about n^2
  // / 8 cells. It declines (false: Clipper2 takes the section) instead of quadratic memory.
  const int spikes = 20000;
  Path64 star;
  for (int i = 0; i < 2 * spikes; ++i) {
    const double a = M_PI * i / spikes, r = (i % 2 == 0) ? 1e7 : 1e3;
    star.emplace_back(std::llround(r * std::cos(a)), std::llround(r * std::sin(a)));
  }
  const Paths64 in{star};
  Paths64 out;
  EXPECT_FALSE(osteon::detail::winding_region({&in}, positive, out));
}
