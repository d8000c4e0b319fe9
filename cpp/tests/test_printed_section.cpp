// The printed section's offsets against closed forms (cpp/src/printed_section.cpp).
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "osteon/printed_section.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::rectangle;
using osteon::testing::regular_polygon;

namespace {

// PrusaSlicer's walls for 2 perimeters of 0.45 mm at 0.2 mm layers (python/osteon/printed.py):
// w/2 + s/2 + s with s = w - h (1 - pi/4).
const double kSpacing = 0.45 - 0.2 * (1 - M_PI / 4);
const double kWall = 0.225 + 1.5 * kSpacing;

PrintOptions fdm(double wall, double skin, double eta_build, double eta_layer, double min_area) {
  PrintOptions o;
  o.kind = PrintOptions::kLayered;
  o.wall_depth = wall;
  o.skin_depth = skin;
  o.infill_build = eta_build;
  o.infill_layer = eta_layer;
  o.solid_infill_below_area = min_area;
  return o;
}

// W of a centred b x h rectangle (axes u, v) minus (1 - eta) x a centred bi x hi one.
double rectangle_modulus(double b, double h, double bi, double hi, double eta) {
  const double k = 1 - eta;
  const double ju = (h * b * b * b - k * hi * bi * bi * bi) / 12;  // about the v axis (u^2)
  const double jv = (b * h * h * h - k * bi * hi * hi * hi) / 12;
  const Vec2 corner(b / 2, h / 2);
  return 1.0 / Vec2(corner.x() / ju, corner.y() / jv).norm();
}

}  // namespace

TEST(PrintedSection, LayerOfARodIsTheTubeOfTheWallDepth) {
  const int n = 512;
  const double r = 5.0;
  const SectionPolygon cut{regular_polygon(r, n), {}};
  const SectionProperties solid = section_properties(cut);
  // Build direction along the normal: the section is a layer, walls all round.
  const PrintedSection p =
      printed_section(cut, solid, Vec2::Zero(), 1.0, fdm(kWall, 0.8, 0.0, 0.0, 0.0), true);
  ASSERT_TRUE(p.valid);
  // The inset of the regular n-gon by d is the n-gon of circumradius R - d / cos(pi / n).
  const double ri = r - kWall / std::cos(M_PI / n);
  std::vector<Vec2> hole = regular_polygon(ri, n);
  const SectionProperties tube = section_properties({regular_polygon(r, n), {hole}});
  // (the outline is simplified within 0.005 mm before the offsets: 0.1 % here)
  EXPECT_NEAR(p.modulus / tube.modulus, 1.0, 2e-3);
  EXPECT_NEAR(p.wall_area / tube.area, 1.0, 2e-3);
  EXPECT_NEAR(p.infill_area, solid.area - tube.area, 1e-3 * solid.area);
  EXPECT_NEAR(p.skin_area, 0.0, 1e-3);
  ASSERT_EQ(p.sparse.size(), 1u);
}

TEST(PrintedSection, RectangleAtAnyAngleHasEllipseWallsAndShiftedSkins) {
  const double b = 12.0, h = 8.0, skin = 0.8, eta = 0.2;
  const SectionPolygon cut{rectangle(b, h), {}};
  const SectionProperties solid = section_properties(cut);
  for (double deg : {0.0, 30.0, 60.0, 89.0, 90.0}) {
    SCOPED_TRACE(deg);
    const double t = deg * M_PI / 180, c = std::cos(t), s = std::sin(t);
    // Build direction's projection along u: walls t_w cos(theta) deep across u, t_w across v;
    // skins t_s sin(theta) deep across u.
    const PrintedSection p =
        printed_section(cut, solid, Vec2(s, 0.0), c, fdm(kWall, skin, eta, eta, 0.0), false);
    ASSERT_TRUE(p.valid);
    const double eroded = (b - 2 * kWall * std::max(c, 1e-3)) * (h - 2 * kWall);
    const double bi = b - 2 * std::max(kWall * std::max(c, 1e-3), skin * s), hi = h - 2 * kWall;
    EXPECT_NEAR(p.wall_area, solid.area - eroded, 2e-3);
    EXPECT_NEAR(p.infill_area, bi * hi, 2e-3);
    EXPECT_NEAR(p.skin_area, eroded - bi * hi, 2e-3);
    EXPECT_NEAR(p.modulus / rectangle_modulus(b, h, bi, hi, eta), 1.0, 1e-4);
  }
}

