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
