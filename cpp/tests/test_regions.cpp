#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "clipper2/clipper.h"
#include "junction_core.hpp"
#include "loose_pieces.hpp"
#include "osteon/analysis.hpp"
#include "osteon/section.hpp"
#include "osteon/slicer.hpp"
#include "region_choice.hpp"
#include "simplify_path.hpp"
#include "test_helpers.hpp"
#include "thickness.hpp"

using namespace osteon;
using osteon::testing::OwnedMesh;
using osteon::testing::prism;
using osteon::testing::rectangle;
using osteon::testing::regular_polygon;

namespace {

// Appends mesh b (optionally with its faces reversed, i.e. facing inward) to a.
void append(OwnedMesh& a, const OwnedMesh& b, bool reversed = false) {
  const std::int32_t base = static_cast<std::int32_t>(a.v.size() / 3);
  a.v.insert(a.v.end(), b.v.begin(), b.v.end());
  for (std::size_t f = 0; f < b.f.size(); f += 3) {
    if (reversed)
      a.f.insert(a.f.end(), {base + b.f[f], base + b.f[f + 2], base + b.f[f + 1]});
    else
      a.f.insert(a.f.end(), {base + b.f[f], base + b.f[f + 1], base + b.f[f + 2]});
  }
}

OwnedMesh shifted(OwnedMesh m, const Vec3& d) {
  for (std::size_t i = 0; i < m.v.size(); i += 3)
    for (int k = 0; k < 3; ++k) m.v[i + k] += d[k];
  return m;
}

// Signed volume by the divergence theorem: > 0 when the faces face outward.
double signed_volume(const OwnedMesh& m) {
  double vol = 0;
  for (std::size_t f = 0; f < m.f.size(); f += 3) {
    const Vec3 a(&m.v[3 * m.f[f]]), b(&m.v[3 * m.f[f + 1]]), c(&m.v[3 * m.f[f + 2]]);
    vol += a.dot(b.cross(c)) / 6;
  }
  return vol;
}

// The helper's prism faces inward; this one faces outward (positive volume).
OwnedMesh outward_prism(const std::vector<Vec2>& poly, double length) {
  OwnedMesh m;
  append(m, prism(poly, length), true);
  return m;
}

double polygon_area(const std::vector<Vec2>& p) { return std::abs(signed_area(p)); }

// Sutherland-Hodgman: the intersection of two convex counter-clockwise polygons.
std::vector<Vec2> clip_convex(std::vector<Vec2> subject, const std::vector<Vec2>& clip) {
  for (std::size_t e = 0; e < clip.size(); ++e) {
    const Vec2 a = clip[e], b = clip[(e + 1) % clip.size()];
    auto side = [&](const Vec2& p) {
      return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
    };
    std::vector<Vec2> out;
    for (std::size_t i = 0; i < subject.size(); ++i) {
      const Vec2 p = subject[i], q = subject[(i + 1) % subject.size()];
      const double sp = side(p), sq = side(q);
      if (sp >= 0) out.push_back(p);
      if ((sp >= 0) != (sq >= 0)) out.push_back(p + (sp / (sp - sq)) * (q - p));
    }
    subject = out;
  }
  return subject;
}

// Area, first and second moments (about the origin) of a polygon, by triangle fans: a different
// formula from section.cpp's Green's-theorem sums.
struct Moments {
  double a = 0, sx = 0, sy = 0, xx = 0, yy = 0, xy = 0;
};
Moments moments(const std::vector<Vec2>& p) {
  Moments m;
  for (std::size_t i = 1; i + 1 < p.size(); ++i) {
    const Vec2 v[3] = {p[0], p[i], p[i + 1]};
    const double a =
        0.5 * ((v[1] - v[0]).x() * (v[2] - v[0]).y() - (v[1] - v[0]).y() * (v[2] - v[0]).x());
    // Exact for a triangle: integral of x^2 = a/6 (sum x_i^2 + sum_{i<j} x_i x_j), etc.
    double sxx = 0, syy = 0, sxy = 0;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const double w = r == c ? 2.0 : 1.0;
        sxx += w * v[r].x() * v[c].x();
        syy += w * v[r].y() * v[c].y();
        sxy += w * v[r].x() * v[c].y();
      }
    m.a += a;
    m.sx += a * (v[0].x() + v[1].x() + v[2].x()) / 3;
    m.sy += a * (v[0].y() + v[1].y() + v[2].y()) / 3;
    m.xx += a * sxx / 12;
    m.yy += a * syy / 12;
    m.xy += a * sxy / 12;
  }
  return m;
}

SectionGeometry cut_at(const OwnedMesh& m, double x, const BoneDomain* domain = nullptr,
                       std::vector<CutSegment>* keep = nullptr) {
  const PlaneFrame plane = PlaneFrame::make(Vec3(x, 0, 0), Vec3::UnitX());
  std::vector<CutSegment> segs;
  cut_mesh(m.view(), plane, segs, nullptr);
  if (keep != nullptr) *keep = segs;
  return select_region(assemble_loops(segs, 0.0), domain);
}

const double kArea64 = 0.5 * 64 * 25 * std::sin(2 * M_PI / 64);  // r = 5 64-gon, 78.41 mm^2

}  // namespace

TEST(Regions, LoopsKeepTheFacesOrientation) {
  const auto m = outward_prism(regular_polygon(5, 64), 40);
  ASSERT_GT(signed_volume(m), 0);  // outward-facing
  const PlaneFrame plane = PlaneFrame::make(Vec3(13.7, 0, 0), Vec3::UnitX());
  std::vector<CutSegment> segs;
  cut_mesh(m.view(), plane, segs, nullptr);
  const PlaneCut cut = assemble_loops(segs, 0.0);
  ASSERT_EQ(cut.loops.size(), 1u);
  EXPECT_NEAR(signed_area(cut.loops[0]), kArea64, 1e-9);  // counter-clockwise
  OwnedMesh inward;
  append(inward, m, true);
  ASSERT_LT(signed_volume(inward), 0);
  segs.clear();
  cut_mesh(inward.view(), plane, segs, nullptr);
  EXPECT_NEAR(signed_area(assemble_loops(segs, 0.0).loops.at(0)), -kArea64, 1e-9);
}

