// Internal state of an Analyzer, shared with the correction loop (not a public header).
//
// A run is a pipeline of named stages, each a method of Analyzer::Impl in its own file
// (the way Manifold's impl.h maps methods to files):
//
//   analysis.cpp                Analyzer, validate_options, analyze, Impl::run (the pipeline),
//                               Impl::check_inputs, Impl::check_vertices
//   analysis_plan.cpp           Impl::assign_vertex_bones, Impl::plan_sections
//   analysis_reuse.cpp          Impl::mark_dirty, Impl::reuse_last_run (list_moved_faces,
//                               list_bone_vertices), Impl::remember_inputs
//   analysis_cut.cpp            Impl::prepare_cuts (bone_reach2), Impl::cut_local (phase 1),
//                               Impl::cut_retries (phase 2)
//   analysis_junction.cpp       Impl::find_junction_cores
//   analysis_loads.cpp          Impl::compute_loads
//   analysis_vertex_stress.cpp  Impl::compute_vertex_stress
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <vector>

#include "loads.hpp"
#include "loose_pieces.hpp"
#include "notch_reuse.hpp"
#include "osteon/analysis.hpp"
#include "osteon/printed_section.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

/// Axis-aligned box in 3D, mm.
struct Box3 {
  Vec3 lo = Vec3::Constant(1e300);
  Vec3 hi = Vec3::Constant(-1e300);
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool empty() const { return lo.x() > hi.x(); }
  /// Does the slab |(x - point) . normal| <= half (mm; 0 = the plane itself) reach the box?
  bool meets_slab(const Vec3& point, const Vec3& normal, double half) const {
    double below = 1e300, above = -1e300;
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(),
                        (c & 4) ? hi.z() : lo.z());
      const double s = (corner - point).dot(normal);
      below = std::min(below, s);
      above = std::max(above, s);
    }
    return below <= half && above >= -half;
  }
};

/// Stage timer: OSTEON_PROFILE=1 prints the wall time of each stage of a run to stderr, and the
/// process's CPU time (all threads) in it: CPU / wall near 1 on two cores is a stage that keeps
/// one core idle.
struct StageTimer {
  bool on = std::getenv("OSTEON_PROFILE") != nullptr;
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  std::clock_t last_cpu = std::clock();
  void lap(const char* stage) {
    if (!on) return;
    const auto now = std::chrono::steady_clock::now();
    const std::clock_t cpu = std::clock();
    std::fprintf(stderr, "osteon %-16s %8.3f ms wall %8.3f ms cpu\n", stage,
                 std::chrono::duration<double, std::milli>(now - last).count(),
                 1e3 * static_cast<double>(cpu - last_cpu) / CLOCKS_PER_SEC);
    last = now;
    last_cpu = cpu;
  }
};

/// Where a section is and how its downstream side is found.
struct SectionSpec {
  int bone = 0;
  std::int8_t kind = kInterior;
  int boundary = 0;       // index into slab params of the bone
  bool plus_side = true;  // downstream lies beyond the param (towards the tail)
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  int job = 0;  // slicing job that computes it
};

/// Geometry of a computed section, kept between runs for partial re-analysis.
struct SectionState {
  bool found = false;
  bool whole_plane = true;  // false: the cut was proven inside `region` alone
  CutRegion region;         // where the cut was made (a cylinder or a ball), mm
  std::uint32_t flags = 0;
  double area = 0.0;
  double modulus = 0.0;
  Vec3 center = Vec3::Zero();
  Vec3 thin_axis = Vec3::Zero();  // unit, in the plane: the direction across the thinnest width
  double aspect = 1.0;            // width / thickness
  double thickness = 0.0;         // minimum width of the region, mm (NaN: not computed yet)
  double thickness_bound = 0.0;   // a lower bound of its minimum width (hull), mm
  std::shared_ptr<const SectionPolygon> analysed;  // the region analysed (its thickness, later)
  std::vector<std::vector<Vec3>> loops;  // keep_outlines: outer boundary, then holes, 3D mm
  // The whole cut (before a junction core replaced it): frame, region, area and modulus.
  PlaneFrame frame;           // plane frame of `cut` (origin = bone point)
  SectionPolygon cut;         // region of the whole cut around the bone point, plane coords, mm
  double cut_area = 0.0;      // mm^2
  double cut_modulus = 0.0;   // mm^3
  double junction_delta = 0;  // > 0: junction check made with neighbour planes at +-delta, mm
  std::vector<std::vector<Vec3>> cut_loops;  // keep_outlines, junction only: the whole cut's loops
  // The printed section (AnalysisOptions::print; solid: modulus is the solid one, areas 0).
  double solid_modulus = 0.0;  // W of the region as cut, mm^3 (modulus: as printed)
  double wall_area = 0.0;      // mm^2
  double skin_area = 0.0;      // mm^2
  double infill_area = 0.0;    // mm^2
  std::vector<std::vector<Vec3>> infill_loops;  // keep_outlines: the sparse region's loops, 3D mm
};

