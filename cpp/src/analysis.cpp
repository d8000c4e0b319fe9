#include "osteon/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "analysis_impl.hpp"
#include "parallel.hpp"
#include "thickness.hpp"

namespace osteon {

namespace {

// Whether every coordinate of the vertices [begin, end) is finite and, if so, their box (mm).
bool finite_box(const MeshView& mesh, Index begin, Index end, Vec3& lo, Vec3& hi) {
  bool ok = true;
  for (Index i = 3 * begin; i < 3 * end; ++i) ok &= std::isfinite(mesh.vertices[i]);
  if (!ok) return false;
  Vec3 l = mesh.vertex(begin), h = l;
  for (Index i = begin + 1; i < end; ++i) {
    const Vec3 p = mesh.vertex(i);
    l = l.cwiseMin(p);
    h = h.cwiseMax(p);
  }
  lo = l;
  hi = h;
  return true;
}

// Whether every face index lies in [0, num_vertices): one branch-free pass (it vectorises; a
// 1.5M-face mesh has 4.5M indices, checked serially before any worker starts), the first bad
// index named by the caller only when there is one.
bool face_indices_valid(const std::vector<std::int32_t>& faces, Index num_vertices) {
  // As unsigned, a negative index is >= 2^31 > any valid one (num_vertices fits in 32 bits, or
  // every non-negative int32 is valid).
  const std::uint32_t limit = static_cast<std::uint32_t>(
      std::min<Index>(num_vertices, Index(std::numeric_limits<std::int32_t>::max()) + 1));
  std::uint32_t bad = 0;
  for (const std::int32_t f : faces) bad |= static_cast<std::uint32_t>(f) >= limit;
  return bad == 0;
}

}  // namespace

void validate_options(const AnalysisOptions& o, const Skeleton& skeleton) {
  if (!(o.force > 0) || !std::isfinite(o.force))
    throw std::invalid_argument("force must be a positive finite number of newtons");
  if (!(o.allowable_stress > 0) || !std::isfinite(o.allowable_stress))
    throw std::invalid_argument("allowable_stress must be a positive finite stress in MPa");
  validate_layer_options(o.build_direction, o.layer_strength_ratio);
  if (!(o.interval > 0) || !std::isfinite(o.interval))
    throw std::invalid_argument("interval must be a positive finite length in mm");
  if (o.held_bone < -1 || o.held_bone >= skeleton.num_bones())
    throw std::invalid_argument("root (held bone) index " + std::to_string(o.held_bone) +
                                " out of range for " + std::to_string(skeleton.num_bones()) +
                                " bones");
  if (std::isnan(o.gap_tolerance)) throw std::invalid_argument("gap_tolerance must not be NaN");
  if (!(o.min_thickness >= 0) || !std::isfinite(o.min_thickness))
    throw std::invalid_argument("min_thickness must be a finite length >= 0 mm");
  validate_print_options(o.print);
  if (!(o.notch_sensitivity >= 0 && o.notch_sensitivity <= 1))
    throw std::invalid_argument("notch_sensitivity must be a number from 0 to 1");
  if (!(o.min_notch_radius > 0) || !std::isfinite(o.min_notch_radius))
    throw std::invalid_argument("min_notch_radius must be a positive finite length in mm");
}

void fill_section_thickness(const std::vector<std::shared_ptr<const SectionPolygon>>& pending,
                            std::vector<double>& thickness) {
  for (std::size_t i = 0; i < pending.size() && i < thickness.size(); ++i)
    if (pending[i]) thickness[i] = region_thickness(*pending[i]);
}

void complete_section_thickness(AnalysisResult& result) {
  fill_section_thickness(result.thickness_pending, result.section_thickness);
  result.thickness_pending.clear();
}

Analyzer::Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
                   const BoneWeights* weights, int num_bones, const AnalysisOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  s.num_vertices = num_vertices;
  s.num_bones = num_bones;
  if (num_vertices <= 0) throw std::invalid_argument("empty mesh: vertices has no rows");
  if (num_faces <= 0 || faces == nullptr)
    throw std::invalid_argument("empty mesh: faces has no rows");
  if (num_bones <= 0) throw std::invalid_argument("skeleton has no bones");
  s.faces.assign(faces, faces + 3 * num_faces);
  if (!face_indices_valid(s.faces, num_vertices))
    for (Index i = 0; i < 3 * num_faces; ++i) {
      const std::int32_t f = s.faces[i];
      if (f < 0 || f >= num_vertices)
        throw std::invalid_argument("face index out of range: faces[" + std::to_string(i / 3) +
                                    "] refers to vertex " + std::to_string(f) + " but there are " +
                                    std::to_string(num_vertices) + " vertices");
    }
  if (weights != nullptr) {
    validate_weights(*weights, num_vertices, num_bones);
    s.has_weights = true;
    s.dominant = dominant_bones(*weights);  // all the analysis needs of the weights
  }
}

