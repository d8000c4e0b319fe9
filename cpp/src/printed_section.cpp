// The printed section (docs/printing.md, "The printed section"): walls, skins and sparse infill
// of an FDM print, or the shell of a hollowed resin print, in one section plane, and the
// transformed section's modulus.
//
// Geometry, for a part that is locally a prism along the section normal n, with b the build
// direction, theta = angle(n, b), e_s the unit projection of b into the plane and e_t the
// in-plane axis across it: a boundary point whose in-plane outward normal is w lies in the walls
// within in-plane depth t_w sqrt(1 - (w.b)^2) (the slicer insets each layer's contour by t_w in
// the layer plane, and the layer contour's normal is w's projection into that plane), which is
// the support function of the ellipse with semi-axes t_w cos(theta) along e_s and t_w along e_t:
// the walls are the cut minus its erosion by that ellipse (an isotropic inset by t_w where s is
// stretched by 1 / cos(theta)). A point lies in a skin when the layers within the skin depth t_s
// above or below do not cover it (PrusaSlicer's top/bottom solid layers): in the plane those
// layers are the cut shifted by t_s sin(theta) along e_s. Islands of the sparse region whose
// layer area (section area / cos(theta)) is under solid_infill_below_area are filled solid.
#include "osteon/printed_section.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "clipper2/clipper.h"
#include "round_to_unit.hpp"
#include "simplify_path.hpp"
#include "skin_growth.hpp"
#include "wall_inset.hpp"
#include "winding_region.hpp"