/// What set_section_region needs of the options: keep the loops, and how the part is printed.
struct RegionOptions {
  explicit RegionOptions(const AnalysisOptions& options)
      : keep(options.keep_outlines),
        print(options.print.kind == PrintOptions::kSolid ? nullptr : &options.print),
        build(options.build_direction.normalized()) {}
  bool keep = false;
  const PrintOptions* print = nullptr;  // null: solid (the section as cut, no print code runs)
  Vec3 build = Vec3::UnitZ();           // unit build direction
};

/// Sets a found section's properties (area, W, centroid, thin axis, aspect, thickness and, with
/// `ro.keep`, its 3D loops) from a region in `frame`'s plane coordinates; false (nothing changed)
/// when the region is degenerate. The thickness is left NaN (the region and a lower bound of
/// its thickness are kept): section_thickness_at computes it when it is needed.
/// With a print (`ro.print`), W is the printed section's (printed_section.hpp), solid_modulus
/// the cut's.
bool set_section_region(SectionState& st, const PlaneFrame& frame, const SectionPolygon& polygon,
                        const RegionOptions& ro);

/// The section's thickness (mm), computed from its kept region on first need.
double section_thickness_at(SectionState& st);

/// Working data of one run, handed from stage to stage (see Analyzer::Impl::run).
struct RunState {
  RunState(const double* vertices_in, const Skeleton& skeleton, const Box3* dirty_in,
           Progress* progress_in, FaceGrid& grid_in)
      : vertices(vertices_in),
        sk(skeleton),
        dirty(dirty_in),
        progress(progress_in),
        grid(grid_in) {}

  const double* vertices;  // #V by 3 row-major, mm
  const Skeleton& sk;      // posed skeleton
  const Box3* dirty;       // partial run: only sections crossing this box are re-cut
  Progress* progress;      // null: no progress, no cancel
  MeshView mesh;
  double diag = 0.0;  // bounding-box diagonal, mm
  double gap = 0.0;   // gap tolerance in use, mm
  StageTimer timer;

  /// Throws Cancelled when the caller asked to stop (called between sections).
  void check_cancel() const {
    if (progress != nullptr) progress->check();
  }
  /// Counts n more sections whose cut is done.
  void sections_done(std::int64_t n = 1) const {
    if (progress != nullptr) progress->sections_done.fetch_add(n, std::memory_order_relaxed);
  }

  // Vertex bones (assign_vertex_bones).
  std::vector<int> vertex_bone;  // V bone of each vertex
  std::vector<Index> per_bone;   // B number of vertices of each bone

  // Reuse (plan_sections, mark_dirty, reuse_last_run).
  bool partial = false;    // re-cut only what `dirty` reaches; the plan is the last run's
  bool may_reuse = false;  // exact reuse of the last run's sections (live mode)
  std::vector<SectionSpec> prev_specs;
  std::vector<SectionState> prev_states;
  std::vector<std::uint8_t> job_dirty;      // per job: must be cut
  std::vector<std::uint8_t> section_dirty;  // per section: must be cut

