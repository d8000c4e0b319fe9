#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "osteon/layers.hpp"

using namespace osteon;

TEST(Layers, TheTwoLimitsAreExact) {
  const double x = 60.0, r = 0.5;
  EXPECT_DOUBLE_EQ(layer_allowable(x, r, 1.0), 30.0);  // normal along the build direction: Z
  EXPECT_DOUBLE_EQ(layer_allowable(x, r, 0.0), 60.0);  // normal in the layer plane: X
}

TEST(Layers, FortyFiveDegreesIsTheHarmonicMean) {
  // cos^2 = sin^2 = 1/2: 1/[s] = (1/Z + 1/X)/2 -> [s] = 2XZ/(X+Z) = 40 MPa for X=60, Z=30.
  EXPECT_NEAR(layer_allowable(60.0, 0.5, 0.5), 40.0, 1e-12);
}

TEST(Layers, MatchesTsaiHillWithTheImpliedShearStrength) {
  const double x = 50.0, r = 0.65, z = r * x, s = layer_shear_strength(x, r);
  for (double deg = 0; deg <= 90; deg += 7.5) {
    const double t = deg * M_PI / 180, c = std::cos(t), sn = std::sin(t);
    const double inv2 = std::pow(c, 4) / (z * z) + std::pow(sn, 4) / (x * x) +
                        c * c * sn * sn * (1 / (s * s) - 1 / (x * x));
    EXPECT_NEAR(layer_allowable(x, r, c * c), 1 / std::sqrt(inv2), 1e-9 * x) << deg;
  }
  EXPECT_NEAR(layer_shear_strength(60.0, 1.0), 60.0 / std::sqrt(3.0), 1e-12);  // von Mises
}

TEST(Layers, MonotoneBetweenTheLimits) {
  double last = 0;
  for (int k = 0; k <= 100; ++k) {  // cos^2 from 1 (across) to 0 (along)
    const double a = layer_allowable(60.0, 0.6, 1.0 - k / 100.0);
    EXPECT_GE(a, last);
    last = a;
  }
}

TEST(Layers, IsotropicIsBitIdentical) {
  std::vector<Vec3> normals = {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0.6, 0, 0.8),
                               Vec3(1, 1, 1).normalized()};
  std::vector<double> allow;
  std::vector<std::uint8_t> across;
  section_allowables(normals, Vec3(0.3, -0.2, 1), 57.3, 1.0, allow, across);
  for (std::size_t i = 0; i < normals.size(); ++i) {
    EXPECT_EQ(allow[i], 57.3);
    EXPECT_EQ(across[i], 0);
  }
}

TEST(Layers, SectionsUseTheirAngleToTheBuildDirection) {
  std::vector<Vec3> normals = {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0),
                               Vec3(1, 0, 1).normalized()};
  std::vector<double> allow;
  std::vector<std::uint8_t> across;
  section_allowables(normals, Vec3(0, 0, 5), 60.0, 0.5, allow, across);  // any length
  EXPECT_DOUBLE_EQ(allow[0], 30.0);
  EXPECT_DOUBLE_EQ(allow[1], 30.0);  // sign of the normal does not matter
  EXPECT_DOUBLE_EQ(allow[2], 60.0);
  EXPECT_NEAR(allow[3], 40.0, 1e-12);
  EXPECT_EQ(across[0], 1);
  EXPECT_EQ(across[2], 0);
  EXPECT_EQ(across[3], 1);  // at 45 deg the weaker layer term (1/Z) is the larger
  // Lying along x: the layer term dominates only within atan(sqrt(1/ratio)) of the build axis.
  EXPECT_TRUE(across_layers(0.5, std::pow(std::cos(54.0 * M_PI / 180), 2)));
  EXPECT_FALSE(across_layers(0.5, std::pow(std::cos(55.0 * M_PI / 180), 2)));
}

TEST(Layers, BadOptionsAreRejected) {
  EXPECT_THROW(validate_layer_options(Vec3(0, 0, 0), 0.5), std::invalid_argument);
  EXPECT_THROW(validate_layer_options(Vec3(0, NAN, 1), 0.5), std::invalid_argument);
  EXPECT_THROW(validate_layer_options(Vec3(0, 0, 1), 0.0), std::invalid_argument);
  EXPECT_THROW(validate_layer_options(Vec3(0, 0, 1), INFINITY), std::invalid_argument);
  EXPECT_NO_THROW(validate_layer_options(Vec3(0, 0, 2), 0.7));
}
