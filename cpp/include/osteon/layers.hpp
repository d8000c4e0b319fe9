// Layer strength of an FDM print (issue 18, docs/printing.md): the allowable bending stress of a
// section depends on the angle between its normal and the build direction.
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/types.hpp"

namespace osteon {

/// Allowable uniaxial normal stress, MPa, along a direction at angle theta to the build
/// direction, given cos2 = cos^2(theta) in [0, 1]:
///   1 / [sigma](theta) = cos^2(theta) / Z + sin^2(theta) / X,   Z = ratio * X,
/// i.e. the off-axis Tsai-Hill criterion with the shear strength of layer_shear_strength().
/// Exact limits: cos2 = 1 (stress across the layers) gives Z, cos2 = 0 (stress along the
/// layers) gives X; ratio == 1 returns in_plane bit for bit for every angle.
/// in_plane: X, MPa (> 0); ratio: Z / X (> 0).
double layer_allowable(double in_plane, double ratio, double cos2);

/// Interlayer shear strength S, MPa, that makes Tsai-Hill reduce to layer_allowable():
/// 1/S^2 = 1/X^2 + 2/(X Z). Isotropic (Z = X): S = X / sqrt(3), von Mises' value.
double layer_shear_strength(double in_plane, double ratio);

/// True when the layer term dominates the allowable (cos^2/Z > sin^2/X) and the layers are the
/// weaker direction (ratio < 1): the section fails "across layers". Always false for ratio >= 1.
bool across_layers(double ratio, double cos2);

/// Throws std::invalid_argument unless build_direction is finite and non-zero and ratio is a
/// positive finite number.
void validate_layer_options(const Vec3& build_direction, double ratio);

/// Per section allowable stress and failure mode for one build direction.
/// normals: S unit section normals; build_direction: any non-zero vector (normalised here);
/// in_plane: X, MPa; ratio: Z / X. Writes allowable (S,) MPa and across (S,) 0/1.
/// Isotropic (ratio == 1): allowable == in_plane exactly, across == 0.
void section_allowables(const std::vector<Vec3>& normals, const Vec3& build_direction,
                        double in_plane, double ratio, std::vector<double>& allowable,
                        std::vector<std::uint8_t>& across);

}  // namespace osteon
