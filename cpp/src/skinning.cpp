#include "osteon/skinning.hpp"

#include <algorithm>
#include <stdexcept>

namespace osteon {

void skin_cross_section_scales(const double* rest, Index num_vertices, const Skeleton& s,
                               const BoneWeights& w, const std::vector<double>& bone_scale,
                               double* out) {
  const int nb = s.num_bones();
  if (static_cast<int>(bone_scale.size()) != nb)
    throw std::invalid_argument("bone_scale must have one entry per bone");
  if (out != rest) std::copy(rest, rest + 3 * num_vertices, out);
  std::vector<Vec3> axis(nb);
  for (int b = 0; b < nb; ++b) axis[b] = s.direction(b);
  for (Index v = 0; v < num_vertices; ++v) {
    double total = 0.0;
    bool moves = false;
    for (Index k = w.row_start[v]; k < w.row_start[v + 1]; ++k) {
      total += std::max(w.weight[k], 0.0);
      moves |= w.weight[k] > 0 && bone_scale[w.bone[k]] != 1.0;
    }
    if (!moves || !(total > 0)) continue;  // unweighted or only unscaled bones: bitwise unchanged
    const Vec3 p(rest[3 * v], rest[3 * v + 1], rest[3 * v + 2]);
    Vec3 delta = Vec3::Zero();
    for (Index k = w.row_start[v]; k < w.row_start[v + 1]; ++k) {
      const int b = w.bone[k];
      if (bone_scale[b] == 1.0 || !(w.weight[k] > 0.0)) continue;
      const Vec3 rel = p - s.heads[b];
      const Vec3 across = rel - rel.dot(axis[b]) * axis[b];
      delta += (w.weight[k] / total) * (bone_scale[b] - 1.0) * across;
    }
    const Vec3 q = p + delta;
    out[3 * v] = q.x();
    out[3 * v + 1] = q.y();
    out[3 * v + 2] = q.z();
  }
}

}  // namespace osteon