TEST(Regions, InnerShellAddsNothing) {
  // An r = 2 closed cylinder inside an r = 5 one (an eye inside a head): the printed section is
  // the outer 64-gon, 78.4 mm^2, not the 65.9 mm^2 ring an even-odd rule gives.
  OwnedMesh m = outward_prism(regular_polygon(5, 64), 40);
  append(m, outward_prism(regular_polygon(2, 64), 40));
  const SectionGeometry g = cut_at(m, 20.3);
  ASSERT_TRUE(g.found);
  EXPECT_FALSE(g.flags & kFlagHollow);
  EXPECT_EQ(g.containing, 2);
  EXPECT_TRUE(g.polygon.holes.empty());
  const SectionProperties p = section_properties(g.polygon);
  EXPECT_NEAR(p.area, kArea64, 1e-9);
  EXPECT_NEAR(p.area, 78.4137, 1e-4);
  const SectionProperties alone = section_properties(SectionPolygon{regular_polygon(5, 64), {}});
  EXPECT_NEAR(p.modulus, alone.modulus, 1e-9 * alone.modulus);
}

TEST(Regions, RealTubeKeepsItsHole) {
  // The inner surface of a tube faces inward (into the bore): winding 0 there, a real hole.
  OwnedMesh m = outward_prism(regular_polygon(5, 64), 40);
  append(m, outward_prism(regular_polygon(2, 64), 40), true);
  const SectionGeometry g = cut_at(m, 20.3);
  ASSERT_TRUE(g.found);
  EXPECT_TRUE(g.flags & kFlagHollow);  // the bone point is in the bore
  ASSERT_EQ(g.polygon.holes.size(), 1u);
  const double inner = 0.5 * 64 * 4 * std::sin(2 * M_PI / 64);
  EXPECT_NEAR(section_properties(g.polygon).area, kArea64 - inner, 1e-9);
}

TEST(Regions, OverlappingCylindersGiveTheirUnion) {
  // Two closed r = 5 cylinders 4 mm apart (a limb sunk into the body): the union.
  const auto a = regular_polygon(5, 64);
  std::vector<Vec2> b = a;
  for (Vec2& p : b) p.x() += 4;  // plane u = world y
  OwnedMesh m = outward_prism(a, 40);
  append(m, shifted(outward_prism(a, 40), Vec3(0, 4, 0)));
  const SectionGeometry g = cut_at(m, 20.3);
  ASSERT_TRUE(g.found);
  EXPECT_FALSE(g.flags & kFlagHollow);
  EXPECT_TRUE(g.polygon.holes.empty());
  const SectionProperties p = section_properties(g.polygon);
  // Reference by inclusion-exclusion: M(A u B) = M(A) + M(B) - M(A n B), with A n B clipped by
  // Sutherland-Hodgman and the moments from triangle fans.
  const Moments ma = moments(a), mb = moments(b), mi = moments(clip_convex(a, b));
  const double area = ma.a + mb.a - mi.a;
  // Close to the two circles' union (the 117.5 mm^2): 2 pi r^2 minus the lens.
  const double lens = 2 * 25 * std::acos(0.4) - 2 * std::sqrt(84.0);
  EXPECT_NEAR(area, 2 * M_PI * 25 - lens, 0.2);
  EXPECT_NEAR(p.area, area, 1e-9 * area);
  const Vec2 c((ma.sx + mb.sx - mi.sx) / area, (ma.sy + mb.sy - mi.sy) / area);
  EXPECT_NEAR((p.centroid - c).norm(), 0, 1e-9);
  Mat2 j;
  j << ma.xx + mb.xx - mi.xx - area * c.x() * c.x(), ma.xy + mb.xy - mi.xy - area * c.x() * c.y(),
      ma.xy + mb.xy - mi.xy - area * c.x() * c.y(), ma.yy + mb.yy - mi.yy - area * c.y() * c.y();
  EXPECT_NEAR((p.second_moment - j).norm(), 0, 1e-9 * j.norm());
  // W = 1 / max |J^-1 (p - c)| over the union's extreme points: the vertices of A outside B and
  // of B outside A (the farthest point of a convex function over a polygon is a hull vertex).
  const Mat2 inv = j.inverse();
  double worst = 0;
  for (const Vec2& q : a)
    if (!point_in_loop(b, q)) worst = std::max(worst, (inv * (q - c)).norm());
  for (const Vec2& q : b)
    if (!point_in_loop(a, q)) worst = std::max(worst, (inv * (q - c)).norm());
  EXPECT_NEAR(p.modulus, 1 / worst, 1e-9 / worst);
}

TEST(Regions, SelfOverlapOfPlaneLoopsMerges) {
  // Direct use of material_regions: two overlapping squares and a far one give two regions.
  std::vector<Vec2> s1 = rectangle(4, 4), s2 = rectangle(4, 4), far = rectangle(2, 2);
  for (Vec2& p : s2) p += Vec2(2, 0);
  for (Vec2& p : far) p += Vec2(20, 0);
  const auto regions = material_regions({s1, s2, far});
  ASSERT_EQ(regions.size(), 2u);
  double total = 0;
  for (const auto& r : regions) total += polygon_area(r.outer);
  EXPECT_NEAR(total, 24.0 + 4.0, 1e-9);
}

TEST(Regions, OutsideBoneTakesItsOwnDomainNotTheNearestSliver) {
  // Bone 0 owns a thick r = 5 cylinder centred at y = -8; bone 1 owns a thin r = 0.5 rod at
  // y = +2. The bone point (y = 0) lies in neither: the nearest loop is bone 1's rod, but bone
  // 0's section is its own cylinder.
  OwnedMesh m = shifted(outward_prism(regular_polygon(5, 32), 40), Vec3(0, -8, 0));
  const std::size_t first = m.v.size() / 3;
  append(m, shifted(outward_prism(regular_polygon(0.5, 16), 40), Vec3(0, 2, 0)));
  std::vector<int> vertex_bone(m.v.size() / 3, 0);
  std::fill(vertex_bone.begin() + first, vertex_bone.end(), 1);
  std::vector<CutSegment> segs;
  const SectionGeometry nearest = cut_at(m, 20.3, nullptr, &segs);
  ASSERT_TRUE(nearest.found);
  EXPECT_NEAR(section_properties(nearest.polygon).centroid.x(), 2.0, 1e-9);
  const BoneDomain domain{&segs, vertex_bone.data(), 0};
  const SectionGeometry own = cut_at(m, 20.3, &domain);
  ASSERT_TRUE(own.found);
  EXPECT_TRUE(own.flags & kFlagOutside);
  EXPECT_FALSE(own.flags & kFlagUnreliable);
  EXPECT_NEAR(section_properties(own.polygon).centroid.x(), -8.0, 1e-9);
  // A bone that owns no face of this plane: nothing can be tied to it.
  const BoneDomain none{&segs, vertex_bone.data(), 2};
  const SectionGeometry doubt = cut_at(m, 20.3, &none);
  EXPECT_FALSE(doubt.found);
  EXPECT_TRUE(doubt.flags & kFlagUnreliable);
}

