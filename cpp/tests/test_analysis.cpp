#include <gtest/gtest.h>

#include <cmath>

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
