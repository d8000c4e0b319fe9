// Line-triangle intersection shared by the grid's line crossings and the loose-piece test.
#pragma once

#include "osteon/types.hpp"

namespace osteon::detail {

/// Moller-Trumbore for the infinite line point + t * dir against triangle (a, a+e1, a+e2), mm.
/// Returns true and sets `t` (the line parameter of the hit) when the line crosses the closed
/// triangle; false when it misses it or runs parallel to its plane.
inline bool line_hits_triangle(const Vec3& point, const Vec3& dir, const Vec3& a, const Vec3& e1,
                               const Vec3& e2, double& t) {
  const Vec3 p = dir.cross(e2);
  const double det = e1.dot(p);
  if (det == 0.0) return false;
  const double inv = 1.0 / det;
  const Vec3 s = point - a;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 q = s.cross(e1);
  const double v = dir.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  t = e2.dot(q) * inv;
  return true;
}

}  // namespace osteon::detail