TEST(Regions, ThicknessIsTheMinimumWidth) {
  const double d64 = 2 * 5 * std::cos(M_PI / 64);  // a regular 64-gon's width across flats
  EXPECT_NEAR(region_thickness(SectionPolygon{regular_polygon(5, 64), {}}), d64, 1e-12);
  EXPECT_NEAR(region_thickness(SectionPolygon{rectangle(30, 0.4), {}}), 0.4, 1e-12);
  // A rotated plate: still its thickness.
  std::vector<Vec2> plate = rectangle(30, 0.4);
  const double t = 0.3;
  for (Vec2& p : plate)
    p = Vec2(std::cos(t) * p.x() - std::sin(t) * p.y(), std::sin(t) * p.x() + std::cos(t) * p.y());
  EXPECT_NEAR(region_thickness(SectionPolygon{plate, {}}), 0.4, 1e-12);
  // A triangle: its smallest height.
  EXPECT_NEAR(region_thickness(SectionPolygon{{{0, 0}, {4, 0}, {0, 3}}, {}}), 12.0 / 5.0, 1e-12);
  EXPECT_EQ(region_thickness(SectionPolygon{{{0, 0}, {1, 1}}, {}}), 0.0);
}

namespace {

std::vector<Vec2> reversed(std::vector<Vec2> loop) {
  std::reverse(loop.begin(), loop.end());
  return loop;
}

std::vector<Vec2> moved(std::vector<Vec2> loop, const Vec2& d) {
  for (Vec2& p : loop) p += d;
  return loop;
}

// The region around the origin in Clipper2's union of all loops (material_regions), for
// comparison with select_region's shortcut for loops that do not cross.
SectionProperties clipper_region(const std::vector<std::vector<Vec2>>& loops) {
  for (const SectionPolygon& poly : material_regions(loops)) {
    bool in = point_in_loop(poly.outer, Vec2::Zero());
    for (const auto& hole : poly.holes) in = in && !point_in_loop(hole, Vec2::Zero());
    if (in) return section_properties(poly);
  }
  return {};
}

}  // namespace

TEST(Regions, NestedLoopsGiveClippersUnion) {
  // Loops that do not cross are resolved without the clipper: the same region as Clipper2's
  // non-zero union. A far loop whose box reaches the others keeps the cluster from the one-loop
  // fast path.
  const auto outer = regular_polygon(5, 64);
  const auto far = moved(regular_polygon(1, 16), Vec2(5.5, 5.5));
  const std::vector<std::vector<std::vector<Vec2>>> cases = {
      {outer, regular_polygon(2, 64), far},                                 // an eye inside a head
      {outer, moved(reversed(regular_polygon(2, 64)), Vec2(2.5, 0)), far},  // a real hole
      {outer, regular_polygon(2, 64), moved(reversed(regular_polygon(1, 32)), Vec2(3, 0)),
       far},  // an eye and a hole
      {outer, reversed(regular_polygon(4, 64)), regular_polygon(3, 64),
       reversed(regular_polygon(2, 64)), far},  // an island in the tube's hole, with its hole
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    PlaneCut cut;
    cut.loops = cases[c];
    // The origin sits in material in each case except the island's hole (c = 3: the origin is
    // in the island's hole, r < 2, so the region is the island's wall: flag hollow).
    const SectionGeometry geom = select_region(cut);
    ASSERT_TRUE(geom.found) << c;
    const SectionProperties got = section_properties(geom.polygon);
    if (c == 3) {
      EXPECT_TRUE(geom.flags & kFlagHollow);
      EXPECT_NEAR(got.area,
                  polygon_area(regular_polygon(3, 64)) - polygon_area(regular_polygon(2, 64)),
                  1e-9);
      continue;
    }
    const SectionProperties want = clipper_region(cut.loops);
    ASSERT_TRUE(want.valid) << c;
    EXPECT_NEAR(got.area, want.area, 1e-9 * want.area) << c;
    EXPECT_NEAR(got.modulus, want.modulus, 1e-9 * want.modulus) << c;
    EXPECT_NEAR((got.centroid - want.centroid).norm(), 0.0, 1e-9) << c;
    EXPECT_EQ(geom.polygon.holes.size(), c == 0 ? 0u : 1u) << c;
  }
}

