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

}  // namespace osteon
