// The walls' inset for the printed section (docs/printing.md, "Cost"): Clipper2's offset with
// its simple convex corners resolved before its union pass (internal to the engine).
#pragma once

#include "clipper2/clipper.h"

namespace osteon::detail {

/// Clipper2Lib::InflatePaths(paths, -delta, JoinType::Round, EndType::Polygon, 2.0,
/// arc_tolerance) for closed paths (outer boundaries counter-clockwise, holes clockwise) and
/// delta > 0, cheaper: Clipper2's raw offset path has, at each convex corner, the two offset
/// edges' ends and the corner itself (a small clockwise loop that its union pass removes, with
/// the crossing computed by the pass). Where that crossing lies within the middle halves of both
/// offset edges (the loop then holds only points within delta of the corner's two edges,
/// outside the inset), the raw path here takes the crossing itself, exact: one point in place of
/// three and no crossing for the union to find. Everything else (round joins, the union with the
/// positive fill rule, the orientation) is Clipper2's. The same region up to Clipper2's integer
/// rounding of those corners (0.5 unit).
Clipper2Lib::Paths64 inset_paths(const Clipper2Lib::Paths64& paths, double delta,
                                 double arc_tolerance);

}  // namespace osteon::detail
