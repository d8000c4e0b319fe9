// Choice of the section around a bone among a plane cut's loops, and the one-plane convenience
// (see osteon/slicer.hpp). The slicer's other parts: slicer_grid.cpp (face grid),
// slicer_cut.cpp (plane cut), slicer_loops.cpp (loop assembly).
#include "osteon/slicer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace osteon {
namespace {

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
  bool contains(const Box2& b) const {
    return b.lo.x() >= lo.x() && b.lo.y() >= lo.y() && b.hi.x() <= hi.x() && b.hi.y() <= hi.y();
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

}  // namespace

SectionGeometry select_section(const PlaneCut& cut) {
  SectionGeometry geom;
  geom.flags = cut.flags & (kFlagGapClosed | kFlagNonManifold);
  const Vec2 origin = Vec2::Zero();
  const std::size_t n = cut.loops.size();
  std::vector<Box2> boxes(n);
  std::vector<double> area(n);
  std::vector<int> containing;
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i] = box_of(cut.loops[i]);
    area[i] = std::abs(signed_area(cut.loops[i]));
    if (boxes[i].contains(origin) && point_in_loop(cut.loops[i], origin))
      containing.push_back(static_cast<int>(i));
  }
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
  int outer = -1;
  if (!containing.empty()) {
    // Loops containing the point are nested: sort outermost first; depth = position.
    std::sort(containing.begin(), containing.end(),
              [&](int a, int b) { return area[a] > area[b]; });
    const std::size_t count = containing.size();
    geom.containing = static_cast<int>(count);
    if (count % 2 == 1) {
      outer = containing[count - 1];
    } else {
      outer = containing[count - 2];
      geom.flags |= kFlagHollow;
    }
  } else {
    // Bone outside the mesh here: use the nearest loop (or nearest open geometry: skip).
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
      const double d = squared_distance_to_polyline(cut.loops[i], true, origin);
      if (d < best) {
        best = d;
        outer = static_cast<int>(i);
      }
    }
    double best_open = std::numeric_limits<double>::infinity();
    for (const auto& chain : cut.open_chains)
      best_open = std::min(best_open, squared_distance_to_polyline(chain, false, origin));
    if (outer < 0 || best_open < best) {
      geom.flags |= kFlagEmpty | ((outer < 0 && cut.open_chains.empty()) ? 0u : kFlagOpen);
      return geom;
    }
    geom.flags |= kFlagOutside;
  }
  // Holes: loops inside the outer boundary that are not inside another such loop.
  std::vector<int> inside;
  for (std::size_t i = 0; i < n; ++i) {
    if (static_cast<int>(i) == outer || area[i] >= area[outer]) continue;
    if (!boxes[outer].contains(boxes[i])) continue;
    if (point_in_loop(cut.loops[outer], cut.loops[i][0])) inside.push_back(static_cast<int>(i));
  }
  for (int i : inside) {
    bool direct = true;
    for (int j : inside) {
      if (i == j || area[j] <= area[i] || !boxes[j].contains(boxes[i])) continue;
      if (point_in_loop(cut.loops[j], cut.loops[i][0])) {
        direct = false;
        break;
      }
    }
    if (direct) geom.polygon.holes.push_back(cut.loops[i]);
  }
  geom.polygon.outer = cut.loops[outer];
  for (const auto& chain : cut.open_chains)
    if (chain.size() >= 2 && boxes[outer].overlaps(box_of(chain))) geom.flags |= kFlagOpen;
  geom.found = true;
  return geom;
}

SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance) {
  std::vector<CutSegment> segments;
  cut_mesh(mesh, plane, segments, nullptr);
  return select_section(assemble_loops(segments, gap_tolerance));
}

}  // namespace osteon