namespace osteon {
namespace {

using detail::round_to_unit;

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::PolyPath64;

constexpr double kScale = 1e4;  // Clipper units per mm (0.1 um)
// Smallest cos(theta) used: a section nearly along the build direction erodes by an ellipse
// 1000 times flatter than its walls (the walls' depth along e_s is then t_w / 1000).
constexpr double kMinCos = 1e-3;
constexpr double kSimplify = 0.005;  // mm: the outline is simplified within this before offsets

// OSTEON_PRINTED_CLIPPER=1 in the environment: the walls' inset and the skins and islands by
// Clipper2's own passes only, the reference that the faster paths (wall_inset.hpp,
// winding_region.hpp) are checked against (bench/compare_printed.py,
// tests/python/test_printed_sections.py).
bool clipper_reference() {
  const char* v = std::getenv("OSTEON_PRINTED_CLIPPER");
  return v != nullptr && v[0] == '1';
}

// The section's loops in Clipper units of the (s, t) axes; outer boundary counter-clockwise,
// holes clockwise (what Clipper's offset expects).
Paths64 to_clipper(const SectionPolygon& cut, const Vec2& es, const Vec2& et) {
  Paths64 out;
  auto add = [&](const std::vector<Vec2>& loop, bool hole) {
    if (loop.size() < 3) return;
    Path64 path;
    path.reserve(loop.size());
    for (const Vec2& p : loop)
      path.emplace_back(round_to_unit(p.dot(es) * kScale), round_to_unit(p.dot(et) * kScale));
    if ((Clipper2Lib::Area(path) > 0) == hole) std::reverse(path.begin(), path.end());
    out.push_back(std::move(path));
  };
  add(cut.outer, false);
  for (const auto& hole : cut.holes) add(hole, true);
  return out;
}

// Stretches s by `stretch` (Clipper units; 1 / stretch undoes it).
Paths64 stretched(Paths64 paths, double stretch) {
  if (stretch != 1.0)
    for (Path64& path : paths)
      for (auto& q : path) q.x = round_to_unit(static_cast<double>(q.x) * stretch);
  return paths;
}

double area_mm2(const Paths64& paths) { return Clipper2Lib::Area(paths) / (kScale * kScale); }

std::vector<Vec2> to_plane(const Path64& path, const Vec2& es, const Vec2& et) {
  std::vector<Vec2> loop(path.size());
  for (std::size_t k = 0; k < path.size(); ++k)
    loop[k] = (static_cast<double>(path[k].x) * es + static_cast<double>(path[k].y) * et) / kScale;
  return loop;
}

// True when no point of the region of `paths` (outer boundaries counter-clockwise, holes
// clockwise, non-overlapping) lies `depth` (units) or more inside it, i.e. its inset by `depth`
// is empty, proven by its second moments: a region holding a disc of radius r has, about its
// own centroid, a second moment of at least pi r^4 / 4 in every direction (the disc's about its
// centre; the parallel axes and the rest of the region only add), so r <= (4 lambda_min /
// pi)^(1/4); and its extent across any direction is at least 2 r (the minor principal axis
// is taken). The moments are summed about the first vertex (no cancellation of large
// coordinates); the test keeps a relative margin of 1e-6 for their rounding.
bool thinner_than(const Paths64& paths, double depth) {
  if (!(depth > 0) || paths.empty() || paths[0].empty()) return false;
  const double x0 = static_cast<double>(paths[0][0].x), y0 = static_cast<double>(paths[0][0].y);
  double a = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;  // twice, 6x, 12x, 12x, 24x
  for (const Path64& path : paths)
    for (std::size_t k = 0; k < path.size(); ++k) {
      const auto& p = path[k];
      const auto& q = path[k + 1 == path.size() ? 0 : k + 1];
      const double px = static_cast<double>(p.x) - x0, py = static_cast<double>(p.y) - y0;
      const double qx = static_cast<double>(q.x) - x0, qy = static_cast<double>(q.y) - y0;
      const double cross = px * qy - qx * py;
      a += cross;
      sx += cross * (px + qx);
      sy += cross * (py + qy);
      sxx += cross * (px * px + px * qx + qx * qx);
      syy += cross * (py * py + py * qy + qy * qy);
      sxy += cross * (px * qy + 2 * px * py + 2 * qx * qy + qx * py);
    }
  const double area = a / 2;
  if (!(area > 0)) return false;
  const double cx = sx / 6 / area, cy = sy / 6 / area;
  const double jxx = sxx / 12 - area * cx * cx, jyy = syy / 12 - area * cy * cy;
  const double jxy = sxy / 24 - area * cx * cy;
  const double mean = 0.5 * (jxx + jyy), half = std::hypot(0.5 * (jxx - jyy), jxy);
  const double lambda_min = mean - half;  // the smaller principal second moment
  const double disc = M_PI / 4 * depth * depth * depth * depth;
  if (lambda_min < disc * (1 - 1e-6) - 1e-6 * (mean + half)) return true;
  // The region's extent across the minor principal axis (e), which a disc of radius r
  // needs to be at least 2 r: thin long sections, whose moments the length makes large.
  // (any direction bounds r; the minor axis (-jxy, jxx - lambda_min) bounds it best)
  const double ax = -jxy, ay = 0.5 * (jxx - jyy) + half, norm = std::hypot(ax, ay);
  const double ux = norm > 0 ? ax / norm : 1.0, uy = norm > 0 ? ay / norm : 0.0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Path64& path : paths)
    for (const auto& p : path) {
      const double d = (static_cast<double>(p.x) - x0) * ux + (static_cast<double>(p.y) - y0) * uy;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  return hi - lo < 2 * depth * (1 - 1e-9);
}

// Whether thinner_than is worth asking: the cut's own second moments (before the outline's
// simplification), in the stretched (s, t) axes (a stretch k of s scales J_ss by k^3, J_st by
// k^2 and J_tt by k), under twice the disc's of radius `depth` (mm). Only a filter: where it
// says no, the inset is computed as always (the bound of the outline as offset decides).
bool may_be_thinner(const SectionProperties& solid, const Vec2& es, const Vec2& et, double k,
                    double depth) {
  const Mat2& j = solid.second_moment;
  const double jss = k * k * k * es.dot(j * es), jtt = k * et.dot(j * et);
  const double jst = k * k * es.dot(j * et);
  const double lambda_min = 0.5 * (jss + jtt) - std::hypot(0.5 * (jss - jtt), jst);
  // A region of extent w across a direction has a second moment of at most area w^2 / 4
  // across it (a variance over an interval of length w), so w >= 2 sqrt(lambda_min / area).
  return lambda_min < 2.0 * M_PI / 4 * depth * depth * depth * depth ||
         lambda_min < 1.1 * k * solid.area * depth * depth;
}

// Moments of a set of regions about a reference point c: area, first moment, second moment.
struct Moments {
  double area = 0.0;
  Vec2 first = Vec2::Zero();
  Mat2 second = Mat2::Zero();
  void add(const SectionProperties& p, const Vec2& c, double sign = 1.0) {
    if (!(p.area > 0)) return;
    const Vec2 d = p.centroid - c;
    area += sign * p.area;
    first += sign * p.area * d;
    second += sign * (p.second_moment + p.area * d * d.transpose());
  }
};

// The islands of a Clipper tree (an outer boundary and its holes each; islands in holes too),
// those whose layer area is at least `min_area` (mm^2) kept, in plane coordinates.
void collect_islands(const PolyPath64& node, double layer_per_section, double min_area,
                     const Vec2& es, const Vec2& et, std::vector<SectionPolygon>& islands) {
  for (const auto& outer : node) {
    double a = Clipper2Lib::Area(outer->Polygon());
    for (const auto& hole : *outer) a += Clipper2Lib::Area(hole->Polygon());
    if (a / (kScale * kScale) * layer_per_section >= min_area) {
      SectionPolygon island;
      island.outer = to_plane(outer->Polygon(), es, et);
      for (const auto& hole : *outer) island.holes.push_back(to_plane(hole->Polygon(), es, et));
      islands.push_back(std::move(island));
    }
    for (const auto& hole : *outer)
      collect_islands(*hole, layer_per_section, min_area, es, et, islands);
  }
}

// 1 when p lies inside the loop, 0 outside, -1 on it (crossings of the ray +x, exact).
int encloses(const Path64& loop, const Clipper2Lib::Point64& p) {
  bool in = false;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const auto& a = loop[k];
    const auto& b = loop[k + 1 == loop.size() ? 0 : k + 1];
    if ((a.y > p.y) == (b.y > p.y)) {
      if (a.y == p.y && b.y == p.y && std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x))
        return -1;
      continue;
    }
    const double side = static_cast<double>(b.x - a.x) * static_cast<double>(p.y - a.y) -
                        static_cast<double>(b.y - a.y) * static_cast<double>(p.x - a.x);
    if (side == 0) return -1;
    if ((side > 0) == (b.y > a.y)) in = !in;
  }
  return in ? 1 : 0;
}

