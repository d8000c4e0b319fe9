// The printed section: what an FDM slicer (walls, skins, sparse infill) or a hollowed resin print
// makes of a section plane, and the transformed-section modulus of it (docs/printing.md,
// "The printed section"). The print profile -> these scalars mapping is python/osteon/printed.py.
#pragma once

#include <cmath>
#include <vector>

#include "osteon/section.hpp"
#include "osteon/types.hpp"

namespace osteon {

/// How the part is printed, as the engine needs it (scalars only). kind 0 = solid: the section
/// as cut, none of this code runs (bit-identical to an analysis without a print profile).
struct PrintOptions {
  enum Kind : int { kSolid = 0, kLayered = 1, kShell = 2 };
  int kind = kSolid;        ///< kLayered: FDM (walls in the layer plane, skins along the build
                            ///< direction); kShell: an isotropic shell (hollowed resin print)
  double wall_depth = 0.0;  ///< FDM: perimeters' depth in the layer plane; shell: its thickness, mm
  double skin_depth = 0.0;  ///< FDM: solid top/bottom skins along the build direction, mm
  double infill_build = 1.0;  ///< infill stiffness fraction eta for stress along the build dir
  double infill_layer = 1.0;  ///< infill stiffness fraction eta for stress in the layer plane
  double solid_infill_below_area = 0.0;  ///< a layer's infill island under this is solid, mm^2
  /// FDM: skins lie only under surfaces at most this steep from the layer plane, radians
  /// (pi/2: all; PrusaSlicer drops a hollow print's skin strips narrower than two lines).
  double skin_max_slope = M_PI / 2;
  double layer_height = 0.0;  ///< FDM: layer height, mm (the rows of the skin widening)
  /// FDM: a skin strip narrower than twice this is widened by it into the sparse infill, mm
  /// (PrusaSlicer / Bambu / Orca: 3 x the solid infill's line width; 0: not widened).
  double skin_growth = 0.0;
};

/// A section as printed: the transformed section's properties and the sparse region.
struct PrintedSection {
  double modulus = 0.0;      ///< W of the transformed section at the solid fibres, mm^3
  double wall_area = 0.0;    ///< perimeters (FDM) or the shell (resin), mm^2
  double skin_area = 0.0;    ///< solid infill: skins and small islands filled solid, mm^2
  double infill_area = 0.0;  ///< the sparse (FDM) or hollow (resin) region, mm^2
  double infill_eta = 1.0;   ///< stiffness fraction of the sparse region along the normal
  /// The sparse region's loops in the polygon's 2D coordinates (outer boundaries counter-
  /// clockwise, holes clockwise), mm.
  std::vector<std::vector<Vec2>> sparse;
  bool valid = false;  ///< false: the transformed section is degenerate (W = 0)
};

/// The printed section of `cut` (plane coordinates, mm), whose solid properties are `solid`.
/// `build_in_plane`: the build direction's components along the plane's two axes (b.u, b.v);
/// `cos_theta`: |b.n|, the cosine of the angle between the build direction and the normal.
/// FDM: the sparse region is the cut eroded by the wall ellipse (semi-axes wall_depth cos(theta)
/// along the in-plane build axis, wall_depth across it) intersected with the cut shifted by
/// +-skin_depth sin(theta) along that axis; its islands whose layer area (area / cos(theta))
/// is under solid_infill_below_area are solid; with skin_growth, skin strips narrower than
/// 2 x skin_growth in a layer are widened by it (skin_growth.hpp). Shell: the cut eroded by
/// wall_depth, hollow.
/// `keep_sparse`: fill PrintedSection::sparse.
PrintedSection printed_section(const SectionPolygon& cut, const SectionProperties& solid,
                               const Vec2& build_in_plane, double cos_theta,
                               const PrintOptions& options, bool keep_sparse);

/// Throws std::invalid_argument when a print option is out of range (unknown kind, a negative
/// or non-finite depth or area, an infill fraction outside 0..1).
void validate_print_options(const PrintOptions& options);

/// Stiffness fraction of the infill for normal stress at angle theta to the build direction:
/// the Reuss (series) bound 1/eta = cos^2/eta_build + sin^2/eta_layer (0 when a needed one is 0).
double infill_stiffness(double cos_theta, double eta_build, double eta_layer);

}  // namespace osteon
