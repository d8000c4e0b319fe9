// Stress concentration at a change of section (issue 33, docs/notch.md): the corner finder and
// its use on an analysis. Engine-internal header (the Kt fit: osteon/notch.hpp).
#pragma once

#include <functional>
#include <vector>

#include "notch_reuse.hpp"
#include "osteon/analysis.hpp"
#include "osteon/mesh.hpp"
#include "osteon/notch.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

/// Per-section result of the corner search (S entries each).
struct NotchField {
  std::vector<double> kt;         ///< Kt, 1 where no corner
  std::vector<double> radius;     ///< corner radius used (measured, at least min_radius), mm; NaN
  std::vector<double> step;       ///< D/d of the step, NaN where no corner
  std::vector<double> effective;  ///< 1 + q (Kt m - 1), m: plane-in-fillet ratio (1: none)
  std::vector<double> arm_ratio;  ///< moment at the corner / the section's moment (>= 1), 1: none
};

/// Finds, along each bone's sections, the steps of the equivalent radius sqrt(A / pi) between
/// neighbours (ratio >= kStepRatio), measures the fillet radius of the concave corner between
/// them on the mesh (the meridian circle fitted through the normals of meridian profiles: the
/// surface cut by half-planes through the thin section's axis, docs/notch.md), and
/// sets Kt on the section at the thin side. Reads from `r`: section_bone, section_param,
/// section_point, section_normal, section_center, load_point, section_area, section_cut_area,
/// moment_arm. `min_radius` (mm): a corner is never sharper than the printer makes it;
/// `sensitivity` q (0..1): governing stress = (1 + q (Kt - 1)) x nominal.
/// `face_grid` returns the run's face grid over `mesh` (built on first call): a corner is
/// measured from the faces near it only. `threads`: workers for the corners' searches (each
/// thin section's search is one job; the result does not depend on it). `memo` (a reused
/// Analyzer's): in a live update (`change.known`: what moved since the last run) the last
/// update's corners are reused where `change` proves them unchanged (notch_reuse.hpp); other runs
/// search every corner and clear the memo. (The profiles are chained and summed in an order of
/// their own, not the grid's, so a corner reads the same bits in either mode.)
NotchField find_notches(const MeshView& mesh, const std::function<const FaceGrid&()>& face_grid,
                        const AnalysisResult& r, double min_radius, double sensitivity,
                        int threads = 1, CornerMemo* memo = nullptr,
                        const MeshChange& change = MeshChange{});

}  // namespace osteon