// collect_islands for loops that neither cross nor overlap (a union's result: outer boundaries
// positive, holes negative): each hole belongs to the smallest outer boundary around it, which
// is Clipper2's tree. False where a hole has no outer boundary around it.
bool collect_loops(const Paths64& loops, double layer_per_section, double min_area, const Vec2& es,
                   const Vec2& et, std::vector<SectionPolygon>& islands) {
  const std::size_t n = loops.size();
  std::vector<double> area(n), total(n);
  for (std::size_t i = 0; i < n; ++i) total[i] = area[i] = Clipper2Lib::Area(loops[i]);
  std::vector<std::ptrdiff_t> parent(n, -1);
  for (std::size_t h = 0; h < n; ++h) {
    if (!(area[h] < 0)) continue;
    for (std::size_t o = 0; o < n; ++o) {
      if (!(area[o] > 0) ||
          (parent[h] >= 0 && area[o] >= area[static_cast<std::size_t>(parent[h])]))
        continue;
      int inside = -1;  // a vertex of the hole off the outer boundary decides
      for (std::size_t k = 0; k < loops[h].size() && inside < 0; ++k)
        inside = encloses(loops[o], loops[h][k]);
      if (inside == 1) parent[h] = static_cast<std::ptrdiff_t>(o);
    }
    if (parent[h] < 0) return false;
    total[static_cast<std::size_t>(parent[h])] += area[h];
  }
  for (std::size_t o = 0; o < n; ++o) {
    if (!(area[o] > 0) || !(total[o] / (kScale * kScale) * layer_per_section >= min_area)) continue;
    SectionPolygon island;
    island.outer = to_plane(loops[o], es, et);
    for (std::size_t h = 0; h < n; ++h)
      if (parent[h] == static_cast<std::ptrdiff_t>(o))
        island.holes.push_back(to_plane(loops[h], es, et));
    islands.push_back(std::move(island));
  }
  return true;
}

// inset ∩ (cut shifted by +shift) ∩ (cut shifted by -shift): Clipper2's intersection below.
bool in_both_shifted(const detail::Windings& w) { return w[0] > 0 && w[1] + w[2] - 1 > 0; }

// Skins under the surfaces at most `max_slope` steep from the layer plane: each such boundary
// edge swept `depth` into the section along the in-plane build axis s (Clipper units, s not
// stretched). The surface's slope follows from its in-plane normal w: |w.b| = |w_s| sin(theta).
Paths64 flat_skins(const Paths64& section, double depth, double sin_theta, double max_slope) {
  Paths64 quads;
  const double min_cos = std::cos(max_slope);
  for (const Path64& loop : section) {
    // Outer loops run counter-clockwise and holes clockwise: the material is on the left.
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const auto& p = loop[k];
      const auto& q = loop[k + 1 == loop.size() ? 0 : k + 1];
      const double dx = static_cast<double>(q.x - p.x), dy = static_cast<double>(q.y - p.y);
      const double len = std::hypot(dx, dy);
      if (!(len > 0)) continue;
      const double ws = dy / len;  // outward normal (dy, -dx) / len, its s component
      if (std::abs(ws) * sin_theta < min_cos) continue;
      const auto shift = static_cast<std::int64_t>(std::llround(ws > 0 ? -depth : depth));
      quads.push_back({p, q, {q.x + shift, q.y}, {p.x + shift, p.y}});
    }
  }
  return Clipper2Lib::Union(quads, Clipper2Lib::FillRule::NonZero);
}

