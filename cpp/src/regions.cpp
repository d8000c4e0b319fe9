#include "osteon/regions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <utility>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "clipper2/clipper.h"
#include "line_triangle.hpp"
#include "simplify_path.hpp"

namespace osteon {
namespace {

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::Point64;
using Clipper2Lib::PointInPolygonResult;
using Clipper2Lib::PolyPath64;
using Clipper2Lib::PolyTree64;

// Plane coordinates <-> Clipper2's integers: a power-of-two scale (exact in binary) that maps the
// largest coordinate to about 2^40, far inside Clipper2's range (2^61) and resolving ~1e-12 of
// the extent.
struct Scaler {
  double scale = 1.0, inv = 1.0;
  explicit Scaler(const std::vector<std::vector<Vec2>>& loops) {
    double extent = 0.0;
    for (const auto& loop : loops)
      for (const Vec2& p : loop) extent = std::max({extent, std::abs(p.x()), std::abs(p.y())});
    if (extent > 0 && std::isfinite(extent)) {
      int e = 0;
      std::frexp(extent, &e);  // extent < 2^e
      scale = std::ldexp(1.0, 40 - e);
      inv = std::ldexp(1.0, e - 40);
    }
  }
  // std::llround (halves away from zero), without the library call for |x| < 2^52: x minus its
  // truncation is exact there.
  static std::int64_t round(double x) {
    if (!(std::abs(x) < 4503599627370496.0)) return static_cast<std::int64_t>(std::llround(x));
    const auto i = static_cast<std::int64_t>(x);
    const double f = x - static_cast<double>(i);
    return f >= 0.5 ? i + 1 : (f <= -0.5 ? i - 1 : i);
  }
  Point64 to(const Vec2& p) const { return Point64(round(p.x() * scale), round(p.y() * scale)); }
  Vec2 from(const Point64& q) const {
    return Vec2(static_cast<double>(q.x) * inv, static_cast<double>(q.y) * inv);
  }
  std::vector<Vec2> from(const Path64& path) const {
    std::vector<Vec2> out;
    out.reserve(path.size());
    for (const Point64& q : path) out.push_back(from(q));
    return out;
  }
};

struct Box2 {
  Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  void add(const Vec2& p) {
    lo.x() = std::min(lo.x(), p.x());
    lo.y() = std::min(lo.y(), p.y());
    hi.x() = std::max(hi.x(), p.x());
    hi.y() = std::max(hi.y(), p.y());
  }
  bool contains(const Vec2& p) const {
    return p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() && p.y() <= hi.y();
  }
  bool overlaps(const Box2& b) const {
    return !(b.lo.x() > hi.x() || b.hi.x() < lo.x() || b.lo.y() > hi.y() || b.hi.y() < lo.y());
  }
};

Box2 box_of(const std::vector<Vec2>& pts) {
  Box2 b;
#if defined(__SSE2__)
  // Both coordinates at once: minpd(q, lo) is q < lo ? q : lo per lane, i.e. std::min(lo, q)
  // (NaN and equal zeros included), maxpd(q, hi) likewise std::max(hi, q): the same box as add().
  __m128d lo = _mm_loadu_pd(b.lo.data()), hi = _mm_loadu_pd(b.hi.data());
  for (const Vec2& p : pts) {
    const __m128d q = _mm_loadu_pd(p.data());
    lo = _mm_min_pd(q, lo);
    hi = _mm_max_pd(q, hi);
  }
  _mm_storeu_pd(b.lo.data(), lo);
  _mm_storeu_pd(b.hi.data(), hi);
#else
  for (const Vec2& p : pts) b.add(p);
#endif
  return b;
}

void union_nonzero(const std::vector<std::vector<Vec2>>& loops, const Scaler& s, PolyTree64& tree) {
  Paths64 paths;
  paths.reserve(loops.size());
  for (const auto& loop : loops) {
    if (loop.size() < 3) continue;
    Path64 path;
    path.reserve(loop.size());
    for (const Vec2& p : loop) path.push_back(s.to(p));
    paths.push_back(std::move(path));
  }
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(paths);
  clipper.Execute(Clipper2Lib::ClipType::Union, Clipper2Lib::FillRule::NonZero, tree);
}

// Every outer (material) node of the tree, islands inside holes included.
void collect_outers(const PolyPath64& node, std::vector<const PolyPath64*>& out) {
  for (const auto& outer : node) {
    out.push_back(outer.get());
    for (const auto& hole : *outer) collect_outers(*hole, out);
  }
}

SectionPolygon polygon_of(const PolyPath64& outer, const Scaler& s) {
  SectionPolygon poly;
  poly.outer = s.from(outer.Polygon());
  for (const auto& hole : outer) poly.holes.push_back(s.from(hole->Polygon()));
  return poly;
}

// True when q lies in the region of `outer` (inside or on its boundary, not strictly in a hole).
bool in_region(const PolyPath64& outer, const Point64& q) {
  if (Clipper2Lib::PointInPolygon(q, outer.Polygon()) == PointInPolygonResult::IsOutside)
    return false;
  for (const auto& hole : outer)
    if (Clipper2Lib::PointInPolygon(q, hole->Polygon()) == PointInPolygonResult::IsInside)
      return false;
  return true;
}

// The outer node whose region holds q, searching islands inside holes; `hollow` is set when q
// lies in a hole with no island around it (the region around the hole is returned).
const PolyPath64* locate(const PolyPath64& node, const Point64& q, bool& hollow) {
  for (const auto& outer : node) {
    if (Clipper2Lib::PointInPolygon(q, outer->Polygon()) == PointInPolygonResult::IsOutside)
      continue;
    for (const auto& hole : *outer) {
      if (Clipper2Lib::PointInPolygon(q, hole->Polygon()) != PointInPolygonResult::IsInside)
        continue;
      if (const PolyPath64* island = locate(*hole, q, hollow)) return island;
      hollow = true;
      return outer.get();
    }
    hollow = false;
    return outer.get();
  }
  return nullptr;
}

double squared_distance_to_polyline(const std::vector<Vec2>& pts, bool closed, const Vec2& q) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = pts.size();
  if (n == 1) return (pts[0] - q).squaredNorm();
  const std::size_t edges = closed ? n : n - 1;
  for (std::size_t i = 0; i < edges; ++i) {
    const Vec2& a = pts[i];
    const Vec2& b = pts[(i + 1) % n];
    const Vec2 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - q).squaredNorm());
  }
  return best;
}

// True when the triangle a segment was cut from belongs to the domain's bone: at least two of
// its three vertices (the ends of the two crossed edges, one shared) are the bone's.
bool owned(const CutSegment& s, const BoneDomain& d) {
  std::int64_t v[4] = {static_cast<std::int64_t>(s.edge[0] >> 32),
                       static_cast<std::int64_t>(s.edge[0] & 0xffffffffu),
                       static_cast<std::int64_t>(s.edge[1] >> 32),
                       static_cast<std::int64_t>(s.edge[1] & 0xffffffffu)};
  std::sort(v, v + 4);
  int count = 0;
  for (int k = 0; k < 4; ++k) {
    if (k > 0 && v[k] == v[k - 1]) continue;
    count += d.vertex_bone[v[k]] == d.bone;
  }
  return count >= 2;
}

// True when any two segments of the given loops (not two neighbours of one loop) cross, touch
// or come within rounding distance of each other; then only a polygon clipper can say what the
// non-zero winding of the loops is. Degenerate (zero-length) segments and loops of fewer than
// three points count as touching. Each loop is split into x-monotone chains (runs of segments
// going the same way in x); only chains whose boxes meet are compared, by a merge along x that
// visits exactly the segment pairs whose x-ranges meet, so smooth loops cost about their number
// of segments.
bool loops_may_cross(const std::vector<const std::vector<Vec2>*>& loops) {
  std::size_t m = 0;
  for (const auto* loop : loops) {
    if (loop->size() < 3) return true;
    m += loop->size();
  }
  // Segment i of a loop joins its points i and i + 1. A chain is a run of a loop's segments
  // whose x never decreases, or never increases (then stored backwards): in storage order both
  // ends of the segments' x-ranges never decrease.
  struct Seg {
    double xlo, xhi, ylo, yhi;
    Vec2 a, b;
    std::uint32_t loop, index;
  };
  struct Chain {
    std::uint32_t begin, end;  // its segments in `segs`
    Box2 box;
  };
  std::vector<Seg> segs;
  segs.reserve(m);
  std::vector<Chain> chains;
  chains.reserve(4 * loops.size() + 16);
  Box2 all;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    const auto& loop = *loops[l];
    const std::size_t n = loop.size();
    int dir = 0;
    double ylo = 0, yhi = 0;  // y-range of the open chain's points so far
    // The chain's box: its x-range from its first and last segments (both ends of the x-ranges
    // never decrease in storage order), its y-range from its points.
    auto close = [&](const Vec2& last) {
      Chain& c = chains.back();
      c.end = static_cast<std::uint32_t>(segs.size());
      if (dir < 0) std::reverse(segs.begin() + c.begin, segs.end());
      c.box.lo = Vec2(segs[c.begin].xlo, std::min(ylo, last.y()));
      c.box.hi = Vec2(segs[c.end - 1].xhi, std::max(yhi, last.y()));
      all.add(c.box.lo);
      all.add(c.box.hi);
    };
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& a = loop[i];
      const Vec2& b = loop[i + 1 == n ? 0 : i + 1];
      if (a == b) return true;  // a degenerate segment counts as touching
      const int s = static_cast<int>(b.x() > a.x()) - static_cast<int>(b.x() < a.x());
      if (i == 0 || (s != 0 && dir != 0 && s != dir)) {
        if (i > 0) close(a);
        chains.push_back({static_cast<std::uint32_t>(segs.size()), 0, Box2{}});
        dir = 0;
        ylo = yhi = a.y();
      }
      if (s != 0) dir = s;
      ylo = std::min(ylo, a.y());
      yhi = std::max(yhi, a.y());
      segs.push_back({std::min(a.x(), b.x()), std::max(a.x(), b.x()), std::min(a.y(), b.y()),
                      std::max(a.y(), b.y()), a, b, static_cast<std::uint32_t>(l),
                      static_cast<std::uint32_t>(i)});
    }
    close(loop[0]);
  }
  const Vec2 size = all.hi - all.lo;
  const double extent = std::max(size.x(), size.y());
  if (!(extent > 0) || !std::isfinite(extent)) return true;
  // Orientation values below this (mm^2) are treated as zero: near-touching counts as touching.
  const double eps = 1e-12 * extent * extent;
  const double margin = 1e-9 * extent;
  auto orient = [&](const Vec2& o, const Vec2& a, const Vec2& b) {
    const double c = (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    return c > eps ? 1 : (c < -eps ? -1 : 0);
  };
  // Two segments meet: their boxes come within the margin and neither has both ends strictly on
  // one side of the other (neighbours of one loop share their common point: not tested).
  auto meet = [&](const Seg& s, const Seg& t) {
    if (s.ylo > t.yhi + margin || t.ylo > s.yhi + margin || s.xlo > t.xhi + margin ||
        t.xlo > s.xhi + margin)
      return false;
    if (s.loop == t.loop) {
      const std::uint32_t d = s.index > t.index ? s.index - t.index : t.index - s.index;
      if (d == 1 || d + 1 == loops[s.loop]->size()) return false;
    }
    const int d1 = orient(t.a, t.b, s.a), d2 = orient(t.a, t.b, s.b);
    const int d3 = orient(s.a, s.b, t.a), d4 = orient(s.a, s.b, t.b);
    return d1 * d2 <= 0 && d3 * d4 <= 0;
  };
  // Every pair of segments of two chains whose x-ranges meet within the margin: for each
  // segment of p, those of q form one run [j0, j1) that only moves forward.
  // Both runs start by binary search at the first segment that reaches the other chain's box in
  // x (a short chain against a long one would otherwise walk the long one from its start).
  auto first_reaching = [&](const Chain& c, double x) {
    return static_cast<std::uint32_t>(
        std::partition_point(segs.begin() + c.begin, segs.begin() + c.end,
                             [&](const Seg& t) { return x > t.xhi + margin; }) -
        segs.begin());
  };
  auto chains_meet = [&](const Chain& p, const Chain& q) {
    const std::uint32_t k0 = first_reaching(p, q.box.lo.x());
    if (k0 == p.end) return false;
    std::uint32_t j0 = first_reaching(q, segs[k0].xlo), j1 = j0;
    for (std::uint32_t k = k0; k < p.end; ++k) {
      const Seg& s = segs[k];
      if (s.xlo > q.box.hi.x() + margin) break;  // this and later segments lie beyond q
      while (j0 < q.end && s.xlo > segs[j0].xhi + margin) ++j0;
      while (j1 < q.end && !(segs[j1].xlo > s.xhi + margin)) ++j1;
      for (std::uint32_t j = j0; j < j1; ++j)
        if (meet(s, segs[j])) return true;
    }
    return false;
  };
  // Chain pairs whose boxes meet within the margin, by a sweep over the chains sorted by x.
  std::vector<std::uint32_t> order(chains.size());
  for (std::uint32_t c = 0; c < order.size(); ++c) order[c] = c;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return chains[a].box.lo.x() < chains[b].box.lo.x();
  });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Chain& p = chains[order[i]];
    // Within a chain, segment k + 1 is k's neighbour, and the later ones lie beyond it in x.
    for (std::uint32_t k = p.begin; k < p.end; ++k)
      for (std::uint32_t j = k + 2; j < p.end && !(segs[j].xlo > segs[k].xhi + margin); ++j)
        if (meet(segs[k], segs[j])) return true;
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Chain& q = chains[order[j]];
      if (q.box.lo.x() > p.box.hi.x() + margin) break;
      if (p.box.lo.y() > q.box.hi.y() + margin || q.box.lo.y() > p.box.hi.y() + margin) continue;
      if (chains_meet(p, q)) return true;
    }
  }
  return false;
}

