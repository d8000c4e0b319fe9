// Exact section properties of a plane polygon with holes (paper §4.1-4.2, made exact).
#pragma once

#include <vector>

#include "osteon/types.hpp"

namespace osteon {

/// A section polygon in its plane's 2D coordinates (mm): one outer boundary and its holes.
/// Orientation of the loops does not matter; the outer loop counts as material, holes as void.
struct SectionPolygon {
  std::vector<Vec2> outer;               ///< outer boundary, closed implicitly (last -> first)
  std::vector<std::vector<Vec2>> holes;  ///< loops directly inside the outer boundary
};

/// Area, centroid, second moments and section modulus of a section.
struct SectionProperties {
  double area = 0.0;                  ///< mm^2
  Vec2 centroid = Vec2::Zero();       ///< mm, in the polygon's 2D coordinates
  Mat2 second_moment = Mat2::Zero();  ///< J = integral of (p-c)(p-c)^T dA about the centroid, mm^4
  double modulus = 0.0;               ///< minimum section modulus over all bending directions, mm^3
  bool valid = false;                 ///< false for zero area or a singular J
};

/// Exact polygon integrals (Green's theorem) and W = 1 / max_p |J^-1 (p - c)| over boundary points.
SectionProperties section_properties(const SectionPolygon& polygon);

/// Signed area of a closed loop (positive when counter-clockwise), mm^2.
double signed_area(const std::vector<Vec2>& loop);

/// True when point q lies inside the closed loop (even-odd rule).
bool point_in_loop(const std::vector<Vec2>& loop, const Vec2& q);

}  // namespace osteon
