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

// Each row's intervals of a region, rows flattened (CSR: row k's intervals are
// intervals[start[k] .. start[k + 1])): crossings of the row line with every edge (half-open in
// s, so a vertex on the line counts once), sorted and paired (even-odd). Two passes over the
// edges (count, then fill) keep it to two allocations per region: a section has hundreds of rows.
struct RowIntervals {
  std::vector<int> start;
  std::vector<Interval> intervals;
  std::pair<const Interval*, const Interval*> row(int k) const {
    if (k < 0 || k + 1 >= static_cast<int>(start.size())) return {nullptr, nullptr};
    const Interval* base = intervals.data();
    return {base + start[static_cast<std::size_t>(k)],
            base + start[static_cast<std::size_t>(k + 1)]};
  }
};

template <class Visit>
void for_each_crossing(const StLoops& loops, double s_first, double pitch, int rows, Visit visit) {
  for (const auto& loop : loops)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec2& a = loop[i];
      const Vec2& b = loop[i + 1 == loop.size() ? 0 : i + 1];
      if (a.x() == b.x()) continue;
      const double lo = std::min(a.x(), b.x()), hi = std::max(a.x(), b.x());
      for (int k = std::max(static_cast<int>(std::ceil((lo - s_first) / pitch)), 0); k < rows;
           ++k) {
        const double s = s_first + k * pitch;
        if (s >= hi) break;
        if (s < lo) continue;
        visit(k, a.y() + (s - a.x()) / (b.x() - a.x()) * (b.y() - a.y()));
      }
    }
}

RowIntervals row_intervals(const StLoops& loops, double s_first, double pitch, int rows) {
  std::vector<int> count(static_cast<std::size_t>(rows) + 1, 0);
  for_each_crossing(loops, s_first, pitch, rows,
                    [&](int k, double) { ++count[static_cast<std::size_t>(k) + 1]; });
  for (std::size_t k = 1; k < count.size(); ++k) count[k] += count[k - 1];
  std::vector<double> t(static_cast<std::size_t>(count.back()));
  std::vector<int> fill(count.begin(), count.end() - 1);
  for_each_crossing(loops, s_first, pitch, rows, [&](int k, double y) {
    t[static_cast<std::size_t>(fill[static_cast<std::size_t>(k)]++)] = y;
  });
  RowIntervals out;
  out.start.assign(static_cast<std::size_t>(rows) + 1, 0);
  out.intervals.reserve(t.size() / 2);
  for (int k = 0; k < rows; ++k) {
    const auto first = t.begin() + count[static_cast<std::size_t>(k)];
    const auto last = t.begin() + count[static_cast<std::size_t>(k) + 1];
    std::sort(first, last);
    for (auto c = first; c + 1 < last; c += 2)
      if (*(c + 1) > *c) out.intervals.emplace_back(*c, *(c + 1));
    out.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(out.intervals.size());
  }
  return out;
}

// Interval lists as spans of sorted, disjoint intervals; results go into reused buffers.
struct Span {
  const Interval* first = nullptr;
  const Interval* last = nullptr;
  Span() = default;
  Span(const Interval* f, const Interval* l) : first(f), last(l) {}
  Span(std::pair<const Interval*, const Interval*> p) : first(p.first), last(p.second) {}
  Span(const Intervals& v) : first(v.data()), last(v.data() + v.size()) {}
  bool empty() const { return first == last; }
};

void intersect(Span a, Span b, Intervals& out) {
  out.clear();
  while (a.first != a.last && b.first != b.last) {
    const double lo = std::max(a.first->first, b.first->first);
    const double hi = std::min(a.first->second, b.first->second);
    if (hi > lo) out.emplace_back(lo, hi);
    (a.first->second < b.first->second) ? ++a.first : ++b.first;
  }
}

