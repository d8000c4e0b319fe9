// The section region around the bone point: the material a slicer prints from a plane cut (the
// non-zero-winding union of its oriented loops, docs/robustness.md) and, in it, the region
// around the bone (docs/junctions.md for what happens where bones meet).
#pragma once

#include <vector>

#include "osteon/section.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

/// Which faces belong to the section's bone, to tie a region to a bone outside the mesh: a cut
/// segment belongs to `bone` when at least two of the three vertices of its triangle (found from
/// the two mesh edges it crosses) have vertex_bone == bone.
struct BoneDomain {
  const std::vector<CutSegment>* segments = nullptr;  ///< the plane's cut segments
  const int* vertex_bone = nullptr;                   ///< #V bone of each vertex
  int bone = -1;                                      ///< the section's bone
};

/// Material of a set of closed loops (plane coordinates, mm, orientation from the faces): the
/// union of the loops by the non-zero winding rule (Clipper2, 64-bit integer coordinates with a
/// power-of-two scale that resolves ~1e-12 of the loops' extent), as polygons with holes. An
/// inner shell inside an outer one adds nothing, overlapping shells merge, an inward-facing
/// (reversed) inner loop is a hole.
std::vector<SectionPolygon> material_regions(const std::vector<std::vector<Vec2>>& loops);

/// The section region of a plane cut around the plane origin (the bone point): the
/// material region (outer boundary + its holes) of the non-zero-winding union that contains the
/// origin; if the origin lies in a real hole, the region around that hole (flag kFlagHollow).
/// If the origin lies in no material (flag kFlagOutside): with `domain`, the region holding the
/// greatest length of the bone's own cut segments, or none (kFlagUnreliable, found = false) when
/// no region holds any; without `domain`, the nearest region. `containing` counts the loops
/// around the origin (any orientation), for parity checks.
SectionGeometry select_region(const PlaneCut& cut, const BoneDomain* domain = nullptr);

}  // namespace osteon