// flat_skins' quads as one polygon per run of consecutive edges with the same shift: such a
// run is strictly monotone in t (its edges' t steps all have the sign of w_s), so the union of
// its quads is the region between the run and its copy shifted along s, a simple
// counter-clockwise polygon (the run up or down t on the side away from the shift).
Paths64 flat_skin_sweeps(const Paths64& section, double depth, double sin_theta, double max_slope) {
  Paths64 out;
  const double min_cos = std::cos(max_slope);
  std::vector<std::int64_t> shift;
  for (const Path64& loop : section) {
    const std::size_t n = loop.size();
    shift.assign(n, 0);
    for (std::size_t k = 0; k < n; ++k) {
      const auto& p = loop[k];
      const auto& q = loop[k + 1 == n ? 0 : k + 1];
      const double dx = static_cast<double>(q.x - p.x), dy = static_cast<double>(q.y - p.y);
      const double len = std::hypot(dx, dy);
      if (!(len > 0)) continue;
      const double ws = dy / len;
      if (std::abs(ws) * sin_theta < min_cos) continue;
      shift[k] = static_cast<std::int64_t>(std::llround(ws > 0 ? -depth : depth));
    }
    std::size_t k0 = 0;  // the first edge of a run
    while (k0 < n && (shift[k0] == 0 || shift[k0] == shift[(k0 + n - 1) % n])) ++k0;
    if (k0 == n) continue;  // no edge under a flat surface (a closed loop cannot be one run)
    for (std::size_t i = 0; i < n;) {
      const std::size_t k = (k0 + i) % n;
      std::size_t r = 1;
      while (i + r < n && shift[(k + r) % n] == shift[k]) ++r;
      if (shift[k] != 0) {
        Path64 sweep;
        sweep.reserve(2 * (r + 1));
        for (std::size_t j = 0; j <= r; ++j) sweep.push_back(loop[(k + j) % n]);
        for (std::size_t j = r + 1; j-- > 0;)
          sweep.emplace_back(loop[(k + j) % n].x + shift[k], loop[(k + j) % n].y);
        out.push_back(std::move(sweep));
      }
      i += r;
    }
  }
  return out;
}

// The inset less the flat surfaces' skins: Clipper2's difference below (both non-zero).
bool outside_flat_skins(const detail::Windings& w) { return w[0] != 0 && w[1] == 0; }

// The paths with each run of consecutive vertices beyond one side of `box` (all left of it, or
// all right of it, or all above or below it) shortened to the run's first and last vertex: the
// segment between them stays beyond that side, so every winding number inside the box is the
// same (a path wholly beyond one side winds 0 about it and goes). Where the region sought lies
// in the box (in the inset), the skins' crossings of the cut's copies beyond it are not paid.
Paths64 collapsed_outside(const Paths64& paths, const Clipper2Lib::Rect64& box) {
  auto side = [&box](const Clipper2Lib::Point64& p) {
    return p.x < box.left ? 1 : p.x > box.right ? 2 : p.y < box.top ? 3 : p.y > box.bottom ? 4 : 0;
  };
  Paths64 out;
  std::vector<int> code;
  for (const Path64& path : paths) {
    const std::size_t n = path.size();
    code.resize(n);
    for (std::size_t k = 0; k < n; ++k) code[k] = side(path[k]);
    std::size_t k0 = 0;  // a run's first vertex
    while (k0 < n && code[k0] == code[(k0 + n - 1) % n]) ++k0;
    if (k0 == n) {
      if (n > 0 && code[0] == 0) out.push_back(path);
      continue;
    }
    Path64 q;
    q.reserve(n);
    for (std::size_t i = 0; i < n;) {
      const std::size_t k = (k0 + i) % n;
      std::size_t r = 1;
      if (code[k] != 0)
        while (i + r < n && code[(k + r) % n] == code[k]) ++r;
      q.push_back(path[k]);
      if (r >= 2) q.push_back(path[(k + r - 1) % n]);
      i += r;
    }
    if (q.size() >= 3) out.push_back(std::move(q));
  }
  return out;
}

