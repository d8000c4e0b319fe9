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
/// & Heckbert, "Surface simplification using quadric error metrics", SIGGRAPH 1997: the squared
/// distances to the planes of the faces the two vertices stood on, each weighted by its face's
/// area, mm⁴); the merged vertex goes where that error is least (or to the better end or the
/// midpoint when the planes do not fix a point near the edge). An edge is left when collapsing
/// it would change the topology (the link condition: its ends share exactly the two neighbours
/// opposite it, Dey et al. 1999), turn a face over or by more than 78°, touch a boundary or
/// non-manifold edge, or collapse a tetrahedron; so a closed 2-manifold mesh stays a closed
/// 2-manifold of the same genus, consistently oriented. Deterministic (ties broken by vertex
/// index); one thread. Faces with repeated vertices are dropped first; vertices in no face are
/// not returned. Throws std::invalid_argument for a bad mesh (validate_mesh) or a negative
/// target.
DecimatedMesh decimate_mesh(const MeshView& mesh, Index target_faces);

}  // namespace osteon