Analyzer::Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
                   std::vector<int> vertex_bone, int num_bones, const AnalysisOptions& options)
    : Analyzer(faces, num_faces, num_vertices, nullptr, num_bones, options) {
  if (static_cast<Index>(vertex_bone.size()) != num_vertices)
    throw std::invalid_argument("vertex_bone must have one entry per vertex");
  for (int b : vertex_bone)
    if (b < -1 || b >= num_bones)
      throw std::invalid_argument("vertex_bone: bone index out of range");
  impl_->has_weights = true;
  impl_->dominant = std::move(vertex_bone);
}

Analyzer::~Analyzer() = default;

const AnalysisOptions& Analyzer::options() const { return impl_->options; }

AnalysisResult Analyzer::run(const double* vertices, const Skeleton& skeleton, Progress* progress,
                             bool keep_for_next_run) {
  return impl_->run(vertices, skeleton, nullptr, progress, keep_for_next_run);
}

AnalysisResult Analyzer::Impl::run(const double* vertices, const Skeleton& sk, const Box3* dirty,
                                   Progress* progress, bool keep_for_next_run) {
  RunState run(vertices, sk, dirty, progress, grid);
  run.grid_holds_last_run = grid_holds_last_run;
  grid_holds_last_run = false;  // until this run ends
  try {
    if (progress != nullptr) {
      progress->sections_done = 0;
      progress->sections_total = 0;
    }
    run.check_cancel();
    check_inputs(run);
    run.timer.lap("validate");
    assign_vertex_bones(run);
    run.timer.lap("vertex bones");
    plan_sections(run);
    mark_dirty(run);
    reuse_last_run(run);
    if (progress != nullptr) {
      std::int64_t kept = 0;  // sections this run does not cut again count as done
      for (std::uint8_t d : run.section_dirty) kept += d == 0;
      progress->sections_total = static_cast<std::int64_t>(specs.size());
      progress->sections_done = kept;
    }
    run.timer.lap("sections");
    run.check_cancel();
    prepare_cuts(run);
    run.timer.lap("reach+lines");
    cut_local(run);
    run.timer.lap("slicing phase 1");
    cut_retries(run);
    run.timer.lap("slicing");
    run.check_cancel();
    find_junction_cores(run);
    run.timer.lap("junctions");
    run.check_cancel();
    AnalysisResult result = compute_loads(run);
    run.timer.lap("moment arms");
    run.check_cancel();
    compute_vertex_stress(run, result);
    run.timer.lap("vertex stress");
    if (keep_for_next_run) {
      remember_inputs(run);
      grid_holds_last_run = run.grid_built;
    } else {
      forget_last_run();  // a one-off analysis: nothing to compare the next run with
    }
    if (progress != nullptr) progress->runs_done.fetch_add(1);
    return result;
  } catch (...) {
    forget_last_run();
    throw;
  }
}

void Analyzer::Impl::forget_last_run() {
  specs.clear();
  states.clear();
  slab_params.clear();
  job_bone.clear();
  job_section.clear();
  tree = LoadTree{};
  last_vertices.clear();
  last_heads.clear();
  last_tails.clear();
  last_parents.clear();
  last_gap = -1.0;
  stress_memo.valid = false;
  corner_memo.forget();
  arm_index.forget_slabs();
  load_memo.clear();
  last_reach2.clear();
}

void Analyzer::Impl::check_inputs(RunState& run) {
  const Skeleton& sk = run.sk;
  // The last run checked its skeleton: an unchanged one (live mode's usual case) is not re-checked.
  const bool same_skeleton = !last_heads.empty() && sk.heads == last_heads &&
                             sk.tails == last_tails && sk.parents == last_parents;
  if (!same_skeleton) validate_skeleton(sk);
  if (sk.num_bones() != num_bones)
    throw std::invalid_argument("skeleton has " + std::to_string(sk.num_bones()) +
                                " bones but the analyzer was built for " +
                                std::to_string(num_bones));
  validate_options(options, sk);
  run.mesh =
      MeshView{run.vertices, num_vertices, faces.data(), static_cast<Index>(faces.size() / 3)};
  check_vertices(run);
  run.gap = options.gap_tolerance >= 0 ? options.gap_tolerance : 0.01 * run.diag;
}