// The inset's loops less its outer boundaries of area under `limit` (units^2: the section area
// of min_area less a margin), and less the holes when no outer boundary is left. Exact for the
// skins' islands: an island lies inside one outer boundary of the inset (the skins only remove
// material), so its area is at most that boundary's (holes only subtract), plus what rounding its
// crossings to units adds (under one unit times its perimeter: the margin, 1e-3 of min_area, is 7e6
// units^2 at 70 mm^2, i.e. an island 700 mm long inside a boundary of under 70 mm^2), so it falls
// under the small-area rule anyway. Removing the boundary changes the winding numbers only inside
// it (islands there, nested ones included, are smaller still), and its crossings only split pieces
// that bound none of the islands left (the inset's loops do not touch). The caller's box then
// bounds the islands left, and the shifted cuts are shortened to it.
Paths64 without_small_outers(const Paths64& eroded, double limit) {
  Paths64 kept;
  bool any_outer = false;
  for (const Path64& path : eroded) {
    const double a = Clipper2Lib::Area(path);
    if (a > 0 && a < limit) continue;
    any_outer |= a > 0;
    kept.push_back(path);
  }
  if (!any_outer) kept.clear();
  return kept;
}

// sparse_islands by winding_region and collect_loops; false where the loops are not in
// general position.
bool islands_by_winding(const Paths64& section, const Paths64& eroded, std::int64_t shift,
                        double sin_theta, double max_slope, double layer_per_section,
                        double min_area, const Vec2& es, const Vec2& et,
                        std::vector<SectionPolygon>& islands) {
  if (shift == 0) return collect_loops(eroded, layer_per_section, min_area, es, et, islands);
  // With the small-area rule: the inset less its small outer boundaries (copied only if any).
  const double small = (1.0 - 1e-3) * min_area / layer_per_section * kScale * kScale;  // units^2
  const bool drop =
      small > 0 && std::any_of(eroded.begin(), eroded.end(), [small](const Path64& path) {
        const double a = Clipper2Lib::Area(path);
        return a > 0 && a < small;
      });
  const Paths64 kept = drop ? without_small_outers(eroded, small) : Paths64{};
  const Paths64& inset = drop ? kept : eroded;
  if (inset.empty()) return true;  // every island would be under min_area: none is sparse
  Paths64 region;
  Clipper2Lib::Rect64 box = Clipper2Lib::GetBounds(inset);  // the region lies in the inset
  box.left -= 2, box.top -= 2, box.right += 2, box.bottom += 2;
  if (max_slope >= M_PI / 2) {
    const Paths64 up = collapsed_outside(Clipper2Lib::TranslatePaths(section, shift, 0), box);
    const Paths64 down = collapsed_outside(Clipper2Lib::TranslatePaths(section, -shift, 0), box);
    return detail::winding_region({&inset, &up, &down}, in_both_shifted, region) &&
           collect_loops(region, layer_per_section, min_area, es, et, islands);
  }
  const Paths64 sweeps = collapsed_outside(
      flat_skin_sweeps(section, static_cast<double>(shift), sin_theta, max_slope), box);
  return detail::winding_region({&inset, &sweeps}, outside_flat_skins, region) &&
         collect_loops(region, layer_per_section, min_area, es, et, islands);
}

