// What a run may keep from the last one: partial re-analysis (the correction loop) and exact
// reuse of unchanged sections (live mode) (Analyzer::Impl).
#include <algorithm>
#include <utility>
#include <vector>

#include "analysis_impl.hpp"

namespace osteon {

void Analyzer::Impl::mark_dirty(RunState& run) {
  const Skeleton& sk = run.sk;
  const long jobs = static_cast<long>(job_bone.size());
  run.job_dirty.assign(jobs, 1);
  run.section_dirty.assign(specs.size(), 1);
  if (!run.partial) return;
  const Box3& dirty = *run.dirty;
  run.all_changed = false;
  run.changed = dirty;
  // A section changes only if the moved triangles cross its plane inside the region its cut
  // was proven in (and, for a ball, away from its bone's axis: the inside test uses that line).
  const Vec3 center = 0.5 * (dirty.lo + dirty.hi), half = 0.5 * (dirty.hi - dirty.lo);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const SectionState& st = states[i];
    bool touched = dirty.meets_slab(specs[i].point, specs[i].normal, 0.0);
    if (touched && !st.whole_plane) {
      const int b = specs[i].bone;
      const CutRegion axis_line{sk.heads[b], sk.direction(b), 0.0};
      touched = st.region.meets_box(center, half) || axis_line.meets_box(center, half);
    }
    run.section_dirty[i] = touched;
  }
  std::fill(run.job_dirty.begin(), run.job_dirty.end(), 0);
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (run.section_dirty[i]) run.job_dirty[specs[i].job] = 1;
}

void Analyzer::Impl::reuse_last_run(RunState& run) {
  if (!(run.may_reuse && run.prev_specs.size() == specs.size())) return;
  const Skeleton& sk = run.sk;
  const MeshView& mesh = run.mesh;
  const double* vertices = run.vertices;
  const std::vector<SectionSpec>& prev_specs = run.prev_specs;
  std::vector<SectionState>& prev_states = run.prev_states;  // moved into `states` once reused
  // Exact reuse: a section keeps its geometry when its bone, plane and downstream side are
  // bitwise the same and no moved triangle reaches the region its cut was proven in.
  Box3 moved_box;
  std::vector<std::uint8_t>& moved = moved_scratch;
  moved.resize(num_vertices);  // every entry written below
  run.moved = &moved;
  bool any_moved = false;
  std::vector<std::int32_t>& moved_faces = moved_faces_scratch;
  moved_faces.clear();
  run.moved_faces = &moved_faces;
  for (Index v = 0; v < num_vertices; ++v) {
    const double* a = vertices + 3 * v;
    const double* b = last_vertices.data() + 3 * v;
    moved[v] = a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
    any_moved |= moved[v] != 0;
  }
  if (any_moved) {
    for (std::size_t f = 0; f < faces.size(); f += 3) {
      if (!moved[faces[f]] && !moved[faces[f + 1]] && !moved[faces[f + 2]]) continue;
      moved_faces.push_back(static_cast<std::int32_t>(f / 3));
      for (int k = 0; k < 3; ++k) {
        const Index v = faces[f + k];
        moved_box.add(mesh.vertex(v));
        moved_box.add(
            Vec3(last_vertices[3 * v], last_vertices[3 * v + 1], last_vertices[3 * v + 2]));
      }
    }
  }
  const Vec3 center = 0.5 * (moved_box.lo + moved_box.hi),
             half = 0.5 * (moved_box.hi - moved_box.lo);
  run.all_changed = false;
  run.changed = moved_box;
  std::fill(run.job_dirty.begin(), run.job_dirty.end(), 0);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const SectionSpec& a = specs[i];
    const SectionSpec& b = prev_specs[i];
    const int bone = a.bone;
    bool same = a.bone == b.bone && a.kind == b.kind && a.boundary == b.boundary &&
                a.plus_side == b.plus_side && a.point == b.point && a.normal == b.normal &&
                sk.heads[bone] == last_heads[bone] && sk.tails[bone] == last_tails[bone] &&
                !(prev_states[i].whole_plane && run.gap != last_gap);  // gap closing applies there
    if (same && any_moved && moved_box.meets_slab(a.point, a.normal, 0.0)) {
      const SectionState& st = prev_states[i];
      const CutRegion axis_line{sk.heads[bone], sk.direction(bone), 0.0};
      same = !st.whole_plane && !st.region.meets_box(center, half) &&
             !axis_line.meets_box(center, half);
    }
    if (same) {
      states[i] = std::move(prev_states[i]);
      run.section_dirty[i] = 0;
    } else {
      run.section_dirty[i] = 1;
      run.job_dirty[a.job] = 1;
    }
  }
}

void Analyzer::Impl::remember_inputs(const RunState& run) {
  last_vertices.assign(run.vertices, run.vertices + 3 * num_vertices);
  last_heads = run.sk.heads;
  last_tails = run.sk.tails;
  last_parents = run.sk.parents;
  last_gap = run.gap;
}

}  // namespace osteon
