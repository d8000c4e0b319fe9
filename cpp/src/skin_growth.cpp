// Narrow skins widened into the sparse infill (skin_growth.hpp). Each region crosses a row
// s = s_k in intervals of t; the slicer's 2D rules in the layer plane act on the row as 1D
// interval operations (a part that is locally a prism along the section normal: the layer's
// region is the row's intervals swept along that normal, so a strip's width in the layer plane
// is its interval's length and growing it by g grows the interval by g at each end).
#include "skin_growth.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace osteon::detail {
namespace {

using Interval = std::pair<double, double>;  // [lo, hi] in t, mm, lo < hi
using Intervals = std::vector<Interval>;     // sorted, disjoint

// Each row's intervals of a region: crossings of the row line with every edge (half-open in s,
// so a vertex on the line counts once), sorted and paired (even-odd).
std::vector<Intervals> row_intervals(const StLoops& loops, double s_first, double pitch, int rows) {
  std::vector<std::vector<double>> crossings(static_cast<std::size_t>(rows));
  for (const auto& loop : loops)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec2& a = loop[i];
      const Vec2& b = loop[i + 1 == loop.size() ? 0 : i + 1];
      if (a.x() == b.x()) continue;
      const double lo = std::min(a.x(), b.x()), hi = std::max(a.x(), b.x());
      // Rows k with lo <= s_first + k pitch < hi.
      int k = static_cast<int>(std::ceil((lo - s_first) / pitch));
      for (k = std::max(k, 0); k < rows; ++k) {
        const double s = s_first + k * pitch;
        if (s >= hi) break;
        if (s < lo) continue;
        crossings[static_cast<std::size_t>(k)].push_back(a.y() + (s - a.x()) / (b.x() - a.x()) *
                                                                     (b.y() - a.y()));
      }
    }
  std::vector<Intervals> out(static_cast<std::size_t>(rows));
  for (std::size_t k = 0; k < crossings.size(); ++k) {
    auto& c = crossings[k];
    std::sort(c.begin(), c.end());
    for (std::size_t j = 0; j + 1 < c.size(); j += 2)
      if (c[j + 1] > c[j]) out[k].emplace_back(c[j], c[j + 1]);
  }
  return out;
}

Intervals intersect(const Intervals& a, const Intervals& b) {
  Intervals out;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const double lo = std::max(a[i].first, b[j].first), hi = std::min(a[i].second, b[j].second);
    if (hi > lo) out.emplace_back(lo, hi);
    (a[i].second < b[j].second) ? ++i : ++j;
  }
  return out;
}

Intervals subtract(const Intervals& a, const Intervals& b) {
  Intervals out;
  std::size_t j = 0;
  for (const Interval& x : a) {
    double lo = x.first;
    while (j < b.size() && b[j].second <= lo) ++j;
    for (std::size_t k = j; k < b.size() && b[k].first < x.second; ++k) {
      if (b[k].first > lo) out.emplace_back(lo, b[k].first);
      lo = std::max(lo, b[k].second);
    }
    if (x.second > lo) out.emplace_back(lo, x.second);
  }
  return out;
}

Intervals merged(Intervals a) {
  std::sort(a.begin(), a.end());
  Intervals out;
  for (const Interval& x : a) {
    if (!out.empty() && x.first <= out.back().second)
      out.back().second = std::max(out.back().second, x.second);
    else
      out.push_back(x);
  }
  return out;
}

// A source's parts inside the row's infill region, each in `solid`; those narrower than
// 2 growth also widened by growth at both ends within their interval of `inner`, in `widened`.
void add_source(const Intervals& source, const Intervals& inner, double growth, Intervals& solid,
                Intervals& widened) {
  std::size_t j = 0;
  for (const Interval& x : intersect(source, inner)) {
    solid.push_back(x);
    if (!(x.second - x.first < 2.0 * growth)) {
      widened.push_back(x);
      continue;
    }
    while (j < inner.size() && inner[j].second < x.first) ++j;  // the interval holding x
    const Interval& room = inner[std::min(j, inner.size() - 1)];
    widened.emplace_back(std::max(room.first, x.first - growth),
                         std::min(room.second, x.second + growth));
  }
}

}  // namespace

std::vector<SkinStrip> widened_skin_strips(const StLoops& section, const StLoops& inner,
                                           const StLoops& sparse, double pitch, int layers,
                                           double growth, int max_rows) {
  std::vector<SkinStrip> strips;
  if (!(pitch > 0) || !(growth > 0) || layers < 2 || section.empty()) return strips;
  double s_lo = INFINITY, s_hi = -INFINITY;
  for (const auto& loop : section)
    for (const Vec2& p : loop) s_lo = std::min(s_lo, p.x()), s_hi = std::max(s_hi, p.x());
  const double rows_needed = std::ceil((s_hi - s_lo) / pitch);
  if (!(rows_needed >= 1) || rows_needed > max_rows) return strips;
  const int rows = static_cast<int>(rows_needed);
  const double s_first = s_lo + 0.5 * pitch;  // each row stands for the layer around it
  const auto cut = row_intervals(section, s_first, pitch, rows);
  const auto fill = row_intervals(inner, s_first, pitch, rows);
  const auto kept = row_intervals(sparse, s_first, pitch, rows);
  const Intervals none;
  auto row = [&](const std::vector<Intervals>& r, int k) -> const Intervals& {
    return k >= 0 && k < rows ? r[static_cast<std::size_t>(k)] : none;
  };
  // Top surfaces (not covered by the row above) and bottom surfaces (not by the row below).
  std::vector<Intervals> top(static_cast<std::size_t>(rows)), bottom(top.size());
  for (int k = 0; k < rows; ++k) {
    top[static_cast<std::size_t>(k)] = subtract(row(cut, k), row(cut, k + 1));
    bottom[static_cast<std::size_t>(k)] = subtract(row(cut, k), row(cut, k - 1));
  }
  for (int n = 0; n < rows; ++n) {
    const Intervals& room = row(fill, n);
    if (room.empty() || row(kept, n).empty()) continue;
    Intervals solid, widened;
    for (int d = 0; d < layers; ++d) {
      // The row's own surfaces are printed as top / bottom fill and are not widened.
      const double g = d == 0 ? 0.0 : growth;
      if (n + d < rows) add_source(top[static_cast<std::size_t>(n + d)], room, g, solid, widened);
      if (n - d >= 0) add_source(bottom[static_cast<std::size_t>(n - d)], room, g, solid, widened);
    }
    const Intervals extra =
        intersect(subtract(merged(std::move(widened)), merged(std::move(solid))), row(kept, n));
    const double s = s_first + n * pitch;
    for (const Interval& x : extra)
      strips.push_back({s - 0.5 * pitch, s + 0.5 * pitch, x.first, x.second});
  }
  return strips;
}

}  // namespace osteon::detail
