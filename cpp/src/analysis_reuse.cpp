// What a run may keep from the last one: partial re-analysis (the correction loop) and exact
// reuse of unchanged sections (live mode) (Analyzer::Impl).
#include <algorithm>
#include <cstring>
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
  const std::vector<SectionSpec>& prev_specs = run.prev_specs;
  std::vector<SectionState>& prev_states = run.prev_states;  // moved into `states` once reused
  // Exact reuse: a section keeps its geometry when its bone, plane and downstream side are
  // bitwise the same and no moved triangle reaches the region its cut was proven in.
  // (check_vertices compared the vertices: may_reuse needs the last run's.)
  Box3 moved_box;
  moved_scratch.resize(num_vertices, 0);  // (check_vertices sized it: the last run's are known)
  run.moved = &moved_scratch;
  const bool any_moved = !moved_vertices.empty();
  std::vector<std::int32_t>& moved_faces = moved_faces_scratch;
  moved_faces.clear();
  run.moved_faces = &moved_faces;
  if (any_moved) list_moved_faces(run, moved_box);
  list_bone_vertices(run);
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

void Analyzer::Impl::list_moved_faces(RunState& run, Box3& moved_box) {
  const Index nf = static_cast<Index>(faces.size() / 3);
  if (vertex_face_start.empty()) {  // each vertex's faces (the faces never change)
    vertex_face_start.assign(num_vertices + 1, 0);
    for (std::int32_t v : faces) ++vertex_face_start[v + 1];
    for (Index v = 0; v < num_vertices; ++v) vertex_face_start[v + 1] += vertex_face_start[v];
    vertex_faces.resize(faces.size());
    std::vector<Index> fill(vertex_face_start.begin(), vertex_face_start.end() - 1);
    for (Index k = 0; k < 3 * nf; ++k)
      vertex_faces[fill[faces[k]]++] = static_cast<std::int32_t>(k / 3);
    face_listed.assign(nf, 0);
    corner_listed.assign(num_vertices, 0);
  }
  // The faces of the moved vertices, each once, and the corners of those faces (moved or not):
  // the box of their old and new positions is the box of the moved triangles.
  std::vector<std::int32_t>& moved_faces = moved_faces_scratch;
  std::vector<std::int32_t>& corners = corner_scratch;
  corners.clear();
  for (const Index v : moved_vertices) {
    for (Index k = vertex_face_start[v]; k < vertex_face_start[v + 1]; ++k) {
      const std::int32_t f = vertex_faces[k];
      if (face_listed[f]) continue;
      face_listed[f] = 1;
      moved_faces.push_back(f);
      for (int j = 0; j < 3; ++j) {
        const std::int32_t c = faces[3 * static_cast<Index>(f) + j];
        if (corner_listed[c]) continue;
        corner_listed[c] = 1;
        corners.push_back(c);
      }
    }
  }
  const MeshView& mesh = run.mesh;
  for (std::int32_t c : corners) {
    corner_listed[c] = 0;
    moved_box.add(mesh.vertex(c));
    moved_box.add(Vec3(last_vertices[3 * static_cast<Index>(c)],
                       last_vertices[3 * static_cast<Index>(c) + 1],
                       last_vertices[3 * static_cast<Index>(c) + 2]));
  }
  for (std::int32_t f : moved_faces) face_listed[f] = 0;
}

void Analyzer::Impl::list_bone_vertices(RunState& run) {
  const std::vector<int>& vertex_bone = run.vertex_bone;
  const int nb = num_bones;
  std::vector<std::uint8_t>& changed = run.bone_changed;
  const bool same =
      bone_list_of.size() == vertex_bone.size() &&
      std::memcmp(bone_list_of.data(), vertex_bone.data(), vertex_bone.size() * sizeof(int)) == 0;
  if (!same) {  // every bone's vertices listed again; every bone counts as changed
    bone_vertex_start.assign(nb + 1, 0);
    for (int b : vertex_bone) ++bone_vertex_start[b + 1];
    for (int b = 0; b < nb; ++b) bone_vertex_start[b + 1] += bone_vertex_start[b];
    bone_vertex_list.resize(vertex_bone.size());
    std::vector<Index> fill(bone_vertex_start.begin(), bone_vertex_start.end() - 1);
    for (Index v = 0; v < num_vertices; ++v)
      bone_vertex_list[fill[vertex_bone[v]]++] = static_cast<std::int32_t>(v);
    bone_list_of = vertex_bone;
    changed.assign(nb, 1);
    return;
  }
  changed.assign(nb, 0);
  for (int b = 0; b < nb; ++b)
    changed[b] = !(run.sk.heads[b] == last_heads[b] && run.sk.tails[b] == last_tails[b]);
  for (const std::int32_t v : moved_vertices) changed[vertex_bone[v]] = 1;
}

void Analyzer::Impl::remember_inputs(const RunState& run) {
  // The blocks that differ from the last run's are copied (check_vertices listed them).
  if (run.vertices_compared && last_vertices.size() == static_cast<std::size_t>(3 * num_vertices))
    for (const Index k : changed_blocks) {
      const Index begin = 3 * k * kVertexBlock,
                  end = std::min(3 * num_vertices, begin + 3 * kVertexBlock);
      std::copy(run.vertices + begin, run.vertices + end, last_vertices.begin() + begin);
    }
  else
    last_vertices.assign(run.vertices, run.vertices + 3 * num_vertices);
  last_heads = run.sk.heads;
  last_tails = run.sk.tails;
  last_parents = run.sk.parents;
  last_gap = run.gap;
}

}  // namespace osteon