TEST(Regions, LoopsThatCrossOrTouchGiveClippersUnion) {
  // Loops whose boxes meet but that cross or touch each other (or themselves) must not take the
  // shortcut for nested loops: their material is Clipper2's union, larger than the loop around
  // the bone point alone. The cases stress the crossing test's split of loops into runs that go
  // one way in x: vertical edges, a saw-tooth with a turn at every point, a shared edge, a
  // crossing that is only a touch at one vertex, a loop that crosses itself.
  const auto circle = regular_polygon(5, 64);
  const auto rect = [](double x0, double y0, double x1, double y1) {
    return std::vector<Vec2>{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  };
  std::vector<Vec2> saw;  // a saw-tooth band from x = 3 to x = 9, crossing the circle at x = 5
  for (int k = 0; k <= 24; ++k) saw.emplace_back(3 + 0.25 * k, (k % 2 ? 0.6 : 0.2));
  saw.emplace_back(9, -0.5);
  saw.emplace_back(3, -0.5);
  saw = reversed(saw);  // counter-clockwise: material (clockwise would be a hole)
  // A point of the circle's boundary: a triangle with a vertex exactly on it, reaching out.
  const Vec2 on = circle[3];
  const std::vector<std::vector<std::vector<Vec2>>> cases = {
      {circle, rect(4, -1, 8, 1)},                               // a box through the boundary
      {circle, saw},                                             // a saw-tooth through it
      {rect(-1, -1, 1, 1), rect(1, -1, 3, 1)},                   // two squares sharing an edge
      {rect(-1, -1, 1, 1), rect(1, 0.5, 3, 1.5)},                // ... part of an edge
      {circle, {on, on + Vec2(3, -1), on + Vec2(3, 1)}},         // a vertex on its boundary
      {circle, {{4, -2}, {8, 2}, {8, -2}, {4, 2}}},              // a bow-tie through it
      {rect(-2, -2, 2, 2), {{2, -1}, {4, -1}, {4, 1}, {2, 1}}},  // touching along x = 2
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    PlaneCut cut;
    cut.loops = cases[c];
    const SectionGeometry geom = select_region(cut);
    ASSERT_TRUE(geom.found) << c;
    const SectionProperties got = section_properties(geom.polygon);
    const SectionProperties want = clipper_region(cut.loops);
    ASSERT_TRUE(want.valid) << c;
    if (c == 4)  // a touch at one vertex joins no material: the circle stays a piece of its own
      EXPECT_NEAR(want.area, polygon_area(circle), 1e-9 * want.area);
    else  // the union is larger than the loop around the bone point
      EXPECT_GT(want.area, polygon_area(cut.loops[0]) + 0.1) << c;
    EXPECT_NEAR(got.area, want.area, 1e-9 * want.area) << c;
    EXPECT_NEAR(got.modulus, want.modulus, 1e-9 * want.modulus) << c;
  }
}

TEST(Regions, ThicknessOfAHollowWall) {
  // A 64-gon tube r 5 / r 4: parallel edges cos(pi/64) apart (the wall, ~1 mm), not the
  // outer diameter; an off-centre hole: its thinnest side.
  const auto outer = regular_polygon(5, 64);
  EXPECT_NEAR(region_thickness(SectionPolygon{outer, {reversed(regular_polygon(4, 64))}}),
              std::cos(M_PI / 64), 1e-12);
  // Hole r 1 centred at (3.5, 0): its vertex (4.5, 0) faces the outer edges through (5, 0).
  EXPECT_NEAR(
      region_thickness(SectionPolygon{outer, {moved(regular_polygon(1, 64), Vec2(3.5, 0))}}),
      0.5 * std::cos(M_PI / 64), 1e-12);
  // Two holes 0.3 mm apart: the wall between them.
  const auto h1 = moved(rectangle(2, 2), Vec2(-1.15, 0));
  const auto h2 = moved(rectangle(2, 2), Vec2(1.15, 0));
  EXPECT_NEAR(region_thickness(SectionPolygon{outer, {h1, h2}}), 0.3, 1e-12);
}

TEST(Regions, ThicknessOfAWallAlongALongEdge) {
  // A hole (a 16-gon of radius 1 mm, a vertex at its top) centred at (0, 17) under the top edge
  // y = 20 of an outer loop with few vertices: the wall is 20 - 17 - 1 = 2 mm, found on the
  // middle of an edge whose two ends are far from the hole. A square with corners at +-20 mm,
  // and a 200 x 40 mm rectangle whose corners are farther from the hole (99 mm) than its width
  // (40 mm, the first bound on the thickness): no end of any of its edges is near the hole.
  const auto hole = moved(reversed(regular_polygon(1, 16)), Vec2(0, 17));
  for (const double half_width : {20.0, 100.0}) {
    const auto outer = rectangle(2 * half_width, 40);
    EXPECT_NEAR(region_thickness(SectionPolygon{outer, {hole}}), 2.0, 1e-12) << half_width;
  }
  // The hole turned by half a step: its top edge (the apothem cos(pi/16) above its centre)
  // faces the outer edge, 3 - cos(pi/16) mm away; and one off-centre near the bottom edge.
  std::vector<Vec2> half_step;
  for (const Vec2& p : reversed(regular_polygon(1, 16))) {
    const double t = M_PI / 16;
    half_step.emplace_back(std::cos(t) * p.x() - std::sin(t) * p.y(),
                           std::sin(t) * p.x() + std::cos(t) * p.y());
  }
  const auto outer = rectangle(200, 40);
  EXPECT_NEAR(region_thickness(SectionPolygon{outer, {moved(half_step, Vec2(30, 17))}}),
              3 - std::cos(M_PI / 16), 1e-12);
  EXPECT_NEAR(region_thickness(SectionPolygon{outer, {moved(half_step, Vec2(-40, -18.5))}}),
              1.5 - std::cos(M_PI / 16), 1e-12);
}

TEST(Regions, ThicknessLowerBoundAndThresholdAgreeWithTheThickness) {
  // The bound 2 sqrt(I_min / A) in closed form: a disc of radius r has I = pi r^4 / 4, A = pi r^2,
  // so r (half its width); a b x t plate t / sqrt(3).
  EXPECT_NEAR(region_thickness_lower_bound(M_PI * 25, M_PI * 625 / 4), 5.0, 1e-12);
  EXPECT_NEAR(region_thickness_lower_bound(30 * 0.4, 30 * std::pow(0.4, 3) / 12),
              0.4 / std::sqrt(3.0), 1e-12);
  EXPECT_EQ(region_thickness_lower_bound(0.0, 1.0), 0.0);
  // Random star polygons with and without holes: the bound never exceeds the minimum width, and
  // region_thinner_than(limit) is exactly region_thickness < limit at limits around it.
  std::uint64_t seed = 12345;
  auto uniform = [&]() {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(seed >> 11) / 9007199254740992.0;
  };
  int thin_cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 3 + static_cast<int>(uniform() * 60);
    const double stretch = 0.05 + 2.0 * uniform();
    std::vector<Vec2> outer;
    for (int k = 0; k < n; ++k) {
      const double t = 2 * M_PI * (k + 0.8 * uniform()) / n;
      const double r = 4.0 + 2.0 * uniform();
      outer.emplace_back(r * std::cos(t), stretch * r * std::sin(t));
    }
    SectionPolygon poly{outer, {}};
    if (trial % 2 == 1 && stretch > 0.5) {  // a hole near the middle: a wall of random thickness
      const double hr = 0.5 + 2.5 * uniform() * stretch;
      poly.holes.push_back(moved(reversed(regular_polygon(std::min(hr, 3.0 * stretch), 24)),
                                 Vec2(0.5 * (uniform() - 0.5), 0.5 * stretch * (uniform() - 0.5))));
    }
    const SectionProperties props = section_properties(poly);
    if (!props.valid) continue;
    const Eigen::SelfAdjointEigenSolver<Mat2> eig(props.second_moment);
    const double bound = region_thickness_lower_bound(props.area, eig.eigenvalues()(0));
    const double width = region_thickness(SectionPolygon{outer, {}});
    EXPECT_LE(bound, width * (1 + 1e-12)) << trial;
    const double thickness = region_thickness(poly);
    for (const double f : {0.5, 0.9, 0.999, 1.001, 1.1, 2.0}) {
      const double limit = f * thickness;
      EXPECT_EQ(region_thinner_than(poly, limit, bound), thickness < limit) << trial << " " << f;
      thin_cases += thickness < limit;
    }
  }
  EXPECT_GT(thin_cases, 600);  // both answers were exercised
}