// The non-zero-winding region around the origin, without a clipper, when the cluster's loops
// (indices into `loops`) neither cross nor touch: then they nest, the winding number of the
// face just inside a loop is the sum of the orientations (+1 counter-clockwise, -1 clockwise) of
// the loop and the loops around it, and the region around the origin is bounded outside by the
// outermost loop reached through non-zero faces and inside by the loops whose inside has winding
// zero (real holes). This is exactly the union Clipper2 computes for such loops (the clipper
// itself is used whenever loops may cross, touch or the origin is in no material). `around`:
// the loops holding the origin. Returns false when the shortcut does not apply.
bool nested_region(const std::vector<std::vector<Vec2>>& loops, const std::vector<int>& cluster,
                   const std::vector<int>& around, const std::vector<Box2>& boxes,
                   SectionPolygon& out) {
  const std::size_t k = cluster.size();
  std::vector<const std::vector<Vec2>*> ptrs(k);
  std::vector<double> area(k);
  for (std::size_t i = 0; i < k; ++i) {
    ptrs[i] = &loops[cluster[i]];
    area[i] = signed_area(*ptrs[i]);
    if (!(area[i] != 0) || !std::isfinite(area[i])) return false;
  }
  if (loops_may_cross(ptrs)) return false;
  // Parent of each loop: the smallest loop around it (loops that do not cross nest, so one
  // vertex tells whether a loop lies inside another).
  std::vector<int> parent(k, -1);
  for (std::size_t i = 0; i < k; ++i) {
    const Box2& bi = boxes[cluster[i]];
    for (std::size_t j = 0; j < k; ++j) {
      if (j == i || std::abs(area[j]) <= std::abs(area[i])) continue;
      const Box2& bj = boxes[cluster[j]];
      if (!(bj.contains(bi.lo) && bj.contains(bi.hi))) continue;
      if (parent[i] >= 0 && std::abs(area[j]) >= std::abs(area[parent[i]])) continue;
      if (point_in_loop(*ptrs[j], ptrs[i]->front())) parent[i] = static_cast<int>(j);
    }
  }
  std::vector<int> winding(k, 0), order;
  order.reserve(k);
  // Windings from the roots down: a loop's winding needs its parent's.
  std::vector<std::vector<int>> children(k);
  for (std::size_t i = 0; i < k; ++i)
    if (parent[i] < 0)
      order.push_back(static_cast<int>(i));
    else
      children[parent[i]].push_back(static_cast<int>(i));
  for (std::size_t q = 0; q < order.size(); ++q) {
    const int i = order[q];
    winding[i] = (parent[i] >= 0 ? winding[parent[i]] : 0) + (area[i] > 0 ? 1 : -1);
    for (int c : children[i]) order.push_back(c);
  }
  if (order.size() != k) return false;
  // The innermost loop around the origin.
  int inner = -1;
  for (int g : around) {
    const auto it = std::find(cluster.begin(), cluster.end(), g);
    if (it == cluster.end()) return false;
    const int i = static_cast<int>(it - cluster.begin());
    if (inner < 0 || std::abs(area[i]) < std::abs(area[inner])) inner = i;
  }
  if (inner < 0 || winding[inner] == 0) return false;  // in no material or in a hole: clipper
  int top = inner;
  while (parent[top] >= 0 && winding[parent[top]] != 0) top = parent[top];
  out.outer = *ptrs[top];
  out.holes.clear();
  std::vector<int> stack(children[top].begin(), children[top].end());
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    if (winding[c] == 0)
      out.holes.push_back(*ptrs[c]);
    else
      stack.insert(stack.end(), children[c].begin(), children[c].end());
  }
  return true;
}

}  // namespace

std::vector<SectionPolygon> material_regions(const std::vector<std::vector<Vec2>>& loops) {
  const Scaler s(loops);
  PolyTree64 tree;
  union_nonzero(loops, s, tree);
  std::vector<const PolyPath64*> outers;
  collect_outers(tree, outers);
  std::vector<SectionPolygon> out;
  out.reserve(outers.size());
  for (const PolyPath64* o : outers) out.push_back(polygon_of(*o, s));
  return out;
}

