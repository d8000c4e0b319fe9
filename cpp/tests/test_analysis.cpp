#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "osteon/analysis.hpp"
#include "osteon/correction.hpp"
#include "osteon/skinning.hpp"
#include "osteon/slicer.hpp"
#include "osteon/weights.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::OwnedMesh;
using osteon::testing::prism;
using osteon::testing::rectangle;
using osteon::testing::regular_polygon;

namespace {
Skeleton bar(double length) {
  Skeleton s;
  s.heads = {Vec3::Zero()};
  s.tails = {Vec3(length, 0, 0)};
  s.parents = {-1};
  return s;
}
}  // namespace

TEST(Analysis, CantileverStressIsFdOverW) {
  const auto m = prism(rectangle(6, 6), 90, 31);
  AnalysisOptions o;
  o.force = 10;
  o.interval = 3;
  const AnalysisResult r = analyze(m.view(), bar(90), nullptr, o);
  const double w = 216.0 / (6 * std::sqrt(2.0));
  int checked = 0;
  for (std::size_t i = 0; i < r.stress.size(); ++i) {
    if (r.section_kind[i] != kInterior) continue;
    const double x = r.section_param[i];
    const double d = std::sqrt((90 - x) * (90 - x) + 18.0);  // to a far corner
    EXPECT_NEAR(r.moment_arm[i], d, 1e-9);
    EXPECT_NEAR(r.stress[i], 10 * d / w, 1e-9 * r.stress[i]);
    ++checked;
  }
  EXPECT_EQ(checked, 29);
}

TEST(Analysis, LayerStrengthFollowsTheBuildDirection) {
  // The bar runs along x: lying (+Z up) its sections are checked against X, standing (built
  // along x) against Z = ratio X; isotropic results stay bit-identical for any direction.
  const auto m = prism(rectangle(6, 6), 90, 31);
  AnalysisOptions o;
  o.force = 10;
  o.interval = 3;
  const AnalysisResult iso = analyze(m.view(), bar(90), nullptr, o);
  o.build_direction = Vec3(0.3, -0.2, 0.9);
  const AnalysisResult iso2 = analyze(m.view(), bar(90), nullptr, o);
  ASSERT_EQ(iso.stress.size(), iso2.stress.size());  // bit for bit (NaN where skipped)
  EXPECT_EQ(0,
            std::memcmp(iso.stress.data(), iso2.stress.data(), iso.stress.size() * sizeof(double)));
  EXPECT_EQ(iso.weak, iso2.weak);
  EXPECT_EQ(iso.culled, iso2.culled);
  o.layer_strength_ratio = 0.5;
  o.build_direction = Vec3(0, 0, 1);
  const AnalysisResult lying = analyze(m.view(), bar(90), nullptr, o);
  o.build_direction = Vec3(2, 0, 0);
  const AnalysisResult standing = analyze(m.view(), bar(90), nullptr, o);
  for (std::size_t i = 0; i < lying.stress.size(); ++i) {
    if (lying.section_kind[i] != kInterior) continue;
    EXPECT_EQ(lying.section_allowable[i], o.allowable_stress);
    EXPECT_DOUBLE_EQ(standing.section_allowable[i], 0.5 * o.allowable_stress);
    EXPECT_DOUBLE_EQ(standing.stress_ratio[i], standing.stress[i] / (0.5 * o.allowable_stress));
    EXPECT_FALSE(lying.across_layers[i]);
    EXPECT_TRUE(standing.across_layers[i]);
  }
  EXPECT_DOUBLE_EQ(standing.max_stress_ratio, 2 * lying.max_stress_ratio);
  o.layer_strength_ratio = 0;
  EXPECT_THROW(analyze(m.view(), bar(90), nullptr, o), std::invalid_argument);
}
TEST(Skinning, ScalesAcrossTheBoneOnly) {
  const auto m = prism(rectangle(4, 2), 20);
  const BoneWeights w = nearest_bone_weights(m.view(), bar(20));
  std::vector<double> out(m.v.size());
  skin_cross_section_scales(m.v.data(), m.view().num_vertices, bar(20), w, {2.0}, out.data());
  for (std::size_t i = 0; i < m.v.size(); i += 3) {
    EXPECT_EQ(out[i], m.v[i]);
    EXPECT_NEAR(out[i + 1], 2 * m.v[i + 1], 1e-12);
    EXPECT_NEAR(out[i + 2], 2 * m.v[i + 2], 1e-12);
  }
}

