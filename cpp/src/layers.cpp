// Layer strength of an FDM print: see osteon/layers.hpp and docs/printing.md.
#include "osteon/layers.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace osteon {

double layer_allowable(double in_plane, double ratio, double cos2) {
  if (ratio == 1.0) return in_plane;  // isotropic: exactly X for every direction
  const double c2 = std::clamp(cos2, 0.0, 1.0);
  // 1/[s] = c2/Z + (1-c2)/X = (c2 + (1-c2) ratio) / (ratio X)
  return ratio * in_plane / (c2 + (1.0 - c2) * ratio);
}

double layer_shear_strength(double in_plane, double ratio) {
  const double z = ratio * in_plane;
  return 1.0 / std::sqrt(1.0 / (in_plane * in_plane) + 2.0 / (in_plane * z));
}

bool across_layers(double ratio, double cos2) {
  if (!(ratio < 1.0)) return false;
  const double c2 = std::clamp(cos2, 0.0, 1.0);
  return c2 > ratio * (1.0 - c2);  // c2 / Z > (1 - c2) / X
}

void validate_layer_options(const Vec3& build_direction, double ratio) {
  if (!build_direction.allFinite() || !(build_direction.norm() > 0))
    throw std::invalid_argument("build_direction must be a finite non-zero 3-vector");
  if (!(ratio > 0) || !std::isfinite(ratio))
    throw std::invalid_argument(
        "layer_strength_ratio must be a positive finite number (layer / in-plane strength)");
}

void section_allowables(const std::vector<Vec3>& normals, const Vec3& build_direction,
                        double in_plane, double ratio, std::vector<double>& allowable,
                        std::vector<std::uint8_t>& across) {
  const std::size_t n = normals.size();
  allowable.assign(n, in_plane);
  across.assign(n, 0);
  if (ratio == 1.0) return;
  const Vec3 b = build_direction.normalized();
  for (std::size_t i = 0; i < n; ++i) {
    const double c = normals[i].dot(b);
    const double c2 = std::isfinite(c) ? c * c : 0.0;
    allowable[i] = layer_allowable(in_plane, ratio, c2);
    across[i] = across_layers(ratio, c2);
  }
}

}  // namespace osteon
