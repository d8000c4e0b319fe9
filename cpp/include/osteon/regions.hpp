// Section material as a slicer prints it (SPEC §3): the non-zero-winding union of a plane cut's
// oriented loops, and the region around the bone point in it.
#pragma once

#include <cstdint>
#include <functional>
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

/// The section region of a plane cut around the plane origin (the bone point), SPEC §3: the
/// material region (outer boundary + its holes) of the non-zero-winding union that contains the
/// origin; if the origin lies in a real hole, the region around that hole (flag kFlagHollow).
/// If the origin lies in no material (flag kFlagOutside): with `domain`, the region holding the
/// greatest length of the bone's own cut segments, or none (kFlagUnreliable, found = false) when
/// no region holds any; without `domain`, the nearest region. `containing` counts the loops
/// around the origin (any orientation), for parity checks.
SectionGeometry select_region(const PlaneCut& cut, const BoneDomain* domain = nullptr);

/// The junction core of a section (SPEC §3, docs/junctions.md): the part of `section` that
/// continues through the plane, i.e. that the regions `neighbours` (the regions around the bone
/// point on parallel planes a short distance before and after, in the same plane coordinates,
/// mm) also contain. What the neighbours cover in common is widened by `margin_mm` (their
/// outlines thinned to within a quarter of it first; Clipper2 InflatePaths, round joins) so that
/// facet wobble does not trim a plain tube; of the material trimmed off, only the
/// pieces wider than 2 * opening_mm somewhere (their erosion by opening_mm is not empty: stubs)
/// are left out, whole; thin pieces (the rim of a taper, a tilted bone's crescent) stay. Returns
/// the region of the core around the plane origin (the bone point), or found = false when the
/// origin is not in the core (then the caller keeps the whole section).
///
/// `worth`, when given, is asked with regions the core is sure to contain, before the costly part
/// (the widening, the trimmed pieces): first, when one is found, a rectangle inside the section and
/// every thinned neighbour, joined to the origin inside them (found and checked in passes over
/// the edges, no intersection); then the region around the origin of what the section and the
/// neighbours' thinned outlines have in common, not widened (the core holds both: the widening
/// and the thin pieces only add). Returning false ends the call with found = false (a caller
/// whose test of the core the region already fails: the core is larger, its distances to the
/// section's vertices no larger). The second is not asked when the origin lies in no such region
/// or in one of its holes.
///
/// `may_fail`, when given, is asked before both with a box (mm, lower and upper corners) that holds
/// every region `worth` would be asked with: false says `worth` would return true for any region
/// inside it, and `worth` is not asked at all.
///
/// The work is done near the neighbours' common part: the section is clamped to a rectangle
/// around it (inside, nothing changes), and a trimmed piece reaching that rectangle's edge is
/// judged there only when it already holds a disc of 1.1 * opening_mm (a stub), else on the
/// whole section; the answer is the same as on the whole section (docs/junctions.md, Cost).
SectionGeometry junction_core(
    const SectionPolygon& section, const std::vector<const SectionPolygon*>& neighbours,
    double margin_mm, double opening_mm,
    const std::function<bool(const SectionPolygon& inner)>& worth = {},
    const std::function<bool(const Vec2& lo_mm, const Vec2& hi_mm)>& may_fail = {});

/// Thickness of a region (mm), the width a printer has to lay down there: the smallest of its
/// minimum width (the smallest distance between two parallel lines enclosing the outer boundary,
/// i.e. the narrowest direction of its convex hull) and, around each hole, the thinnest wall
/// (the hole's distance to the outer boundary and to every other hole). A solid round gives its
/// diameter, a b x t plate t, a tube of radii R > r its wall R - r. 0 for fewer than three
/// points.
double region_thickness(const SectionPolygon& polygon);