TEST(Skinning, LongAxisGivesTheAxisScaledAcross) {
  // A joint rig's Blender bone: segment along x, but the bone scales across its own local axis
  // z (long_axis), x along (1, 0, 0) and z = x cross long = (0, -1, 0): p -> (sx px, sz py, pz)
  // about the head, whatever the segment (Blender's pose scale (sx, 1, sz) on those axes).
  const auto m = prism(rectangle(4, 2), 20);
  const Skeleton s = bar(20);
  const BoneWeights w = nearest_bone_weights(m.view(), s);
  AxisScales scales{{2.0}, {3.0}, {Vec3(1, 0, 0)}, {Vec3(0, 0, 5)}};
  std::vector<double> out(m.v.size());
  skin_axis_scales(m.v.data(), m.view().num_vertices, s, w, scales, out.data());
  for (std::size_t i = 0; i < m.v.size(); i += 3) {
    EXPECT_NEAR(out[i], 2 * m.v[i], 1e-12);
    EXPECT_NEAR(out[i + 1], 3 * m.v[i + 1], 1e-12);
    EXPECT_EQ(out[i + 2], m.v[i + 2]);
  }
  // uniform: both axes across the long axis; the long axis along the segment is the default
  AxisScales uniform{{2.0}, {2.0}, {Vec3::Zero()}, {Vec3(0, 0, 1)}};
  skin_axis_scales(m.v.data(), m.view().num_vertices, s, w, uniform, out.data());
  for (std::size_t i = 0; i < m.v.size(); i += 3) {
    EXPECT_NEAR(out[i], 2 * m.v[i], 1e-12);
    EXPECT_NEAR(out[i + 1], 2 * m.v[i + 1], 1e-12);
    EXPECT_EQ(out[i + 2], m.v[i + 2]);
  }
  std::vector<double> a(m.v.size()), b(m.v.size());
  AxisScales along{{2.0}, {1.5}, {Vec3(0, 1, 0)}, {Vec3(1, 0, 0)}};
  skin_axis_scales(m.v.data(), m.view().num_vertices, s, w, along, a.data());
  along.long_axis.clear();
  skin_axis_scales(m.v.data(), m.view().num_vertices, s, w, along, b.data());
  EXPECT_EQ(a, b);
  along.long_axis = {Vec3::Zero()};
  EXPECT_THROW(skin_axis_scales(m.v.data(), m.view().num_vertices, s, w, along, a.data()),
               std::invalid_argument);
}

TEST(Analysis, FreeHeadOnTheEndCapIsCut) {
  // The bar's head lies on the prism's end cap: its end section is the cap's outline (the
  // section just inside), with the cantilever's largest moment, not an empty cut.
  const auto m = prism(rectangle(6, 6), 90, 31);
  AnalysisOptions o;
  o.force = 10;
  o.interval = 3;
  const AnalysisResult r = analyze(m.view(), bar(90), nullptr, o);
  const double w = 216.0 / (6 * std::sqrt(2.0));
  int ends = 0;
  for (std::size_t i = 0; i < r.stress.size(); ++i) {
    EXPECT_EQ(r.section_flags[i], 0u) << "section " << i << " at " << r.section_param[i];
    if (r.section_kind[i] != kEnd || r.section_param[i] != 0.0) continue;
    const double d = std::sqrt(90.0 * 90.0 + 18.0);
    EXPECT_NEAR(r.section_area[i], 36.0, 1e-9);
    EXPECT_NEAR(r.stress[i], 10 * d / w, 1e-6 * r.stress[i]);
    EXPECT_DOUBLE_EQ(r.max_stress, r.stress[i]);
    ++ends;
  }
  EXPECT_EQ(ends, 1);
}

