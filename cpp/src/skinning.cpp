#include "osteon/skinning.hpp"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace osteon {

void skin_cross_section_scales(const double* rest, Index num_vertices, const Skeleton& s,
                               const BoneWeights& w, const std::vector<double>& bone_scale,
                               double* out) {
  if (static_cast<int>(bone_scale.size()) != s.num_bones())
    throw std::invalid_argument("bone_scale must have one entry per bone");
  AxisScales scales{bone_scale, bone_scale, std::vector<Vec3>(s.num_bones(), Vec3::Zero()), {}};
  skin_axis_scales(rest, num_vertices, s, w, scales, out);
}

void skin_axis_scales(const double* rest, Index num_vertices, const Skeleton& s,
                      const BoneWeights& w, const AxisScales& scales, double* out) {
  const int nb = s.num_bones();
  if (static_cast<int>(scales.x.size()) != nb || static_cast<int>(scales.z.size()) != nb ||
      static_cast<int>(scales.x_axis.size()) != nb)
    throw std::invalid_argument("bone scales and axes must have one entry per bone");
  if (!scales.long_axis.empty() && static_cast<int>(scales.long_axis.size()) != nb)
    throw std::invalid_argument("bone long axes must be empty or have one entry per bone");
  if (out != rest) std::copy(rest, rest + 3 * num_vertices, out);
  std::vector<Vec3> axis(nb), x_axis(nb), z_axis(nb);
  std::vector<std::uint8_t> scaled(nb), uniform(nb);
  for (int b = 0; b < nb; ++b) {
    axis[b] = s.direction(b);
    if (!scales.long_axis.empty()) {
      const Vec3& l = scales.long_axis[b];
      if (!l.allFinite() || !(l.norm() > 1e-9))
        throw std::invalid_argument("long axis of bone " + std::to_string(b) +
                                    " must be a finite non-zero vector");
      axis[b] = l.normalized();
    }
    scaled[b] = scales.x[b] != 1.0 || scales.z[b] != 1.0;
    uniform[b] = scales.x[b] == scales.z[b];
    if (uniform[b]) continue;
    // The given axis made exactly perpendicular to the bone (a roll that drifted is harmless).
    const Vec3 x = scales.x_axis[b] - scales.x_axis[b].dot(axis[b]) * axis[b];
    if (!(x.norm() > 1e-9))
      throw std::invalid_argument("x axis of bone " + std::to_string(b) +
                                  " must be a unit vector across the bone");
    x_axis[b] = x.normalized();
    z_axis[b] = x_axis[b].cross(axis[b]);
  }
  for (Index v = 0; v < num_vertices; ++v) {
    double total = 0.0;
    bool moves = false;
    for (Index k = w.row_start[v]; k < w.row_start[v + 1]; ++k) {
      total += std::max(w.weight[k], 0.0);
      moves |= w.weight[k] > 0 && scaled[w.bone[k]];
    }
    if (!moves || !(total > 0)) continue;  // unweighted or only unscaled bones: bitwise unchanged
    const Vec3 p(rest[3 * v], rest[3 * v + 1], rest[3 * v + 2]);
    Vec3 delta = Vec3::Zero();
    for (Index k = w.row_start[v]; k < w.row_start[v + 1]; ++k) {
      const int b = w.bone[k];
      if (!scaled[b] || !(w.weight[k] > 0.0)) continue;
      const Vec3 rel = p - s.heads[b];
      const double share = w.weight[k] / total;
      if (uniform[b]) {
        const Vec3 across = rel - rel.dot(axis[b]) * axis[b];
        delta += share * (scales.x[b] - 1.0) * across;
      } else {
        delta += share * ((scales.x[b] - 1.0) * rel.dot(x_axis[b]) * x_axis[b] +
                          (scales.z[b] - 1.0) * rel.dot(z_axis[b]) * z_axis[b]);
      }
    }
    const Vec3 q = p + delta;
    out[3 * v] = q.x();
    out[3 * v + 1] = q.y();
    out[3 * v + 2] = q.z();
  }
}

}  // namespace osteon
