// Narrow skins widened into the sparse infill (skin_growth.hpp). Each region crosses a row
// s = s_k in intervals of t; the slicer's 2D rules in the layer plane act on the row as 1D
// interval operations (a part that is locally a prism along the section normal: the layer's
// region is the row's intervals swept along that normal, so a strip's width in the layer plane
// is its interval's length and growing it by g grows the interval by g at each end).
#include "skin_growth.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

namespace osteon::detail {
namespace {

using Interval = std::pair<double, double>;  // [lo, hi] in t, mm, lo < hi
using Intervals = std::vector<Interval>;     // sorted, disjoint

// Each row's intervals of a region, rows flattened (CSR: row k's intervals are
// intervals[start[k] .. start[k + 1])): crossings of the row line with every edge (half-open in
// s, so a vertex on the line counts once), sorted and paired (even-odd). The edges that cross rows
// are listed once (crossing_edges), then counted per row and filled: a section has hundreds of
// rows.
struct RowIntervals {
  std::vector<int> start;
  std::vector<Interval> intervals;
  std::pair<const Interval*, const Interval*> row(int k) const {
    if (k < 0 || k + 1 >= static_cast<int>(start.size())) return {nullptr, nullptr};
    return at(k);
  }
  // row(k) for 0 <= k < rows, unchecked (the loops below stay in that range).
  std::pair<const Interval*, const Interval*> at(int k) const {
    const Interval* base = intervals.data();
    return {base + start[static_cast<std::size_t>(k)],
            base + start[static_cast<std::size_t>(k + 1)]};
  }
};

// An edge that crosses rows: its ends and its rows first <= k < last.
struct Crossing {
  const Vec2* a;
  const Vec2* b;
  int first, last;
};

// The edges that cross rows k_lo <= k < k_hi (s = row_s[k] = s_first + k pitch, k counted from
// the first row whatever the range, so a row's crossings do not depend on the range asked;
// row_s[rows] is infinite), each with
// its rows lo <= s < hi (a vertex on a row counts once). A vertex's slot is the number of rows
// 0 <= k < rows with s_first + k pitch < x (the crossings' own expression, monotone in k), so an
// edge's rows are its ends' slots' range. Found walking each loop: the first vertex's slot by
// division, then corrected by the tests; every other one from its predecessor's, one step per
// row crossed: most edges (shorter than a row's pitch) cost a comparison or two, no division.
void crossing_edges(const StLoops& loops, const std::vector<double>& row_s, double pitch, int k_lo,
                    int k_hi, std::vector<Crossing>& out) {
  const int rows = static_cast<int>(row_s.size()) - 1;
  const double s_first = row_s[0];
  const double* const rs = row_s.data();
  out.clear();
  std::size_t vertices = 0;  // at most one crossing edge per vertex: one allocation
  for (const auto& loop : loops) vertices += loop.size();
  out.reserve(vertices);
  auto slot_of = [&](double x, int r) {
    while (rs[r] < x) ++r;  // rs[rows] is infinite
    while (r > 0 && !(rs[r - 1] < x)) --r;
    return r;
  };
  auto add = [&](const Vec2& a, const Vec2& b, int ra, int rb) {
    const int k0 = std::max(std::min(ra, rb), k_lo), k1 = std::min(std::max(ra, rb), k_hi);
    if (k0 < k1) out.push_back({&a, &b, k0, k1});
  };
  for (const auto& loop : loops) {
    if (loop.empty()) continue;
    const double q = (loop.front().x() - s_first) / pitch;
    const int r0 = slot_of(loop.front().x(),
                           q > 0 ? static_cast<int>(std::min(q, static_cast<double>(rows))) : 0);
    int r = r0;
    for (std::size_t i = 1; i < loop.size(); ++i) {
      const int next = slot_of(loop[i].x(), r);
      if (next != r) add(loop[i - 1], loop[i], r, next);
      r = next;
    }
    if (r != r0) add(loop.back(), loop.front(), r, r0);
  }
}

// Each row's number of crossings of the edges: count[k], 0 <= k < rows.
void row_counts(const std::vector<Crossing>& edges, int rows, std::vector<int>& count) {
  // count[k + 1]: +1 at an edge's first row, -1 past its last, summed: row k's crossings.
  count.assign(static_cast<std::size_t>(rows) + 1, 0);
  for (const Crossing& e : edges) {
    ++count[static_cast<std::size_t>(e.first) + 1];
    if (e.last < rows) --count[static_cast<std::size_t>(e.last) + 1];
  }
  for (std::size_t k = 1; k < count.size(); ++k) count[k] += count[k - 1];
  count.erase(count.begin());
}

// The intervals of the rows k with take(k) (the others left empty), from the edges and their
// rows' counts: each row's crossings in the edges' order, sorted and paired (even-odd).
template <class Take>
RowIntervals fill_rows(const std::vector<Crossing>& edges, const std::vector<int>& count,
                       const std::vector<double>& row_s, Take take) {
  const int rows = static_cast<int>(count.size());
  std::vector<int> at(static_cast<std::size_t>(rows) + 1, 0);  // where row k's crossings start
  for (int k = 0; k < rows; ++k)
    at[static_cast<std::size_t>(k) + 1] =
        at[static_cast<std::size_t>(k)] + (take(k) ? count[static_cast<std::size_t>(k)] : 0);
  // Every crossing's slot is written once below: no zeroing (new double[] leaves it as is).
  const std::size_t crossings = static_cast<std::size_t>(at.back());
  const std::unique_ptr<double[]> t(new double[crossings]);
  std::vector<int> fill(at.begin(), at.end() - 1);
  for (const Crossing& e : edges) {
    const Vec2& a = *e.a;
    const Vec2& b = *e.b;
    for (int k = e.first; k < e.last; ++k) {
      if (!take(k)) continue;
      const double s = row_s[static_cast<std::size_t>(k)];
      t[static_cast<std::size_t>(fill[static_cast<std::size_t>(k)]++)] =
          a.y() + (s - a.x()) / (b.x() - a.x()) * (b.y() - a.y());
    }
  }
  RowIntervals out;
  out.start.assign(static_cast<std::size_t>(rows) + 1, 0);
  out.intervals.resize(crossings / 2);  // at most one interval per two crossings
  Interval* next = out.intervals.data();
  for (int k = 0; k < rows; ++k) {
    double* const first = t.get() + at[static_cast<std::size_t>(k)];
    double* const last = t.get() + at[static_cast<std::size_t>(k) + 1];
    if (last - first > 16) {
      std::sort(first, last);
    } else {  // a row crosses a region a few times: std::sort's set-up would cost more
      for (double* c = first + 1; c < last; ++c)
        for (double* d = c; d != first && *(d - 1) > *d; --d) std::swap(*(d - 1), *d);
    }
    for (const double* c = first; c + 1 < last; c += 2)
      if (*(c + 1) > *c) *next++ = Interval(*c, *(c + 1));
    out.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(next - out.intervals.data());
  }
  out.intervals.resize(static_cast<std::size_t>(next - out.intervals.data()));
  return out;
}

// Rows outside k_lo <= k < k_hi are left empty.
RowIntervals row_intervals(const StLoops& loops, const std::vector<double>& row_s, double pitch,
                           int k_lo, int k_hi) {
  const int rows = static_cast<int>(row_s.size()) - 1;
  k_lo = std::max(k_lo, 0), k_hi = std::min(k_hi, rows);
  std::vector<Crossing> edges;
  crossing_edges(loops, row_s, pitch, k_lo, k_hi, edges);
  std::vector<int> count;
  row_counts(edges, rows, count);
  return fill_rows(edges, count, row_s, [](int) { return true; });
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

// Calls overlap(lo, hi) for each non-empty overlap of a and b, in order.
template <class Overlap>
void for_each_overlap(Span a, Span b, Overlap overlap) {
  while (a.first != a.last && b.first != b.last) {
    const double lo = std::max(a.first->first, b.first->first);
    const double hi = std::min(a.first->second, b.first->second);
    (a.first->second < b.first->second) ? ++a.first : ++b.first;
    if (hi > lo) overlap(lo, hi);
  }
}

// a less b, appended to `out`.
void subtract_into(Span a, Span b, Intervals& out) {
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

// The parts of a less b that overlap h, appended to `out` (an interval of a that does not
// overlap h has none).
void subtract_overlapping(Span a, Span b, const Interval& h, Intervals& out) {
  for (; a.first != a.last; ++a.first) {
    double lo = a.first->first;
    const double hi = a.first->second;
    if (!(hi > h.first && lo < h.second)) continue;
    while (b.first != b.last && b.first->second <= lo) ++b.first;
    for (const Interval* k = b.first; k != b.last && k->first < hi; ++k) {
      if (k->first > lo && k->first > h.first && lo < h.second) out.emplace_back(lo, k->first);
      lo = std::max(lo, k->second);
    }
    if (hi > lo && hi > h.first && lo < h.second) out.emplace_back(lo, hi);
  }
}

void merge_in_place(Intervals& a) {
  if (a.size() > 16) {
    std::sort(a.begin(), a.end());
  } else {  // a row's few sources: by insertion (the same order: std::pair's)
    for (std::size_t c = 1; c < a.size(); ++c)
      for (std::size_t d = c; d > 0 && a[d] < a[d - 1]; --d) std::swap(a[d - 1], a[d]);
  }
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
  Intervals solid, widened;
};

// Top surfaces of rows k_lo <= k < k_hi (row k less row k + 1 of `cut`) and bottom ones (row k
// less row k - 1), each kept only where it overlaps the hull of the rows it is a source for
// (`hull`: each row's room from its first to its last interval, empty for a row without sparse
// infill; top: rows k - layers + 1 .. k, bottom: rows k .. k + layers - 1): an interval outside
// it has no part in any of those rooms, and add_source keeps nothing else of it.
void surfaces(const RowIntervals& cut, const std::vector<Interval>& hull, int layers, int k_lo,
              int k_hi, RowIntervals& top, RowIntervals& bottom) {
  const int rows = static_cast<int>(hull.size());
  top.start.assign(static_cast<std::size_t>(rows) + 1, 0);
  bottom.start = top.start;
  // a row's a - b has at most |a| + |b| intervals: at most twice the cut's in all
  top.intervals.reserve(2 * cut.intervals.size());
  bottom.intervals.reserve(2 * cut.intervals.size());
  // reach[k - k_lo]: the hull of rows k - layers + 1 .. k (a top surface of row k is a source
  // for those rows; a bottom one of row k for rows k .. k + layers - 1: reach[k + layers - 1]).
  std::vector<Interval> reach(static_cast<std::size_t>(std::max(k_hi + layers - 1 - k_lo, 0)));
  for (int k = k_lo; k < k_hi + layers - 1; ++k) {
    Interval h(INFINITY, -INFINITY);
    for (int n = std::max(k - layers + 1, 0); n <= std::min(k, rows - 1); ++n) {
      h.first = std::min(h.first, hull[static_cast<std::size_t>(n)].first);
      h.second = std::max(h.second, hull[static_cast<std::size_t>(n)].second);
    }
    reach[static_cast<std::size_t>(k - k_lo)] = h;
  }
  for (int k = 0; k < rows; ++k) {
    if (k >= k_lo && k < k_hi) {
      const Span row = cut.at(k);
      subtract_overlapping(row, cut.row(k + 1), reach[static_cast<std::size_t>(k - k_lo)],
                           top.intervals);
      subtract_overlapping(row, cut.row(k - 1),
                           reach[static_cast<std::size_t>(k + layers - 1 - k_lo)],
                           bottom.intervals);
    }
    top.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(top.intervals.size());
    bottom.start[static_cast<std::size_t>(k) + 1] = static_cast<int>(bottom.intervals.size());
  }
}

// A source's parts inside the row's infill region, each in `solid`; those narrower than
// 2 growth also widened by growth at both ends within their interval of `inner`, in `widened`.
// True when one was widened (otherwise `widened` gained what `solid` did).
bool add_source(Span source, Span inner, double growth, Scratch& w) {
  const Interval* room = inner.first;
  bool grown = false;
  for_each_overlap(source, inner, [&](double lo, double hi) {
    w.solid.emplace_back(lo, hi);
    if (!(hi - lo < 2.0 * growth)) {
      w.widened.emplace_back(lo, hi);
      return;
    }
    grown = true;
    while (room + 1 != inner.last && room->second < lo) ++room;  // the interval holding [lo, hi]
    w.widened.emplace_back(std::max(room->first, lo - growth), std::min(room->second, hi + growth));
  });
  return grown;
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
  // row k's s (the crossings' and the slots' one expression), and an infinite one past the last
  std::vector<double> row_s(static_cast<std::size_t>(rows) + 1, INFINITY);
  for (int k = 0; k < rows; ++k) row_s[static_cast<std::size_t>(k)] = s_first + k * pitch;
  // The sparse region's crossings per row; its intervals only for the rows that widen a skin
  // (below): a row without crossings has none, and only those rows' strips need them.
  std::vector<Crossing> sparse_edges;
  crossing_edges(sparse, row_s, pitch, 0, rows, sparse_edges);
  if (sparse_edges.empty()) return strips;
  std::vector<int> sparse_count;
  row_counts(sparse_edges, rows, sparse_count);
  auto has_sparse = [&sparse_count](int n) {
    return sparse_count[static_cast<std::size_t>(n)] > 0;
  };
  // Only rows crossing sparse infill get strips (n_lo <= n < n_hi): their room, and the
  // surfaces of the rows within `layers` of them (each from its own row and the next one).
  int n_lo = 0, n_hi = rows;
  while (!has_sparse(n_lo)) ++n_lo;
  while (!has_sparse(n_hi - 1)) --n_hi;
  const int k_lo = std::max(n_lo - layers + 1, 0), k_hi = std::min(n_hi + layers - 1, rows);
  const RowIntervals cut = row_intervals(section, row_s, pitch, k_lo - 1, k_hi + 1);
  const RowIntervals fill = row_intervals(inner, row_s, pitch, n_lo, n_hi);
  std::vector<Interval> hull(static_cast<std::size_t>(rows), Interval(INFINITY, -INFINITY));
  for (int n = n_lo; n < n_hi; ++n) {
    const Span room = fill.at(n);
    if (!room.empty() && has_sparse(n))
      hull[static_cast<std::size_t>(n)] = Interval(room.first->first, (room.last - 1)->second);
  }
  RowIntervals top, bottom;
  surfaces(cut, hull, layers, k_lo, k_hi, top, bottom);
  // Each row's widened skin less its solid (`extra`), for the rows where a skin grows.
  std::vector<int> grown_row;       // ascending
  std::vector<int> extra_start{0};  // grown_row[i]'s extra: extra[extra_start[i] ..]
  Intervals extra;
  grown_row.reserve(static_cast<std::size_t>(n_hi - n_lo));  // one allocation each
  extra_start.reserve(static_cast<std::size_t>(n_hi - n_lo) + 1);
  extra.reserve(2 * static_cast<std::size_t>(n_hi - n_lo));
  std::vector<char> grown_mask(static_cast<std::size_t>(rows), 0);
  Scratch w;
  w.solid.reserve(8 * static_cast<std::size_t>(layers));
  w.widened.reserve(8 * static_cast<std::size_t>(layers));
  for (int n = n_lo; n < n_hi; ++n) {
    const Span room = fill.at(n);
    if (room.empty() || !has_sparse(n)) continue;
    // Only the other rows' surfaces are widened: none within `layers`, nothing grows.
    const auto& ts = top.start;
    const auto& bs = bottom.start;
    if (ts[static_cast<std::size_t>(std::min(n + layers, rows))] ==
            ts[static_cast<std::size_t>(n) + 1] &&
        bs[static_cast<std::size_t>(n)] ==
            bs[static_cast<std::size_t>(std::max(n - layers + 1, 0))])
      continue;
    w.solid.clear();
    w.widened.clear();
    bool grown = false;
    for (int d = 0; d < layers; ++d) {
      // The row's own surfaces are printed as top / bottom fill and are not widened.
      const double g = d == 0 ? 0.0 : growth;
      if (n + d < rows) {
        const Span up = top.at(n + d);
        if (!up.empty()) grown |= add_source(up, room, g, w);
      }
      if (n - d >= 0) {
        const Span down = bottom.at(n - d);
        if (!down.empty()) grown |= add_source(down, room, g, w);
      }
    }
    // Nothing widened: `widened` holds what `solid` does, and adds nothing.
    if (!grown) continue;
    merge_in_place(w.widened);
    merge_in_place(w.solid);
    subtract_into(Span(w.widened), Span(w.solid), extra);
    if (extra.size() == static_cast<std::size_t>(extra_start.back())) continue;
    grown_row.push_back(n);
    extra_start.push_back(static_cast<int>(extra.size()));
    grown_mask[static_cast<std::size_t>(n)] = 1;
  }
  if (grown_row.empty()) return strips;
  strips.reserve(extra.size());
  const RowIntervals kept = fill_rows(sparse_edges, sparse_count, row_s,
                                      [&grown_mask](int k) { return grown_mask[k] != 0; });
  for (std::size_t i = 0; i < grown_row.size(); ++i) {
    const int n = grown_row[i];
    const Span row_extra(extra.data() + extra_start[i], extra.data() + extra_start[i + 1]);
    const double s = row_s[static_cast<std::size_t>(n)];
    for_each_overlap(row_extra, kept.at(n), [&](double lo, double hi) {
      strips.push_back({s - 0.5 * pitch, s + 0.5 * pitch, lo, hi});
    });
  }
  return strips;
}

}  // namespace osteon::detail
