// Thickness of a section region: the width a printer has to lay down there (docs/printing.md).
#pragma once

#include <vector>

#include "osteon/section.hpp"

namespace osteon {

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

/// Minimum width (mm) of a point set: the smallest distance between two parallel lines enclosing
/// it (the narrowest direction of its convex hull); 0 for fewer than three points.
double minimum_width(const std::vector<Vec2>& pts);

}  // namespace osteon