TEST(Correction, BarFixedByCubeRootOfStressRatio) {
  const auto m = prism(rectangle(6, 6), 90, 31);
  AnalysisOptions o;
  o.force = 10;
  const AnalysisResult before = analyze(m.view(), bar(90), nullptr, o);
  o.allowable_stress = before.max_stress / 2;
  const BoneWeights w = nearest_bone_weights(m.view(), bar(90));
  const CorrectionResult c = correct(m.view(), bar(90), w, o, CorrectionOptions{});
  EXPECT_TRUE(c.converged);
  EXPECT_EQ(c.rounds.size(), 1u);
  EXPECT_NEAR(c.bone_scale[0], std::cbrt(2.0), 0.02 * std::cbrt(2.0));
  EXPECT_LE(c.after.max_stress, o.allowable_stress);
}

TEST(Weights, DominantBoneFromCsrWithEitherIndexWidth) {
  // Rows: a clear winner, a tie (the first listed wins), all-zero (no bone), round-off only.
  const Index indptr[] = {0, 2, 4, 5, 6};
  const Index wide[] = {0, 2, 1, 0, 2, 1};
  const std::int32_t narrow[] = {0, 2, 1, 0, 2, 1};
  const double data[] = {0.25, 0.75, 0.5, 0.5, 0.0, 1e-13};
  const std::vector<int> expected = {2, 1, -1, -1};
  EXPECT_EQ(dominant_bones_csr(indptr, wide, data, 4, 3, 1), expected);
  EXPECT_EQ(dominant_bones_csr(indptr, narrow, data, 4, 3, 2), expected);
  const std::int32_t out_of_range[] = {0, 3, 1, 0, 2, 1};
  EXPECT_THROW(dominant_bones_csr(indptr, out_of_range, data, 4, 3), std::invalid_argument);
  const double negative[] = {0.25, -0.5, 0.5, 0.5, 0.0, 0.0};
  EXPECT_THROW(dominant_bones_csr(indptr, narrow, negative, 4, 3), std::invalid_argument);
}

namespace {
// Area (mm^2) of a closed planar 3D loop, by the shoelace formula projected on the unit normal.
double loop_area(const AnalysisResult& r, std::int64_t loop, const Vec3& normal) {
  const std::int64_t a = r.outline_loop_start[loop], b = r.outline_loop_start[loop + 1];
  Vec3 sum = Vec3::Zero();
  for (std::int64_t k = a; k < b; ++k)
    sum += r.outline_points[k].cross(r.outline_points[k + 1 < b ? k + 1 : a]);
  return 0.5 * std::abs(sum.dot(normal));
}
}  // namespace

TEST(Analysis, OutlinesEncloseTheSectionArea) {
  // An L of two bones: interior sections, an oblique joint section and free ends.
  const auto m = prism(osteon::testing::regular_polygon(4.0, 24), 60, 21);
  Skeleton s;
  s.heads = {Vec3::Zero(), Vec3(30, 0, 0)};
  s.tails = {Vec3(30, 0, 0), Vec3(60, 0.5, 0)};
  s.parents = {-1, 0};
  AnalysisOptions o;
  o.interval = 4;
  const AnalysisResult plain = analyze(m.view(), s, nullptr, o);
  EXPECT_TRUE(plain.outline_points.empty());
  EXPECT_TRUE(plain.outline_section_start.empty());
  o.keep_outlines = true;
  const AnalysisResult r = analyze(m.view(), s, nullptr, o);
  const std::size_t ns = r.section_area.size();
  ASSERT_EQ(r.outline_section_start.size(), ns + 1);
  ASSERT_EQ(r.outline_loop_start.back(), static_cast<std::int64_t>(r.outline_points.size()));
  int checked = 0;
  for (std::size_t i = 0; i < ns; ++i) {
    EXPECT_EQ(r.section_area[i], plain.section_area[i]);
    const std::int64_t first = r.outline_section_start[i], last = r.outline_section_start[i + 1];
    if (!std::isfinite(r.stress[i])) {
      EXPECT_EQ(first, last);
      continue;
    }
    ASSERT_GT(last, first);
    double area = loop_area(r, first, r.section_normal[i]);
    for (std::int64_t l = first + 1; l < last; ++l) area -= loop_area(r, l, r.section_normal[i]);
    EXPECT_NEAR(area, r.section_area[i], 1e-9 * r.section_area[i]);
    // The points lie on the section plane.
    for (std::int64_t k = r.outline_loop_start[first]; k < r.outline_loop_start[last]; ++k)
      EXPECT_NEAR((r.outline_points[k] - r.section_point[i]).dot(r.section_normal[i]), 0.0, 1e-9);
    ++checked;
  }
  EXPECT_GE(checked, 14);
}

