// The region of closed integer paths by their winding numbers (internal to the engine): what
// Clipper2's boolean passes compute for the printed section (docs/performance.md, "The printed
// section's cost"), from the arrangement of the paths' crossings found in a uniform grid.
#pragma once

#include <array>
#include <vector>

#include "clipper2/clipper.h"

namespace osteon::detail {

/// Winding numbers of a point about each set of paths (at most 3 sets), counter-clockwise
/// loops counting +1 inside.
using Windings = std::array<int, 3>;

/// The points whose winding numbers satisfy `inside` (a rule such as "set 0's winding > 0",
/// Clipper2's FillRule::Positive), as closed loops with the region on their left (outer
/// boundaries counter-clockwise, holes clockwise, Clipper2's orientation). Crossing points are
/// rounded to integers as Clipper2 rounds them; duplicate points and spikes of the input are
/// dropped first. Returns false, and leaves `out` empty, where the paths are not in general
/// position (a vertex on another path's edge, overlapping edges, two crossings at one point,
/// a crossing shared by more than one loop of the result): the caller then uses Clipper2.
bool winding_region(const std::vector<const Clipper2Lib::Paths64*>& sets,
                    bool (*inside)(const Windings&), Clipper2Lib::Paths64& out);

}  // namespace osteon::detail