// The vertices in blocks of kVertexBlock, each block's box kept from run to run: a block
// bitwise equal to the last run's (live mode: all but the moved limb's) keeps its box, and its
// vertices passed this check then; the others are checked for finiteness and boxed (on all
// workers from kVerticesPerPass vertices up). The diagonal is the same bits as one pass over
// every vertex (a minimum and maximum per axis, exact in any order); the blocks that differ and
// the vertices in them that moved are listed for the stages after (RunState::vertices_compared).
void Analyzer::Impl::check_vertices(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Index nblocks = (num_vertices + kVertexBlock - 1) / kVertexBlock;
  const bool have_last = last_vertices.size() == static_cast<std::size_t>(3 * num_vertices) &&
                         static_cast<Index>(block_lo.size()) == nblocks;
  block_lo.resize(nblocks);
  block_hi.resize(nblocks);
  changed_blocks.clear();
  for (Index k = 0; k < nblocks; ++k) {
    const Index begin = k * kVertexBlock, end = std::min(num_vertices, begin + kVertexBlock);
    if (!have_last || std::memcmp(run.vertices + 3 * begin, last_vertices.data() + 3 * begin,
                                  3 * (end - begin) * sizeof(double)) != 0)
      changed_blocks.push_back(k);
  }
  const long per_job = std::max<long>(1, detail::kVerticesPerPass / kVertexBlock);
  const long nchanged = static_cast<long>(changed_blocks.size());
  std::vector<std::uint8_t> finite((nchanged + per_job - 1) / per_job, 1);
  detail::parallel_for(static_cast<long>(finite.size()), options.threads, [&](long job, int) {
    for (long c = job * per_job; c < std::min(nchanged, (job + 1) * per_job); ++c) {
      const Index k = changed_blocks[c];
      const Index begin = k * kVertexBlock, end = std::min(num_vertices, begin + kVertexBlock);
      if (!finite_box(mesh, begin, end, block_lo[k], block_hi[k])) {
        finite[job] = 0;
        return;
      }
    }
  });
  if (std::find(finite.begin(), finite.end(), 0) != finite.end())
    for (Index i = 0; i < 3 * num_vertices; ++i)
      if (!std::isfinite(run.vertices[i]))
        throw std::invalid_argument("vertices contain NaN or infinity (vertex " +
                                    std::to_string(i / 3) + ")");
  Vec3 lo = block_lo[0], hi = block_hi[0];
  for (Index k = 1; k < nblocks; ++k) {
    lo = lo.cwiseMin(block_lo[k]);
    hi = hi.cwiseMax(block_hi[k]);
  }
  run.diag = (hi - lo).norm();
  // The moved vertices (ascending) and their flags (all 0 but theirs between runs; sized by the
  // first run that compares, so a one-off analysis writes no flags: 1 byte per vertex).
  for (std::int32_t v : moved_vertices) moved_scratch[v] = 0;
  moved_vertices.clear();
  run.vertices_compared = have_last;
  if (!have_last) return;
  moved_scratch.resize(num_vertices, 0);
  for (const Index k : changed_blocks) {
    const Index end = std::min(num_vertices, (k + 1) * kVertexBlock);
    for (Index v = k * kVertexBlock; v < end; ++v) {
      const double* a = run.vertices + 3 * v;
      const double* b = last_vertices.data() + 3 * v;
      if (a[0] != b[0] || a[1] != b[1] || a[2] != b[2]) {
        moved_scratch[v] = 1;
        moved_vertices.push_back(static_cast<std::int32_t>(v));
      }
    }
  }
}

AnalysisResult analyze(const MeshView& mesh, const Skeleton& skeleton, const BoneWeights* weights,
                       const AnalysisOptions& options, Progress* progress) {
  validate_mesh(mesh);
  validate_skeleton(skeleton);
  Analyzer analyzer(mesh.faces, mesh.num_faces, mesh.num_vertices, weights, skeleton.num_bones(),
                    options);
  return analyzer.run(mesh.vertices, skeleton, progress, /*keep_for_next_run=*/false);
}

}  // namespace osteon
