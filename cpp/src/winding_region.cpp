// The region of closed integer paths by winding numbers (winding_region.hpp). Every proper
// crossing of two edges is found in a uniform grid over the edges' boxes (exact orientation
// tests in 128-bit integers); the paths cut at their crossings are chains, along each of which
// the winding numbers on the right stay constant and change by +-1 (for the crossed path's set)
// from one chain to the next. One vertical ray per path (from its lowest vertex) fixes them.
// A chain bounds the region where `inside` differs on its two sides; at each crossing one kept
// chain arrives and one leaves, which joins them into loops.
#include "winding_region.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>

#include "noinline.hpp"
#include "round_to_unit.hpp"

namespace osteon::detail {
namespace {

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::Point64;
__extension__ typedef __int128 Wide;

// An allocator whose resize() leaves new elements uninitialised (default-initialised) instead of
// zeroing them: for the arrays below that are written in full before they are read, where the
// zeroing was a pass over memory for nothing.
template <class T>
struct NoZeroAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = NoZeroAllocator<U>;
  };
  NoZeroAllocator() = default;
  template <class U>
  NoZeroAllocator(const NoZeroAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <class T>
using Filled = std::vector<T, NoZeroAllocator<T>>;  // every element written before it is read

// Twice the signed area of (a, b, c): > 0 when c lies left of a -> b.
inline Wide orient(const Point64& a, const Point64& b, const Point64& c) {
  return static_cast<Wide>(b.x - a.x) * (c.y - a.y) - static_cast<Wide>(b.y - a.y) * (c.x - a.x);
}

inline bool spike(const Point64& a, const Point64& b, const Point64& c) {
  if (orient(a, b, c) != 0) return false;
  return static_cast<Wide>(b.x - a.x) * (c.x - b.x) + static_cast<Wide>(b.y - a.y) * (c.y - b.y) <=
         0;
}

// The path without repeated points and spikes (edges folding back on the previous one); empty
// when fewer than 3 points remain.
void clean(const Path64& in, std::vector<Point64>& out) {
  const std::size_t first = out.size();
  auto size = [&] { return out.size() - first; };
  for (const Point64& p : in) {
    if (size() > 0 && out.back() == p) continue;
    out.push_back(p);
    while (size() >= 3 && spike(out[out.size() - 3], out[out.size() - 2], out.back())) {
      out.erase(out.end() - 2);
      if (out[out.size() - 2] == out.back()) out.pop_back();
    }
  }
  while (size() >= 3) {
    const std::size_t n = out.size();
    if (out[n - 1] == out[first])
      out.pop_back();
    else if (spike(out[n - 2], out[n - 1], out[first]))
      out.pop_back();
    else if (spike(out[n - 1], out[first], out[first + 1]))
      out.erase(out.begin() + static_cast<std::ptrdiff_t>(first));
    else
      break;
  }
  if (size() < 3) out.resize(first);
}

struct Crossing {
  int seg[2];    // the two edges (index of their first point)
  int delta[2];  // change of the right-side winding (of the other edge's set) along each edge
  double x, y;
};

struct Occurrence {
  int seg;
  double t;  // position along the edge, 0..1
  int crossing, side;
  bool operator<(const Occurrence& o) const { return seg != o.seg ? seg < o.seg : t < o.t; }
};

struct Arrangement {
  std::vector<Point64> pts;
  Filled<int> path_of;      // per point
  std::vector<int> start;   // per path, and one past the last
  std::vector<int> set_of;  // per path
  std::vector<Crossing> crossings;
  Filled<Occurrence> occ;  // sorted by edge, then along it
  Filled<int> nxt;         // per point: the next point of its path
  int next(int g) const { return nxt[static_cast<std::size_t>(g)]; }
  const Point64& pt(int g) const { return pts[static_cast<std::size_t>(g)]; }
  void clear() {
    pts.clear(), path_of.clear(), start.clear(), set_of.clear();
    crossings.clear(), occ.clear(), nxt.clear();
  }
};

// orient in T: double is exact where coordinate differences stay under 2^26 (products under
// 2^52), which find_crossings checks first.
template <class T>
inline T orient_in(const Point64& a, const Point64& b, const Point64& c) {
  return static_cast<T>(b.x - a.x) * static_cast<T>(c.y - a.y) -
         static_cast<T>(b.y - a.y) * static_cast<T>(c.x - a.x);
}

// An edge's bounding box in Clipper units.
struct EdgeBox {
  std::int64_t x0, y0, x1, y1;
};

// 0: no crossing, 1: a proper crossing (appended), -1: the edges touch or overlap.
template <class T>
int cross_edges(Arrangement& a, int i, int j) {
  const int ni = a.next(i), nj = a.next(j);
  if (nj == i || ni == j) return 0;  // neighbours share their end point only (no spikes)
  const Point64 &p = a.pt(i), &q = a.pt(ni), &r = a.pt(j), &s = a.pt(nj);
  const T d1 = orient_in<T>(r, s, p), d2 = orient_in<T>(r, s, q);
  if ((d1 > 0 && d2 > 0) || (d1 < 0 && d2 < 0)) return 0;
  const T d3 = orient_in<T>(p, q, r), d4 = orient_in<T>(p, q, s);
  if ((d3 > 0 && d4 > 0) || (d3 < 0 && d4 < 0)) return 0;
  if (d1 == 0 || d2 == 0 || d3 == 0 || d4 == 0) return -1;
  const double ti = static_cast<double>(d1) / (static_cast<double>(d1) - static_cast<double>(d2));
  const double tj = static_cast<double>(d3) / (static_cast<double>(d3) - static_cast<double>(d4));
  const int id = static_cast<int>(a.crossings.size());
  // Along i the crossing leads from edge j's left side (d1 > 0: p left of j) to its right.
  a.crossings.push_back({{i, j},
                         {d1 > 0 ? -1 : 1, d3 > 0 ? -1 : 1},
                         static_cast<double>(p.x) + ti * static_cast<double>(q.x - p.x),
                         static_cast<double>(p.y) + ti * static_cast<double>(q.y - p.y)});
  a.occ.push_back({i, ti, id, 0});
  a.occ.push_back({j, tj, id, 1});
  return 1;
}

// a.occ by edge (counting sort: most edges have none or one), then along each edge.
// (Placed from each edge's end backwards, which keeps their order; then each run of two or more
// on one edge sorted, found along the occurrences rather than the edges.)
void sort_occurrences(Arrangement& a, std::vector<int>& end, Filled<Occurrence>& sorted) {
  end.assign(a.pts.size(), 0);
  for (const Occurrence& o : a.occ) ++end[static_cast<std::size_t>(o.seg)];
  for (std::size_t k = 1; k < end.size(); ++k) end[k] += end[k - 1];
  sorted.resize(a.occ.size());
  for (std::size_t k = a.occ.size(); k-- > 0;)
    sorted[static_cast<std::size_t>(--end[static_cast<std::size_t>(a.occ[k].seg)])] = a.occ[k];
  for (std::size_t k = 0; k < sorted.size();) {
    std::size_t r = k + 1;
    while (r < sorted.size() && sorted[r].seg == sorted[k].seg) ++r;
    if (r - k > 1)
      std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(k),
                sorted.begin() + static_cast<std::ptrdiff_t>(r));
    k = r;
  }
  a.occ.swap(sorted);
}

// The uniform grid of find_crossings: each edge listed in the cells its box covers, and the
// cells holding two edges or more.
struct EdgeGrid {
  int nx = 1, ny = 1;
  Filled<int> cell_range;  // per edge: x0, y0, x1, y1 of its cells
  std::vector<int> start;  // per cell: its entries' start (one more at the end)
  Filled<int> entries;     // edges by cell
  std::vector<int> busy;   // cells with two edges or more, in increasing order
  std::vector<int> fill;   // build()'s: per cell, the next entry to fill
  // False where the boxes cover more than 64 cells per edge (many long edges across small cells).
  bool build(const Filled<EdgeBox>& boxes, const EdgeBox& all, double cell);
  std::int64_t pairs() const {  // edge pairs sharing a cell
    std::int64_t sum = 0;
    for (const int c : busy) {
      const std::int64_t k =
          start[static_cast<std::size_t>(c) + 1] - start[static_cast<std::size_t>(c)];
      sum += k * (k - 1) / 2;
    }
    return sum;
  }
};

bool EdgeGrid::build(const Filled<EdgeBox>& boxes, const EdgeBox& all, double cell) {
  const std::size_t n = boxes.size();
  const double w = static_cast<double>(all.x1 - all.x0) + 1.0;
  const double h = static_cast<double>(all.y1 - all.y0) + 1.0;
  nx = static_cast<int>(std::clamp(std::ceil(w / cell), 1.0, 4096.0));
  ny = static_cast<int>(std::clamp(std::ceil(h / cell), 1.0, 4096.0));
  const double sx = nx / w, sy = ny / h;
  cell_range.resize(4 * n);
  std::int64_t covered = 0;  // cells over all edges' boxes
  for (std::size_t g = 0; g < n; ++g) {
    const EdgeBox& e = boxes[g];
    int* b = &cell_range[4 * g];
    b[0] = static_cast<int>(static_cast<double>(e.x0 - all.x0) * sx);
    b[1] = static_cast<int>(static_cast<double>(e.y0 - all.y0) * sy);
    b[2] = std::min(nx - 1, static_cast<int>(static_cast<double>(e.x1 - all.x0) * sx));
    b[3] = std::min(ny - 1, static_cast<int>(static_cast<double>(e.y1 - all.y0) * sy));
    covered += static_cast<std::int64_t>(b[2] - b[0] + 1) * (b[3] - b[1] + 1);
  }
  if (covered > 64 * static_cast<std::int64_t>(n) + 4096) return false;
  start.assign(static_cast<std::size_t>(nx) * ny + 1, 0);
  busy.clear();
  for (std::size_t g = 0; g < n; ++g) {
    const int* b = &cell_range[4 * g];
    for (int cy = b[1]; cy <= b[3]; ++cy)
      for (int cx = b[0]; cx <= b[2]; ++cx)
        if (++start[static_cast<std::size_t>(cy) * nx + cx + 1] == 2) busy.push_back(cy * nx + cx);
  }
  std::sort(busy.begin(), busy.end());
  for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  entries.resize(static_cast<std::size_t>(start.back()));
  fill.assign(start.begin(), start.end() - 1);
  for (std::size_t g = 0; g < n; ++g) {
    const int* b = &cell_range[4 * g];
    for (int cy = b[1]; cy <= b[3]; ++cy)
      for (int cx = b[0]; cx <= b[2]; ++cx)
        entries[static_cast<std::size_t>(fill[static_cast<std::size_t>(cy) * nx + cx]++)] =
            static_cast<int>(g);
  }
  return true;
}

// Every proper crossing, each once: pairs of edges whose boxes overlap are tested in the grid
// cell at the lower corner of their boxes' common cells. The cell's side is first four times
// the edges' mean box extent, at most 16 cells per edge in all: on cow x4's sections 1.3 cells
// per edge and 8 pairs per edge, of which the boxes' test passes 1.7 (1, 2 and 8 times the mean
// extent, or the median, cost more). Where that grid would test more than 64 pairs per edge
// (a few long edges set the mean): one edge per cell's area, as before. False where two edges
// touch or overlap, or where the grid declines (a star of thousands of long spikes would cost
// quadratic memory and pair tests here: Clipper2, n log n, takes the section).
bool find_crossings(Arrangement& a, Filled<EdgeBox>& boxes, EdgeGrid& grid) {
  const std::size_t n = a.pts.size();
  boxes.resize(n);
  EdgeBox all{INT64_MAX, INT64_MAX, INT64_MIN, INT64_MIN};
  double extent = 0.0;
  for (std::size_t g = 0; g < n; ++g) {
    const Point64 &p = a.pts[g], &q = a.pt(a.nxt[g]);
    const EdgeBox& b =
        boxes[g] = {std::min(p.x, q.x), std::min(p.y, q.y), std::max(p.x, q.x), std::max(p.y, q.y)};
    extent += static_cast<double>(std::max(b.x1 - b.x0, b.y1 - b.y0));
    all.x0 = std::min(all.x0, p.x), all.y0 = std::min(all.y0, p.y);
    all.x1 = std::max(all.x1, p.x), all.y1 = std::max(all.y1, p.y);
  }
  // Orientations are exact in double where coordinate differences stay under 2^26.
  const bool small = all.x1 - all.x0 < (1 << 26) && all.y1 - all.y0 < (1 << 26);
  const double w = static_cast<double>(all.x1 - all.x0) + 1.0;
  const double h = static_cast<double>(all.y1 - all.y0) + 1.0;
  const double cells = static_cast<double>(n);
  const std::int64_t most = 64 * static_cast<std::int64_t>(n) + 4096;
  if (!grid.build(boxes, all, std::max(4.0 * extent / cells, std::sqrt(w * h / (16.0 * cells)))) ||
      grid.pairs() > most)
    if (!grid.build(boxes, all, std::sqrt(w * h / cells))) return false;
  for (const int c : grid.busy) {
    const int cx = c % grid.nx, cy = c / grid.nx;
    const std::size_t c0 = static_cast<std::size_t>(grid.start[static_cast<std::size_t>(c)]);
    const std::size_t c1 = static_cast<std::size_t>(grid.start[static_cast<std::size_t>(c) + 1]);
    for (std::size_t u = c0; u < c1; ++u) {
      const int i = grid.entries[u];
      const EdgeBox& bi = boxes[static_cast<std::size_t>(i)];
      const int* ci = &grid.cell_range[4 * static_cast<std::size_t>(i)];
      for (std::size_t v = u + 1; v < c1; ++v) {
        const int j = grid.entries[v];
        const EdgeBox& bj = boxes[static_cast<std::size_t>(j)];
        if (bi.x1 < bj.x0 || bj.x1 < bi.x0 || bi.y1 < bj.y0 || bj.y1 < bi.y0) continue;
        const int* cj = &grid.cell_range[4 * static_cast<std::size_t>(j)];
        if (std::max(ci[0], cj[0]) != cx || std::max(ci[1], cj[1]) != cy) continue;
        if ((small ? cross_edges<double>(a, i, j) : cross_edges<Wide>(a, i, j)) < 0) return false;
      }
    }
  }
  return true;
}

// The winding numbers just below path p's lowest vertex v, from the other paths' edges (ray
// straight down, half-open in x: an edge counts where its box's x0 <= v.x < x1, i.e. where one
// end point has x <= v.x and the other not); false where an edge passes through v.
bool winding_below(const Arrangement& a, const Filled<EdgeBox>& boxes, int p, int v, Windings& w) {
  w = {0, 0, 0};
  const Point64& o = a.pt(v);
  const int n = static_cast<int>(a.pts.size());
  for (int g = 0; g < n; ++g) {
    const EdgeBox& b = boxes[static_cast<std::size_t>(g)];
    if (o.x < b.x0 || b.x1 <= o.x || a.path_of[static_cast<std::size_t>(g)] == p) continue;
    const Point64 &r = a.pt(g), &s = a.pt(a.next(g));
    const bool right = r.x < s.x;
    const Wide side = right ? orient(r, s, o) : orient(s, r, o);
    if (side == 0) return false;
    if (side > 0)
      w[static_cast<std::size_t>(a.set_of[a.path_of[static_cast<std::size_t>(g)]])] +=
          right ? 1 : -1;
  }
  return true;
}

// The winding numbers right of each chain (chain k of a path starts at its k-th occurrence;
// a path without crossings is one chain, index -1 - path). False on an inconsistency.
bool chain_windings(const Arrangement& a, const Filled<EdgeBox>& boxes, Filled<Windings>& right,
                    Filled<Windings>& lone) {
  const int paths = static_cast<int>(a.set_of.size());
  // Every chain's windings are written below, and each path's own where it has no chain.
  right.resize(a.occ.size());
  lone.resize(static_cast<std::size_t>(paths));
  std::size_t o = 0;
  for (int p = 0; p < paths; ++p) {
    const int first = a.start[static_cast<std::size_t>(p)];
    const int last = a.start[static_cast<std::size_t>(p) + 1];
    const std::size_t o0 = o;
    while (o < a.occ.size() && a.occ[o].seg < last) ++o;
    const std::size_t m = o - o0;
    // Relative windings along the path: chain k starts after occurrence k.
    auto step = [&](const Occurrence& e, Windings& w) {
      const Crossing& c = a.crossings[static_cast<std::size_t>(e.crossing)];
      const int other = a.path_of[static_cast<std::size_t>(c.seg[1 - e.side])];
      w[static_cast<std::size_t>(a.set_of[static_cast<std::size_t>(other)])] += c.delta[e.side];
    };
    Windings acc{0, 0, 0};
    for (std::size_t k = 0; k < m; ++k) {
      if (k > 0) step(a.occ[o0 + k], acc);
      right[o0 + k] = acc;
    }
    if (m > 0) {  // passing occurrence 0 again returns to chain 0's windings
      step(a.occ[o0], acc);
      if (acc != right[o0]) return false;
    }
    // Anchor: the lowest vertex (least y, then least x) and the winding just below it.
    int v = first;
    for (int g = first + 1; g < last; ++g)
      if (a.pt(g).y < a.pt(v).y || (a.pt(g).y == a.pt(v).y && a.pt(g).x < a.pt(v).x)) v = g;
    Windings below;
    if (!winding_below(a, boxes, p, v, below)) return false;
    const Wide turn = orient(a.pt(v == first ? last - 1 : v - 1), a.pt(v), a.pt(a.next(v)));
    if (turn == 0) return false;
    const std::size_t own = static_cast<std::size_t>(a.set_of[static_cast<std::size_t>(p)]);
    if (turn < 0) below[own] -= 1;  // below lies left of the edge leaving v
    if (m == 0) {
      lone[static_cast<std::size_t>(p)] = below;
      continue;
    }
    // The chain holding v's outgoing edge: after the last occurrence on an earlier edge.
    std::size_t k = 0;
    while (k < m && a.occ[o0 + k].seg < v) ++k;
    const Windings ref = right[o0 + (k == 0 ? m - 1 : k - 1)];
    for (std::size_t j = 0; j < m; ++j)
      for (std::size_t s = 0; s < 3; ++s) right[o0 + j][s] += below[s] - ref[s];
  }
  return true;
}

}  // namespace

