#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "osteon/analysis.hpp"
#include "osteon/correction.hpp"
#include "osteon/skinning.hpp"
#include "osteon/weights.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::prism;
using osteon::testing::rectangle;

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