void subtract(Span a, Span b, Intervals& out) {
  out.clear();
  for (; a.first != a.last; ++a.first) {
    double lo = a.first->first;
    const double hi = a.first->second;
    while (b.first != b.last && b.first->second <= lo) ++b.first;
    for (const Interval* k = b.first; k != b.last && k->first < hi; ++k) {
      if (k->first > lo) out.emplace_back(lo, k->first);
      lo = std::max(lo, k->second);
    }
    if (hi > lo) out.emplace_back(lo, hi);
  }
}

void merge_in_place(Intervals& a) {
  std::sort(a.begin(), a.end());
  std::size_t n = 0;
  for (const Interval& x : a) {
    if (n > 0 && x.first <= a[n - 1].second)
      a[n - 1].second = std::max(a[n - 1].second, x.second);
    else
      a[n++] = x;
  }
  a.resize(n);
}

struct Scratch {
  Intervals part, solid, widened, extra, kept_extra;
};

// A source's parts inside the row's infill region, each in `solid`; those narrower than
// 2 growth also widened by growth at both ends within their interval of `inner`, in `widened`.
void add_source(Span source, Span inner, double growth, Scratch& w) {
  intersect(source, inner, w.part);
  const Interval* room = inner.first;
  for (const Interval& x : w.part) {
    w.solid.push_back(x);
    if (!(x.second - x.first < 2.0 * growth)) {
      w.widened.push_back(x);
      continue;
    }
    while (room + 1 != inner.last && room->second < x.first) ++room;  // the interval holding x
    w.widened.emplace_back(std::max(room->first, x.first - growth),
                           std::min(room->second, x.second + growth));
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
  layers = std::min(layers, rows);  // sources farther than the section's rows do not exist
  const double s_first = s_lo + 0.5 * pitch;  // each row stands for the layer around it
  const RowIntervals kept = row_intervals(sparse, s_first, pitch, rows);
  if (kept.intervals.empty()) return strips;
  const RowIntervals cut = row_intervals(section, s_first, pitch, rows);
  const RowIntervals fill = row_intervals(inner, s_first, pitch, rows);
  // Top surfaces (not covered by the row above) and bottom surfaces (not by the row below).
  RowIntervals top, bottom;
  top.start.assign(static_cast<std::size_t>(rows) + 1, 0);
  bottom.start = top.start;
  Intervals buffer;
  for (int k = 0; k < rows; ++k) {
    subtract(cut.row(k), cut.row(k + 1), buffer);
    top.intervals.insert(top.intervals.end(), buffer.begin(), buffer.end());
    top.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(top.intervals.size());
    subtract(cut.row(k), cut.row(k - 1), buffer);
    bottom.intervals.insert(bottom.intervals.end(), buffer.begin(), buffer.end());
    bottom.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(bottom.intervals.size());
  }
  Scratch w;
  for (int n = 0; n < rows; ++n) {
    const Span room = fill.row(n), sparse_row = kept.row(n);
    if (room.empty() || sparse_row.empty()) continue;
    w.solid.clear();
    w.widened.clear();
    for (int d = 0; d < layers; ++d) {
      // The row's own surfaces are printed as top / bottom fill and are not widened.
      const double g = d == 0 ? 0.0 : growth;
      const Span up = n + d < rows ? Span(top.row(n + d)) : Span();
      const Span down = n - d >= 0 ? Span(bottom.row(n - d)) : Span();
      if (!up.empty()) add_source(up, room, g, w);
      if (!down.empty()) add_source(down, room, g, w);
    }
    if (w.widened.empty()) continue;
    merge_in_place(w.widened);
    merge_in_place(w.solid);
    subtract(Span(w.widened), Span(w.solid), w.extra);
    intersect(Span(w.extra), sparse_row, w.kept_extra);
    const double s = s_first + n * pitch;
    for (const Interval& x : w.kept_extra)
      strips.push_back({s - 0.5 * pitch, s + 0.5 * pitch, x.first, x.second});
  }
  return strips;
}

}  // namespace osteon::detail
