// The skin widening's rows (cpp/src/skin_growth.cpp): a vertex that lies exactly on a row.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "skin_growth.hpp"

using osteon::Vec2;
using osteon::detail::SkinStrip;
using osteon::detail::StLoops;
using osteon::detail::widened_skin_strips;

namespace {

// The strips of one row, by their s centre, ordered by t.
std::vector<SkinStrip> row_strips(const std::vector<SkinStrip>& strips, double s) {
  std::vector<SkinStrip> out;
  for (const SkinStrip& r : strips)
    if (r.s0 < s && s < r.s1) out.push_back(r);
  std::sort(out.begin(), out.end(),
            [](const SkinStrip& a, const SkinStrip& b) { return a.t0 < b.t0; });
  return out;
}

}  // namespace

// Rows 0.2 mm apart from s = 0.1 (the section spans s in [0, 3]); its top falls 5 mm per mm of
// s, so each row's top surface is 1 mm wide, narrower than 2 x the 1.35 mm growth, and the rows
// below widen those of the 3 rows above them into their sparse region: row 6 (s = 1.3, t in
// [0, 13.5]) is solid over [9.5, 13.5] (its own top and the three above) and widened over [8.15,
// 9.5]. The sparse region has a vertex D on row 6 (s computed as the rows are), the lower end of
// the edge before it: by the half-open rule (lo <= s < hi) the row crosses that edge once and
// the next edge not, so row 6 holds the interval t in [2, 9] and gets the strip [8.15, 9], as
// with D a hair (1e-9 mm) above the row. The division's estimate of an edge's first row,
// (1.3 - 0.1) / 0.2 = 6.000000000000001, rounds past row 6: a row count from it dropped this
// crossing, left the row one crossing (odd) and no sparse interval, hence no strip.
TEST(SkinGrowth, VertexOnARowCountsOnce) {
  const double pitch = 0.2, growth = 1.35;
  const int layers = 4;
  const StLoops section{{{0.0, 0.0}, {3.0, 0.0}, {3.0, 5.0}, {0.0, 20.0}}};
  const double s_first = 0.0 + 0.5 * pitch;  // widened_skin_strips' first row (s_lo = 0)
  const double on_row = s_first + 6 * pitch;
  ASSERT_GT((on_row - s_first) / pitch, 6.0);  // the estimate rounds past the row
  auto sparse = [](double d_s) {
    return StLoops{{{0.05, 2.0}, {2.95, 2.0}, {2.95, 9.5}, {d_s, 9.0}, {0.05, 9.5}}};
  };
  const auto on = widened_skin_strips(section, section, sparse(on_row), pitch, layers, growth);
  const auto off =
      widened_skin_strips(section, section, sparse(on_row + 1e-9), pitch, layers, growth);
  const auto a = row_strips(on, on_row), b = row_strips(off, on_row);
  ASSERT_EQ(b.size(), 1u);  // the widened top surfaces reach row 6's sparse interval
  EXPECT_NEAR(b[0].t0, 20.0 - 5.0 * (on_row + 4 * pitch) - growth, 1e-9);  // row 9's top
  EXPECT_NEAR(b[0].t1, 9.0, 1e-6);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_NEAR(a[0].t0, b[0].t0, 1e-9);
  EXPECT_NEAR(a[0].t1, b[0].t1, 1e-6);
}

// The rule in closed form on the section above (top t = 20 - 5 s, rows s_k = 0.1 + 0.2 k, so
// row k's top surface is [19.5 - (k + 1), 19.5 - k], 1 mm wide) with two sparse islands: row n's
// solid skin is the tops of rows n .. n + 3, [15.5 - n, 19.5 - n]; the narrow tops of rows
// n + 1 .. n + 3 widened by the growth g reach down to (15.5 - n) - g, so the rule adds
// [14.15 - n, 15.5 - n] to the solid fill, within the sparse islands. Rows 0 .. 3 hold the whole
// bottom row's surface (row 0, as wide as the section) among their sources: solid throughout,
// nothing added though island B is there. Rows 11 .. 14 likewise hold row 14's (the last). So
// island A (t in [2, 9], every row) gets rows 6 .. 10's bands, island B (t in [10, 12], rows
// 0 .. 4) only row 4's; rows 0 .. 3 and 5 cross sparse infill but get no strip.
TEST(SkinGrowth, WidenedBandUnderASlopeInTwoIslands) {
  const double pitch = 0.2, growth = 1.35;
  const StLoops section{{{0.0, 0.0}, {3.0, 0.0}, {3.0, 5.0}, {0.0, 20.0}}};
  const StLoops sparse{{{0.05, 2.0}, {2.95, 2.0}, {2.95, 9.0}, {0.05, 9.0}},
                       {{0.05, 10.0}, {0.95, 10.0}, {0.95, 12.0}, {0.05, 12.0}}};
  const auto strips = widened_skin_strips(section, section, sparse, pitch, 4, growth);
  struct Expected {
    int row;
    double t0, t1;
  };
  const std::vector<Expected> expected{{4, 10.15, 11.5}, {6, 8.15, 9.0}, {7, 7.15, 8.5},
                                       {8, 6.15, 7.5},   {9, 5.15, 6.5}, {10, 4.15, 5.5}};
  ASSERT_EQ(strips.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const double s = 0.1 + 0.2 * expected[i].row;
    EXPECT_NEAR(strips[i].s0, s - 0.5 * pitch, 1e-12) << i;
    EXPECT_NEAR(strips[i].s1, s + 0.5 * pitch, 1e-12) << i;
    EXPECT_NEAR(strips[i].t0, expected[i].t0, 1e-9) << i;
    EXPECT_NEAR(strips[i].t1, expected[i].t1, 1e-9) << i;
  }
}
