// The junction core of a section: the part of its region that continues through the plane
// where bones meet (docs/junctions.md).
#pragma once

#include <functional>
#include <vector>

#include "osteon/section.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

/// The junction core of a section (docs/junctions.md): the part of `section` that
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

}  // namespace osteon