// The sparse islands (those whose layer area is at least min_area, mm^2): the inset less the
// skins, where the layers within skin_depth above and below (the cut shifted by
// +-skin_depth sin(theta) = `shift` along s, 0: no skins) do not both cover the point. The
// inset's own loops, or winding_region's intersection, where they are in general position;
// Clipper2's boolean pass otherwise (and for skins under flat surfaces only).
void sparse_islands(bool reference, const Paths64& section, const Paths64& eroded,
                    std::int64_t shift, double sin_theta, double max_slope,
                    double layer_per_section, double min_area, const Vec2& es, const Vec2& et,
                    std::vector<SectionPolygon>& islands) {
  const bool all_slopes = max_slope >= M_PI / 2;
  if (!reference && islands_by_winding(section, eroded, shift, sin_theta, max_slope,
                                       layer_per_section, min_area, es, et, islands))
    return;
  islands.clear();
  Clipper2Lib::Clipper64 clipper;
  clipper.AddSubject(eroded);
  if (shift > 0 && all_slopes) {
    // inset ∩ shifted ∩ shifted in one pass (no boolean for the two shifted cuts first): the
    // clip is both shifted cuts (winding 1 in each's material) and a reversed box around them
    // (winding -1 everywhere), so the clip's winding is positive where both cover the point.
    clipper.AddClip(Clipper2Lib::TranslatePaths(section, shift, 0));
    clipper.AddClip(Clipper2Lib::TranslatePaths(section, -shift, 0));
    const Clipper2Lib::Rect64 box = Clipper2Lib::GetBounds(section);
    const std::int64_t pad = shift + 1;
    clipper.AddClip(Paths64{{{box.left - pad, box.top - pad},
                             {box.left - pad, box.bottom + pad},
                             {box.right + pad, box.bottom + pad},
                             {box.right + pad, box.top - pad}}});
  } else if (shift > 0)
    clipper.AddClip(flat_skins(section, static_cast<double>(shift), sin_theta, max_slope));
  Clipper2Lib::PolyTree64 tree;
  const auto op = shift == 0   ? Clipper2Lib::ClipType::Union
                  : all_slopes ? Clipper2Lib::ClipType::Intersection
                               : Clipper2Lib::ClipType::Difference;
  clipper.Execute(
      op,
      shift > 0 && all_slopes ? Clipper2Lib::FillRule::Positive : Clipper2Lib::FillRule::NonZero,
      tree);
  collect_islands(tree, layer_per_section, min_area, es, et, islands);
}

detail::StLoops st_loops(const Paths64& paths) {
  detail::StLoops out;
  out.reserve(paths.size());
  for (const Path64& path : paths) {
    std::vector<Vec2> loop;
    loop.reserve(path.size());
    for (const auto& q : path)
      loop.emplace_back(static_cast<double>(q.x) / kScale, static_cast<double>(q.y) / kScale);
    out.push_back(std::move(loop));
  }
  return out;
}

// Narrow skins widened into the sparse islands (skin_growth.hpp): their strips leave `sparse`.
void remove_widened_skins(const Paths64& section, const Paths64& eroded,
                          const std::vector<SectionPolygon>& islands, double sin_theta,
                          const PrintOptions& options, const Vec2& es, const Vec2& et,
                          const Vec2& centre, Moments& sparse) {
  detail::StLoops kept;
  auto add = [&](const std::vector<Vec2>& loop) {
    std::vector<Vec2> st(loop.size());
    for (std::size_t k = 0; k < loop.size(); ++k) st[k] = Vec2(loop[k].dot(es), loop[k].dot(et));
    kept.push_back(std::move(st));
  };
  for (const SectionPolygon& island : islands) {
    add(island.outer);
    for (const auto& hole : island.holes) add(hole);
  }
  // Skin layers, at most the rows a section may have (widened_skin_strips' max_rows).
  const int layers =
      static_cast<int>(std::lround(std::min(options.skin_depth / options.layer_height, 20000.0)));
  const auto strips =
      detail::widened_skin_strips(st_loops(section), st_loops(eroded), kept,
                                  options.layer_height / sin_theta, layers, options.skin_growth);
  Mat2 axes;
  axes.col(0) = es;
  axes.col(1) = et;
  for (const auto& r : strips) {
    const double ds = r.s1 - r.s0, dt = r.t1 - r.t0;
    SectionProperties p;
    p.area = ds * dt;
    p.centroid = 0.5 * (r.s0 + r.s1) * es + 0.5 * (r.t0 + r.t1) * et;
    const Vec2 diag(p.area * ds * ds / 12.0, p.area * dt * dt / 12.0);
    p.second_moment = axes * diag.asDiagonal() * axes.transpose();
    sparse.add(p, centre, -1.0);
  }
}

// W of the transformed section (whole cut minus (1 - eta) x the sparse islands) at the cut's
// own boundary points (the solid fibres); 0 when degenerate.
double transformed_modulus(const SectionPolygon& cut, const SectionProperties& solid,
                           const Moments& sparse, double eta) {
  const double k = 1.0 - eta;
  const double area = solid.area - k * sparse.area;
  if (!(area > 1e-12 * solid.area)) return 0.0;
  const Vec2 shift = -k * sparse.first / area;  // centroid of the transformed section - solid's
  const Mat2 J = solid.second_moment - k * sparse.second - area * shift * shift.transpose();
  const double det = J.determinant();
  if (!(det > 1e-14 * J(0, 0) * J(1, 1)) || !(J(0, 0) > 0) || !(J(1, 1) > 0)) return 0.0;
  const Mat2 Jinv = J.inverse();
  const Vec2 c = solid.centroid + shift;
  double peak = 0.0;
  auto scan = [&](const std::vector<Vec2>& loop) {
    for (const Vec2& p : loop) peak = std::max(peak, (Jinv * (p - c)).squaredNorm());
  };
  scan(cut.outer);
  for (const auto& hole : cut.holes) scan(hole);
  return peak > 0 ? 1.0 / std::sqrt(peak) : 0.0;
}

}  // namespace