TEST(Analysis, JunctionCountsOnlyTheBarThroughAStub) {
  // A round bar r = 3 (64-gon) along x, 0..40, and a stub of the same radius fused at x = 20,
  // along z up to 9: two overlapping closed shells (the engine takes their union).
  const double r = 3;
  const OwnedMesh rod = prism(regular_polygon(r, 64), 40, 41);
  OwnedMesh m = rod;
  const OwnedMesh stub = prism(regular_polygon(r, 64), 9, 10);
  const std::int32_t base = static_cast<std::int32_t>(m.v.size() / 3);
  for (std::size_t i = 0; i < stub.v.size(); i += 3) {  // (x, y, z) -> (20 + y, z, x): a rotation
    m.v.push_back(20 + stub.v[i + 1]);
    m.v.push_back(stub.v[i + 2]);
    m.v.push_back(stub.v[i]);
  }
  for (std::int32_t f : stub.f) m.f.push_back(base + f);
  AnalysisOptions o;
  const AnalysisResult a = analyze(m.view(), bar(40), nullptr, o);
  const AnalysisResult plain = analyze(rod.view(), bar(40), nullptr, o);
  ASSERT_EQ(a.section_modulus.size(), plain.section_modulus.size());
  const double w_round = M_PI * r * r * r / 4;
  int through = 0, away = 0;
  for (std::size_t i = 0; i < a.section_modulus.size(); ++i) {
    if (a.section_kind[i] != kInterior) continue;
    const double x = a.section_param[i];
    if (std::abs(x - 20) < r) {  // x = 18, 20, 22: the plane cuts the stub
      ++through;
      EXPECT_TRUE(a.section_flags[i] & kFlagJunction) << x;
      EXPECT_NEAR(a.section_modulus[i] / w_round, 1.0, 0.10) << x;
      EXPECT_GT(a.section_cut_modulus[i], 1.6 * w_round) << x;
      EXPECT_NEAR(a.stress[i], a.moment[i] / a.section_modulus[i], 1e-12 * a.stress[i]);
    } else if (std::abs(x - 20) > r + 1) {
      ++away;
      EXPECT_FALSE(a.section_flags[i] & kFlagJunction) << x;
      EXPECT_NEAR(a.section_modulus[i], plain.section_modulus[i], 0.01 * plain.section_modulus[i]);
    }
  }
  EXPECT_EQ(through, 3);
  EXPECT_GE(away, 12);
  // The prismatic bar: no junction, whole cut == section.
  for (std::size_t i = 0; i < plain.section_modulus.size(); ++i) {
    EXPECT_FALSE(plain.section_flags[i] & kFlagJunction);
    EXPECT_EQ(plain.section_area[i], plain.section_cut_area[i]);
  }
}

TEST(Analysis, JunctionLeavesAShallowBulgeWhole) {
  // The bar of the test above with a knob of the same radius that sticks out only 2 mm beyond
  // the bar (top at z = 5): the planes through it are candidates (cut > 1.5 x the bar's area),
  // but the trimmed material reaches less than 1.25 core radii (3.75 mm) out of the core: a
  // bulge, the bone's own. Every section equals the whole-cut analysis (junctions off).
  const double r = 3;
  OwnedMesh m = prism(regular_polygon(r, 64), 40, 41);
  const OwnedMesh knob = prism(regular_polygon(r, 64), 5, 6);
  const std::int32_t base = static_cast<std::int32_t>(m.v.size() / 3);
  for (std::size_t i = 0; i < knob.v.size(); i += 3) {  // (x, y, z) -> (20 + y, z, x)
    m.v.push_back(20 + knob.v[i + 1]);
    m.v.push_back(knob.v[i + 2]);
    m.v.push_back(knob.v[i]);
  }
  for (std::int32_t f : knob.f) m.f.push_back(base + f);
  AnalysisOptions o;
  const AnalysisResult a = analyze(m.view(), bar(40), nullptr, o);
  o.junctions = false;
  const AnalysisResult whole = analyze(m.view(), bar(40), nullptr, o);
  int candidates = 0;
  for (std::size_t i = 0; i < a.section_modulus.size(); ++i) {
    EXPECT_FALSE(a.section_flags[i] & kFlagJunction) << a.section_param[i];
    EXPECT_EQ(a.section_modulus[i], whole.section_modulus[i]) << a.section_param[i];
    if (a.section_kind[i] == kInterior && a.section_cut_area[i] > 1.5 * M_PI * r * r) ++candidates;
  }
  EXPECT_GE(candidates, 1);
}

