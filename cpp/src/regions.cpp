#include "osteon/regions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "clipper2/clipper.h"
#include "line_triangle.hpp"

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
  Point64 to(const Vec2& p) const {
    return Point64(static_cast<std::int64_t>(std::llround(p.x() * scale)),
                   static_cast<std::int64_t>(std::llround(p.y() * scale)));
  }
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
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
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
  for (const Vec2& p : pts) b.add(p);
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

}  // namespace

SectionGeometry junction_core(const SectionPolygon& section,
                              const std::vector<const SectionPolygon*>& neighbours,
                              double margin_mm, double opening_mm) {
  using Clipper2Lib::FillRule;
  SectionGeometry geom;
  std::vector<std::vector<Vec2>> all{section.outer};
  all.insert(all.end(), section.holes.begin(), section.holes.end());
  for (const SectionPolygon* n : neighbours) {
    all.push_back(n->outer);
    all.insert(all.end(), n->holes.begin(), n->holes.end());
  }
  const Scaler s(all);
  const Paths64 whole = paths_of(section, s);
  Paths64 core = whole;
  // Only the neighbours' material near the section matters: clipped to its box (+ margin).
  const Clipper2Lib::Rect64 box = Clipper2Lib::GetBounds(whole);
  const std::int64_t pad = static_cast<std::int64_t>(2.0 * margin_mm * s.scale) + 1;
  const Clipper2Lib::Rect64 near(box.left - pad, box.top - pad, box.right + pad, box.bottom + pad);
  for (const SectionPolygon* n : neighbours) {
    Paths64 widened = Clipper2Lib::RectClip(near, paths_of(*n, s));
    if (margin_mm > 0) widened = offset(widened, margin_mm * s.scale);
    core = Clipper2Lib::Intersect(core, widened, FillRule::NonZero);
  }
  // The trimmed-off material, piece by piece: a piece is a stub (left out whole) only when it is
  // wider than 2 * opening somewhere (its erosion by `opening` is not empty); a thin piece (the
  // rim of a taper, a tilted bone's crescent) goes back into the core.
  PolyTree64 trimmed;
  {
    Clipper2Lib::Clipper64 clipper;
    clipper.AddSubject(whole);
    clipper.AddClip(core);
    clipper.Execute(Clipper2Lib::ClipType::Difference, FillRule::NonZero, trimmed);
  }
  std::vector<const PolyPath64*> pieces;
  collect_outers(trimmed, pieces);
  Paths64 kept = core;
  for (const PolyPath64* piece : pieces) {
    Paths64 paths{piece->Polygon()};
    for (const auto& hole : *piece) paths.push_back(hole->Polygon());
    if (opening_mm > 0 && offset(paths, -opening_mm * s.scale).empty())
      kept.insert(kept.end(), paths.begin(), paths.end());
  }
  core = Clipper2Lib::Union(kept, FillRule::NonZero);
  PolyTree64 tree;
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(core);
  clipper.Execute(Clipper2Lib::ClipType::Union, FillRule::NonZero, tree);
  bool hollow = false;
  if (const PolyPath64* outer = locate(tree, s.to(Vec2::Zero()), hollow)) {
    if (hollow) geom.flags |= kFlagHollow;
    geom.polygon = polygon_of(*outer, s);
    geom.found = true;
  }
  return geom;
}

double region_thickness(const SectionPolygon& polygon) {
  std::vector<Vec2> pts = polygon.outer;
  if (pts.size() < 3) return 0.0;
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  // Andrew's monotone chain: counter-clockwise convex hull.
  std::vector<Vec2> hull(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  const std::size_t h = hull.size();
  if (h < 3) return 0.0;
  // Rotating calipers: for each hull edge the farthest hull point; the width is the minimum.
  auto height = [&](std::size_t e, std::size_t m) {
    const Vec2& a = hull[e];
    const Vec2& b = hull[(e + 1) % h];
    const double len = (b - a).norm();
    return len > 0 ? cross(a, b, hull[m]) / len : 0.0;
  };
  double best = std::numeric_limits<double>::infinity();
  std::size_t far = 1;
  for (std::size_t e = 0; e < h; ++e) {
    if (far == e) far = (e + 1) % h;
    for (std::size_t steps = 0; steps < h && height(e, (far + 1) % h) >= height(e, far); ++steps)
      far = (far + 1) % h;
    if ((hull[(e + 1) % h] - hull[e]).norm() > 0) best = std::min(best, height(e, far));
  }
  return std::isfinite(best) ? best : 0.0;
}

}  // namespace osteon

