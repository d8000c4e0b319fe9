// Quadric edge-collapse decimation of a closed triangle mesh (issue 35: a cheap first pass before
// auto_skeleton's pygel3d simplification of meshes with many faces). Units: mm.
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/mesh.hpp"

namespace osteon {

/// A decimated copy: vertices (#V' by 3 row-major, mm) and faces (#F' by 3 row-major).
struct DecimatedMesh {
  std::vector<double> vertices;
  std::vector<std::int32_t> faces;
};

/// Collapses edges of `mesh`, cheapest first, until at most `target_faces` faces remain or no
/// edge may be collapsed. The cost of an edge is the quadric error of its merged vertex (Garland
/// & Heckbert, "Surface simplification using quadric error metrics", SIGGRAPH 1997: the sum of
/// squared distances, mm², to the area-weighted planes of the faces the two vertices stood on),
/// the merged vertex goes where that error is least (or to the better end or the midpoint when
/// the planes do not fix a point). An edge is left when collapsing it would change the
/// topology (the link condition: its ends share exactly the two neighbours opposite it,
/// Dey et al. 1999), flip a face's normal, touch a boundary edge, or leave a piece of fewer than
/// four faces; so a closed 2-manifold mesh stays a closed 2-manifold of the same genus.
/// Deterministic (ties broken by vertex index); one thread. Faces with repeated vertices are
/// dropped first; vertices in no face are not returned. Throws std::invalid_argument for a bad
/// mesh (validate_mesh) or a negative target.
DecimatedMesh decimate_mesh(const MeshView& mesh, Index target_faces);

}  // namespace osteon