namespace {

// The kept chains joined into loops at their crossings.
struct Assembly {
  const Arrangement& a;
  std::vector<int> begin, end;   // per path: its occurrences' range
  std::vector<signed char> dir;  // per chain: +1 kept as it runs, -1 reversed, 0 not kept
  std::vector<int> leaving;      // per crossing: the kept chain leaving it, -1 none
  int next_occ(int u) const {
    const int p = a.path_of[static_cast<std::size_t>(a.occ[static_cast<std::size_t>(u)].seg)];
    return u + 1 == end[static_cast<std::size_t>(p)] ? begin[static_cast<std::size_t>(p)] : u + 1;
  }
  int from(int u) const {  // the crossing a kept chain leaves
    return a.occ[static_cast<std::size_t>(dir[static_cast<std::size_t>(u)] > 0 ? u : next_occ(u))]
        .crossing;
  }
  int to(int u) const {
    return a.occ[static_cast<std::size_t>(dir[static_cast<std::size_t>(u)] > 0 ? next_occ(u) : u)]
        .crossing;
  }
  // Chain u's points from its first crossing up to (not including) the next crossing.
  void emit(int u, Path64& loop) const {
    const Occurrence& e = a.occ[static_cast<std::size_t>(u)];
    const int v = next_occ(u);
    const Occurrence& f = a.occ[static_cast<std::size_t>(v)];
    const int p = a.path_of[static_cast<std::size_t>(e.seg)];
    const int first = a.start[static_cast<std::size_t>(p)];
    const int n = a.start[static_cast<std::size_t>(p) + 1] - first;
    int count = ((f.seg - e.seg) % n + n) % n;
    if (count == 0 && v <= u) count = n;  // around the whole path
    const bool fwd = dir[static_cast<std::size_t>(u)] > 0;
    const Crossing& c = a.crossings[static_cast<std::size_t>(fwd ? e.crossing : f.crossing)];
    loop.emplace_back(round_to_unit(c.x), round_to_unit(c.y));
    for (int i = 0; i < count; ++i) {
      const int k = fwd ? i + 1 : count - i;  // steps after e's edge start
      loop.push_back(a.pt(first + (e.seg - first + k) % n));
    }
  }
};

void add_loop(Path64& loop, Paths64& out) {
  Path64 clean_loop;
  clean_loop.reserve(loop.size());
  for (const Point64& p : loop)
    if (clean_loop.empty() || clean_loop.back() != p) clean_loop.push_back(p);
  while (clean_loop.size() > 1 && clean_loop.back() == clean_loop.front()) clean_loop.pop_back();
  if (clean_loop.size() >= 3 && Clipper2Lib::Area(clean_loop) != 0)
    out.push_back(std::move(clean_loop));
  loop.clear();
}

// Joins the kept chains into loops; false where a crossing has more than one way on.
bool assemble(Assembly& s, const Filled<Windings>& lone, const Filled<Windings>& right,
              bool (*inside)(const Windings&), Paths64& out) {
  const Arrangement& a = s.a;
  const int paths = static_cast<int>(a.set_of.size());
  const int chains = static_cast<int>(a.occ.size());
  s.dir.assign(a.occ.size(), 0);
  s.leaving.assign(a.crossings.size(), -1);
  std::vector<int> arriving(a.crossings.size(), 0);
  Path64 loop;
  for (int p = 0; p < paths; ++p) {
    const std::size_t own = static_cast<std::size_t>(a.set_of[static_cast<std::size_t>(p)]);
    auto side = [&](Windings w) {  // +1 region on the left, -1 on the right, 0 neither
      const bool r = inside(w);
      ++w[own];
      const bool l = inside(w);
      return l == r ? 0 : (l ? 1 : -1);
    };
    const int b = s.begin[static_cast<std::size_t>(p)], e = s.end[static_cast<std::size_t>(p)];
    if (b == e) {  // a path no other crosses: a loop of the result, or none
      const int d = side(lone[static_cast<std::size_t>(p)]);
      if (d == 0) continue;
      const int first = a.start[static_cast<std::size_t>(p)];
      loop.assign(a.pts.begin() + first, a.pts.begin() + a.start[static_cast<std::size_t>(p) + 1]);
      if (d < 0) std::reverse(loop.begin(), loop.end());
      add_loop(loop, out);
      continue;
    }
    for (int u = b; u < e; ++u) {
      s.dir[static_cast<std::size_t>(u)] =
          static_cast<signed char>(side(right[static_cast<std::size_t>(u)]));
      if (s.dir[static_cast<std::size_t>(u)] == 0) continue;
      int& leave = s.leaving[static_cast<std::size_t>(s.from(u))];
      if (leave >= 0 || ++arriving[static_cast<std::size_t>(s.to(u))] > 1) return false;
      leave = u;
    }
  }
  for (std::size_t x = 0; x < a.crossings.size(); ++x)
    if ((s.leaving[x] >= 0) != (arriving[x] == 1)) return false;
  std::vector<char> done(a.occ.size(), 0);
  for (int u = 0; u < chains; ++u) {
    if (s.dir[static_cast<std::size_t>(u)] == 0 || done[static_cast<std::size_t>(u)]) continue;
    int w = u, steps = 0;
    do {
      if (done[static_cast<std::size_t>(w)] || ++steps > chains) return false;
      done[static_cast<std::size_t>(w)] = 1;
      s.emit(w, loop);
      w = s.leaving[static_cast<std::size_t>(s.to(w))];
    } while (w != u);
    add_loop(loop, out);
  }
  return true;
}

}  // namespace