namespace osteon {
namespace {

int find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// True when point p lies inside the closed triangle set `faces` (parity of crossings of a ray).
bool inside_shell(const MeshView& mesh, const std::vector<std::int32_t>& faces, const Vec3& p) {
  const Vec3 dir = Vec3(1.0, 0.3141592653589793, 0.2718281828459045).normalized();
  int hits = 0;
  for (std::size_t k = 0; k < faces.size(); k += 3) {
    const Vec3 a = mesh.vertex(faces[k]);
    const Vec3 e1 = mesh.vertex(faces[k + 1]) - a, e2 = mesh.vertex(faces[k + 2]) - a;
    double t = 0.0;
    if (detail::line_hits_triangle(p, dir, a, e1, e2, t) && t > 0.0) ++hits;
  }
  return hits % 2 == 1;
}

}  // namespace

std::vector<std::vector<std::int32_t>> loose_pieces(const MeshView& mesh,
                                                    const std::vector<int>& vertex_bone,
                                                    int held_bone) {
  const Index nv = mesh.num_vertices, nf = mesh.num_faces;
  std::vector<std::int32_t> parent(nv);
  for (Index v = 0; v < nv; ++v) parent[v] = static_cast<std::int32_t>(v);
  auto join = [&](std::int32_t a, std::int32_t b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (Index f = 0; f < nf; ++f) {
    join(mesh.faces[3 * f], mesh.faces[3 * f + 1]);
    join(mesh.faces[3 * f], mesh.faces[3 * f + 2]);
  }
  auto count_roots = [&]() {
    Index roots = 0;
    for (Index v = 0; v < nv; ++v) roots += find_root(parent, static_cast<std::int32_t>(v)) == v;
    return roots;
  };
  if (count_roots() <= 1) return {};
  // Shells touching at exactly the same position (unwelded meshes) are one piece.
  std::vector<std::int32_t> order(nv);
  for (Index v = 0; v < nv; ++v) order[v] = static_cast<std::int32_t>(v);
  auto less = [&](std::int32_t a, std::int32_t b) {
    const double* p = mesh.vertices + 3 * static_cast<Index>(a);
    const double* q = mesh.vertices + 3 * static_cast<Index>(b);
    return std::lexicographical_compare(p, p + 3, q, q + 3);
  };
  std::sort(order.begin(), order.end(), less);
  for (Index k = 1; k < nv; ++k)
    if (!less(order[k - 1], order[k])) join(order[k - 1], order[k]);
  // Pieces: vertices, faces and boxes.
  std::vector<std::int32_t> piece_of(nv, -1), root_piece(nv, -1);
  std::vector<std::vector<std::int32_t>> verts;
  for (Index v = 0; v < nv; ++v) {
    const std::int32_t r = find_root(parent, static_cast<std::int32_t>(v));
    if (root_piece[r] < 0) {
      root_piece[r] = static_cast<std::int32_t>(verts.size());
      verts.emplace_back();
    }
    piece_of[v] = root_piece[r];
    verts[piece_of[v]].push_back(static_cast<std::int32_t>(v));
  }
  const std::size_t np = verts.size();
  if (np <= 1) return {};
  std::vector<std::vector<std::int32_t>> faces(np);
  for (Index f = 0; f < nf; ++f) {
    auto& out = faces[piece_of[mesh.faces[3 * f]]];
    out.insert(out.end(), mesh.faces + 3 * f, mesh.faces + 3 * f + 3);
  }
  std::vector<Vec3> lo(np, Vec3::Constant(std::numeric_limits<double>::infinity())),
      hi(np, Vec3::Constant(-std::numeric_limits<double>::infinity()));
  std::vector<Index> held_count(np, 0);
  for (Index v = 0; v < nv; ++v) {
    const int p = piece_of[v];
    lo[p] = lo[p].cwiseMin(mesh.vertex(v));
    hi[p] = hi[p].cwiseMax(mesh.vertex(v));
    held_count[p] += vertex_bone[v] == held_bone;
  }
  std::size_t held = 0;
  for (std::size_t p = 1; p < np; ++p)
    if (held_count[p] > held_count[held] ||
        (held_count[p] == held_count[held] && verts[p].size() > verts[held].size()))
      held = p;
  auto overlap = [&](std::size_t a, std::size_t b) {
    if ((lo[a].array() > hi[b].array()).any() || (lo[b].array() > hi[a].array()).any())
      return false;
    // Vertices of the smaller piece (16 sampled) inside the larger one.
    const bool a_small = faces[a].size() <= faces[b].size();
    const std::size_t from = a_small ? a : b, into = a_small ? b : a;
    if (faces[into].empty()) return false;
    const std::size_t n = verts[from].size(), step = std::max<std::size_t>(1, n / 16);
    for (std::size_t k = 0; k < n; k += step)
      if (inside_shell(mesh, faces[into], mesh.vertex(verts[from][k]))) return true;
    return false;
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
    if (!attached[p] && !faces[p].empty()) loose.push_back(std::move(verts[p]));
  return loose;
}

}  // namespace osteon