TEST(Regions, ThicknessOfALoopThatCrossesItself) {
  // A bow-tie ordering of a 4 x 3 rectangle's corners: the linear-time hull of a simple polygon
  // does not apply; the width is still the hull's, 3.
  EXPECT_NEAR(region_thickness(SectionPolygon{{{0, 0}, {4, 3}, {4, 0}, {0, 3}}, {}}), 3.0, 1e-12);
  // A star (a self-crossing pentagram) through the vertices of a regular pentagon of
  // circumradius 1: the pentagon's width, 1 + cos(pi / 5).
  std::vector<Vec2> star;
  for (int k = 0; k < 5; ++k) {
    const double t = M_PI / 2 + 2 * M_PI * (2 * k % 5) / 5;
    star.emplace_back(std::cos(t), std::sin(t));
  }
  EXPECT_NEAR(region_thickness(SectionPolygon{star, {}}), 1 + std::cos(M_PI / 5), 1e-12);
}

TEST(Regions, JunctionCoreLeavesOutAStubKeepsTapersAndTilts) {
  // A round bar r = 3 (64-gon) with a stub 6 wide reaching to 9 from its axis, cut through the
  // stub; the neighbour planes see the bar alone.
  const auto bar = regular_polygon(3, 64);
  std::vector<Vec2> stub = {{-3, 0}, {3, 0}, {3, 9}, {-3, 9}};
  const std::vector<SectionPolygon> whole = material_regions({bar, stub});
  ASSERT_EQ(whole.size(), 1u);
  SectionPolygon neighbour;
  neighbour.outer = bar;
  const SectionProperties round = section_properties(neighbour);
  const SectionGeometry core = junction_core(whole[0], {&neighbour, &neighbour}, 0.15, 0.9);
  ASSERT_TRUE(core.found);
  const SectionProperties p = section_properties(core.polygon);
  // The core is the bar plus the stub's root within the 0.15 margin: at most the band of width
  // 0.15 over the upper half circle (the stub is as wide as the bar), pi * 3.15 * 0.15 more.
  EXPECT_GE(p.area, round.area - 1e-6);
  EXPECT_LE(p.area, round.area + M_PI * 3.15 * 0.15);
  EXPECT_NEAR(p.modulus / round.modulus, 1.0, 0.05);
  EXPECT_GT(section_properties(whole[0]).modulus, 2.5 * round.modulus);
  // A taper: neighbours r = 2.6 and 3.4 (the rim trimmed off is 0.4 - 0.15 wide, under 2 x 0.9):
  // nothing is left out.
  SectionPolygon section, smaller, larger;
  section.outer = bar;
  smaller.outer = regular_polygon(2.6, 64);
  larger.outer = regular_polygon(3.4, 64);
  const SectionGeometry taper = junction_core(section, {&smaller, &larger}, 0.15, 0.9);
  ASSERT_TRUE(taper.found);
  EXPECT_NEAR(section_properties(taper.polygon).area, round.area, 1e-6 * round.area);
  EXPECT_NEAR(section_properties(taper.polygon).modulus, round.modulus, 1e-6 * round.modulus);
  // A tilted bone: neighbours shifted by -0.5 and +0.5 (crescents 0.5 - 0.15 wide): unchanged.
  SectionPolygon left, right;
  left.outer = bar;
  right.outer = bar;
  for (Vec2& q : left.outer) q.x() -= 0.5;
  for (Vec2& q : right.outer) q.x() += 0.5;
  const SectionGeometry tilt = junction_core(section, {&left, &right}, 0.15, 0.9);
  ASSERT_TRUE(tilt.found);
  EXPECT_NEAR(section_properties(tilt.polygon).area, round.area, 1e-6 * round.area);
  // The bone point outside the core (the neighbours hold only far material): not found.
  SectionPolygon far;
  far.outer = rectangle(2, 2);
  for (Vec2& q : far.outer) q.y() += 7;
  EXPECT_FALSE(junction_core(whole[0], {&far, &far}, 0.15, 0.9).found);
}

