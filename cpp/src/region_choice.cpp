#include "region_choice.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "clipper2/clipper.h"
#include "region_geometry.hpp"

namespace osteon {
namespace {

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::Point64;
using Clipper2Lib::PointInPolygonResult;
using Clipper2Lib::PolyPath64;
using Clipper2Lib::PolyTree64;

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

// True when q lies in the region of `outer` (inside or on its boundary, not strictly in a hole).
bool in_region(const PolyPath64& outer, const Point64& q) {
  if (Clipper2Lib::PointInPolygon(q, outer.Polygon()) == PointInPolygonResult::IsOutside)
    return false;
  for (const auto& hole : outer)
    if (Clipper2Lib::PointInPolygon(q, hole->Polygon()) == PointInPolygonResult::IsInside)
      return false;
  return true;
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

// A segment of a loop (segment i joins its points i and i + 1), with its box.
struct LoopSegment {
  double xlo, xhi, ylo, yhi;
  Vec2 a, b;
  std::uint32_t loop, index;
};

// A run of a loop's segments whose x never decreases, or never increases (then stored
// backwards): in storage order both ends of the segments' x-ranges never decrease.
struct MonotoneChain {
  std::uint32_t begin, end;  // its segments in the segment list
  Box2 box;
};

// Splits the loops into x-monotone chains (`segs`, `chains`; `all`: the box of every chain).
// Returns false when a segment is degenerate (zero length: counts as touching).
bool split_monotone_chains(const std::vector<const std::vector<Vec2>*>& loops,
                           std::vector<LoopSegment>& segs, std::vector<MonotoneChain>& chains,
                           Box2& all) {
  for (std::size_t l = 0; l < loops.size(); ++l) {
    const auto& loop = *loops[l];
    const std::size_t n = loop.size();
    int dir = 0;
    double ylo = 0, yhi = 0;  // y-range of the open chain's points so far
    // The chain's box: its x-range from its first and last segments (both ends of the x-ranges
    // never decrease in storage order), its y-range from its points.
    auto close = [&](const Vec2& last) {
      MonotoneChain& c = chains.back();
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
      if (a == b) return false;
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
  return true;
}

// Whether segments of the chains meet, near-touching counting as touching: orientation values
// below `eps` (mm^2) are zero, boxes within `margin` (mm) meet.
class SegmentMeeting {
 public:
  SegmentMeeting(const std::vector<const std::vector<Vec2>*>& loops,
                 const std::vector<LoopSegment>& segs, double extent)
      : loops_(loops), segs_(segs), eps_(1e-12 * extent * extent), margin_(1e-9 * extent) {}

  double margin() const { return margin_; }

  // Two segments meet: their boxes come within the margin and neither has both ends strictly
  // on one side of the other (neighbours of one loop share their common point: not tested).
  bool meet(const LoopSegment& s, const LoopSegment& t) const {
    const double margin = margin_;
    if (s.ylo > t.yhi + margin || t.ylo > s.yhi + margin || s.xlo > t.xhi + margin ||
        t.xlo > s.xhi + margin)
      return false;
    if (s.loop == t.loop) {
      const std::uint32_t d = s.index > t.index ? s.index - t.index : t.index - s.index;
      if (d == 1 || d + 1 == loops_[s.loop]->size()) return false;
    }
    const int d1 = orient(t.a, t.b, s.a), d2 = orient(t.a, t.b, s.b);
    const int d3 = orient(s.a, s.b, t.a), d4 = orient(s.a, s.b, t.b);
    return d1 * d2 <= 0 && d3 * d4 <= 0;
  }

  // Two segments of one chain meet (segment k + 1 is k's neighbour, and the later ones lie
  // beyond it in x).
  bool chain_meets_itself(const MonotoneChain& p) const {
    const auto& segs = segs_;
    for (std::uint32_t k = p.begin; k < p.end; ++k)
      for (std::uint32_t j = k + 2; j < p.end && !(segs[j].xlo > segs[k].xhi + margin_); ++j)
        if (meet(segs[k], segs[j])) return true;
    return false;
  }

  // Every pair of segments of two chains whose x-ranges meet within the margin: for each
  // segment of p, those of q form one run [j0, j1) that only moves forward.
  bool chains_meet(const MonotoneChain& p, const MonotoneChain& q) const {
    const auto& segs = segs_;
    const double margin = margin_;
    const std::uint32_t k0 = first_reaching(p, q.box.lo.x());
    if (k0 == p.end) return false;
    std::uint32_t j0 = first_reaching(q, segs[k0].xlo), j1 = j0;
    for (std::uint32_t k = k0; k < p.end; ++k) {
      const LoopSegment& s = segs[k];
      if (s.xlo > q.box.hi.x() + margin) break;  // this and later segments lie beyond q
      while (j0 < q.end && s.xlo > segs[j0].xhi + margin) ++j0;
      while (j1 < q.end && !(segs[j1].xlo > s.xhi + margin)) ++j1;
      for (std::uint32_t j = j0; j < j1; ++j)
        if (meet(s, segs[j])) return true;
    }
    return false;
  }

 private:
  int orient(const Vec2& o, const Vec2& a, const Vec2& b) const {
    const double c = (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    return c > eps_ ? 1 : (c < -eps_ ? -1 : 0);
  }
  // The first segment of c that reaches x (binary search: a short chain against a long one
  // would otherwise walk the long one from its start).
  std::uint32_t first_reaching(const MonotoneChain& c, double x) const {
    return static_cast<std::uint32_t>(
        std::partition_point(segs_.begin() + c.begin, segs_.begin() + c.end,
                             [&](const LoopSegment& t) { return x > t.xhi + margin_; }) -
        segs_.begin());
  }

  const std::vector<const std::vector<Vec2>*>& loops_;
  const std::vector<LoopSegment>& segs_;
  double eps_, margin_;
};

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
  std::vector<LoopSegment> segs;
  segs.reserve(m);
  std::vector<MonotoneChain> chains;
  chains.reserve(4 * loops.size() + 16);
  Box2 all;
  if (!split_monotone_chains(loops, segs, chains, all)) return true;
  const Vec2 size = all.hi - all.lo;
  const double extent = std::max(size.x(), size.y());
  if (!(extent > 0) || !std::isfinite(extent)) return true;
  const SegmentMeeting meeting(loops, segs, extent);
  const double margin = meeting.margin();
  // Chain pairs whose boxes meet within the margin, by a sweep over the chains sorted by x.
  std::vector<std::uint32_t> order(chains.size());
  for (std::uint32_t c = 0; c < order.size(); ++c) order[c] = c;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return chains[a].box.lo.x() < chains[b].box.lo.x();
  });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const MonotoneChain& p = chains[order[i]];
    if (meeting.chain_meets_itself(p)) return true;
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const MonotoneChain& q = chains[order[j]];
      if (q.box.lo.x() > p.box.hi.x() + margin) break;
      if (p.box.lo.y() > q.box.hi.y() + margin || q.box.lo.y() > p.box.hi.y() + margin) continue;
      if (meeting.chains_meet(p, q)) return true;
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

// The region found: its flags completed (an open polyline near it) and marked found.
SectionGeometry finish_region(SectionGeometry geom, SectionPolygon&& poly, const PlaneCut& cut) {
  const Box2 box = box_of(poly.outer);
  for (const auto& chain : cut.open_chains)
    if (chain.size() >= 2 && box.overlaps(box_of(chain))) geom.flags |= kFlagOpen;
  geom.polygon = std::move(poly);
  geom.found = true;
  return geom;
}

// The loops whose boxes reach, directly or through each other, a loop around the origin
// (`containing`, first): loops apart from that cluster cannot touch the region around it.
std::vector<int> touching_cluster(const std::vector<Box2>& boxes,
                                  const std::vector<int>& containing) {
  const std::size_t n = boxes.size();
  std::vector<std::uint8_t> in(n, 0);
  std::vector<int> cluster(containing);
  for (int i : containing) in[i] = 1;
  for (std::size_t k = 0; k < cluster.size(); ++k)
    for (std::size_t j = 0; j < n; ++j)
      if (!in[j] && boxes[j].overlaps(boxes[cluster[k]])) {
        in[j] = 1;
        cluster.push_back(static_cast<int>(j));
      }
  return cluster;
}

// The region (index into `outers`) holding the greatest length of the bone's own cut (its
// skinning domain), or -1 when none holds any.
int region_of_domain(const std::vector<const PolyPath64*>& outers, const BoneDomain& domain,
                     const Scaler& s) {
  std::vector<double> length(outers.size(), 0.0);
  for (const CutSegment& seg : *domain.segments) {
    if (!owned(seg, domain)) continue;
    const Point64 mid = s.to(0.5 * (seg.point[0] + seg.point[1]));
    for (std::size_t r = 0; r < outers.size(); ++r)
      if (in_region(*outers[r], mid)) {
        length[r] += (seg.point[1] - seg.point[0]).norm();
        break;
      }
  }
  const auto best = std::max_element(length.begin(), length.end());
  return *best > 0 ? static_cast<int>(best - length.begin()) : -1;
}

// The bone point lies in no material of the union `tree`: the bone is outside the mesh here.
// With a domain, the region of the bone's own cut; without, the nearest region, unless open
// geometry is nearer (then skip).
SectionGeometry region_off_the_bone(const PlaneCut& cut, const BoneDomain* domain,
                                    const PolyTree64& tree, const Scaler& s, SectionGeometry geom) {
  const Vec2 origin = Vec2::Zero();
  geom.flags |= kFlagOutside;
  std::vector<const PolyPath64*> outers;
  collect_outers(tree, outers);
  if (outers.empty()) {
    geom.flags |= kFlagEmpty | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
  if (domain != nullptr && domain->segments != nullptr && domain->vertex_bone != nullptr) {
    const int r = region_of_domain(outers, *domain, s);
    if (r >= 0) return finish_region(geom, polygon_of(*outers[r], s), cut);
    // Nothing of the plane's material can be tied to the bone.
    geom.flags |= kFlagUnreliable | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
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
  return finish_region(geom, std::move(polys[pick]), cut);
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
      return finish_region(geom, std::move(poly), cut);
    }
  }
  if (n == 0) {
    geom.flags |= kFlagEmpty | (cut.open_chains.empty() ? 0u : kFlagOpen);
    return geom;
  }
  if (!containing.empty()) {
    // Only the cluster of loops around the point is merged (the whole plane of a large model
    // has many far loops).
    const std::vector<int> cluster = touching_cluster(boxes, containing);
    SectionPolygon nested;
    if (nested_region(cut.loops, cluster, containing, boxes, nested))
      return finish_region(geom, std::move(nested), cut);
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
        return finish_region(geom, polygon_of(*outer, sn), cut);
      }
    }
  }
  const Scaler s(cut.loops);
  PolyTree64 tree;
  union_nonzero(cut.loops, s, tree);
  bool hollow = false;
  if (const PolyPath64* outer = locate(tree, s.to(origin), hollow)) {
    if (hollow) geom.flags |= kFlagHollow;
    return finish_region(geom, polygon_of(*outer, s), cut);
  }
  return region_off_the_bone(cut, domain, tree, s, geom);
}

}  // namespace osteon
