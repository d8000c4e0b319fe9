#include "osteon/mesh.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace osteon {

void validate_mesh(const MeshView& mesh) {
  if (mesh.num_vertices <= 0 || mesh.vertices == nullptr)
    throw std::invalid_argument("empty mesh: vertices has no rows");
  if (mesh.num_faces <= 0 || mesh.faces == nullptr)
    throw std::invalid_argument("empty mesh: faces has no rows");
  if (mesh.num_vertices > INT32_MAX)
    throw std::invalid_argument("mesh too large: more than 2^31 vertices");
  for (Index i = 0; i < 3 * mesh.num_vertices; ++i) {
    if (!std::isfinite(mesh.vertices[i]))
      throw std::invalid_argument("vertices contain NaN or infinity (vertex " +
                                  std::to_string(i / 3) + ")");
  }
  for (Index i = 0; i < 3 * mesh.num_faces; ++i) {
    const std::int32_t f = mesh.faces[i];
    if (f < 0 || f >= mesh.num_vertices)
      throw std::invalid_argument("face index out of range: faces[" + std::to_string(i / 3) +
                                  "] refers to vertex " + std::to_string(f) + " but there are " +
                                  std::to_string(mesh.num_vertices) + " vertices");
  }
}

double bounding_diagonal(const MeshView& mesh) {
  if (mesh.num_vertices <= 0) return 0.0;
  Vec3 lo = mesh.vertex(0), hi = lo;
  for (Index i = 1; i < mesh.num_vertices; ++i) {
    const Vec3 p = mesh.vertex(i);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

}  // namespace osteon