TEST(Regions, JunctionCoreAsksFirstWithARegionTheCoreHolds) {
  // The early answer of the junction stage (docs/junctions.md, Cost) rests on the region handed
  // to `worth` lying inside the core: the section and the neighbours' common part, not widened.
  const auto bar = regular_polygon(3, 64);
  std::vector<Vec2> stub = {{-3, 0}, {3, 0}, {3, 9}, {-3, 9}};
  const SectionPolygon t_cut = material_regions({bar, stub})[0];
  SectionPolygon round, smaller, larger, left, right, body, body_low, body_high;
  round.outer = bar;
  smaller.outer = regular_polygon(2.6, 64);
  larger.outer = regular_polygon(3.4, 64);
  left.outer = bar;
  right.outer = bar;
  for (Vec2& q : left.outer) q.x() -= 0.5;
  for (Vec2& q : right.outer) q.x() += 0.5;
  // A limb's top inside a body: the cut is the body (40 x 24, the bone point off its centre),
  // the neighbour planes see it a little narrower and shifted.
  auto box = [](double w, double h, double dx, double dy) {
    std::vector<Vec2> r = rectangle(w, h);
    for (Vec2& q : r) q += Vec2(dx, dy);
    return r;
  };
  body.outer = box(40, 24, 12, 3);
  body_low.outer = box(38, 23, 11.5, 3);
  body_high.outer = box(39, 22, 12.5, 3.5);
  // A cross (two 60 x 16 bars), the neighbours a little larger and shifted: the rectangle the
  // common box's proportions give is stopped by the section's inner corners (about 16 x 16), a
  // neighbour's arm ends just inside its sides; arms on the middle of its sides reach out along
  // the bars (four of about 22 x 9.6).
  SectionPolygon cross, cross_low, cross_high;
  cross.outer = {{-30, -8}, {-8, -8}, {-8, -30}, {8, -30}, {8, -8}, {30, -8},
                 {30, 8},   {8, 8},   {8, 30},   {-8, 30}, {-8, 8}, {-30, 8}};
  cross_low.outer = cross.outer;
  cross_high.outer = cross.outer;
  for (Vec2& q : cross_low.outer) q = 1.04 * q + Vec2(0.2, 0.1);
  for (Vec2& q : cross_high.outer) q = 1.03 * q - Vec2(0.1, 0.3);
  struct Case {
    const SectionPolygon* section;
    std::vector<const SectionPolygon*> neighbours;
    // The section and the neighbours' common part (by hand), up to the neighbours' thinning
    // to within 0.25 x the margin: at most that band along the perimeter.
    double inner_area;
    double thinning;
  };
  const std::vector<Case> cases = {
      {&t_cut, {&round, &round}, section_properties(round).area, 2 * M_PI * 3 * 0.25 * 0.15},
      {&round, {&smaller, &larger}, section_properties(smaller).area, 2 * M_PI * 2.6 * 0.25 * 0.15},
      {&round, {&left, &right}, -1.0, 0.0},
      {&body, {&body_low, &body_high}, 37.5 * 22, 1e-9},  // x in [-7, 30.5], y in [-7.5, 14.5]
      {&cross, {&cross_low, &cross_high}, -1.0, 0.0},
  };
  for (const Case& c : cases) {
    const SectionGeometry plain = junction_core(*c.section, c.neighbours, 0.15, 0.9);
    ASSERT_TRUE(plain.found);
    // Asked first, perhaps, with a rectangle inside the section and the neighbours, then with
    // their common part.
    std::vector<SectionPolygon> asked;
    const SectionGeometry core =
        junction_core(*c.section, c.neighbours, 0.15, 0.9, [&](const SectionPolygon& p) {
          asked.push_back(p);
          return true;
        });
    // ... then perhaps with arms on its sides.
    ASSERT_GE(asked.size(), 1u);
    ASSERT_LE(asked.size(), 3u);
    for (std::size_t k = 0; k + 1 < asked.size(); ++k) EXPECT_LE(asked[k].outer.size(), 20u);
    if (c.section == &cross) {
      ASSERT_EQ(asked.size(), 3u);
      EXPECT_GT(section_properties(asked[1]).area, 4 * section_properties(asked[0]).area);
    }
    ASSERT_TRUE(core.found);
    // Asking changes nothing.
    EXPECT_EQ(core.polygon.outer, plain.polygon.outer);
    const double core_area = section_properties(core.polygon).area;
    const SectionPolygon& inner = asked.back();
    const double inner_area = section_properties(inner).area;
    if (c.inner_area > 0) {
      EXPECT_LE(inner_area, c.inner_area + 1e-9 * c.inner_area);
      EXPECT_GE(inner_area, c.inner_area - c.thinning);
    }
    // Inside the core: the union of each with the core is the core.
    for (const SectionPolygon& region : asked) {
      const double area = section_properties(region).area;
      EXPECT_LE(area, core_area + 1e-9 * core_area);
      const auto both = material_regions({core.polygon.outer, region.outer});
      ASSERT_EQ(both.size(), 1u);
      EXPECT_NEAR(section_properties(both[0]).area, core_area, 1e-6 * core_area);
    }
    // `may_fail` is handed a box holding every region asked; its "no" skips the asking.
    Vec2 lo, hi;
    int boxes = 0;
    const SectionGeometry boxed = junction_core(
        *c.section, c.neighbours, 0.15, 0.9, [](const SectionPolygon&) { return false; },
        [&](const Vec2& l, const Vec2& h) {
          lo = l;
          hi = h;
          ++boxes;
          return false;
        });
    EXPECT_EQ(boxes, 1);
    EXPECT_EQ(boxed.polygon.outer, plain.polygon.outer);
    for (const SectionPolygon& region : asked)
      for (const Vec2& q : region.outer)
        EXPECT_TRUE(q.x() >= lo.x() && q.x() <= hi.x() && q.y() >= lo.y() && q.y() <= hi.y());
    // A neighbour given twice (a neck that is also a neighbour plane) is read once: the same
    // answers as with a copy of it, a distinct neighbour.
    {
      std::vector<const SectionPolygon*> twice = c.neighbours, copied = c.neighbours;
      const SectionPolygon copy = *c.neighbours.back();
      twice.push_back(c.neighbours.back());
      copied.push_back(&copy);
      std::vector<SectionPolygon> asked_twice, asked_copied;
      const SectionGeometry a =
          junction_core(*c.section, twice, 0.15, 0.9, [&](const SectionPolygon& p) {
            asked_twice.push_back(p);
            return true;
          });
      const SectionGeometry b =
          junction_core(*c.section, copied, 0.15, 0.9, [&](const SectionPolygon& p) {
            asked_copied.push_back(p);
            return true;
          });
      EXPECT_EQ(a.polygon.outer, b.polygon.outer);
      ASSERT_EQ(asked_twice.size(), asked_copied.size());
      for (std::size_t k = 0; k < asked_twice.size(); ++k)
        EXPECT_EQ(asked_twice[k].outer, asked_copied[k].outer);
    }
    // A "no" ends the call: no core.
    EXPECT_FALSE(junction_core(*c.section, c.neighbours, 0.15, 0.9, [](const SectionPolygon&) {
                   return false;
                 }).found);
  }
}

TEST(Regions, JunctionCoreJudgesPiecesNearTheCoreAsOnTheWholeSection) {
  // junction_core works on the section near the neighbours' common part (a 20 x 20 square here,
  // margin 0.5, opening 3: the box grown by about 2.4 x 3); a trimmed piece that leaves that box
  // is judged there only when it holds a disc of 1.1 x the opening, else on the whole section.
  // Each answer is the one of the whole section, by hand.
  SectionPolygon square;
  square.outer = rectangle(20, 20);
  auto with = [&](std::vector<std::vector<Vec2>> parts) {
    parts.push_back(square.outer);
    const std::vector<SectionPolygon> regions = material_regions(parts);
    EXPECT_EQ(regions.size(), 1u);
    return regions.front();
  };
  auto core_area = [&](const SectionPolygon& section) {
    const SectionGeometry core = junction_core(section, {&square, &square}, 0.5, 3.0);
    EXPECT_TRUE(core.found);
    return section_properties(core.polygon).area;
  };
  const std::vector<Vec2> neck = {{9, -1}, {60, -1}, {60, 1}, {9, 1}};  // 2 wide: thin
  const std::vector<Vec2> blob = {{30, -15}, {60, -15}, {60, 15}, {30, 15}};
  const std::vector<Vec2> slab = {{9, -8}, {60, -8}, {60, 8}, {9, 8}};  // 16 wide: a stub
  // A neck, thin near the square, ending in a wide blob far out: one stub, left out whole (the
  // square and the neck's root within the margin stay).
  EXPECT_NEAR(core_area(with({{{9, -1}, {30, -1}, {30, 1}, {9, 1}}, blob})), 400 + 0.5 * 2, 1e-6);
  // The neck alone, thin all along: back into the core.
  EXPECT_NEAR(core_area(with({neck})), 400 + 51 * 2 - 2, 1e-6);
  // A wide stub: left out, from the part near the square alone.
  EXPECT_NEAR(core_area(with({slab})), 400 + 0.5 * 16, 1e-6);
  // A thin spike well inside the box and the wide stub: the spike stays, the stub goes.
  const std::vector<Vec2> spike = {{-1, 9}, {1, 9}, {1, 14}, {-1, 14}};
  EXPECT_NEAR(core_area(with({spike, slab})), 400 + 2 * 4 + 0.5 * 16, 1e-6);
}

