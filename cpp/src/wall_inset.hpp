// The walls' inset for the printed section (docs/performance.md, "The printed section's cost"):
// Clipper2's offset with its union pass done by winding_region (internal to the engine).
#pragma once

#include "clipper2/clipper.h"

namespace osteon::detail {

/// Clipper2Lib::InflatePaths(paths, -delta, JoinType::Round, EndType::Polygon, 2.0,
/// arc_tolerance) for closed paths (outer boundaries counter-clockwise, holes clockwise) and
/// delta >= 0.5, cheaper: Clipper2's raw offset path point for point (ClipperOffset's
/// DoGroupOffset, OffsetPoint, DoRound: offset edges, round joins, a three-point loop at each
/// convex corner), then the region of positive winding of that path (what Clipper2's union pass
/// keeps) from winding_region, with Clipper2's own pass where that declines. The same region up
/// to the rounding of crossing points to integer units.
Clipper2Lib::Paths64 wall_inset(const Clipper2Lib::Paths64& paths, double delta,
                                double arc_tolerance);

}  // namespace osteon::detail
