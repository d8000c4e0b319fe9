// Bone skeleton: heads, tails and parent links, as Blender armatures and rig files give them.
#pragma once

#include <string>
#include <vector>

#include "osteon/types.hpp"

namespace osteon {

/// A skeleton of B bones; bone b runs from heads[b] to tails[b] (mm); parents[b] = -1 for a root.
struct Skeleton {
  std::vector<Vec3> heads;         ///< B head positions, mm
  std::vector<Vec3> tails;         ///< B tail positions, mm
  std::vector<int> parents;        ///< B parent indices, -1 = root bone
  std::vector<std::string> names;  ///< B names (may be empty: then "bone_<b>")

  /// Number of bones B.
  int num_bones() const { return static_cast<int>(heads.size()); }
  /// Bone length |tail - head|, mm.
  double length(int b) const { return (tails[b] - heads[b]).norm(); }
  /// Unit direction head -> tail.
  Vec3 direction(int b) const { return (tails[b] - heads[b]).normalized(); }
  /// Name of bone b (generated when names are empty).
  std::string name(int b) const;
};

/// Throws std::invalid_argument naming the problem: no bones, size mismatch, non-finite position,
/// zero-length bone, parent index out of range or self, parent cycle.
void validate_skeleton(const Skeleton& skeleton);

/// Indices of the bones with parent -1, in index order.
std::vector<int> root_bones(const Skeleton& skeleton);

/// Parameter (mm from the head, clamped to [0, length]) of the point of bone b nearest to p.
double project_onto_bone(const Skeleton& skeleton, int b, const Vec3& p);

/// Squared distance (mm^2) from p to the segment of bone b.
double squared_distance_to_bone(const Skeleton& skeleton, int b, const Vec3& p);

}  // namespace osteon