TEST(Regions, SimplifyClosedIsClippersSimplifyPath) {
  // detail::simplify_closed (the junction stage's thinning) removes the vertices Clipper2's
  // SimplifyPath removes, in the same order: the same path, point for point. Noisy circles with
  // runs of collinear and repeated points, integer and double coordinates, several tolerances.
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 4 + static_cast<int>(rng() % 500);
    const double radius = 1000.0 * (1.0 + 99.0 * unit(rng)), noise = radius * 0.02 * unit(rng);
    Clipper2Lib::Path64 path;
    Clipper2Lib::PathD path_d;
    for (int k = 0; k < n; ++k) {
      const double t = 2 * M_PI * k / n;
      const double r = radius + noise * (unit(rng) - 0.5);
      const Clipper2Lib::Point64 p(static_cast<std::int64_t>(r * std::cos(t)),
                                   static_cast<std::int64_t>(r * std::sin(t)));
      path.push_back(p);
      if (rng() % 7 == 0) path.push_back(p);     // repeated
      if (rng() % 9 == 0 && path.size() >= 2) {  // collinear
        const auto& a = path[path.size() - 2];
        path.push_back({2 * p.x - a.x, 2 * p.y - a.y});
      }
      path_d.emplace_back(r * std::cos(t), r * std::sin(t));
    }
    for (const double eps : {0.5, 3.0, 0.002 * radius, 0.02 * radius, 0.3 * radius}) {
      EXPECT_EQ(osteon::detail::simplify_closed(path, eps), Clipper2Lib::SimplifyPath(path, eps));
      const Clipper2Lib::PathD mine = osteon::detail::simplify_closed(path_d, eps);
      const Clipper2Lib::PathD theirs = Clipper2Lib::SimplifyPath(path_d, eps);
      ASSERT_EQ(mine.size(), theirs.size());
      for (std::size_t k = 0; k < mine.size(); ++k) {
        EXPECT_EQ(mine[k].x, theirs[k].x);
        EXPECT_EQ(mine[k].y, theirs[k].y);
      }
    }
  }
}

TEST(Regions, LoosePiecesCountsFaceShellsLikeASearch) {
  // Shells of random faces (vertex indices shuffled, faces interleaved, isolated vertices): the
  // face shells counted (union-find with a skip for faces that join nothing) equal the connected
  // components of a search over the faces; a vertex of no face (not printed) is no shell.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 40; ++trial) {
    const int shells = 1 + trial % 6, per = 3 + trial % 9, isolated = trial % 3;
    const int nv = shells * per + isolated;
    std::vector<int> perm(nv);
    for (int v = 0; v < nv; ++v) perm[v] = v;
    std::shuffle(perm.begin(), perm.end(), rng);
    std::vector<std::int32_t> faces;
    for (int s = 0; s < shells; ++s) {
      const int base = s * per;
      std::uniform_int_distribution<int> pick(0, per - 1);
      // A strip joins the shell; extra random faces inside it repeat joins.
      for (int k = 0; k + 2 < per; ++k)
        faces.insert(faces.end(), {perm[base + k], perm[base + k + 1], perm[base + k + 2]});
      for (int k = 0; k < per; ++k)
        faces.insert(faces.end(),
                     {perm[base + pick(rng)], perm[base + pick(rng)], perm[base + pick(rng)]});
    }
    // Interleave the shells' faces.
    const int nf = static_cast<int>(faces.size() / 3);
    std::vector<int> order(nf);
    for (int f = 0; f < nf; ++f) order[f] = f;
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<std::int32_t> shuffled;
    for (int f : order)
      shuffled.insert(shuffled.end(), faces.begin() + 3 * f, faces.begin() + 3 * f + 3);
    std::vector<double> xyz(3 * nv);
    std::uniform_real_distribution<double> u(-50.0, 50.0);
    for (double& x : xyz) x = u(rng);
    // Reference: components by a search over vertex adjacency.
    std::vector<std::vector<int>> adj(nv);
    for (int f = 0; f < nf; ++f)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) adj[shuffled[3 * f + a]].push_back(shuffled[3 * f + b]);
    std::vector<std::uint8_t> seen(nv, 0);
    Index components = 0;
    for (int v = 0; v < nv; ++v) {
      if (seen[v] || adj[v].empty()) continue;
      ++components;
      std::vector<int> stack{v};
      seen[v] = 1;
      while (!stack.empty()) {
        const int w = stack.back();
        stack.pop_back();
        for (int x : adj[w])
          if (!seen[x]) {
            seen[x] = 1;
            stack.push_back(x);
          }
      }
    }
    const MeshView mesh{xyz.data(), nv, shuffled.data(), nf};
    const std::vector<int> vertex_bone(nv, 0);
    Index face_shells = -1;
    loose_pieces(mesh, vertex_bone, 0, 0.0, &face_shells);
    EXPECT_EQ(face_shells, components) << "trial " << trial;
    EXPECT_EQ(face_shells, shells) << "trial " << trial;
  }
}

