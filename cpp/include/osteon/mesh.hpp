// Non-owning view of a triangle mesh (row-major arrays, as NumPy hands them over).
#pragma once

#include <cstdint>

#include "osteon/types.hpp"

namespace osteon {

/// A triangle mesh borrowed from the caller; nothing is copied.
struct MeshView {
  const double* vertices = nullptr;     ///< V  #V by 3 row-major vertex positions, mm
  Index num_vertices = 0;               ///< #V
  const std::int32_t* faces = nullptr;  ///< F  #F by 3 row-major vertex indices into V
  Index num_faces = 0;                  ///< #F

  /// Position of vertex i, mm.
  Vec3 vertex(Index i) const {
    return Vec3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
  }
};

/// Throws std::invalid_argument naming the problem: empty mesh, non-finite coordinate,
/// face index negative or out of range.
void validate_mesh(const MeshView& mesh);

/// Length of the bounding-box diagonal of the vertices, mm (0 for an empty mesh).
double bounding_diagonal(const MeshView& mesh);

}  // namespace osteon
