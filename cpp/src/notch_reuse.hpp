// Live mode's reuse of the corner search (issue 34): the corner search's faces in an order of
// their own, so that a measurement depends on the faces it reads alone. Engine-internal header.
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/types.hpp"

namespace osteon {

/// Orders a corner's local faces (3 mesh vertex indices each) by their vertex indices and lists
/// their distinct vertices in first-appearance order (`slot`: each listed vertex's entry, -1
/// elsewhere, as before the call). The face grid hands the faces out cell by cell, and its cells
/// follow the mesh's box: without this order a pose that moves the box (a hand at the model's
/// edge) reorders the sums of a corner far away, and its Kt moves in the last bits; with it the
/// measurement depends on the faces alone, which is what makes its reuse exact.
void canonical_face_order(std::vector<std::int32_t>& faces, std::vector<std::int32_t>& vertices,
                          std::vector<int>& slot);

}  // namespace osteon
