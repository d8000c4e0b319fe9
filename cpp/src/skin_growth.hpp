// Narrow skins widened into the sparse infill, layer by layer, as PrusaSlicer, Bambu Studio and
// OrcaSlicer do it (docs/printing.md, "Skins widened under slopes").
#pragma once
#include <vector>

#include "osteon/types.hpp"

namespace osteon::detail {

/// Closed loops in the section's (s, t) axes, mm: s along the build direction's trace in the
/// plane (+s up), t across it. Outer boundaries and holes of non-overlapping regions (even-odd).
using StLoops = std::vector<std::vector<Vec2>>;

/// A strip of the sparse region the slicer fills solid: s in [s0, s1], t in [t0, t1], mm.
struct SkinStrip {
  double s0, s1, t0, t1;
};

/// The layers' rule, on rows of the section one layer apart along s (`pitch` = layer height /
/// sin(theta), mm): a row's top skin sources are the parts of rows at most `layers` - 1 above
/// it (and itself) that the row above them does not cover, its bottom sources likewise below;
/// each source's part inside the row's infill region (`inner`: the cut less the walls) is solid,
/// and one narrower than 2 x `growth` (mm) is widened by `growth` on each side within that
/// region (PrintObject::discover_horizontal_shells: "make sure the new internal solid is wide
/// enough", margin = 3 x the solid infill's width). Returns the strips that widening adds to the
/// solid fill inside `sparse` (the sparse islands kept so far), one per row and interval; empty
/// when nothing is widened or the rows would be more than `max_rows`.
std::vector<SkinStrip> widened_skin_strips(const StLoops& section, const StLoops& inner,
                                           const StLoops& sparse, double pitch, int layers,
                                           double growth, int max_rows = 20000);

}  // namespace osteon::detail