/// A lower bound (mm) of a region's minimum width (the convex hull part of region_thickness;
/// the walls around holes are not bounded), from its area (mm^2) and its smaller principal
/// second moment about the centroid (mm^4): 2 sqrt(I_min / A). Across the hull's narrowest
/// direction the region lies in a strip that wide, and an area spread over a strip of width t
/// has a second moment about its centroid of at most A t^2 / 4 (all of it at the two edges).
/// Half the diameter for a disc, t / sqrt(3) for a plate. 0 when degenerate.
double region_thickness_lower_bound(double area_mm2, double smaller_second_moment_mm4);

/// region_thickness(polygon) < limit_mm, decided without computing the thickness where it can:
/// `width_bound_mm` (region_thickness_lower_bound) at or above the limit skips the hull, and
/// the walls around holes are searched only within the limit (cheap when they are thick).
bool region_thinner_than(const SectionPolygon& polygon, double limit_mm, double width_bound_mm);

}  // namespace osteon

namespace osteon {

/// Loose pieces of a mesh: its shells (faces connected by shared vertices or by vertices at
/// exactly the same position) that neither touch nor overlap the held piece, directly or through
/// other attached shells. The held piece is the shell with the most vertices of `held_bone`
/// (vertex_bone, #V), else the largest. Two shells overlap when a vertex of one (16 sampled of
/// each) lies inside the other (ray parity) or an edge of one crosses a face of the other (in
/// the common part of their boxes; past ~1e8 edge-face pairs they count as attached), or when
/// they are closer than `contact_gap` mm (a vertex of either within that distance of a face of
/// the other): a printer fuses a gap narrower than it can print. Returns the vertex indices of
/// each loose piece. `face_shells`, when given, receives the number of shells the faces alone
/// make (shared vertex indices; positions not used; a vertex of no face is not printed and is no
/// shell, nor part of any piece): 1 means no loose piece whatever the vertices' positions, which
/// a caller with fixed faces (Analyzer) may keep.
std::vector<std::vector<std::int32_t>> loose_pieces(const MeshView& mesh,
                                                    const std::vector<int>& vertex_bone,
                                                    int held_bone, double contact_gap = 0.0,
                                                    Index* face_shells = nullptr);

/// loose_pieces() for repeated use (an Analyzer's live runs): the same answer, with the working
/// arrays kept from call to call (a live update allocates and frees no memory for it: freed
/// arrays go back to the system and their pages come back zero-filled, at a cost per page) and,
/// when `same_faces`, the faces' shells of the previous call reused (they do not depend on the
/// vertices' positions).
class LoosePieceFinder {
 public:
  /// As loose_pieces(mesh, vertex_bone, held_bone, contact_gap (mm), face_shells); same_faces:
  /// the mesh's faces and vertex count are those of the previous call; grid (optional): a face
  /// grid built from this mesh, which the inside tests walk along their ray instead of testing
  /// every face of a piece (the same answer).
  std::vector<std::vector<std::int32_t>> find(const MeshView& mesh,
                                              const std::vector<int>& vertex_bone, int held_bone,
                                              double contact_gap, Index* face_shells,
                                              bool same_faces, const FaceGrid* grid = nullptr);

 private:
  /// The faces' shells (they do not depend on the vertices' positions).
  void find_shells(const MeshView& mesh);
  bool have_shells_ = false;
  Index shells_ = 0;                    // shells of the faces alone
  std::vector<std::int32_t> shell_of_;  // #V shell of each vertex (by smallest vertex; -1: no face)
  std::vector<Index> shell_vstart_, shell_fstart_;  // shell k: [start[k], start[k + 1])
  std::vector<std::int32_t> shell_vertices_;        // each shell's vertices, ascending
  std::vector<std::int32_t> shell_faces_;           // each shell's faces (3 per face), mesh order
  std::int32_t largest_ = 0;                        // the shell with the most vertices
  std::vector<std::int32_t> other_vertices_;        // vertices of the other shells, ascending
  // Scratch kept for its storage.
  std::vector<std::int32_t> parent_, order_, piece_of_shell_;
  std::vector<std::vector<std::int32_t>> merged_;  // lists of pieces of several shells
};

}  // namespace osteon