void validate_print_options(const PrintOptions& o) {
  if (o.kind != PrintOptions::kSolid && o.kind != PrintOptions::kLayered &&
      o.kind != PrintOptions::kShell)
    throw std::invalid_argument("print kind must be 0 (solid), 1 (FDM) or 2 (resin shell)");
  auto length = [](double v, const char* what) {
    if (!(v >= 0) || !std::isfinite(v))
      throw std::invalid_argument(std::string(what) + " must be a finite number >= 0");
  };
  length(o.wall_depth, "print wall depth (mm)");
  length(o.skin_depth, "print skin depth (mm)");
  length(o.solid_infill_below_area, "print solid_infill_below_area (mm^2)");
  length(o.skin_max_slope, "print skin_max_slope (radians)");
  length(o.layer_height, "print layer height (mm)");
  length(o.skin_growth, "print skin growth (mm)");
  if (!(o.infill_build >= 0 && o.infill_build <= 1) ||
      !(o.infill_layer >= 0 && o.infill_layer <= 1))
    throw std::invalid_argument("print infill stiffness fractions must be within 0..1");
}

double infill_stiffness(double cos_theta, double eta_build, double eta_layer) {
  const double c2 = std::min(cos_theta * cos_theta, 1.0), s2 = 1.0 - c2;
  if ((c2 > 0 && !(eta_build > 0)) || (s2 > 0 && !(eta_layer > 0))) return 0.0;
  const double compliance = (c2 > 0 ? c2 / eta_build : 0.0) + (s2 > 0 ? s2 / eta_layer : 0.0);
  return compliance > 0 ? 1.0 / compliance : 1.0;
}