  // Cuts (prepare_cuts, cut_local, cut_retries).
  int workers = 1;
  // The Analyzer's grid (its buffers are reused from run to run: live mode rebuilds it on every
  // update); it holds this run's mesh only once build_grid() ran.
  FaceGrid& grid;
  bool grid_built = false;
  // Live mode: the grid holds the last run's mesh and `moved_faces` lists the faces with a
  // vertex moved since (null: not known): the grid keeps its layout and re-files those alone.
  const std::vector<std::int32_t>* moved_faces = nullptr;
  bool grid_holds_last_run = false;
  // The live rebuild's margin: 5 % of the extent on each side (the figurine's bent elbow moves
  // the hand 0.2-0.4 mm, ~0.3 %, beyond the last box per update; docs/performance.md).
  static constexpr double kLiveGridMargin = 0.05;
  /// Buckets this run's mesh into `grid` (once per run).
  void build_grid(int threads) {
    if (grid_built) return;
    // Live update: re-file the moved faces in the kept layout (up to a quarter of the faces
    // moved; more are faster rebuilt). When a limb left the kept box, or most of the mesh moved,
    // the grid is rebuilt with a margin, so that the next poses moving that limb a little
    // further re-file again (the sections do not depend on the layout: docs/performance.md).
    // Any other build (one-off analyses, an Analyzer's first run, partial runs, a changed plan)
    // is on the mesh's own box.
    const bool live = grid_holds_last_run && moved_faces != nullptr;
    const bool refiled =
        live && 4 * static_cast<Index>(moved_faces->size()) <= mesh.num_faces &&
        grid.refile(mesh, moved_faces->data(), static_cast<Index>(moved_faces->size()), threads);
    if (!refiled) grid.build(mesh, 12, threads, live ? kLiveGridMargin : 0.0);
    grid_built = true;
  }
  std::vector<double> reach;                   // B radius of the local cut around the bone, mm
  std::vector<Vec3> axis;                      // B unit bone directions
  std::vector<std::vector<double>> crossings;  // B sorted bone-axis crossings of the mesh, mm
  std::vector<std::uint8_t> retry;             // per section: Retry of phase 2
  std::vector<std::vector<CutSegment>> kept;   // per section: segments of its narrower cuts
  std::vector<std::vector<std::vector<CutSegment>>> family_segments;  // per worker scratch
  std::vector<std::vector<CutSegment>> single_segments;               // per worker scratch
  std::atomic<int> local_used{0}, local_failed{0};
  long retried = 0;

  // check_vertices compared the vertices with the last run's: Impl::moved_vertices lists those
  // that moved, Impl::changed_blocks the blocks that hold them (false: no last run).
  bool vertices_compared = false;
  // Live reuse (reuse_last_run): per vertex, whether it moved since the last run (null: not
  // known, e.g. a full or partial run); the Analyzer's storage.
  const std::vector<std::uint8_t>* moved = nullptr;
  // Live reuse (list_bone_vertices): per bone, whether a vertex of it moved, its head or tail
  // did, or its vertices are others than the last run's (empty: not known, all changed).
  std::vector<std::uint8_t> bone_changed;

  // What changed since the last run (partial and live runs): junction cores whose neighbour
  // planes reach it are re-checked. all_changed: a fresh run.
  bool all_changed = true;
  Box3 changed;
  long junction_checks = 0;

  // Loads (built during cut_retries, used by compute_loads).
  const MomentArmIndex* arms = nullptr;  // the Analyzer's arm_index, once built
};

struct Analyzer::Impl {
  AnalysisOptions options;
  // Shells of the faces' connectivity (fixed for an Analyzer; 0: not counted yet). One shell has
  // no loose piece whatever the vertices do: later runs (live mode) skip the search.
  Index face_shells = 0;
  std::vector<std::int32_t> faces;
  Index num_vertices = 0;
  int num_bones = 0;
  bool has_weights = false;  // weights given: `dominant` holds each vertex's bone (-1: none)
  std::vector<int> dominant;
  std::vector<double> unweighted_xyz;  // scratch: positions of the vertices no bone weighs, mm

  // State of the last run.
  std::vector<SectionSpec> specs;
  std::vector<SectionState> states;
  std::vector<std::vector<double>> slab_params;
  std::vector<int> job_bone;     // >= 0: interior family of that bone; -1: a single plane
  std::vector<int> job_section;  // first section of the job
  LoadTree tree;
  // Built by each run that cuts (RunState::build_grid), kept for its buffers; a live update whose
  // last run built it re-files only the moved faces in its kept layout (FaceGrid::refile).
  FaceGrid grid;
  // Loose pieces (full runs; a partial run keeps them): vertex lists, and #V 1 = loose vertex.
  std::vector<std::vector<std::int32_t>> loose;
  std::vector<std::uint8_t> loose_vertex;
  // Kept from run to run with their storage (live mode: no memory freed and faulted in again on
  // every update): the loose-piece search (the faces' shells found once) and the moment-arm index.
  LoosePieceFinder loose_finder;
  MomentArmIndex arm_index;

