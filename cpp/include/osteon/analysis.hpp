// Skeleton-sectional stress analysis (paper §4, docs/method.md): sections, loads, stress.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "osteon/layers.hpp"
#include "osteon/mesh.hpp"
#include "osteon/printed_section.hpp"
#include "osteon/progress.hpp"
#include "osteon/result_fields.hpp"
#include "osteon/section.hpp"
#include "osteon/skeleton.hpp"
#include "osteon/weights.hpp"

namespace osteon {

/// Settings of one analysis. Units: N, MPa, mm.
struct AnalysisOptions {
  double force = 20.0;             ///< force F on the worst point of each branch, N
  double allowable_stress = 60.0;  ///< [sigma] = material strength / safety factor, MPa
  double interval = 2.0;           ///< spacing h of the sections along each bone, mm
  int held_bone = -1;              ///< bone held at its head; -1 = the main root bone
  double gap_tolerance = -1.0;     ///< open cuts closed across gaps up to this, mm; <0: 1% of size
  int threads = 0;                 ///< worker threads; 0 = all cores
  bool local_cuts = true;  ///< cut near the bone first (same result, faster); false: whole planes
  bool reuse_sections = true;  ///< Analyzer::run re-cuts only sections a change can reach (exact)
  bool keep_outlines = false;  ///< fill AnalysisResult's outline_* (the loops of each section)
  /// Junction cores (docs/junctions.md): where a section cuts a side branch's stub, count only
  /// the material that continues through the plane (flag kFlagJunction); false: whole cuts.
  bool junctions = true;
  /// FDM build direction in the model frame (any non-zero vector; default +Z) and layer strength
  /// ratio Z/X (1 = isotropic): each section's allowable is layer_allowable() of the angle
  /// between its normal and this direction (osteon/layers.hpp, docs/printing.md).
  Vec3 build_direction = Vec3(0, 0, 1);
  double layer_strength_ratio = 1.0;  ///< layer / in-plane strength; allowable_stress is in-plane
  double min_thickness = 0.8;         ///< thinner sections (mm) are flagged too_thin; 0 = no check
  /// Compute section_thickness only where the too_thin check needs it (a cheap lower bound
  /// decides the rest); the others are NaN, their regions left in
  /// AnalysisResult::thickness_pending for complete_section_thickness(). Python reads them on
  /// first use of Analysis.section_thickness.
  bool defer_thickness = false;
  /// How the part is printed (osteon/printed_section.hpp, docs/printing.md): walls, skins and
  /// sparse infill (FDM, in the frame of build_direction) or a hollow shell (resin); W becomes
  /// the printed section's. Default kind solid: the section as cut.
  PrintOptions print;
  /// Stress concentration at corners (docs/notch.md): notch sensitivity q (0..1), governing
  /// stress = (1 + q (Kt - 1)) x nominal; 1 = the full elastic peak (brittle, the safe side).
  double notch_sensitivity = 1.0;
  /// A corner is never sharper than the print makes it: measured radii below this are raised to
  /// it, mm (default: half a 0.4 mm nozzle's line, docs/notch.md).
  double min_notch_radius = 0.2;
};

/// Where a section sits on its bone.
enum SectionKind : std::int8_t {
  kInterior = 0,  ///< at k*interval along the bone
  kJoint = 1,     ///< at a joint of two bones (one per pair at joints of more than two)
  kEnd = 2,       ///< at a free bone end
};

/// Result of one analysis: one entry per section (S), per vertex (V). mm, N, MPa. The members
/// and their docs are the rows of OSTEON_RESULT_FIELDS (result_fields.hpp), the one list of
/// outputs shared with the Python binding.
struct AnalysisResult {
#define OSTEON_RESULT_MEMBER(type, name, init, shape, unit, doc) type name init;
  OSTEON_RESULT_FIELDS(OSTEON_RESULT_MEMBER)
#undef OSTEON_RESULT_MEMBER
  /// S with AnalysisOptions::defer_thickness: the region of each section whose thickness was
  /// not computed (null elsewhere); complete_section_thickness() fills them in. Empty otherwise.
  /// Not an output: the binding hands it to Python as an opaque handle (thickness_pending).
  std::vector<std::shared_ptr<const SectionPolygon>> thickness_pending;
};

/// Writes the thickness (mm, cpp/src/thickness.hpp) of every region in `pending` (S, null: none)
/// into `thickness` (S,); the regions stay (a second call writes the same).
void fill_section_thickness(const std::vector<std::shared_ptr<const SectionPolygon>>& pending,
                            std::vector<double>& thickness);

/// Computes the thickness of every section left in result.thickness_pending
/// (AnalysisOptions::defer_thickness) into result.section_thickness and empties the list.
void complete_section_thickness(AnalysisResult& result);

/// Throws std::invalid_argument when an option is out of range (force, stress, interval <= 0...).
void validate_options(const AnalysisOptions& options, const Skeleton& skeleton);

/// Number of sections an analysis of `skeleton` (mm) at `interval` (mm) plans, before any cut:
/// per bone the interior planes k*interval strictly inside it (ceil(L / h) - 1), plus one section
/// per free bone end and one per pair of bones meeting at a joint. Exactly the length of every
/// per-section array of AnalysisResult (independent of the mesh and the held bone). Cheap
/// (O(B^2) in the bones, no mesh): a front end can warn before a setting makes millions of
/// sections. Counts beyond the engine's limit (10^6 on one bone) are returned, not thrown.
/// Throws std::invalid_argument for a non-positive or non-finite interval.
std::int64_t count_sections(const Skeleton& skeleton, double interval);

/// Reusable analysis of one mesh topology (faces, weights and options fixed; vertices and
/// skeleton pose may change between runs, as in live mode).
class Analyzer {
 public:
  /// faces: #F by 3 row-major; weights may be null (each vertex bound to its nearest bone).
  Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
           const BoneWeights* weights, int num_bones, const AnalysisOptions& options);
  /// Same, given each vertex's dominant bone (#V, -1 = unweighted) instead of the weights.
  Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
           std::vector<int> vertex_bone, int num_bones, const AnalysisOptions& options);
  ~Analyzer();
  Analyzer(const Analyzer&) = delete;
  Analyzer& operator=(const Analyzer&) = delete;

  /// Analyses vertices (#V by 3 row-major, mm) with the (posed) skeleton. With `progress`, its
  /// counters follow the run (sections_total once planned, sections_done as cuts finish,
  /// runs_done + 1 at the end) and Progress::cancel() from another thread stops the run between
  /// sections with osteon::Cancelled: no result, and this Analyzer forgets its last run (the
  /// next run is a full one, identical to a fresh Analyzer's). `keep_for_next_run` = false (a
  /// one-off analysis: analyze()): the same result, but the run keeps no copy of its inputs for
  /// a partial re-run, so the next run is a full one (on 1.5M faces the copy is 18 MB written to
  /// fresh pages on the calling thread after the last stage).
  AnalysisResult run(const double* vertices, const Skeleton& skeleton, Progress* progress = nullptr,
                     bool keep_for_next_run = true);

  /// Options in use.
  const AnalysisOptions& options() const;

  struct Impl;
  /// Engine-internal state (used by the correction loop for partial re-analysis).
  Impl& internals() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// One-off analysis of a mesh (see Analyzer; `progress` as in Analyzer::run).
AnalysisResult analyze(const MeshView& mesh, const Skeleton& skeleton, const BoneWeights* weights,
                       const AnalysisOptions& options, Progress* progress = nullptr);

}  // namespace osteon
