// Linear blend skinning with per-bone cross-section scales, as Blender's Armature modifier does it.
#pragma once

#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/skeleton.hpp"
#include "osteon/weights.hpp"

namespace osteon {

/// Deforms rest vertices: each bone b scales the two axes across itself by bone_scale[b] about its
/// own axis (length kept); a vertex moves by the weight-normalised blend of its bones' transforms;
/// a vertex with no weight, or weights only on unscaled bones, does not move (bitwise).
/// rest: #V by 3 row-major mm; out: #V by 3 row-major mm (may alias rest).
void skin_cross_section_scales(const double* rest, Index num_vertices, const Skeleton& skeleton,
                               const BoneWeights& weights, const std::vector<double>& bone_scale,
                               double* out);

/// Per-bone scales across each bone along two axes, as Blender's pose-bone scale X and Z: x_axis
/// is the bone's local X (unit, across the bone), Z = X x direction (Blender's X x Y).
struct AxisScales {
  std::vector<double> x;     ///< B scale along each bone's x axis (1 = unchanged)
  std::vector<double> z;     ///< B scale along each bone's z axis
  std::vector<Vec3> x_axis;  ///< B unit axis across each bone; not used where x == z
  /// B unit axes that keep scale 1 (the "length" axis), or empty: each bone's segment direction.
  /// A joint rig's Blender bone (FBX/glTF import) points elsewhere than its segment; scaling
  /// across its own local axis nearest the segment is what Blender's pose scale does.
  std::vector<Vec3> long_axis;
};

/// As skin_cross_section_scales, with a scale per axis; where x == z (and long_axis is empty) it
/// is that function exactly. Each bone b scales about the line through its head along
/// long_axis[b] (its direction when long_axis is empty): x along x_axis made perpendicular to
/// that line, z along z = x × long. rest, out: #V by 3 row-major mm (out may alias rest).
void skin_axis_scales(const double* rest, Index num_vertices, const Skeleton& skeleton,
                      const BoneWeights& weights, const AxisScales& scales, double* out);

}  // namespace osteon