TEST(PrintedSection, SmallIslandsAndThinPartsAreSolid) {
  const SectionPolygon cut{rectangle(12.0, 8.0), {}};
  const SectionProperties solid = section_properties(cut);
  // At theta = 60 deg the walls are kWall / 2 deep across u: the island is ~71 mm^2, its layer
  // area = section area / cos(theta) ~141 mm^2: solid under the threshold only.
  const double c = 0.5;
  const double layer = (12 - kWall) * (8 - 2 * kWall) / c;
  PrintedSection p = printed_section(cut, solid, Vec2(std::sqrt(0.75), 0), c,
                                     fdm(kWall, 0.0, 0.0, 0.0, 0.99 * layer), false);
  EXPECT_GT(p.infill_area, 0.0);
  p = printed_section(cut, solid, Vec2(std::sqrt(0.75), 0), c,
                      fdm(kWall, 0.0, 0.0, 0.0, 1.01 * layer), false);
  EXPECT_EQ(p.infill_area, 0.0);
  EXPECT_NEAR(p.modulus / solid.modulus, 1.0, 1e-12);
  // Thinner than its walls: no inset, all wall, solid.
  const SectionPolygon thin{rectangle(1.5, 10.0), {}};
  const SectionProperties thin_solid = section_properties(thin);
  p = printed_section(thin, thin_solid, Vec2::Zero(), 1.0, fdm(kWall, 0.8, 0.0, 0.0, 0.0), false);
  EXPECT_EQ(p.infill_area, 0.0);
  EXPECT_NEAR(p.wall_area, thin_solid.area, 1e-9);
  EXPECT_NEAR(p.modulus / thin_solid.modulus, 1.0, 1e-12);
}

TEST(PrintedSection, ResinShellIsIsotropic) {
  const int n = 512;
  const SectionPolygon cut{regular_polygon(5.0, n), {}};
  const SectionProperties solid = section_properties(cut);
  PrintOptions o;
  o.kind = PrintOptions::kShell;
  o.wall_depth = 2.0;
  o.infill_build = o.infill_layer = 0.0;
  const double ri = 5.0 - 2.0 / std::cos(M_PI / n);
  const SectionProperties tube =
      section_properties({regular_polygon(5.0, n), {regular_polygon(ri, n)}});
  for (double c : {1.0, 0.5, 0.0}) {
    const PrintedSection p =
        printed_section(cut, solid, Vec2(std::sqrt(1 - c * c), 0), c, o, false);
    EXPECT_NEAR(p.modulus / tube.modulus, 1.0, 1e-3);
  }
}

TEST(PrintedSection, InfillStiffnessIsTheReussBound) {
  EXPECT_DOUBLE_EQ(infill_stiffness(1.0, 0.15, 0.02), 0.15);
  EXPECT_NEAR(infill_stiffness(0.0, 0.15, 0.02), 0.02, 1e-15);
  EXPECT_NEAR(infill_stiffness(std::sqrt(0.5), 0.15, 0.02), 1 / (0.5 / 0.15 + 0.5 / 0.02), 1e-15);
  EXPECT_EQ(infill_stiffness(0.5, 0.15, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(infill_stiffness(1.0, 0.15, 0.0), 0.15);
}

TEST(PrintedSection, BadOptionsThrow) {
  PrintOptions o = fdm(kWall, 0.8, 0.1, 0.1, 0.0);
  EXPECT_NO_THROW(validate_print_options(o));
  o.wall_depth = -1;
  EXPECT_THROW(validate_print_options(o), std::invalid_argument);
  o = fdm(kWall, 0.8, 1.5, 0.1, 0.0);
  EXPECT_THROW(validate_print_options(o), std::invalid_argument);
  o.kind = 7;
  EXPECT_THROW(validate_print_options(o), std::invalid_argument);
}

TEST(PrintedSection, HollowPrintSkinsOnlyUnderFlatSurfaces) {
  // Lying (theta = 90 deg, build along u): a rectangle's top and bottom are flat, so limiting
  // skins to flat surfaces changes nothing; a diamond whose sides are 30 deg steep has skins
  // under them (0.8 mm below, deeper than the walls) only while 30 deg counts as flat.
  PrintOptions all = fdm(kWall, 0.8, 0.0, 0.0, 0.0), flat = all;
  flat.skin_max_slope = 0.4;  // radians
  const SectionPolygon rect{rectangle(12.0, 8.0), {}};
  const SectionProperties rp = section_properties(rect);
  const PrintedSection a = printed_section(rect, rp, Vec2(1, 0), 0.0, all, false);
  const PrintedSection b = printed_section(rect, rp, Vec2(1, 0), 0.0, flat, false);
  EXPECT_NEAR(a.skin_area, b.skin_area, 1e-6);
  EXPECT_NEAR(a.modulus, b.modulus, 1e-9 * a.modulus);
  const double d = 6 * std::tan(M_PI / 6);  // along u, the build direction
  const SectionPolygon diamond{{{-d, 0}, {0, -6}, {d, 0}, {0, 6}}, {}};
  const SectionProperties dp = section_properties(diamond);
  EXPECT_GT(printed_section(diamond, dp, Vec2(1, 0), 0.0, all, false).skin_area, 1.0);
  EXPECT_NEAR(printed_section(diamond, dp, Vec2(1, 0), 0.0, flat, false).skin_area, 0.0, 1e-6);
}