TEST(Analysis, DeferredThicknessIsFilledInAsComputedAtOnce) {
  // A 6 x 0.5 mm plate bar (too thin for min_thickness 0.8) and a 6 x 2 mm one: deferred, the
  // too_thin check computes only the plate's thickness; the 2 mm bar's waits in the pending list
  // until complete_section_thickness, which gives what the eager run gives (its thickness, 2 mm).
  for (const double t : {0.5, 2.0}) {
    const auto m = prism(rectangle(6, t), 90, 31);
    AnalysisOptions o;
    o.interval = 3;
    const AnalysisResult eager = analyze(m.view(), bar(90), nullptr, o);
    o.defer_thickness = true;
    AnalysisResult lazy = analyze(m.view(), bar(90), nullptr, o);
    EXPECT_EQ(lazy.section_flags, eager.section_flags);
    int pending = 0;
    for (std::size_t i = 0; i < lazy.section_thickness.size(); ++i) {
      const bool waits = !lazy.thickness_pending.empty() && lazy.thickness_pending[i];
      pending += waits;
      EXPECT_EQ(std::isnan(lazy.section_thickness[i]),
                waits || std::isnan(eager.section_thickness[i]));
    }
    EXPECT_EQ(pending > 0, t > o.min_thickness) << t;
    complete_section_thickness(lazy);
    EXPECT_TRUE(lazy.thickness_pending.empty());
    for (std::size_t i = 0; i < lazy.section_thickness.size(); ++i) {
      if (std::isnan(eager.section_thickness[i])) continue;
      EXPECT_EQ(lazy.section_thickness[i], eager.section_thickness[i]) << i;
      if (eager.section_kind[i] == kInterior) {
        EXPECT_NEAR(eager.section_thickness[i], t, 1e-9);
      }
    }
  }
}

// A live Analyzer checks the vertices in blocks kept from run to run (Impl::check_vertices): a
// NaN in an update's changed block is refused with the first bad vertex named, and a later live
// update (the tip thinned: one block moved) is a one-off analysis's.
TEST(Analysis, LiveUpdateChecksChangedBlocksAndRecovers) {
  const auto m = prism(regular_polygon(5, 64), 90, 40);  // 2 560 vertices: three blocks
  const Index nv = m.view().num_vertices;
  AnalysisOptions o;
  o.interval = 3;
  Analyzer an(m.f.data(), m.view().num_faces, nv, nullptr, 1, o);
  an.run(m.v.data(), bar(90));
  std::vector<double> bad = m.v;
  bad[3 * 2000 + 1] = std::nan("");
  bad[3 * 2100 + 2] = INFINITY;
  try {
    an.run(bad.data(), bar(90));
    FAIL() << "a NaN vertex was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(vertex 2000)"), std::string::npos) << e.what();
  }
  an.run(m.v.data(), bar(90));  // a full run again (the failed one forgot the last run)
  OwnedMesh thin = m;
  for (Index v = 0; v < nv; ++v)
    if (thin.v[3 * v] > 60) thin.v[3 * v + 1] *= 0.8, thin.v[3 * v + 2] *= 0.8;
  const AnalysisResult live = an.run(thin.v.data(), bar(90));
  const AnalysisResult one_off = analyze(thin.view(), bar(90), nullptr, o);
  ASSERT_EQ(live.stress.size(), one_off.stress.size());
  for (std::size_t i = 0; i < live.stress.size(); ++i)
    EXPECT_NEAR(live.stress[i], one_off.stress[i], 1e-12 * one_off.stress[i]);
}