  // check_vertices: the vertices in blocks, each block's box (mm; the last run's once it ended),
  // this run's blocks that differ bitwise from the last run's and, in them, the vertices that
  // moved (ascending); per vertex, moved or not (RunState::moved; 0 but for moved_vertices).
  static constexpr Index kVertexBlock = 1024;
  std::vector<Vec3> block_lo, block_hi;
  std::vector<Index> changed_blocks;
  std::vector<std::int32_t> moved_vertices;
  std::vector<std::uint8_t> moved_scratch;
  // The faces with a moved vertex (RunState::moved_faces), and whether `grid` holds the last
  // run's mesh (that run built it).
  std::vector<std::int32_t> moved_faces_scratch;
  // list_moved_faces: each vertex's faces (CSR, built on the first live update that moved a
  // vertex), marks (all 0 between calls) and the moved faces' corners.
  std::vector<Index> vertex_face_start;
  std::vector<std::int32_t> vertex_faces, corner_scratch;
  std::vector<std::uint8_t> face_listed, corner_listed;
  // Live mode: each bone's vertices in vertex order (CSR, for the vertex bones `bone_list_of`),
  // and each bone's largest squared distance of a vertex from its axis in the last run (mm^2).
  std::vector<Index> bone_vertex_start;
  std::vector<std::int32_t> bone_vertex_list;
  std::vector<int> bone_list_of;
  std::vector<double> last_reach2;
  bool grid_holds_last_run = false;
  // The last run's per-vertex stress and what it was computed from: in live mode a vertex whose
  // bone, position, bone head and axis and its bone's section params are bitwise unchanged lies
  // at the same place between the same two sections (vertex_param, vertex_slab); it keeps its
  // value when those two sections' stress and culling are unchanged too, else only the
  // interpolation is redone (the same arithmetic on the same numbers either way).
  struct VertexStressMemo {
    bool valid = false;
    std::vector<std::vector<double>> param, stress;  // per bone: sections' params and stresses
    std::vector<std::vector<std::uint8_t>> culled;   // per bone: sections culled
    std::vector<Vec3> heads, axis;
    std::vector<int> vertex_bone;
    std::vector<std::uint8_t> loose_vertex;  // empty: no loose piece
    std::vector<double> vertex_stress;
    std::vector<std::uint8_t> vertex_culled;
    std::vector<double> vertex_param;       // mm along the bone (vertices with sections)
    std::vector<std::int32_t> vertex_slab;  // sections of the bone below vertex_param
    std::vector<std::int32_t> work;         // scratch: the vertices a live update visits
  } stress_memo;

  // The last run's load point per section and the query that found it (section_loads): live
  // mode asks the moment-arm index again only where the query or its region changed.
  struct LoadMemo {
    int bone = -1, boundary = -1;
    bool plus_side = false;
    Vec3 center = Vec3::Zero();
    double arm = 0.0;
    Index vertex = -1;
  };
  std::vector<LoadMemo> load_memo;

  // The last run's corners (notch_reuse.hpp): live mode searches only those a change reaches.
  CornerMemo corner_memo;

  // Inputs of the last run, so that the next run re-cuts only what changed (live mode).
  std::vector<double> last_vertices;
  std::vector<Vec3> last_heads, last_tails;
  std::vector<int> last_parents;
  double last_gap = -1.0;

  /// Full or partial run: with `dirty` set, only sections whose plane crosses the box are re-cut
  /// (the skeleton must be the one of the previous run). Calls the stages below in order. With
  /// `progress`, reports sections and stops with Cancelled when asked; any exception (a cancel,
  /// bad input) makes the Impl forget its last run, so that no half-made plan is reused.
  AnalysisResult run(const double* vertices, const Skeleton& skeleton, const Box3* dirty,
                     Progress* progress = nullptr, bool keep_for_next_run = true);
  /// Forgets the last run (plan, sections, inputs): the next run is a full one.
  void forget_last_run();