TEST(Regions, LoosePieceFinderKeptAcrossMovesAnswersAsAFreshSearch) {
  // A bar (the held piece), a small box and a prism, with the faces fixed and the vertices moved
  // between calls (live mode): the box floats apart, sinks into the bar, touches the bar's end at
  // exactly shared positions, then floats again; the kept finder (shells of the first call, kept
  // arrays) lists the same loose pieces as a fresh loose_pieces() each time.
  using osteon::testing::prism;
  using osteon::testing::rectangle;
  const auto bar = prism(rectangle(4, 4), 40, 11);
  const auto box = prism(rectangle(2, 2), 2, 2);
  const auto rod = prism(rectangle(1, 1), 6, 3);
  std::vector<std::int32_t> faces;
  std::vector<double> rest;
  for (const auto* part : {&bar, &box, &rod}) {
    const auto base = static_cast<std::int32_t>(rest.size() / 3);
    for (std::int32_t k : part->f) faces.push_back(base + k);
    rest.insert(rest.end(), part->v.begin(), part->v.end());
  }
  const Index nv = static_cast<Index>(rest.size() / 3);
  const Index box_first = static_cast<Index>(bar.v.size() / 3);
  const Index rod_first = box_first + static_cast<Index>(box.v.size() / 3);
  const std::vector<int> vertex_bone(nv, 0);
  // Offsets (mm) of the box and of the rod for each call.
  const Vec3 box_at[] = {{60, 0, 0}, {20, 0, 0}, {40, 1, 1}, {60, 0, 0}, {-1, 0, 0}};
  const Vec3 rod_at[] = {{0, 30, 0}, {10, 0, 0}, {17, 0, 0}, {17, 0, 0}, {0, 50, 0}};
  LoosePieceFinder finder, gridded;  // the second walks a face grid for its inside tests
  int loose_seen = 0;
  for (int call = 0; call < 5; ++call) {
    std::vector<double> xyz = rest;
    for (Index v = box_first; v < nv; ++v) {
      const Vec3& at = v < rod_first ? box_at[call] : rod_at[call];
      for (int k = 0; k < 3; ++k) xyz[3 * v + k] += at[k];
    }
    const MeshView mesh{xyz.data(), nv, faces.data(), static_cast<Index>(faces.size() / 3)};
    Index kept_shells = -1, fresh_shells = -1;
    const auto kept = finder.find(mesh, vertex_bone, 0, 0.2, &kept_shells, true);
    const auto fresh = loose_pieces(mesh, vertex_bone, 0, 0.2, &fresh_shells);
    EXPECT_EQ(kept, fresh) << "call " << call;
    FaceGrid grid;
    grid.build(mesh, 12, 1);
    EXPECT_EQ(gridded.find(mesh, vertex_bone, 0, 0.2, nullptr, true, &grid), fresh)
        << "call " << call;
    EXPECT_EQ(kept_shells, 3);
    EXPECT_EQ(fresh_shells, 3);
    loose_seen += static_cast<int>(kept.size());
  }
  // Both apart; both inside the bar; the box on the bar's end face (a corner at one of the
  // bar's own positions: one piece) and the rod inside; the box apart again (the last call's
  // joins are not kept) and the rod inside; the box through the bar's end and the rod apart.
  EXPECT_EQ(loose_seen, 2 + 0 + 0 + 1 + 1);
}

TEST(Regions, AFaceOfOneVertexThriceIsNoTriangle) {
  // The same bar and box, and the stray vertex given a "face" of itself three times (found by
  // the API fuzz test: such a face was counted to no shell's face list and written before the
  // first one, out of bounds). It is no triangle: the vertex is still in no face, no shell and
  // no piece, and the box is loose whichever of the box's or the stray's faces come first.
  using osteon::testing::prism;
  using osteon::testing::rectangle;
  const auto bar = prism(rectangle(4, 4), 40, 11);
  const auto box = prism(rectangle(2, 2), 2, 2);
  for (const bool stray_first : {false, true}) {
    std::vector<double> xyz = bar.v;
    std::vector<std::int32_t> faces;
    const auto base = static_cast<std::int32_t>(xyz.size() / 3);
    for (std::size_t k = 0; k < box.v.size(); k += 3)
      xyz.insert(xyz.end(), {box.v[k] + 40.3, box.v[k + 1], box.v[k + 2]});
    const auto stray = static_cast<std::int32_t>(xyz.size() / 3);
    xyz.insert(xyz.end(), {40.15, 0.0, 0.0});
    if (stray_first) faces.insert(faces.end(), {stray, stray, stray});
    faces.insert(faces.end(), bar.f.begin(), bar.f.end());
    for (std::int32_t k : box.f) faces.push_back(base + k);
    if (!stray_first) faces.insert(faces.end(), {stray, stray, stray});
    const Index nv = static_cast<Index>(xyz.size() / 3);
    const MeshView mesh{xyz.data(), nv, faces.data(), static_cast<Index>(faces.size() / 3)};
    const std::vector<int> vertex_bone(nv, 0);
    Index face_shells = -1;
    LoosePieceFinder finder;
    const auto loose = finder.find(mesh, vertex_bone, 0, 0.2, &face_shells, false);
    EXPECT_EQ(face_shells, 2);
    ASSERT_EQ(loose.size(), 1u);
    std::vector<std::int32_t> box_vertices;
    for (std::int32_t v = base; v < stray; ++v) box_vertices.push_back(v);
    EXPECT_EQ(loose[0], box_vertices);
    EXPECT_EQ(loose_pieces(mesh, vertex_bone, 0, 0.2), loose);
  }
}

TEST(Regions, AVertexOfNoFaceIsNoPiece) {
  // A bar, a box floating 0.3 mm past its end, and a stray vertex (in no face) between them,
  // 0.15 mm from each: the stray vertex is not printed, so it neither counts as a shell nor
  // holds the box on (contact gap 0.2 mm); the box is loose.
  using osteon::testing::prism;
  using osteon::testing::rectangle;
  const auto bar = prism(rectangle(4, 4), 40, 11);
  const auto box = prism(rectangle(2, 2), 2, 2);
  std::vector<double> xyz = bar.v;
  std::vector<std::int32_t> faces = bar.f;
  const auto base = static_cast<std::int32_t>(xyz.size() / 3);
  for (std::size_t k = 0; k < box.v.size(); k += 3)
    xyz.insert(xyz.end(), {box.v[k] + 40.3, box.v[k + 1], box.v[k + 2]});
  for (std::int32_t k : box.f) faces.push_back(base + k);
  xyz.insert(xyz.end(), {40.15, 0.0, 0.0});
  const Index nv = static_cast<Index>(xyz.size() / 3);
  const MeshView mesh{xyz.data(), nv, faces.data(), static_cast<Index>(faces.size() / 3)};
  const std::vector<int> vertex_bone(nv, 0);
  Index face_shells = -1;
  const auto loose = loose_pieces(mesh, vertex_bone, 0, 0.2, &face_shells);
  EXPECT_EQ(face_shells, 2);
  ASSERT_EQ(loose.size(), 1u);
  std::vector<std::int32_t> box_vertices;
  for (std::int32_t v = base; v < nv - 1; ++v) box_vertices.push_back(v);
  EXPECT_EQ(loose[0], box_vertices);
  // Only the bar and the stray vertex: one shell, nothing loose.
  std::vector<double> bar_xyz = bar.v;
  bar_xyz.insert(bar_xyz.end(), {60.0, 0.0, 0.0});
  const MeshView lone{bar_xyz.data(), static_cast<Index>(bar_xyz.size() / 3), bar.f.data(),
                      static_cast<Index>(bar.f.size() / 3)};
  EXPECT_TRUE(
      loose_pieces(lone, std::vector<int>(bar_xyz.size() / 3, 0), 0, 0.2, &face_shells).empty());
  EXPECT_EQ(face_shells, 1);
}
