#include "thickness.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "region_geometry.hpp"

namespace osteon {
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

// By rotating calipers on its convex hull. The hull is first taken in linear time
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