SectionGeometry select_region(const PlaneCut& cut, const BoneDomain* domain) {
  SectionGeometry geom;
  geom.flags = cut.flags & (kFlagGapClosed | kFlagNonManifold);
  const Vec2 origin = Vec2::Zero();
  const std::size_t n = cut.loops.size();
  std::vector<Box2> boxes(n);
  std::vector<int> containing;
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i] = box_of(cut.loops[i]);
    if (boxes[i].contains(origin) && point_in_loop(cut.loops[i], origin))
      containing.push_back(static_cast<int>(i));
  }
  geom.containing = static_cast<int>(containing.size());
  // An unclosed polyline around the bone point means the cut here is incomplete: skip it.
  for (const auto& chain : cut.open_chains) {
    if (chain.size() >= 2 && box_of(chain).contains(origin)) {
      geom.flags |= kFlagOpen;
      if (containing.empty()) {
        geom.flags |= kFlagEmpty;
        return geom;
      }
    }
  }
  auto finish = [&](SectionPolygon&& poly) {
    const Box2 box = box_of(poly.outer);
    for (const auto& chain : cut.open_chains)
      if (chain.size() >= 2 && box.overlaps(box_of(chain))) geom.flags |= kFlagOpen;
    geom.polygon = std::move(poly);
    geom.found = true;
    return geom;
  };
  // Fast path: one loop around the point and no other loop near it (its box meets no other
  // box): the union there is that loop, whatever its orientation.
  if (containing.size() == 1) {
    const int i = containing[0];
    bool alone = true;
    for (std::size_t j = 0; j < n && alone; ++j)
      if (static_cast<int>(j) != i && boxes[j].overlaps(boxes[i])) alone = false;
    if (alone) {
      SectionPolygon poly;
      poly.outer = cut.loops[i];
      return finish(std::move(poly));
    }
  }
  if (n == 0) {
    geom.flags |= kFlagEmpty | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
  if (!containing.empty()) {
    // The region around the point comes only from the loops whose boxes reach, directly or
    // through each other, a loop around it: loops apart from that cluster cannot touch it, so
    // only the cluster is merged (the whole plane of a large model has many far loops).
    std::vector<std::uint8_t> in(n, 0);
    std::vector<int> cluster(containing);
    for (int i : containing) in[i] = 1;
    for (std::size_t k = 0; k < cluster.size(); ++k)
      for (std::size_t j = 0; j < n; ++j)
        if (!in[j] && boxes[j].overlaps(boxes[cluster[k]])) {
          in[j] = 1;
          cluster.push_back(static_cast<int>(j));
        }
    SectionPolygon nested;
    if (nested_region(cut.loops, cluster, containing, boxes, nested))
      return finish(std::move(nested));
    if (cluster.size() < n) {
      std::vector<std::vector<Vec2>> near;
      near.reserve(cluster.size());
      for (int i : cluster) near.push_back(cut.loops[i]);
      const Scaler sn(near);
      PolyTree64 tree;
      union_nonzero(near, sn, tree);
      bool hollow = false;
      if (const PolyPath64* outer = locate(tree, sn.to(origin), hollow)) {
        if (hollow) geom.flags |= kFlagHollow;
        return finish(polygon_of(*outer, sn));
      }
    }
  }
  const Scaler s(cut.loops);
  PolyTree64 tree;
  union_nonzero(cut.loops, s, tree);
  bool hollow = false;
  if (const PolyPath64* outer = locate(tree, s.to(origin), hollow)) {
    if (hollow) geom.flags |= kFlagHollow;
    return finish(polygon_of(*outer, s));
  }
  // The bone point lies in no material: the bone is outside the mesh here.
  geom.flags |= kFlagOutside;
  std::vector<const PolyPath64*> outers;
  collect_outers(tree, outers);
  if (outers.empty()) {
    geom.flags |= kFlagEmpty | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
  if (domain != nullptr && domain->segments != nullptr && domain->vertex_bone != nullptr) {
    // The region holding the greatest length of the bone's own cut (its skinning domain).
    std::vector<double> length(outers.size(), 0.0);
    for (const CutSegment& seg : *domain->segments) {
      if (!owned(seg, *domain)) continue;
      const Point64 mid = s.to(0.5 * (seg.point[0] + seg.point[1]));
      for (std::size_t r = 0; r < outers.size(); ++r)
        if (in_region(*outers[r], mid)) {
          length[r] += (seg.point[1] - seg.point[0]).norm();
          break;
        }
    }
    const auto best = std::max_element(length.begin(), length.end());
    if (*best > 0) return finish(polygon_of(*outers[best - length.begin()], s));
    // Nothing of the plane's material can be tied to the bone.
    geom.flags |= kFlagUnreliable | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
  // No domain: the nearest region, unless open geometry is nearer (then skip).
  double best = std::numeric_limits<double>::infinity();
  std::size_t pick = 0;
  std::vector<SectionPolygon> polys;
  for (const PolyPath64* o : outers) polys.push_back(polygon_of(*o, s));
  for (std::size_t r = 0; r < polys.size(); ++r) {
    const double d = squared_distance_to_polyline(polys[r].outer, true, origin);
    if (d < best) {
      best = d;
      pick = r;
    }
  }
  double best_open = std::numeric_limits<double>::infinity();
  for (const auto& chain : cut.open_chains)
    best_open = std::min(best_open, squared_distance_to_polyline(chain, false, origin));
  if (best_open < best) {
    geom.flags |= kFlagEmpty | kFlagOpen;
    return geom;
  }
  return finish(std::move(polys[pick]));
}

namespace {

double minimum_width(const std::vector<Vec2>& pts);

// Clipper2 paths of a section polygon, oriented: the outer boundary counter-clockwise, holes
// clockwise (a SectionPolygon's loops may have either orientation).
Paths64 paths_of(const SectionPolygon& poly, const Scaler& s) {
  Paths64 out;
  auto add = [&](const std::vector<Vec2>& loop, bool outer) {
    if (loop.size() < 3) return;
    Path64 path;
    path.reserve(loop.size());
    for (const Vec2& p : loop) path.push_back(s.to(p));
    if ((signed_area(loop) > 0) != outer) std::reverse(path.begin(), path.end());
    out.push_back(std::move(path));
  };
  add(poly.outer, true);
  for (const auto& hole : poly.holes) add(hole, false);
  return out;
}

// Offset by delta (Clipper2 units), round joins with arcs of about 1 % of |delta| in error.
Paths64 offset(const Paths64& paths, double delta) {
  return Clipper2Lib::InflatePaths(paths, delta, Clipper2Lib::JoinType::Round,
                                   Clipper2Lib::EndType::Polygon, 2.0, 0.01 * std::abs(delta));
}

// Adds a closed path's shoelace sums (Clipper2 units): a += 2 x signed area, cx and cy += 6 x
// area x centroid coordinate (centroid = (cx, cy) / (3 a) over the paths summed).
void add_centroid_sums(const Path64& path, double& a, double& cx, double& cy) {
  for (std::size_t k = 0, n = path.size(); k < n; ++k) {
    const double x0 = path[k].x, y0 = path[k].y;
    const double x1 = path[k + 1 == n ? 0 : k + 1].x, y1 = path[k + 1 == n ? 0 : k + 1].y;
    const double c = x0 * y1 - x1 * y0;
    a += c;
    cx += (x0 + x1) * c;
    cy += (y0 + y1) * c;
  }
}

// True when the region (an outer path and its holes, Clipper2 units) holds the disc of radius
// `radius` around q: q inside the outer path, in no hole, and no edge nearer than `radius`.
bool holds_disc(const Paths64& region, const Vec2& q, double radius) {
  const Point64 qi(static_cast<std::int64_t>(std::llround(q.x())),
                   static_cast<std::int64_t>(std::llround(q.y())));
  if (Clipper2Lib::PointInPolygon(qi, region.front()) != PointInPolygonResult::IsInside)
    return false;
  for (std::size_t h = 1; h < region.size(); ++h)
    if (Clipper2Lib::PointInPolygon(qi, region[h]) != PointInPolygonResult::IsOutside) return false;
  const double r2 = radius * radius;
  for (const Path64& path : region) {
    for (std::size_t k = 0, m = path.size(); k < m; ++k) {
      const Vec2 p0(static_cast<double>(path[k].x), static_cast<double>(path[k].y));
      const Vec2 p1(static_cast<double>(path[(k + 1) % m].x),
                    static_cast<double>(path[(k + 1) % m].y));
      const Vec2 d = p1 - p0;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0 ? std::clamp((q - p0).dot(d) / len2, 0.0, 1.0) : 0.0;
      if ((q - (p0 + t * d)).squaredNorm() <= r2) return false;
    }
  }
  return true;
}

// True when the region (an outer path and its holes, Clipper2 units) holds the disc of radius
// `radius` around its outer boundary's centroid: one cheap witness that the region is wider
// than 2 * radius (its erosion by less than radius is not empty). False says nothing.
bool holds_centroid_disc(const Paths64& region, double radius) {
  if (region.front().size() < 3) return false;
  double a = 0.0, cx = 0.0, cy = 0.0;
  add_centroid_sums(region.front(), a, cx, cy);
  if (a == 0.0) return false;
  return holds_disc(region, Vec2(cx / (3.0 * a), cy / (3.0 * a)), radius);
}

// What the edge a-b adds to the winding number around q (q on no edge): +1 crossing the
// horizontal line through q upwards with q on its left, -1 downwards with q on its right (exact).
int winding_step(const Point64& a, const Point64& b, const Point64& q) {
  if ((a.y <= q.y) == (b.y <= q.y)) return 0;
  const int c = Clipper2Lib::CrossProductSign(a, b, q);
  if (a.y <= q.y) return c > 0 ? 1 : 0;
  return c < 0 ? -1 : 0;
}

// Winding number of a closed path around q (q on none of its edges), exact.
int winding_number(const Path64& path, const Point64& q) {
  int w = 0;
  for (std::size_t k = 0, n = path.size(); k < n; ++k)
    w += winding_step(path[k], path[k + 1 == n ? 0 : k + 1], q);
  return w;
}

Path64 rect_path(const Clipper2Lib::Rect64& r, bool positive) {
  Path64 path{{r.left, r.top}, {r.right, r.top}, {r.right, r.bottom}, {r.left, r.bottom}};
  if (!positive) std::reverse(path.begin(), path.end());
  return path;
}

// The closed paths with everything outside the rectangle r replaced by a path along r's boundary
// that winds around r the same way: an edge that meets r (its box does) is kept with its own
// ends; a vertex both of whose edges miss r is clamped onto r's boundary (runs along one side
// merged); a loop that misses r altogether becomes r's outline, as often as it winds around r.
// An edge that misses r lies in one open half-plane beside r, and so does its clamped image, and
// every edge in between: points inside r keep their winding numbers. The region inside r, its
// boundary there and every intersection Clipper2 computes there (from the same edge ends) are
// those of the paths themselves; the cost of what follows is that of the part near r.
Paths64 clamp_to_rect(const Paths64& paths, const Clipper2Lib::Rect64& r) {
  Paths64 out;
  out.reserve(paths.size());
  auto meets = [&](const Point64& a, const Point64& b) {
    return std::max(a.x, b.x) >= r.left && std::min(a.x, b.x) <= r.right &&
           std::max(a.y, b.y) >= r.top && std::min(a.y, b.y) <= r.bottom;
  };
  auto on_one_side = [&](const Point64& a, const Point64& b, const Point64& c) {
    return (a.x == b.x && b.x == c.x && (a.x == r.left || a.x == r.right)) ||
           (a.y == b.y && b.y == c.y && (a.y == r.top || a.y == r.bottom));
  };
  std::vector<char> moved;
  for (const Path64& path : paths) {
    const std::size_t n = path.size();
    std::size_t first = n;
    for (std::size_t k = 0; k < n && first == n; ++k)
      if (meets(path[k], path[k + 1 == n ? 0 : k + 1])) first = k;
    if (first == n) {
      const int w = n < 3 ? 0 : winding_number(path, r.MidPoint());
      for (int k = 0; k < std::abs(w); ++k) out.push_back(rect_path(r, w > 0));
      continue;
    }
    Path64 loop;
    loop.reserve(n);
    moved.clear();
    bool before = meets(path[(first + n - 1) % n], path[first]);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t k = (first + j) % n;
      const bool after = meets(path[k], path[(k + 1) % n]);
      if (before || after) {
        loop.push_back(path[k]);
        moved.push_back(0);
      } else {
        const Point64 c(std::clamp(path[k].x, r.left, r.right),
                        std::clamp(path[k].y, r.top, r.bottom));
        if (!(moved.back() && loop.back() == c)) {
          while (loop.size() >= 2 && moved.back() && moved[moved.size() - 2] &&
                 on_one_side(loop[loop.size() - 2], loop.back(), c)) {
            loop.pop_back();
            moved.pop_back();
          }
          loop.push_back(c);
          moved.push_back(1);
        }
      }
      before = after;
    }
    out.push_back(std::move(loop));
  }
  return out;
}

// Clipper2 rectangle grown by d on every side.
Clipper2Lib::Rect64 grown(const Clipper2Lib::Rect64& r, std::int64_t d) {
  return {r.left - d, r.top - d, r.right + d, r.bottom + d};
}

// The Chebyshev distance max(|u|, |v|) from (0, 0) to the segment a-b: the largest t for which the
// square |u|, |v| <= t misses it. Convex and piecewise linear along the segment, so its least value
// is at an end, a kink (u = 0 or v = 0) or where |u| = |v|.
double chebyshev_to_segment(double ax, double ay, double bx, double by) {
  double best =
      std::min(std::max(std::abs(ax), std::abs(ay)), std::max(std::abs(bx), std::abs(by)));
  const double dx = bx - ax, dy = by - ay;
  auto at = [&](double t) {
    if (t > 0 && t < 1)
      best = std::min(best, std::max(std::abs(ax + t * dx), std::abs(ay + t * dy)));
  };
  if (dx != 0) at(-ax / dx);
  if (dy != 0) at(-ay / dy);
  if (dx != dy) at((ay - ax) / (dx - dy));
  if (dx != -dy) at(-(ax + ay) / (dx + dy));
  return best;
}

// Sign of (a - o) x (b - o), exact (Clipper2's CrossProductSign).
int cross(const Point64& o, const Point64& a, const Point64& b) {
  return Clipper2Lib::CrossProductSign(o, a, b);
}

// True when the segment a-b meets the closed rectangle r (exact).
bool segment_meets_rect(const Point64& a, const Point64& b, const Clipper2Lib::Rect64& r) {
  if (std::max(a.x, b.x) < r.left || std::min(a.x, b.x) > r.right || std::max(a.y, b.y) < r.top ||
      std::min(a.y, b.y) > r.bottom)
    return false;
  const Point64 corners[4] = {
      {r.left, r.top}, {r.right, r.top}, {r.right, r.bottom}, {r.left, r.bottom}};
  bool below = false, above = false;
  for (const Point64& c : corners) {
    const int side = cross(a, b, c);
    below = below || side <= 0;
    above = above || side >= 0;
  }
  return below && above;
}

// True when the segments a-b and c-d meet (touching counts; exact).
bool segments_meet(const Point64& a, const Point64& b, const Point64& c, const Point64& d) {
  if (std::max(a.x, b.x) < std::min(c.x, d.x) || std::max(c.x, d.x) < std::min(a.x, b.x) ||
      std::max(a.y, b.y) < std::min(c.y, d.y) || std::max(c.y, d.y) < std::min(a.y, b.y))
    return false;
  const int d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  return !((d1 > 0 && d2 > 0) || (d1 < 0 && d2 < 0) || (d3 > 0 && d4 > 0) || (d3 < 0 && d4 < 0));
}

// A rectangle (axis-parallel, Clipper2 units) inside every one of the non-zero regions, 2 units
// clear of every edge, and joined to `origin` inside them all (it holds the origin, or a segment
// from its centre to the origin, or to a corner of the origin's own such rectangle, crosses no
// edge): a region that the part the regions have in common around the origin holds. Centred on
// the origin, the first region's centroid or the common box's centre, with the common box's
// proportions, as large as the edges allow (one pass over them), then checked exactly. False when
// none is found.
bool rect_inside(const std::vector<const Paths64*>& regions, const Point64& origin,
                 Clipper2Lib::Rect64& out) {
  Clipper2Lib::Rect64 common = Clipper2Lib::GetBounds(*regions.front());
  for (const Paths64* region : regions) {
    const Clipper2Lib::Rect64 r = Clipper2Lib::GetBounds(*region);
    common =
        Clipper2Lib::Rect64(std::max(common.left, r.left), std::max(common.top, r.top),
                            std::min(common.right, r.right), std::min(common.bottom, r.bottom));
  }
  const double hx = 0.5 * static_cast<double>(common.right - common.left);
  const double hy = 0.5 * static_cast<double>(common.bottom - common.top);
  if (!(hx > 8 && hy > 8)) return false;
  constexpr int kCentres = 3;
  Point64 centres[kCentres] = {origin, origin, common.MidPoint()};
  {
    double area = 0.0, cx = 0.0, cy = 0.0;
    for (const Path64& path : *regions.front()) add_centroid_sums(path, area, cx, cy);
    if (area != 0.0)
      centres[1] = Point64(static_cast<std::int64_t>(std::llround(cx / (3.0 * area))),
                           static_cast<std::int64_t>(std::llround(cy / (3.0 * area))));
  }
  // t[c]: the largest scale of the box (hx, hy) around centre c that no edge enters; an edge's
  // box gives a lower bound first (most edges are far).
  double t[kCentres];
  std::fill(t, t + kCentres, std::numeric_limits<double>::infinity());
  const double ix = 1.0 / hx, iy = 1.0 / hy;
  double cx[kCentres], cy[kCentres];
  for (int c = 0; c < kCentres; ++c) {
    cx[c] = static_cast<double>(centres[c].x);
    cy[c] = static_cast<double>(centres[c].y);
  }
  for (const Paths64* region : regions) {
    for (const Path64& path : *region) {
      for (std::size_t k = 0, n = path.size(); k < n; ++k) {
        const Point64& p = path[k];
        const Point64& q = path[k + 1 == n ? 0 : k + 1];
        const double px = static_cast<double>(p.x), py = static_cast<double>(p.y);
        const double qx = static_cast<double>(q.x), qy = static_cast<double>(q.y);
        const double x0 = std::min(px, qx), x1 = std::max(px, qx);
        const double y0 = std::min(py, qy), y1 = std::max(py, qy);
        for (int c = 0; c < kCentres; ++c) {
          const double gx = std::max({x0 - cx[c], cx[c] - x1, 0.0}) * ix;
          const double gy = std::max({y0 - cy[c], cy[c] - y1, 0.0}) * iy;
          if (std::max(gx, gy) >= t[c]) continue;
          t[c] = std::min(t[c], chebyshev_to_segment((px - cx[c]) * ix, (py - cy[c]) * iy,
                                                     (qx - cx[c]) * ix, (qy - cy[c]) * iy));
        }
      }
    }
  }
  // Checked exactly in one pass: the centre c inside every region, no edge meeting the rectangle
  // grown by 2, and (unless `joined`) none meeting the segment from c to `to`.
  auto inside = [&](const Clipper2Lib::Rect64& r, const Point64& c, bool joined,
                    const Point64& to) {
    const Clipper2Lib::Rect64 clear = grown(r, 2);
    for (const Paths64* region : regions) {
      int w = 0;
      for (const Path64& path : *region) {
        for (std::size_t k = 0, n = path.size(); k < n; ++k) {
          const Point64& p = path[k];
          const Point64& q = path[k + 1 == n ? 0 : k + 1];
          if (segment_meets_rect(p, q, clear) || (!joined && segments_meet(p, q, c, to)))
            return false;
          w += winding_step(p, q, c);
        }
      }
      if (w == 0) return false;
    }
    return true;
  };
  auto rect_at = [&](int c, Clipper2Lib::Rect64& r) {
    const double f = 0.999 * t[c];
    const auto dx = static_cast<std::int64_t>(f * hx) - 4;
    const auto dy = static_cast<std::int64_t>(f * hy) - 4;
    r = Clipper2Lib::Rect64(centres[c].x - dx, centres[c].y - dy, centres[c].x + dx,
                            centres[c].y + dy);
    return dx > 0 && dy > 0;
  };
  int order[kCentres] = {0, 1, 2};
  std::sort(order, order + kCentres, [&](int i, int j) { return t[i] > t[j]; });
  int r0_state = -1;  // the origin's own rectangle: unknown, absent, found
  Clipper2Lib::Rect64 r0;
  auto has_r0 = [&]() {
    if (r0_state < 0) r0_state = rect_at(0, r0) && inside(r0, origin, true, origin) ? 1 : 0;
    return r0_state == 1;
  };
  for (const int pick : order) {
    Clipper2Lib::Rect64 r;
    if (!rect_at(pick, r)) break;
    if (pick == 0) {
      if (!has_r0()) continue;
      out = r0;
      return true;
    }
    const Point64 c = centres[pick];
    // Joined to the origin directly, or else through the origin's rectangle (a segment to one of
    // its corners).
    const bool holds = r.Contains(origin);
    if (inside(r, c, holds, origin)) {
      out = r;
      return true;
    }
    if (holds || !has_r0()) continue;
    const Point64 corners[4] = {
        {r0.left, r0.top}, {r0.right, r0.top}, {r0.right, r0.bottom}, {r0.left, r0.bottom}};
    bool ok = r.Intersects(r0) && inside(r, c, true, c);
    for (int k = 0; !ok && k < 4; ++k) ok = inside(r, c, false, corners[k]);
    if (ok) {
      out = r;
      return true;
    }
  }
  return false;
}

// True when no edge of the regions meets the rectangle r grown by 2 (exact).
bool rect_clear(const std::vector<const Paths64*>& regions, const Clipper2Lib::Rect64& r) {
  const Clipper2Lib::Rect64 clear = grown(r, 2);
  for (const Paths64* region : regions)
    for (const Path64& path : *region)
      for (std::size_t k = 0, n = path.size(); k < n; ++k)
        if (segment_meets_rect(path[k], path[k + 1 == n ? 0 : k + 1], clear)) return false;
  return true;
}

// A region around a rectangle r found by rect_inside: r and, on each side, an arm (a rectangle
// standing on that side, on all of it or on its middle 60 %: a neighbour's corner near r's
// often blocks the whole side) as deep as the edges allow, found in one pass over them and then
// checked exactly (an arm whose check fails is left out). No edge comes within 2 units of r or
// an arm, and each arm touches r along a side: like r, the region lies inside every region and
// is joined to the origin. The outline goes round r, out along each arm and back. A body cut
// whose bone point sits near its rim gets a region many times larger than r.
std::vector<Point64> rect_with_arms(const std::vector<const Paths64*>& regions,
                                    const Clipper2Lib::Rect64& r) {
  // Per side (left, top, right, bottom) and band (whole side, middle 60 %): the room ahead.
  constexpr int kBands = 2;
  struct Arm {
    double lo, hi, front, room;  // band across the side, the side's line, room (all with sign)
  };
  Arm arms[4][kBands];
  for (int side = 0; side < 4; ++side) {
    const bool vertical = side % 2 == 0;  // left and right sides: the arm grows along x
    const double sign = side < 2 ? -1.0 : 1.0;
    const double a0 = static_cast<double>(vertical ? r.top : r.left);
    const double a1 = static_cast<double>(vertical ? r.bottom : r.right);
    const double front = sign * static_cast<double>(side == 0   ? r.left
                                                    : side == 1 ? r.top
                                                    : side == 2 ? r.right
                                                                : r.bottom);
    for (int band = 0; band < kBands; ++band) {
      const double cut = band == 0 ? 0.0 : std::floor(0.2 * (a1 - a0));
      arms[side][band] = {a0 + cut - 2, a1 - cut + 2, front + 2,
                          std::numeric_limits<double>::infinity()};
    }
  }
  for (const Paths64* region : regions) {
    for (const Path64& path : *region) {
      for (std::size_t k = 0, n = path.size(); k < n; ++k) {
        const Point64& p = path[k];
        const Point64& q = path[k + 1 == n ? 0 : k + 1];
        // Most edges are beside neither band of sides (r's x and y ranges, +2).
        if ((std::max(p.x, q.x) < r.left - 2 || std::min(p.x, q.x) > r.right + 2) &&
            (std::max(p.y, q.y) < r.top - 2 || std::min(p.y, q.y) > r.bottom + 2))
          continue;
        for (int side = 0; side < 4; ++side) {
          const bool vertical = side % 2 == 0;
          const double sign = side < 2 ? -1.0 : 1.0;
          const double pa = sign * static_cast<double>(vertical ? p.x : p.y);
          const double qa = sign * static_cast<double>(vertical ? q.x : q.y);
          const double pc = static_cast<double>(vertical ? p.y : p.x);
          const double qc = static_cast<double>(vertical ? q.y : q.x);
          for (Arm& arm : arms[side]) {
            if (std::max(pa, qa) < arm.front || std::max(pc, qc) < arm.lo ||
                std::min(pc, qc) > arm.hi)
              continue;
            // The edge's part inside the band: its extreme `along` values are at its ends there
            // or where it crosses the band's lines. A part behind the side does not count.
            double near = std::numeric_limits<double>::infinity(), far = -near;
            auto add = [&](double a) {
              near = std::min(near, a);
              far = std::max(far, a);
            };
            if (pc >= arm.lo && pc <= arm.hi) add(pa);
            if (qc >= arm.lo && qc <= arm.hi) add(qa);
            for (const double c : {arm.lo, arm.hi})
              if ((pc - c) * (qc - c) < 0) add(pa + (c - pc) / (qc - pc) * (qa - pa));
            if (far >= arm.front) arm.room = std::min(arm.room, near - arm.front);
          }
        }
      }
    }
  }
  // Per side the larger arm that passes the exact check; the outline (Clipper2's y axis points
  // down: left side upwards, top side rightwards, ...).
  std::vector<Point64> out;
  const Point64 corners[4] = {
      {r.left, r.bottom}, {r.left, r.top}, {r.right, r.top}, {r.right, r.bottom}};
  for (int side = 0; side < 4; ++side) {
    out.push_back(corners[side]);
    Clipper2Lib::Rect64 best;
    double best_area = 0.0;
    for (const Arm& arm : arms[side]) {
      if (!(arm.room > 8)) continue;
      const auto depth = static_cast<std::int64_t>(std::min(arm.room * 0.999, 4e18)) - 4;
      const auto lo = static_cast<std::int64_t>(arm.lo) + 2;
      const auto hi = static_cast<std::int64_t>(arm.hi) - 2;
      const double area = static_cast<double>(depth) * static_cast<double>(hi - lo);
      if (area <= best_area) continue;
      Clipper2Lib::Rect64 a = side == 0   ? Clipper2Lib::Rect64(r.left - depth, lo, r.left, hi)
                              : side == 1 ? Clipper2Lib::Rect64(lo, r.top - depth, hi, r.top)
                              : side == 2 ? Clipper2Lib::Rect64(r.right, lo, r.right + depth, hi)
                                          : Clipper2Lib::Rect64(lo, r.bottom, hi, r.bottom + depth);
      if (!rect_clear(regions, a)) continue;
      best = a;
      best_area = area;
    }
    if (best_area == 0.0) continue;
    // Out along the arm and back, in the direction the outline runs along this side.
    if (side == 0) {
      out.insert(out.end(), {{best.right, best.bottom},
                             {best.left, best.bottom},
                             {best.left, best.top},
                             {best.right, best.top}});
    } else if (side == 1) {
      out.insert(out.end(), {{best.left, best.bottom},
                             {best.left, best.top},
                             {best.right, best.top},
                             {best.right, best.bottom}});
    } else if (side == 2) {
      out.insert(out.end(), {{best.left, best.top},
                             {best.right, best.top},
                             {best.right, best.bottom},
                             {best.left, best.bottom}});
    } else {
      out.insert(out.end(), {{best.right, best.top},
                             {best.right, best.bottom},
                             {best.left, best.bottom},
                             {best.left, best.top}});
    }
  }
  return out;
}

// Clipper2's Intersect(a, b) (non-zero), with the operand whose box is the larger clamped to the
// other's box first (clamp_to_rect: nothing inside changes, and the intersection lies inside).
Paths64 intersect_near(const Paths64& a, const Paths64& b) {
  using Clipper2Lib::FillRule;
  if (a.empty() || b.empty()) return Clipper2Lib::Intersect(a, b, FillRule::NonZero);
  const Clipper2Lib::Rect64 ra = Clipper2Lib::GetBounds(a), rb = Clipper2Lib::GetBounds(b);
  auto size = [](const Clipper2Lib::Rect64& r) {
    return static_cast<double>(r.right - r.left) * static_cast<double>(r.bottom - r.top);
  };
  if (size(ra) > size(rb))
    return Clipper2Lib::Intersect(clamp_to_rect(a, grown(rb, 2)), b, FillRule::NonZero);
  return Clipper2Lib::Intersect(a, clamp_to_rect(b, grown(ra, 2)), FillRule::NonZero);
}

// The pieces of subject minus clip (non-zero), each its outer path followed by its holes.
std::vector<Paths64> difference_pieces(const Paths64& subject, const Paths64& clip) {
  PolyTree64 tree;
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(subject);
  clipper.AddClip(clip);
  clipper.Execute(Clipper2Lib::ClipType::Difference, Clipper2Lib::FillRule::NonZero, tree);
  std::vector<const PolyPath64*> outers;
  collect_outers(tree, outers);
  std::vector<Paths64> pieces;
  pieces.reserve(outers.size());
  for (const PolyPath64* outer : outers) {
    Paths64 paths{outer->Polygon()};
    for (const auto& hole : *outer) paths.push_back(hole->Polygon());
    pieces.push_back(std::move(paths));
  }
  return pieces;
}

}  // namespace

SectionGeometry junction_core(
    const SectionPolygon& section, const std::vector<const SectionPolygon*>& neighbours,
    double margin_mm, double opening_mm,
    const std::function<bool(const SectionPolygon& inner)>& worth,
    const std::function<bool(const Vec2& lo_mm, const Vec2& hi_mm)>& may_fail) {
  using Clipper2Lib::FillRule;
  using Clipper2Lib::Rect64;
  SectionGeometry geom;
  std::vector<std::vector<Vec2>> all{section.outer};
  all.insert(all.end(), section.holes.begin(), section.holes.end());
  for (const SectionPolygon* n : neighbours) {
    all.push_back(n->outer);
    all.insert(all.end(), n->holes.begin(), n->holes.end());
  }
  const Scaler s(all);
  const Paths64 whole = paths_of(section, s);
  // Only the neighbours' material near the section matters: clipped to its box (+ margin).
  const Rect64 box = Clipper2Lib::GetBounds(whole);
  const std::int64_t pad = static_cast<std::int64_t>(2.0 * margin_mm * s.scale) + 1;
  const Rect64 near(box.left - pad, box.top - pad, box.right + pad, box.bottom + pad);
  // What both neighbours cover, widened by the margin. Their facets are first thinned to within a
  // quarter of the margin (Clipper2 SimplifyPaths: a few dozen vertices instead of hundreds), and
  // the common part is widened once (the offset's cost is in the self-crossings of every facet's
  // raw offset): the widening still exceeds 3/4 of the margin everywhere.
  std::vector<Paths64> regions(neighbours.size());
  for (std::size_t k = 0; k < neighbours.size(); ++k) {
    // A neighbour given twice (a neck that is also a neighbour plane) is clipped and thinned once.
    const auto same = std::find(neighbours.begin(), neighbours.begin() + k, neighbours[k]);
    if (same != neighbours.begin() + k) {
      regions[k] = regions[same - neighbours.begin()];
      continue;
    }
    regions[k] = Clipper2Lib::RectClip(near, paths_of(*neighbours[k], s));
    if (margin_mm > 0) regions[k] = detail::simplify_closed(regions[k], 0.25 * margin_mm * s.scale);
  }
  const Point64 origin = s.to(Vec2::Zero());
  // A region the core is sure to hold, first a rectangle inside the section and every (thinned)
  // neighbour, joined to the origin (one pass over the edges, no intersection): on a section that
  // is nearly all core it already fails the caller's test.
  // Neither is asked when `may_fail` says no region inside their common box can fail the test.
  bool ask = worth && !regions.empty();
  if (ask && may_fail) {
    Rect64 b = Clipper2Lib::GetBounds(whole);
    for (const Paths64& region : regions) {
      const Rect64 r = Clipper2Lib::GetBounds(region);
      b = Rect64(std::max(b.left, r.left), std::max(b.top, r.top), std::min(b.right, r.right),
                 std::min(b.bottom, r.bottom));
    }
    b = grown(b, 2);  // Clipper2's intersections round to the nearest unit
    ask = b.right > b.left && b.bottom > b.top &&
          may_fail(s.from(Point64(b.left, b.top)), s.from(Point64(b.right, b.bottom)));
  }
  if (ask) {
    std::vector<const Paths64*> all_regions{&whole};
    // (a neighbour given twice once: its edges would only be checked twice)
    for (std::size_t k = 0; k < regions.size(); ++k)
      if (std::find(neighbours.begin(), neighbours.begin() + k, neighbours[k]) ==
          neighbours.begin() + k)
        all_regions.push_back(&regions[k]);
    Rect64 r;
    if (rect_inside(all_regions, origin, r)) {
      SectionPolygon rect;
      rect.outer = {s.from(Point64(r.left, r.top)), s.from(Point64(r.right, r.top)),
                    s.from(Point64(r.right, r.bottom)), s.from(Point64(r.left, r.bottom))};
      if (!worth(rect)) return geom;
      // Too small to tell: the rectangle with arms as deep as the edges allow.
      const std::vector<Point64> armed = rect_with_arms(all_regions, r);
      if (armed.size() > 4) {
        rect.outer.clear();
        for (const Point64& q : armed) rect.outer.push_back(s.from(q));
        if (!worth(rect)) return geom;
      }
    }
  }
  Paths64 covered;
  for (std::size_t k = 0; k < regions.size(); ++k)
    covered = k == 0 ? std::move(regions[k]) : intersect_near(covered, regions[k]);
  const double opening = opening_mm * s.scale;
  // The core lies inside the common part's box grown by the margin (`inside`); the section is
  // worked on near it only: inside `band`, that box (and the origin) grown by 2.4 x the opening
  // (room for the discs that tell a trimmed stub, below), with everything farther out replaced by
  // a path along the rectangle (clamp_to_rect: nothing inside changes).
  Rect64 inside, band;
  Paths64 part = whole;
  bool local = !covered.empty();
  if (local) {
    inside = grown(Clipper2Lib::GetBounds(covered),
                   static_cast<std::int64_t>(std::ceil(1.02 * margin_mm * s.scale)) + 2);
    band = inside;
    band.left = std::min(band.left, origin.x);
    band.right = std::max(band.right, origin.x);
    band.top = std::min(band.top, origin.y);
    band.bottom = std::max(band.bottom, origin.y);
    band = grown(band, opening > 0 ? static_cast<std::int64_t>(std::ceil(2.4 * opening)) + 8 : 2);
    part = clamp_to_rect(whole, grown(band, 2));
  }
  // What the core is sure to hold (the section and the common part before widening, around the
  // origin): a caller may stop here when that already fails its test.
  if (ask && !covered.empty()) {
    PolyTree64 inner;
    Clipper2Lib::Clipper64 clipper;
    clipper.AddSubject(part);
    clipper.AddClip(covered);
    clipper.Execute(Clipper2Lib::ClipType::Intersection, FillRule::NonZero, inner);
    bool hollow = false;
    const PolyPath64* outer = locate(inner, origin, hollow);
    if (outer != nullptr && !hollow && !worth(polygon_of(*outer, s))) return geom;
  }
  if (margin_mm > 0) covered = offset(covered, margin_mm * s.scale);
  if (local && !covered.empty()) {
    const Rect64 b = Clipper2Lib::GetBounds(covered);
    local = b.left > inside.left && b.right < inside.right && b.top > inside.top &&
            b.bottom < inside.bottom;
  }
  if (!local) part = whole;
  Paths64 core = Clipper2Lib::Intersect(part, covered, FillRule::NonZero);
  // The trimmed-off material, piece by piece: a piece is a stub (left out whole) only when it is
  // wider than 2 * opening somewhere (its erosion by `opening` is not empty); a thin piece (the
  // rim of a taper, a tilted bone's crescent) goes back into the core.
  auto thin = [&](const Paths64& paths) {
    // Cheap answers first: a piece holding a disc of radius `opening` has at least the disc's
    // area and is at least 2 * opening wide in every direction.
    bool thin = opening > 0 && std::abs(Clipper2Lib::Area(paths)) < M_PI * opening * opening;
    // Otherwise its erosion, on its outline thinned to within 5 % of `opening` (a stub's
    // outline has hundreds of facets; the answer moves by no more than that) -- unless a disc
    // of 1.1 x opening around its centroid fits in it (a stub usually: then it is no narrower
    // than 2.2 x opening anywhere across that disc, and the eroded, thinned outline keeps the
    // centroid, 1.1 - 0.05 - 0.01 (the arcs' error) x opening clear of it).
    if (!thin && opening > 0 && !holds_centroid_disc(paths, 1.1 * opening))
      thin = minimum_width(s.from(paths.front())) * s.scale < 2.0 * opening ||
             offset(detail::simplify_closed(paths, 0.05 * opening), -opening).empty();
    return thin;
  };
  Paths64 merged = core;
  // With no opening every trimmed piece is a stub: none goes back.
  bool whole_pieces = !local;
  if (local && opening > 0) {
    // The trimmed material inside `band`: a piece clear of the band's edge is a whole piece of
    // what the section loses; a piece reaching the edge is part of one, which is a stub when the
    // part already holds a disc of 1.1 x opening (see above: the thinned erosion keeps its
    // centre). Else the pieces are taken from the whole section.
    Paths64 clip = core;
    Rect64 all_box = Clipper2Lib::GetBounds(part);
    all_box.left = std::min(all_box.left, band.left);
    all_box.right = std::max(all_box.right, band.right);
    all_box.top = std::min(all_box.top, band.top);
    all_box.bottom = std::max(all_box.bottom, band.bottom);
    clip.push_back(rect_path(grown(all_box, 4), true));
    clip.push_back(rect_path(band, false));
    const std::vector<Paths64> pieces = difference_pieces(part, clip);
    const std::int64_t half = (band.right - band.left) / 2, mid_x = band.left + half;
    const std::int64_t mid_y = band.top + (band.bottom - band.top) / 2;
    const double inset = std::ceil(1.2 * opening) + 4.0, disc = 1.1 * opening + 4.0;
    const Vec2 lo(static_cast<double>(band.left) + inset, static_cast<double>(band.top) + inset);
    const Vec2 hi(static_cast<double>(band.right) - inset,
                  static_cast<double>(band.bottom) - inset);
    const Vec2 probes[8] = {{lo.x(), lo.y()},
                            {hi.x(), lo.y()},
                            {hi.x(), hi.y()},
                            {lo.x(), hi.y()},
                            {static_cast<double>(mid_x), lo.y()},
                            {hi.x(), static_cast<double>(mid_y)},
                            {static_cast<double>(mid_x), hi.y()},
                            {lo.x(), static_cast<double>(mid_y)}};
    for (const Paths64& paths : pieces) {
      const Rect64 b = Clipper2Lib::GetBounds(paths.front());
      const bool edge = b.left <= band.left + 2 || b.right >= band.right - 2 ||
                        b.top <= band.top + 2 || b.bottom >= band.bottom - 2;
      if (!edge) {
        if (thin(paths)) merged.insert(merged.end(), paths.begin(), paths.end());
        continue;
      }
      bool stub = holds_centroid_disc(paths, disc);
      for (int k = 0; !stub && k < 8; ++k) stub = holds_disc(paths, probes[k], disc);
      if (!stub) {
        whole_pieces = true;
        break;
      }
    }
    if (whole_pieces) merged = core;
  }
  if (whole_pieces) {
    for (const Paths64& paths : difference_pieces(whole, core))
      if (thin(paths)) merged.insert(merged.end(), paths.begin(), paths.end());
  }
  // The core and the thin pieces merged (one union, straight into the tree).
  PolyTree64 tree;
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(merged);
  clipper.Execute(Clipper2Lib::ClipType::Union, FillRule::NonZero, tree);
  bool hollow = false;
  if (const PolyPath64* outer = locate(tree, origin, hollow)) {
    if (hollow) geom.flags |= kFlagHollow;
    geom.polygon = polygon_of(*outer, s);
    geom.found = true;
  }
  return geom;
}

namespace {

double cross2(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Counter-clockwise convex hull of any point set (Andrew's monotone chain, O(n log n)).
std::vector<Vec2> hull_sorted(std::vector<Vec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Vec2> hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

// Counter-clockwise convex hull of a simple closed polygon in O(n) (Melkman's algorithm). For a
// polygon that is not simple the result may miss points: the caller checks.
std::vector<Vec2> hull_of_simple(const std::vector<Vec2>& loop) {
  const std::size_t n = loop.size();
  std::size_t i2 = 2;
  while (i2 < n && cross2(loop[0], loop[1], loop[i2]) == 0) ++i2;
  if (i2 == n) return {};
  std::vector<Vec2> d(2 * n + 3);
  std::size_t bot = n, top = n + 3;  // d[bot] == d[top - 1]
  const bool ccw = cross2(loop[0], loop[1], loop[i2]) > 0;
  d[bot] = loop[i2];
  d[bot + 1] = ccw ? loop[0] : loop[1];
  d[bot + 2] = ccw ? loop[1] : loop[0];
  d[bot + 3] = loop[i2];
  top = bot + 3;  // index of the last element
  for (std::size_t i = i2 + 1; i < n; ++i) {
    const Vec2& p = loop[i];
    // Turns at both ends of the deque (the pops and the push at the top never touch d[bot],
    // d[bot + 1]: at least one point stays between them and the top).
    double at_bot = cross2(d[bot], d[bot + 1], p);
    double at_top = cross2(d[top - 1], d[top], p);
    if (at_bot > 0 && at_top > 0) continue;
    while (top - bot >= 2 && at_top <= 0) {
      --top;
      if (top - bot >= 2) at_top = cross2(d[top - 1], d[top], p);
    }
    d[++top] = p;
    while (top - bot >= 2 && at_bot <= 0) {
      ++bot;
      if (top - bot >= 2) at_bot = cross2(d[bot], d[bot + 1], p);
    }
    d[--bot] = p;
  }
  return std::vector<Vec2>(d.begin() + bot, d.begin() + top);
}

// Rotating calipers over a counter-clockwise hull: the smallest height of the hull over one of
// its edges (the antipodal point only moves forward; one square root per edge). Sets the edge.
double hull_width(const std::vector<Vec2>& hull, Vec2& edge_a, Vec2& edge_b) {
  const std::size_t h = hull.size();
  double best = std::numeric_limits<double>::infinity();
  if (h < 3) return best;
  std::size_t far = 1;
  for (std::size_t e = 0; e < h; ++e) {
    const Vec2& a = hull[e];
    const Vec2& b = hull[e + 1 == h ? 0 : e + 1];
    if (far == e) far = e + 1 == h ? 0 : e + 1;
    // The antipodal vertex only moves forward while the height over (a, b) does not drop.
    double height = cross2(a, b, hull[far]);
    for (std::size_t steps = 0; steps < h; ++steps) {
      const std::size_t next = far + 1 == h ? 0 : far + 1;
      const double ahead = cross2(a, b, hull[next]);
      if (!(ahead >= height)) break;
      far = next;
      height = ahead;
    }
    // Edges whose height over the width found so far is clearly larger cannot give the minimum:
    // no square root or division for them (squares compared with a 1e-9 relative margin, far
    // above rounding, where none of the factors can overflow or underflow).
    const double len2 = (b - a).squaredNorm();
    if (best >= 1e-50 && best <= 1e50 && len2 >= 1e-100 && len2 <= 1e100 && height >= 0 &&
        height * height >= best * best * len2 * (1 + 1e-9))
      continue;
    const double len = std::sqrt(len2);
    if (len > 0 && height / len < best) {
      best = height / len;
      edge_a = a;
      edge_b = b;
    }
  }
  return best;
}

// Minimum width of a closed polygon (mm): the smallest distance between two parallel lines
// enclosing it, by rotating calipers on its convex hull. The hull is first taken in linear time
// as for a simple polygon; the width is exact when every point lies within the slab it found
// (then no direction is narrower), otherwise the hull is recomputed from sorted points. 0 below
// three points.
double minimum_width(const std::vector<Vec2>& pts) {
  if (pts.size() < 3) return 0.0;
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();
  double width = hull_width(hull_of_simple(pts), a, b);
  if (std::isfinite(width)) {
    const double len = (b - a).norm();
    const Box2 box = box_of(pts);
    const double eps = 1e-12 * (box.hi - box.lo).norm();
    // Heights clearly inside [-eps, width + eps] (a 1e-9 relative margin, far above rounding,
    // where no product can underflow or overflow) need no division.
    const bool quick = len >= 1e-100 && len <= 1e100 && eps >= 1e-200 && width + eps <= 1e100;
    const double lo = quick ? -eps * len * (1 - 1e-9) : 0.0;
    const double hi = quick ? (width + eps) * len * (1 - 1e-9) : -1.0;
    bool inside = true;
    for (const Vec2& p : pts) {
      const double c = cross2(a, b, p);
      if (c >= lo && c <= hi) continue;
      const double h = c / len;
      if (h < -eps || h > width + eps) {
        inside = false;
        break;
      }
    }
    if (inside) return width;
  }
  width = hull_width(hull_sorted(pts), a, b);
  return std::isfinite(width) ? width : 0.0;
}

// Smallest distance (mm) between two closed loops that do not cross (the nearest vertex of one
// to an edge of the other, both ways), or `bound` when they are no nearer than that. Only the
// edges of each loop that come within `bound` of the other's box are visited: an edge counts
// when its own box reaches the other's box widened by the bound, so a long edge whose ends are
// both far but whose middle passes close is visited too.
double loop_distance(const std::vector<Vec2>& a, const std::vector<Vec2>& b, double bound) {
  double best = bound * bound;
  // A first bound from a few vertices of `a` to every vertex of `b` keeps the visited parts small.
  const std::size_t step = std::max<std::size_t>(1, a.size() / 8);
  for (std::size_t i = 0; i < a.size(); i += step)
    for (const Vec2& q : b) best = std::min(best, (a[i] - q).squaredNorm());
  auto near = [](const std::vector<Vec2>& loop, const Box2& box, double d) {
    // Indices i of edges (i, i + 1) that may come within d of the box: the edge's own box meets
    // the box widened by d (conservative: every edge within d is among them, and every vertex
    // within d is the first end of one of them).
    std::vector<std::uint32_t> out;
    const std::size_t n = loop.size();
    const double x0 = box.lo.x() - d, x1 = box.hi.x() + d;
    const double y0 = box.lo.y() - d, y1 = box.hi.y() + d;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& p = loop[i];
      const Vec2& q = loop[i + 1 == n ? 0 : i + 1];
      if (std::max(p.x(), q.x()) >= x0 && std::min(p.x(), q.x()) <= x1 &&
          std::max(p.y(), q.y()) >= y0 && std::min(p.y(), q.y()) <= y1)
        out.push_back(static_cast<std::uint32_t>(i));
    }
    return out;
  };
  auto one_way = [&](const std::vector<Vec2>& from, const std::vector<Vec2>& to) {
    const Box2 to_box = box_of(to);
    const std::vector<std::uint32_t> points = near(from, to_box, std::sqrt(best));
    if (points.empty()) return;
    Box2 from_box;
    for (std::uint32_t i : points) from_box.add(from[i]);
    const std::vector<std::uint32_t> edges = near(to, from_box, std::sqrt(best));
    const std::size_t n = to.size();
    // The edges in groups of 16 with their boxes: a group farther from the point than the
    // nearest edge so far (plus a margin far above the rounding of the distances, ~1e-15 of the
    // coordinates) holds no nearer edge, so skipping it leaves the minimum as it is.
    constexpr std::size_t kGroup = 16;
    std::vector<Box2> groups((edges.size() + kGroup - 1) / kGroup);
    for (std::size_t k = 0; k < edges.size(); ++k) {
      groups[k / kGroup].add(to[edges[k]]);
      groups[k / kGroup].add(to[edges[k] + 1 == n ? 0 : edges[k] + 1]);
    }
    double size = 0.0;  // largest coordinate magnitude involved
    for (const Box2& box : {to_box, from_box})
      size = std::max({size, std::abs(box.lo.x()), std::abs(box.lo.y()), std::abs(box.hi.x()),
                       std::abs(box.hi.y())});
    const bool prune = size > 1e-100 && size < 1e100;
    const double margin = 1e-12 * size;
    for (std::uint32_t i : points) {
      const Vec2& q = from[i];
      for (std::size_t g = 0; g < groups.size(); ++g) {
        if (prune) {
          const Box2& box = groups[g];
          const double dx = std::max({box.lo.x() - q.x(), 0.0, q.x() - box.hi.x()});
          const double dy = std::max({box.lo.y() - q.y(), 0.0, q.y() - box.hi.y()});
          const double reach = std::sqrt(best) + margin;
          if (dx * dx + dy * dy > reach * reach) continue;
        }
        const std::size_t end = std::min(edges.size(), (g + 1) * kGroup);
        for (std::size_t k = g * kGroup; k < end; ++k) {
          const std::uint32_t e = edges[k];
          const Vec2& p0 = to[e];
          const Vec2 d = to[e + 1 == n ? 0 : e + 1] - p0;
          const double len2 = d.squaredNorm();
          const double t = len2 > 0 ? std::clamp((q - p0).dot(d) / len2, 0.0, 1.0) : 0.0;
          best = std::min(best, (p0 + t * d - q).squaredNorm());
        }
      }
    }
  };
  one_way(a, b);
  one_way(b, a);
  return std::sqrt(best);
}

}  // namespace

double region_thickness_lower_bound(double area_mm2, double smaller_second_moment_mm4) {
  if (!(area_mm2 > 0) || !(smaller_second_moment_mm4 > 0)) return 0.0;
  const double bound = 2.0 * std::sqrt(smaller_second_moment_mm4 / area_mm2);
  return std::isfinite(bound) ? bound : 0.0;
}

namespace {

// The thinnest wall around the region's holes (mm): each hole's distance to the outer boundary
// and to the other holes, or `bound` when none is thinner (only parts within it are searched).
double thinnest_wall(const SectionPolygon& polygon, double bound) {
  const auto& holes = polygon.holes;
  for (std::size_t h = 0; h < holes.size(); ++h) {
    if (holes[h].size() < 3) continue;
    bound = loop_distance(holes[h], polygon.outer, bound);
    for (std::size_t k = h + 1; k < holes.size(); ++k)
      if (holes[k].size() >= 3) bound = loop_distance(holes[h], holes[k], bound);
  }
  return bound;
}

}  // namespace

bool region_thinner_than(const SectionPolygon& polygon, double limit_mm, double width_bound_mm) {
  if (!(limit_mm > 0)) return false;
  if (!(width_bound_mm >= limit_mm) && minimum_width(polygon.outer) < limit_mm) return true;
  // With nothing nearer, loop_distance gives back sqrt(limit^2), which is the limit exactly
  // (a correctly rounded root of a rounded square), so only a thinner wall is below it.
  return thinnest_wall(polygon, limit_mm) < limit_mm;
}

double region_thickness(const SectionPolygon& polygon) {
  return thinnest_wall(polygon, minimum_width(polygon.outer));
}

}  // namespace osteon

namespace osteon {
namespace {

int find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The ray of the inside tests: a fixed direction that mesh edges are unlikely to follow.
Vec3 inside_ray() { return Vec3(1.0, 0.3141592653589793, 0.2718281828459045).normalized(); }

// True when the inside ray from p crosses triangle t (3 vertex indices). (Inline: the inside
// tests call it per face.)
inline bool ray_crosses(const MeshView& mesh, const std::int32_t* t, const Vec3& p,
                        const Vec3& dir) {
  const Vec3 a = mesh.vertex(t[0]);
  const Vec3 e1 = mesh.vertex(t[1]) - a, e2 = mesh.vertex(t[2]) - a;
  double hit = 0.0;
  return detail::line_hits_triangle(p, dir, a, e1, e2, hit) && hit > 0.0;
}

// True when point p lies inside the closed triangle set `faces` (`corners` = 3 per face; parity
// of crossings of a ray).
bool inside_shell(const MeshView& mesh, const std::int32_t* faces, std::size_t corners,
                  const Vec3& p) {
  const Vec3 dir = inside_ray();
  int hits = 0;
  for (std::size_t k = 0; k < corners; k += 3) hits += ray_crosses(mesh, faces + k, p, dir);
  return hits % 2 == 1;
}

// inside_shell over the faces of one piece (shell_of: #V shell of each vertex of a face;
// piece_of_shell: the piece of each shell; a face belongs to its vertices' shell), visiting only
// the grid cells that the ray's line passes near: every face the line hits lies in such a cell, and
// each face is tested as inside_shell tests it, so the parity is the same (a live run's grid is
// there anyway; the whole held body is not scanned for each sampled vertex).
bool inside_piece(const MeshView& mesh, const FaceGrid& grid,
                  const std::vector<std::int32_t>& shell_of,
                  const std::vector<std::int32_t>& piece_of_shell, std::int32_t piece,
                  const Vec3& p) {
  const Vec3 dir = inside_ray();
  int hits = 0;
  grid.for_faces_near(CutRegion{p, dir, 0.0}, [&](const std::int32_t* t) {
    hits += piece_of_shell[shell_of[t[0]]] == piece && ray_crosses(mesh, t, p, dir);
  });
  return hits % 2 == 1;
}

// Squared distance (mm²) from p to the closed triangle (a, b, c): the closest point by its
// Voronoi region (vertex, edge or face), as in Ericson's Real-Time Collision Detection, 5.1.5.
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  const double denom = 1.0 / (va + vb + vc);
  return (ap - (vb * denom) * ab - (vc * denom) * ac).squaredNorm();
}

}  // namespace

std::vector<std::vector<std::int32_t>> loose_pieces(const MeshView& mesh,
                                                    const std::vector<int>& vertex_bone,
                                                    int held_bone, double contact_gap,
                                                    Index* face_shells) {
  return LoosePieceFinder().find(mesh, vertex_bone, held_bone, contact_gap, face_shells, false);
}

void LoosePieceFinder::find_shells(const MeshView& mesh) {
  const Index nv = mesh.num_vertices, nf = mesh.num_faces;
  std::vector<std::int32_t>& parent = parent_;
  parent.resize(nv);
  for (Index v = 0; v < nv; ++v) parent[v] = static_cast<std::int32_t>(v);
  // A set's root is its smallest vertex (the larger root always joins the smaller one).
  auto join_roots = [&](std::int32_t a, std::int32_t b) {
    if (a == b) return a;
    if (a > b) std::swap(a, b);
    parent[b] = a;
    return a;
  };
  std::vector<std::uint8_t> used(nv, 0);
  for (Index f = 0; f < nf; ++f) {
    const std::int32_t* t = mesh.faces + 3 * f;
    // Most faces join nothing new: their vertices already point at one root (so an earlier
    // face marked them used; only a face of one vertex thrice, no triangle, marks nothing).
    const std::int32_t p0 = parent[t[0]];
    if (parent[t[1]] == p0 && parent[t[2]] == p0 && parent[p0] == p0) continue;
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
    const std::int32_t r = join_roots(find_root(parent, t[0]), find_root(parent, t[1]));
    join_roots(r, find_root(parent, t[2]));
  }
  // Shells numbered by their smallest vertex (a root comes before the rest of its set). A vertex
  // of no face is not printed: it is no shell (a stray vertex of a modelled figurine would
  // otherwise make it two shells and send every live run through the search).
  std::int32_t shells = 0;  // the roots of used vertices
  for (Index v = 0; v < nv; ++v) shells += used[v] && parent[v] == v;
  shells_ = shells;
  have_shells_ = true;
  shell_of_.assign(nv, -1);  // (its size tells the next call which mesh the shells are of)
  if (shells <= 1) return;   // no loose piece whatever the positions: nothing more to keep
  shells = 0;
  for (Index v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    const std::int32_t r = find_root(parent, static_cast<std::int32_t>(v));
    shell_of_[v] = r == v ? shells++ : shell_of_[r];
  }
  // Each shell's vertices (ascending) and faces (as in the mesh), and the largest shell.
  shell_vstart_.assign(shells + 1, 0);
  shell_fstart_.assign(shells + 1, 0);
  for (Index v = 0; v < nv; ++v)
    if (shell_of_[v] >= 0) ++shell_vstart_[shell_of_[v] + 1];
  // A face of one vertex thrice whose vertex is in no other face is no triangle and in no shell
  // (its vertex was never marked used): it is left out of the face lists.
  for (Index f = 0; f < nf; ++f)
    if (const std::int32_t k = shell_of_[mesh.faces[3 * f]]; k >= 0) ++shell_fstart_[k + 1];
  largest_ = 0;
  for (std::int32_t k = 0; k < shells; ++k)
    if (shell_vstart_[k + 1] > shell_vstart_[largest_ + 1]) largest_ = k;
  for (std::int32_t k = 0; k < shells; ++k) {
    shell_vstart_[k + 1] += shell_vstart_[k];
    shell_fstart_[k + 1] += shell_fstart_[k];
  }
  shell_vertices_.resize(shell_vstart_[shells]);
  shell_faces_.resize(3 * shell_fstart_[shells]);
  other_vertices_.clear();
  std::vector<Index> fill(shell_vstart_.begin(), shell_vstart_.end() - 1);
  for (Index v = 0; v < nv; ++v) {
    const std::int32_t k = shell_of_[v];
    if (k < 0) continue;
    shell_vertices_[fill[k]++] = static_cast<std::int32_t>(v);
    if (k != largest_) other_vertices_.push_back(static_cast<std::int32_t>(v));
  }
  fill.assign(shell_fstart_.begin(), shell_fstart_.end() - 1);
  for (Index f = 0; f < nf; ++f) {
    const std::int32_t* t = mesh.faces + 3 * f;
    if (const std::int32_t k = shell_of_[t[0]]; k >= 0)
      std::copy(t, t + 3, shell_faces_.begin() + 3 * fill[k]++);
  }
}

std::vector<std::vector<std::int32_t>> LoosePieceFinder::find(const MeshView& mesh,
                                                              const std::vector<int>& vertex_bone,
                                                              int held_bone, double contact_gap,
                                                              Index* face_shells, bool same_faces,
                                                              const FaceGrid* grid) {
  const Index nv = mesh.num_vertices;
  const double gap = std::isfinite(contact_gap) ? std::max(0.0, contact_gap) : 0.0;
  if (!same_faces || !have_shells_ || static_cast<Index>(shell_of_.size()) != nv) find_shells(mesh);
  if (face_shells != nullptr) *face_shells = shells_;
  if (shells_ <= 1) return {};
  const auto shells = static_cast<std::int32_t>(shells_);
  // Shells touching at exactly the same position (unwelded meshes) are one piece: a union-find
  // over the shells, whose root is its smallest shell (so the pieces are numbered, below, by
  // their smallest vertex, as shells are). Positions shared within one shell change nothing, so
  // only the vertices outside the largest shell are sorted; each vertex of the largest shell
  // inside their box looks its position up among them (a figurine with a small separate part:
  // no sort of the whole mesh on every live run).
  std::vector<std::int32_t>& parent = parent_;
  parent.resize(shells);
  for (std::int32_t k = 0; k < shells; ++k) parent[k] = k;
  auto join = [&](std::int32_t u, std::int32_t v) {
    std::int32_t a = find_root(parent, shell_of_[u]), b = find_root(parent, shell_of_[v]);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    parent[b] = a;
  };
  std::vector<std::int32_t>& order = order_;
  order.assign(other_vertices_.begin(), other_vertices_.end());
  Vec3 others_lo = Vec3::Constant(std::numeric_limits<double>::infinity()), others_hi = -others_lo;
  for (std::int32_t v : order) {
    others_lo = others_lo.cwiseMin(mesh.vertex(v));
    others_hi = others_hi.cwiseMax(mesh.vertex(v));
  }
  auto less = [&](std::int32_t a, std::int32_t b) {
    const double* p = mesh.vertices + 3 * static_cast<Index>(a);
    const double* q = mesh.vertices + 3 * static_cast<Index>(b);
    return std::lexicographical_compare(p, p + 3, q, q + 3);
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < order.size(); ++k)
    if (!less(order[k - 1], order[k])) join(order[k - 1], order[k]);
  for (Index k = shell_vstart_[largest_], e = shell_vstart_[largest_ + 1]; k < e; ++k) {
    const std::int32_t u = shell_vertices_[k];
    const Vec3 p = mesh.vertex(u);
    if ((p.array() < others_lo.array()).any() || (p.array() > others_hi.array()).any()) continue;
    const auto it = std::lower_bound(order.begin(), order.end(), u, less);
    if (it != order.end() && !less(u, *it)) join(u, *it);
  }
  // Pieces: shells, or unions of shells (their vertices in ascending order, their faces in any:
  // every test below on a piece's faces asks whether some face does something).
  std::vector<std::int32_t>& piece_of_shell = piece_of_shell_;
  piece_of_shell.assign(shells, -1);
  std::size_t np = 0;
  for (std::int32_t k = 0; k < shells; ++k) {
    const std::int32_t r = find_root(parent, k);
    if (piece_of_shell[r] < 0) piece_of_shell[r] = static_cast<std::int32_t>(np++);
    piece_of_shell[k] = piece_of_shell[r];
  }
  if (np <= 1) return {};
  struct Span {
    const std::int32_t* first = nullptr;
    std::size_t count = 0;
    const std::int32_t* begin() const { return first; }
    const std::int32_t* end() const { return first + count; }
    std::size_t size() const { return count; }
    bool empty() const { return count == 0; }
    std::int32_t operator[](std::size_t k) const { return first[k]; }
  };
  std::vector<Span> verts(np), faces(np);
  std::vector<std::int32_t> piece_shells(np, 0), slot(np, -1);
  for (std::int32_t k = 0; k < shells; ++k) ++piece_shells[piece_of_shell[k]];
  std::size_t merged = 0;  // pieces of several shells: their lists are built in merged_
  for (std::int32_t k = 0; k < shells; ++k) {
    const std::size_t q = piece_of_shell[k];
    const Index v0 = shell_vstart_[k], v1 = shell_vstart_[k + 1];
    const Index f0 = 3 * shell_fstart_[k], f1 = 3 * shell_fstart_[k + 1];
    if (piece_shells[q] == 1) {
      verts[q] = {shell_vertices_.data() + v0, static_cast<std::size_t>(v1 - v0)};
      faces[q] = {shell_faces_.data() + f0, static_cast<std::size_t>(f1 - f0)};
      continue;
    }
    if (slot[q] < 0) {
      slot[q] = static_cast<std::int32_t>(merged++);
      if (merged_.size() < 2 * merged) merged_.resize(2 * merged);
      merged_[2 * slot[q]].clear();
      merged_[2 * slot[q] + 1].clear();
    }
    std::vector<std::int32_t>& vs = merged_[2 * slot[q]];
    std::vector<std::int32_t>& fs = merged_[2 * slot[q] + 1];
    vs.insert(vs.end(), shell_vertices_.begin() + v0, shell_vertices_.begin() + v1);
    fs.insert(fs.end(), shell_faces_.begin() + f0, shell_faces_.begin() + f1);
  }
  for (std::size_t q = 0; q < np; ++q) {
    if (slot[q] < 0) continue;
    std::vector<std::int32_t>& vs = merged_[2 * slot[q]];
    const std::vector<std::int32_t>& fs = merged_[2 * slot[q] + 1];
    std::sort(vs.begin(), vs.end());
    verts[q] = {vs.data(), vs.size()};
    faces[q] = {fs.data(), fs.size()};
  }
  std::vector<Vec3> lo(np, Vec3::Constant(std::numeric_limits<double>::infinity())),
      hi(np, Vec3::Constant(-std::numeric_limits<double>::infinity()));
  std::vector<Index> held_count(np, 0);
  for (Index v = 0; v < nv; ++v) {
    const std::int32_t k = shell_of_[v];
    if (k < 0) continue;
    const int p = piece_of_shell[k];
    lo[p] = lo[p].cwiseMin(mesh.vertex(v));
    hi[p] = hi[p].cwiseMax(mesh.vertex(v));
    held_count[p] += vertex_bone[v] == held_bone;
  }
  std::size_t held = 0;
  for (std::size_t p = 1; p < np; ++p)
    if (held_count[p] > held_count[held] ||
        (held_count[p] == held_count[held] && verts[p].size() > verts[held].size()))
      held = p;
  // Shells closer than the gap (a vertex of one within `gap` of a face of the other) touch for
  // the printer. Only the parts inside the common box widened by the gap are visited; past a
  // work cap they count as attached (doubt keeps a piece held).
  auto within_gap = [&](std::size_t a, std::size_t b) {
    if (gap <= 0) return false;
    const Vec3 clo = (lo[a].cwiseMax(lo[b]).array() - gap).matrix();
    const Vec3 chi = (hi[a].cwiseMin(hi[b]).array() + gap).matrix();
    auto in_box = [&](const Vec3& p) {
      return !((p.array() < clo.array()).any() || (p.array() > chi.array()).any());
    };
    auto near_vertices = [&](std::size_t piece) {
      std::vector<std::int32_t> out;
      for (std::int32_t v : verts[piece])
        if (in_box(mesh.vertex(v))) out.push_back(v);
      return out;
    };
    auto near_faces = [&](std::size_t piece) {
      std::vector<std::int32_t> out;
      const auto& fs = faces[piece];
      for (std::size_t k = 0; k < fs.size(); k += 3) {
        const Vec3 p = mesh.vertex(fs[k]), q = mesh.vertex(fs[k + 1]), r = mesh.vertex(fs[k + 2]);
        const Vec3 l = p.cwiseMin(q).cwiseMin(r), h = p.cwiseMax(q).cwiseMax(r);
        if (!((l.array() > chi.array()).any() || (h.array() < clo.array()).any()))
          out.insert(out.end(), fs.begin() + k, fs.begin() + k + 3);
      }
      return out;
    };
    const double gap2 = gap * gap;
    auto vertex_near_face = [&](const std::vector<std::int32_t>& vs,
                                const std::vector<std::int32_t>& fs) {
      if (static_cast<double>(vs.size()) * static_cast<double>(fs.size()) > 3e7) return true;
      for (std::int32_t v : vs) {
        const Vec3 p = mesh.vertex(v);
        for (std::size_t k = 0; k < fs.size(); k += 3)
          if (point_triangle_distance2(p, mesh.vertex(fs[k]), mesh.vertex(fs[k + 1]),
                                       mesh.vertex(fs[k + 2])) <= gap2)
            return true;
      }
      return false;
    };
    return vertex_near_face(near_vertices(a), near_faces(b)) ||
           vertex_near_face(near_vertices(b), near_faces(a));
  };
  auto overlap = [&](std::size_t a, std::size_t b) {
    if ((lo[a].array() > hi[b].array() + gap).any() || (lo[b].array() > hi[a].array() + gap).any())
      return false;
    if ((lo[a].array() > hi[b].array()).any() || (lo[b].array() > hi[a].array()).any())
      return within_gap(a, b);
    // Vertices of either piece (16 sampled of each) inside the other one.
    auto some_inside = [&](std::size_t from, std::size_t into) {
      if (faces[into].empty()) return false;
      const std::size_t n = verts[from].size(), step = std::max<std::size_t>(1, n / 16);
      for (std::size_t k = 0; k < n; k += step)
        if (grid != nullptr
                ? inside_piece(mesh, *grid, shell_of_, piece_of_shell,
                               static_cast<std::int32_t>(into), mesh.vertex(verts[from][k]))
                : inside_shell(mesh, faces[into].begin(), faces[into].size(),
                               mesh.vertex(verts[from][k])))
          return true;
      return false;
    };
    if (some_inside(a, b) || some_inside(b, a)) return true;
    // Surfaces that pass through each other (a wing plate through a body): an edge of one
    // crosses a face of the other, inside the boxes' common part. Past a work cap the pieces
    // count as attached: calling a piece loose drops its load, so doubt keeps it held.
    const Vec3 clo = lo[a].cwiseMax(lo[b]), chi = hi[a].cwiseMin(hi[b]);
    auto in_common = [&](const Vec3& p, const Vec3& q, const Vec3& r) {
      const Vec3 l = p.cwiseMin(q).cwiseMin(r), h = p.cwiseMax(q).cwiseMax(r);
      return !((l.array() > chi.array()).any() || (h.array() < clo.array()).any());
    };
    std::vector<std::int32_t> fa, fb;
    for (int side = 0; side < 2; ++side) {
      auto& out = side == 0 ? fa : fb;
      const auto& fs = faces[side == 0 ? a : b];
      for (std::size_t k = 0; k < fs.size(); k += 3)
        if (in_common(mesh.vertex(fs[k]), mesh.vertex(fs[k + 1]), mesh.vertex(fs[k + 2])))
          out.insert(out.end(), fs.begin() + k, fs.begin() + k + 3);
    }
    if (fa.empty() || fb.empty()) return within_gap(a, b);
    if (static_cast<double>(fa.size()) * static_cast<double>(fb.size()) > 9e7) return true;
    auto edges_cross = [&](const std::vector<std::int32_t>& edges_of,
                           const std::vector<std::int32_t>& faces_of) {
      for (std::size_t k = 0; k < edges_of.size(); k += 3)
        for (int e = 0; e < 3; ++e) {
          const Vec3 p = mesh.vertex(edges_of[k + e]);
          const Vec3 d = mesh.vertex(edges_of[k + (e + 1) % 3]) - p;
          for (std::size_t m = 0; m < faces_of.size(); m += 3) {
            const Vec3 t0 = mesh.vertex(faces_of[m]);
            double t = 0.0;
            if (detail::line_hits_triangle(p, d, t0, mesh.vertex(faces_of[m + 1]) - t0,
                                           mesh.vertex(faces_of[m + 2]) - t0, t) &&
                t >= 0.0 && t <= 1.0)
              return true;
          }
        }
      return false;
    };
    return edges_cross(fa, fb) || edges_cross(fb, fa) || within_gap(a, b);
  };
  std::vector<std::uint8_t> attached(np, 0);
  std::vector<std::size_t> queue{held};
  attached[held] = 1;
  for (std::size_t q = 0; q < queue.size(); ++q)
    for (std::size_t p = 0; p < np; ++p)
      if (!attached[p] && overlap(queue[q], p)) {
        attached[p] = 1;
        queue.push_back(p);
      }
  std::vector<std::vector<std::int32_t>> loose;
  for (std::size_t p = 0; p < np; ++p)
    if (!attached[p] && !faces[p].empty()) loose.emplace_back(verts[p].begin(), verts[p].end());
  return loose;
}

}  // namespace osteon
