// Local scaling correction (paper §5, docs/method.md): thicken weak bones until none is weak.
#pragma once

#include <string>
#include <vector>

#include "osteon/analysis.hpp"

namespace osteon {

/// Stop rules and targets of the correction loop.
struct CorrectionOptions {
  double max_scale = 3.0;      ///< largest cross-section scale of one bone
  int max_rounds = 100;        ///< largest number of scaling rounds
  double target_ratio = 0.99;  ///< aim each scaled section at this fraction of the allowable stress
  /// Flat sections (width / thickness >= flat_aspect) are thickened across their thickness only,
  /// by s = sqrt(stress / target) (W of a plate grows as t^2), instead of both axes by cbrt.
  bool thin_direction = false;
  double flat_aspect = 2.0;
  /// B local X axes of the bones (e.g. Blender's, so that pose-bone scale X/Z reproduce the
  /// result); empty: each bone's axes follow the first flat section scaled on it.
  std::vector<Vec3> bone_x_axes;
  /// B axes each bone scales across (they keep scale 1), or empty: the bones' segments. A joint
  /// rig imported into Blender (FBX/glTF) has bones whose local Y is not the segment the
  /// engine analyses; giving the bone's local axis nearest the segment here (and bone_x_axes
  /// perpendicular to it) makes Blender's pose scale X/Y/Z reproduce the result exactly.
  std::vector<Vec3> bone_long_axes;
};

/// One scaling round: which bone, by what factor, and the largest stress after it.
struct CorrectionRound {
  int bone = -1;
  double factor = 1.0;          ///< scale applied in this round (multiplied into the bone's scale)
  double max_stress_after = 0;  ///< MPa, after the round
  int axis = 0;                 ///< 0: both axes across the bone; 1: its x axis only; 2: z only
};

/// Result of a correction: per-bone scales, the corrected vertices, and analyses before/after.
struct CorrectionResult {
  std::vector<double> bone_scale;       ///< B cross-section scale per bone: sqrt(x * z)
  std::vector<double> bone_scale_x;     ///< B scale along each bone's x axis
  std::vector<double> bone_scale_z;     ///< B scale along each bone's z axis (= x for both axes)
  std::vector<Vec3> bone_x_axis;        ///< B each bone's x axis (unit, across the bone)
  std::vector<double> vertices;         ///< #V by 3 row-major corrected vertices, mm
  std::vector<CorrectionRound> rounds;  ///< the rounds taken, in order
  bool converged = false;               ///< true when no section is weak after
  std::string reason;                   ///< why the loop stopped
  std::vector<int> unfixed_sections;    ///< sections still weak at the end (indices into after)
  double max_displacement = 0.0;        ///< largest vertex displacement, mm
  double volume_change_percent = 0.0;   ///< enclosed volume added, % of the original
  AnalysisResult before, after;
};

/// Runs the correction loop on the rest mesh (#V by 3 mm) with the given skinning weights. With
/// `progress`: sections of the analysis under way and runs_done (the first analysis, one per
/// round, the final one) follow the loop, and Progress::cancel() stops it with Cancelled (no
/// result) between sections or rounds.
CorrectionResult correct(const MeshView& mesh, const Skeleton& skeleton, const BoneWeights& weights,
                         const AnalysisOptions& options, const CorrectionOptions& correction,
                         Progress* progress = nullptr);

/// Signed volume enclosed by a closed triangle mesh, mm^3.
double enclosed_volume(const MeshView& mesh);

}  // namespace osteon