namespace {

// winding_region's arrays, kept by each thread from call to call (a section's printed stage
// calls it two or three times): no allocation once they are large enough. The work takes them
// by reference: each use of a thread_local in a shared library is a call that finds it.
struct Work {
  Arrangement a;
  Filled<EdgeBox> boxes;
  EdgeGrid grid;             // build() sets every field
  std::vector<int> occ_end;  // sort_occurrences' per edge
  Filled<Occurrence> sorted;
  Filled<Windings> right, lone;
};

OSTEON_NOINLINE bool winding_region_in(Work& work, const std::vector<const Paths64*>& sets,
                                       bool (*inside)(const Windings&), Paths64& out) {
  Arrangement& a = work.a;
  a.clear();
  a.start.push_back(0);
  std::size_t points = 0;
  for (std::size_t s = 0; s < sets.size() && s < 3; ++s)
    for (const Path64& path : *sets[s]) points += path.size();
  a.pts.reserve(points);  // clean() keeps at most every point
  for (std::size_t s = 0; s < sets.size() && s < 3; ++s)
    for (const Path64& path : *sets[s]) {
      clean(path, a.pts);
      if (static_cast<int>(a.pts.size()) == a.start.back()) continue;
      a.set_of.push_back(static_cast<int>(s));
      a.start.push_back(static_cast<int>(a.pts.size()));
    }
  if (a.pts.empty()) return true;
  a.path_of.resize(a.pts.size());
  a.nxt.resize(a.pts.size());
  for (std::size_t p = 0; p + 1 < a.start.size(); ++p) {
    const int b = a.start[p], e = a.start[p + 1];
    std::fill(a.path_of.begin() + b, a.path_of.begin() + e, static_cast<int>(p));
    for (int g = b; g < e; ++g) a.nxt[static_cast<std::size_t>(g)] = g + 1 == e ? b : g + 1;
  }
  if (!find_crossings(a, work.boxes, work.grid)) return false;
  sort_occurrences(a, work.occ_end, work.sorted);
  for (std::size_t k = 1; k < a.occ.size(); ++k)  // two crossings too close to order on an edge
    if (a.occ[k].seg == a.occ[k - 1].seg && !(a.occ[k].t - a.occ[k - 1].t > 1e-12)) return false;
  Assembly s{a, {}, {}, {}, {}};
  const std::size_t paths = a.set_of.size();
  s.begin.assign(paths, 0);
  s.end.assign(paths, 0);
  for (std::size_t p = 0, o = 0; p < paths; ++p) {
    s.begin[p] = static_cast<int>(o);
    while (o < a.occ.size() && a.occ[o].seg < a.start[p + 1]) ++o;
    s.end[p] = static_cast<int>(o);
  }
  Filled<Windings>&right = work.right, &lone = work.lone;
  if (!chain_windings(a, work.boxes, right, lone) || !assemble(s, lone, right, inside, out)) {
    out.clear();
    return false;
  }
  return true;
}

}  // namespace

bool winding_region(const std::vector<const Paths64*>& sets, bool (*inside)(const Windings&),
                    Paths64& out) {
  out.clear();
  static thread_local Work work;
  Work* w = &work;
#if defined(__GNUC__)
  // Hides the address from the optimiser: known constant, it would be propagated into the work's
  // functions and each use there would look the thread's copy up again (measured: 1.8 M lookups).
  asm("" : "+r"(w));
#endif
  return winding_region_in(*w, sets, inside, out);
}

}  // namespace osteon::detail
