#include "junction_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "clipper2/clipper.h"
#include "region_geometry.hpp"
#include "simplify_path.hpp"
#include "thickness.hpp"

namespace osteon {
namespace {

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::Point64;
using Clipper2Lib::PointInPolygonResult;
using Clipper2Lib::PolyPath64;
using Clipper2Lib::PolyTree64;

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

// Every loop of the section and its neighbours (the scale must fit them all).
std::vector<std::vector<Vec2>> loops_of(const SectionPolygon& section,
                                        const std::vector<const SectionPolygon*>& neighbours) {
  std::vector<std::vector<Vec2>> all{section.outer};
  all.insert(all.end(), section.holes.begin(), section.holes.end());
  for (const SectionPolygon* n : neighbours) {
    all.push_back(n->outer);
    all.insert(all.end(), n->holes.begin(), n->holes.end());
  }
  return all;
}

// The neighbours' material near the section (`whole`): clipped to its box (+ 2 margins) and
// their facets thinned to within a quarter of the margin (Clipper2 SimplifyPaths: a few dozen
// vertices instead of hundreds; the common part is widened once, later: the offset's cost is
// in the self-crossings of every facet's raw offset, and the widening still exceeds 3/4 of the
// margin everywhere).
std::vector<Paths64> thinned_neighbours(const Paths64& whole,
                                        const std::vector<const SectionPolygon*>& neighbours,
                                        double margin_mm, const Scaler& s) {
  using Clipper2Lib::Rect64;
  const Rect64 box = Clipper2Lib::GetBounds(whole);
  const std::int64_t pad = static_cast<std::int64_t>(2.0 * margin_mm * s.scale) + 1;
  const Rect64 near(box.left - pad, box.top - pad, box.right + pad, box.bottom + pad);
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
  return regions;
}

// `may_fail` asked with the common box of the section and the thinned neighbours: false when no
// region inside it can fail the caller's test.
bool common_box_may_fail(
    const Paths64& whole, const std::vector<Paths64>& regions, const Scaler& s,
    const std::function<bool(const Vec2& lo_mm, const Vec2& hi_mm)>& may_fail) {
  using Clipper2Lib::Rect64;
  Rect64 b = Clipper2Lib::GetBounds(whole);
  for (const Paths64& region : regions) {
    const Rect64 r = Clipper2Lib::GetBounds(region);
    b = Rect64(std::max(b.left, r.left), std::max(b.top, r.top), std::min(b.right, r.right),
               std::min(b.bottom, r.bottom));
  }
  b = grown(b, 2);  // Clipper2's intersections round to the nearest unit
  return b.right > b.left && b.bottom > b.top &&
         may_fail(s.from(Point64(b.left, b.top)), s.from(Point64(b.right, b.bottom)));
}

// The caller's test of a region the core is sure to hold: a rectangle inside the section and
// every (thinned) neighbour, joined to the origin (one pass over the edges, no intersection),
// then, when too small to tell, that rectangle with arms as deep as the edges allow. False when
// `worth` says no (on a section that is nearly all core this already fails the caller's test).
bool inner_rectangle_worth(const Paths64& whole,
                           const std::vector<const SectionPolygon*>& neighbours,
                           const std::vector<Paths64>& regions, const Point64& origin,
                           const Scaler& s,
                           const std::function<bool(const SectionPolygon& inner)>& worth) {
  std::vector<const Paths64*> all_regions{&whole};
  // (a neighbour given twice once: its edges would only be checked twice)
  for (std::size_t k = 0; k < regions.size(); ++k)
    if (std::find(neighbours.begin(), neighbours.begin() + k, neighbours[k]) ==
        neighbours.begin() + k)
      all_regions.push_back(&regions[k]);
  Clipper2Lib::Rect64 r;
  if (!rect_inside(all_regions, origin, r)) return true;
  SectionPolygon rect;
  rect.outer = {s.from(Point64(r.left, r.top)), s.from(Point64(r.right, r.top)),
                s.from(Point64(r.right, r.bottom)), s.from(Point64(r.left, r.bottom))};
  if (!worth(rect)) return false;
  const std::vector<Point64> armed = rect_with_arms(all_regions, r);
  if (armed.size() > 4) {
    rect.outer.clear();
    for (const Point64& q : armed) rect.outer.push_back(s.from(q));
    if (!worth(rect)) return false;
  }
  return true;
}

// The caller's test of what the core is sure to hold: the section (`part`) and the common part
// before widening (`covered`), around the origin. False when `worth` says no.
bool common_part_worth(const Paths64& part, const Paths64& covered, const Point64& origin,
                       const Scaler& s,
                       const std::function<bool(const SectionPolygon& inner)>& worth) {
  PolyTree64 inner;
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(part);
  clipper.AddClip(covered);
  clipper.Execute(Clipper2Lib::ClipType::Intersection, Clipper2Lib::FillRule::NonZero, inner);
  bool hollow = false;
  const PolyPath64* outer = locate(inner, origin, hollow);
  return outer == nullptr || hollow || worth(polygon_of(*outer, s));
}

// True when a trimmed piece is thin (no stub): it is not wider than 2 * opening anywhere (its
// erosion by `opening`, in Clipper2 units, is empty).
bool thin_piece(const Paths64& paths, double opening, const Scaler& s) {
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
}

// The trimmed material inside `band` (the part of the section worked on, `part`, less what the
// neighbours cover, `covered`: that is part less the core, in one operation -- see
// junction_core): a piece clear of the band's edge is a whole piece of what the section loses, and
// goes into `merged` when thin; a piece reaching the edge is part of one, which is a stub when
// the part already holds a disc of 1.1 x opening (see thin_piece: the thinned erosion keeps its
// centre). Returns false when some edge piece is no sure stub: then the pieces must be taken
// from the whole section.
bool add_thin_band_pieces(const Paths64& part, const Paths64& covered,
                          const Clipper2Lib::Rect64& band, double opening, const Scaler& s,
                          Paths64& merged) {
  Paths64 clip = covered;
  Clipper2Lib::Rect64 all_box = Clipper2Lib::GetBounds(part);
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
  const Vec2 hi(static_cast<double>(band.right) - inset, static_cast<double>(band.bottom) - inset);
  const Vec2 probes[8] = {{lo.x(), lo.y()},
                          {hi.x(), lo.y()},
                          {hi.x(), hi.y()},
                          {lo.x(), hi.y()},
                          {static_cast<double>(mid_x), lo.y()},
                          {hi.x(), static_cast<double>(mid_y)},
                          {static_cast<double>(mid_x), hi.y()},
                          {lo.x(), static_cast<double>(mid_y)}};
  for (const Paths64& paths : pieces) {
    const Clipper2Lib::Rect64 b = Clipper2Lib::GetBounds(paths.front());
    const bool edge = b.left <= band.left + 2 || b.right >= band.right - 2 ||
                      b.top <= band.top + 2 || b.bottom >= band.bottom - 2;
    if (!edge) {
      if (thin_piece(paths, opening, s)) merged.insert(merged.end(), paths.begin(), paths.end());
      continue;
    }
    bool stub = holds_centroid_disc(paths, disc);
    for (int k = 0; !stub && k < 8; ++k) stub = holds_disc(paths, probes[k], disc);
    if (!stub) return false;
  }
  return true;
}

// The region around the origin of the union of `merged` (the core and the thin pieces; one
// union, straight into the tree).
SectionGeometry region_around_origin(const Paths64& merged, const Point64& origin,
                                     const Scaler& s) {
  SectionGeometry geom;
  PolyTree64 tree;
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(merged);
  clipper.Execute(Clipper2Lib::ClipType::Union, Clipper2Lib::FillRule::NonZero, tree);
  bool hollow = false;
  if (const PolyPath64* outer = locate(tree, origin, hollow)) {
    if (hollow) geom.flags |= kFlagHollow;
    geom.polygon = polygon_of(*outer, s);
    geom.found = true;
  }
  return geom;
}

}  // namespace

SectionGeometry junction_core(
    const SectionPolygon& section, const std::vector<const SectionPolygon*>& neighbours,
    double margin_mm, double opening_mm,
    const std::function<bool(const SectionPolygon& inner)>& worth,
    const std::function<bool(const Vec2& lo_mm, const Vec2& hi_mm)>& may_fail) {
  using Clipper2Lib::FillRule;
  using Clipper2Lib::Rect64;
  const Scaler s(loops_of(section, neighbours));
  const Paths64 whole = paths_of(section, s);
  // What both neighbours cover (widened by the margin below).
  std::vector<Paths64> regions = thinned_neighbours(whole, neighbours, margin_mm, s);
  const Point64 origin = s.to(Vec2::Zero());
  // The caller is asked about regions the core is sure to hold (neither is asked when `may_fail`
  // says no region inside their common box can fail the test).
  const bool ask =
      worth && !regions.empty() && (!may_fail || common_box_may_fail(whole, regions, s, may_fail));
  if (ask && !inner_rectangle_worth(whole, neighbours, regions, origin, s, worth)) return {};
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
  if (ask && !covered.empty() && !common_part_worth(part, covered, origin, s, worth)) return {};
  if (margin_mm > 0) covered = offset(covered, margin_mm * s.scale);
  if (local && !covered.empty()) {
    const Rect64 b = Clipper2Lib::GetBounds(covered);
    local = b.left > inside.left && b.right < inside.right && b.top > inside.top &&
            b.bottom < inside.bottom;
  }
  if (!local) part = whole;
  const Paths64 core = Clipper2Lib::Intersect(part, covered, FillRule::NonZero);
  // The trimmed-off material, piece by piece: a piece is a stub (left out whole) only when it is
  // wider than 2 * opening somewhere; a thin piece (the rim of a taper, a tilted bone's
  // crescent) goes back into the core. With no opening every trimmed piece is a stub. The pieces
  // are the section less `covered` (the same set as less the core), in one Clipper2 operation:
  // the core's vertices where `covered` crosses the section's edges are rounded to its integer
  // grid, up to half a unit off those edges, and the section less the core kept slivers that
  // narrow along them, which could join a thin rim to a stub at a vertex of the section as
  // floating-point noise fell (issue 33/16: the sample figurine's thighs, 71.1 <-> 73.7 mm^2
  // under +-1e-6 x its size; docs/junctions.md).
  Paths64 merged = core;
  bool whole_pieces = !local;
  if (local && opening > 0 && !add_thin_band_pieces(part, covered, band, opening, s, merged)) {
    whole_pieces = true;
    merged = core;
  }
  if (whole_pieces) {
    for (const Paths64& paths : difference_pieces(whole, covered))
      if (thin_piece(paths, opening, s)) merged.insert(merged.end(), paths.begin(), paths.end());
  }
  return region_around_origin(merged, origin, s);
}

}  // namespace osteon