  // Stages of a run, in order (files listed at the top of this header).
  /// Checks the skeleton, options and vertices; sets the mesh view, size and gap tolerance.
  void check_inputs(RunState& run);
  /// Step of check_inputs: the vertices finite, their diagonal, and which moved since last run.
  void check_vertices(RunState& run);
  /// 1. Each vertex's bone: its dominant weight, or the nearest bone where it has none.
  void assign_vertex_bones(RunState& run);
  /// 2. Full runs: the load tree and the sections (interior planes, joints, free ends), with the
  /// last run's sections kept aside for reuse.
  void plan_sections(RunState& run);
  /// Partial runs: marks the sections whose cut the dirty box can change.
  void mark_dirty(RunState& run);
  /// Live mode: keeps the last run's geometry of every section no moved triangle can reach.
  void reuse_last_run(RunState& run);
  /// The faces with a moved vertex (moved_faces_scratch, each once) and the box of their
  /// corners' old and new positions (reuse_last_run, something moved).
  void list_moved_faces(RunState& run, Box3& moved_box);
  /// Live mode: each bone's vertices (kept while the vertex bones stay) and which bones changed
  /// (RunState::bone_changed).
  void list_bone_vertices(RunState& run);
  /// 3a. The face grid, each bone's local-cut radius and its axis crossings.
  void prepare_cuts(RunState& run);
  /// Step of prepare_cuts: each bone's largest squared distance of a vertex from its axis.
  void bone_reach2(RunState& run);
  /// 3b. Phase 1: one local cut per family of parallel planes; queues what it cannot prove.
  void cut_local(RunState& run);
  /// 3c. Phase 2: queued sections re-cut wider or whole (and, beside them, the loose pieces
  /// found and the moment-arm index built over the vertices of the attached ones).
  void cut_retries(RunState& run);
  /// Steps of cut_retries: the units to re-cut (families first), the loose pieces and the
  /// moment-arm index (one more unit), a joint's re-cut, a family's re-cuts.
  std::vector<int> retry_units(RunState& run);
  void find_loose_pieces_and_arms(RunState& run);
  void retry_joint(RunState& run, int job, int worker);
  void retry_family(RunState& run, int job, int worker);
  /// 3d. Junctions (docs/method.md, Sections; docs/junctions.md): sections whose whole cut is
  /// much larger than their bone's typical section are re-cut at +-delta; where only a core
  /// continues through the plane, the section's properties are the core's (flag kFlagJunction).
  void find_junction_cores(RunState& run);
  /// Steps of find_junction_cores: each bone's typical section, the candidates, the planes of a
  /// candidate's neighbours (its family's sections m intervals away, or two planes cut), and
  /// one candidate's check.
  struct JunctionFamily {
    int first, count, m;  // the family's sections [first, first + count); m: 0 = cut planes
  };
  void typical_sections(std::vector<double>& delta, std::vector<double>& median) const;
  JunctionFamily junction_family(int i, double delta) const;
  std::vector<int> junction_candidates(RunState& run, const std::vector<double>& delta,
                                       const std::vector<double>& median);
  bool cut_neighbour_planes(RunState& run, int i, double delta, std::vector<CutSegment>& segs,
                            SectionPolygon (&regions)[2],
                            std::vector<const SectionPolygon*>& neighbours, int& sides) const;
  void check_junction(RunState& run, int i, double delta, double median,
                      const std::vector<std::uint8_t>& neighbour_ok,
                      std::vector<CutSegment>& scratch);
  /// 4. Per section: load point, moment arm, moment, stress, culled and weak flags.
  AnalysisResult compute_loads(RunState& run);
  /// Steps of compute_loads: each section's load, moment and stress; the sections that drive
  /// results (unreliable slivers and too-thin sections flagged); the outlines packed.
  AnalysisResult section_loads(RunState& run);
  std::vector<std::uint8_t> usable_sections(AnalysisResult& r);
  void pack_outlines(AnalysisResult& r) const;
  /// 5. Per vertex: stress interpolated along its bone between its sections.
  void compute_vertex_stress(RunState& run, AnalysisResult& result);
  /// Keeps this run's inputs so that the next run re-cuts only what changed.
  void remember_inputs(const RunState& run);
};

}  // namespace osteon