PrintedSection printed_section(const SectionPolygon& cut, const SectionProperties& solid,
                               const Vec2& build_in_plane, double cos_theta,
                               const PrintOptions& options, bool keep_sparse) {
  PrintedSection out;
  const bool reference = clipper_reference();
  const bool layered = options.kind == PrintOptions::kLayered;
  const double c = std::clamp(std::abs(cos_theta), 0.0, 1.0);
  const double sin_theta = std::sqrt(std::max(0.0, 1.0 - c * c));
  // In-plane axes: s along the build direction's projection (any axis when it has none).
  const double b_len = build_in_plane.norm();
  const Vec2 es = layered && b_len > 1e-12 ? Vec2(build_in_plane / b_len) : Vec2(1.0, 0.0);
  const Vec2 et(-es.y(), es.x());
  const double stretch = layered ? 1.0 / std::max(c, kMinCos) : 1.0;
  // The cut's outline within kSimplify of it (a mesh cut is finely faceted; the slicer
  // itself simplifies its slices to ~0.01 mm): what the offsets cost scales with its vertices.
  // A shell's outline within its round joins' own tolerance (1 % of its depth: 0.02 mm for a
  // 2 mm shell), as precise as its inset: no rule of the shell has a threshold, so W moves
  // smoothly (<= 2.4e-3 of W on tests/data); FDM keeps kSimplify, where a coarser outline moves
  // islands across the small-area and widening thresholds (docs/performance.md, print8).
  Paths64 section = to_clipper(cut, es, et);
  const double simplify = options.kind == PrintOptions::kShell
                              ? std::max(kSimplify, 0.01 * options.wall_depth)
                              : kSimplify;
  for (Path64& path : section) path = detail::simplify_closed(path, simplify * kScale);
  // Walls: the cut eroded by the wall ellipse (FDM) or by the shell (resin), as an isotropic
  // inset in stretched coordinates; round joins within 0.005 mm or 1 % of the depth.
  Paths64 eroded = section;
  double wall_reach = 0.0;  // Clipper units along s that every inset point keeps inside the cut
  if (options.wall_depth > 0) {
    const double delta = options.wall_depth * kScale;
    const double arc_tolerance = std::max(0.005 * kScale, 0.01 * delta);
    const Paths64 wide = stretched(section, stretch);
    if (!reference && may_be_thinner(solid, es, et, stretch, options.wall_depth) &&
        thinner_than(wide, delta - arc_tolerance - 4.0))
      eroded.clear();  // no point lies that deep inside: all walls, no inset to compute
    else
      eroded = stretched(
          reference ? Clipper2Lib::InflatePaths(wide, -delta, Clipper2Lib::JoinType::Round,
                                                Clipper2Lib::EndType::Polygon, 2.0, arc_tolerance)
                    : detail::wall_inset(wide, delta, arc_tolerance),
          1.0 / stretch);
    // Less the arcs' chords and 4 units for the rounding of the stretch there and back.
    wall_reach = (delta - arc_tolerance) / stretch - 4.0;
  }
  const auto shift =
      static_cast<std::int64_t>(std::llround(options.skin_depth * sin_theta * kScale));
  // Skins that the walls already hold leave the sparse region as it is: an inset point q keeps
  // q + l e_s inside the cut for |l| <= wall_reach (the wall ellipse's half-axis along s is
  // wall_depth cos(theta), i.e. delta / stretch; the flattened round joins come at most
  // arc_tolerance closer to the boundary), so with shift <= wall_reach the interior of the inset
  // lies in both shifted cuts (all slopes: inset ∩ shifted ∩ shifted = inset) and meets no
  // swept edge quad (flat_skins: a point q of a quad has q -+ mu e_s on the boundary, mu <=
  // shift, which an interior inset point cannot have). Exact up to measure zero, so the same
  // region: the Clipper passes of the skins are skipped (most sections of a limb along the
  // build direction: tan(theta) <= wall_depth / skin_depth).
  const bool skins = layered && shift > 0 && static_cast<double>(shift) > wall_reach;
  const double layer_per_section = layered ? 1.0 / std::max(c, kMinCos) : 1.0;
  const double min_area = layered ? options.solid_infill_below_area : 0.0;
  const double eroded_area = std::min(area_mm2(eroded), solid.area);
  out.infill_eta = layered ? infill_stiffness(c, options.infill_build, options.infill_layer)
                           : std::clamp(options.infill_build, 0.0, 1.0);
  out.wall_area = solid.area - eroded_area;
  std::vector<SectionPolygon> islands;
  Moments sparse;
  const auto outers = std::count_if(eroded.begin(), eroded.end(),
                                    [](const Path64& p) { return Clipper2Lib::Area(p) > 0; });
  if (!skins && (outers <= 1 || !(min_area > 0))) {
    // The inset is the sparse region (one island, or no small-area rule): its loops as they
    // are (outer boundaries positive, holes negative), no Clipper pass more.
    if (!(outers == 1 && eroded_area * layer_per_section < min_area))
      for (const Path64& path : eroded) {
        SectionPolygon loop{to_plane(path, es, et), {}};
        sparse.add(section_properties(loop), solid.centroid,
                   Clipper2Lib::Area(path) > 0 ? 1.0 : -1.0);
        if (keep_sparse) out.sparse.push_back(std::move(loop.outer));
      }
    out.infill_area = std::clamp(sparse.area, 0.0, eroded_area);
    out.skin_area = eroded_area - out.infill_area;
    out.modulus = transformed_modulus(cut, solid, sparse, out.infill_eta);
    out.valid = out.modulus > 0 && std::isfinite(out.modulus);
    return out;
  }
  // Skins, and small islands solid: PrusaSlicer's solid_infill_below_area, on the layer's area.
  // (No inset: no island, the section is all walls.)
  if (!eroded.empty())
    sparse_islands(reference, section, eroded, skins ? shift : 0, sin_theta, options.skin_max_slope,
                   layer_per_section, min_area, es, et, islands);
  for (const SectionPolygon& island : islands)
    sparse.add(section_properties(island), solid.centroid);
  if (skins && !islands.empty() && options.skin_growth > 0 && options.layer_height > 0 &&
      sin_theta > 1e-6)
    remove_widened_skins(section, eroded, islands, sin_theta, options, es, et, solid.centroid,
                         sparse);
  out.infill_area = std::min(sparse.area, eroded_area);
  out.skin_area = eroded_area - out.infill_area;
  out.modulus = transformed_modulus(cut, solid, sparse, out.infill_eta);
  out.valid = out.modulus > 0 && std::isfinite(out.modulus);
  if (keep_sparse)
    for (SectionPolygon& island : islands) {
      out.sparse.push_back(std::move(island.outer));
      for (auto& hole : island.holes) out.sparse.push_back(std::move(hole));
    }
  return out;
}

}  // namespace osteon
