// Live mode's reuse of the corner search (issue 34): a corner whose search inputs are bitwise
// the last run's and whose searched region no moved triangle reaches keeps the last run's
// measurement (docs/performance.md, "Live update"). Engine-internal header.
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/types.hpp"

namespace osteon {

/// The measurement of one corner on the mesh (notch.cpp's Corner, kept between runs).
struct CornerFit {
  bool found = false;
  double radius = 0.0;   ///< fillet radius of the sharpest sector, mm (0: a sharp edge)
  double axial = 0.0;    ///< where the fillet meets the thin side, along the axis, mm
  double opening = 0.0;  ///< the most acute sector's opening angle, radians
};

/// What changed in the mesh since the last run: the box of every triangle with a moved vertex,
/// old and new positions (mm); `known` false: not known (every corner is searched again).
struct MeshChange {
  bool known = false;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);  // lo > hi: nothing moved
};

/// One gathering of the corner search: the steps of one thin section towards one side (bone
/// point, unit axis thin -> thick, thin radius, each step's reach in order, mm) and the corners
/// measured (one per step).
struct CornerGroup {
  Vec3 point = Vec3::Zero(), u = Vec3::Zero();
  double r_thin = 0.0;
  std::vector<double> reach;
  std::vector<CornerFit> corners;
  /// The ball holding the searched region (axial -0.25 .. 1.25 of the largest reach from the
  /// thin plane, within 2.5 r_thin of the axis: notch.cpp's fillet_points), widened by a margin.
  void bound(Vec3& center, double& radius) const;
  /// Same search inputs, bit for bit.
  bool same_inputs(const CornerGroup& o) const {
    return point == o.point && u == o.u && r_thin == o.r_thin && reach == o.reach;
  }
};

/// The last run's corner groups, kept by a reused Analyzer.
struct CornerMemo {
  bool valid = false;  ///< `groups` hold the last run's corners (a live update's)
  bool armed = false;  ///< the last run was a full one: a live update may follow
  std::vector<CornerGroup> groups;
  void forget() {
    valid = false;
    armed = false;
    groups.clear();
  }
  /// The last run's measurement of `g` (its corners copied into g.corners) if its inputs are the
  /// same and no moved triangle reaches its searched region; false: search it again.
  bool recall(CornerGroup& g, const MeshChange& change) const;
};

}  // namespace osteon
