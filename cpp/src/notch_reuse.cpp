// Live mode's reuse of the corner search (issue 34, notch_reuse.hpp).
#include "notch_reuse.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace osteon {

void CornerGroup::bound(Vec3& center, double& radius) const {
  double largest = 0.0;
  for (double r : reach) largest = std::max(largest, r);
  center = point + 0.5 * largest * u;
  radius = std::hypot(2.5 * r_thin, 0.75 * largest);
  // The search tests axial positions and distances in rounded arithmetic (~1e-16 of the
  // coordinates); a margin far above that keeps every vertex it could take inside the ball.
  radius += 1e-6 * (radius + center.cwiseAbs().maxCoeff());
}

bool CornerMemo::recall(CornerGroup& g, const MeshChange& change) const {
  if (!valid || !change.known) return false;
  for (const CornerGroup& old : groups) {
    if (!old.same_inputs(g) || old.corners.size() != g.reach.size()) continue;
    if (!(change.lo.x() > change.hi.x())) {  // something moved: does it reach the region?
      Vec3 center;
      double radius = 0.0;
      g.bound(center, radius);
      const Vec3 nearest = center.cwiseMax(change.lo).cwiseMin(change.hi);
      if ((nearest - center).squaredNorm() <= radius * radius) return false;
    }
    g.corners = old.corners;
    return true;
  }
  return false;
}

}  // namespace osteon
