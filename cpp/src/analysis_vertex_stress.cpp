// Stage 5 of a run: per-vertex stress, linear along the vertex's bone between its sections
// (Analyzer::Impl).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "analysis_impl.hpp"
#include "parallel.hpp"
#include "sorted_index.hpp"

namespace osteon {

namespace {

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Per bone, its sections sorted along it: params (mm), stresses (MPa; the worst of several joint
// sections at one point) and culled flags. Unreliable and too-thin sections are left out (they
// do not set the colour scale).
struct BoneProfiles {
  std::vector<std::vector<double>> param, stress;
  std::vector<std::vector<std::uint8_t>> culled;
};

BoneProfiles bone_profiles(const std::vector<SectionSpec>& specs,
                           const std::vector<SectionState>& states, const AnalysisResult& r,
                           int nb) {
  std::vector<std::vector<int>> bone_sections(nb);
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (states[i].found && !(r.section_flags[i] & (kFlagUnreliable | kFlagTooThin)))
      bone_sections[specs[i].bone].push_back(static_cast<int>(i));
  BoneProfiles out;
  auto& sp = out.param;
  auto& ss = out.stress;
  auto& sc = out.culled;
  sp.resize(nb);
  ss.resize(nb);
  sc.resize(nb);
  for (int b = 0; b < nb; ++b) {
    auto& list = bone_sections[b];
    std::sort(list.begin(), list.end(),
              [&](int x, int y) { return r.section_param[x] < r.section_param[y]; });
    for (int i : list) {
      const double p = r.section_param[i];
      if (!sp[b].empty() && p - sp[b].back() <= 1e-9 * (1.0 + std::abs(p))) {
        // Several joint sections at one point: show the worst.
        ss[b].back() = std::max(ss[b].back(), r.stress[i]);
        sc[b].back() = sc[b].back() && r.culled[i];
        continue;
      }
      sp[b].push_back(p);
      ss[b].push_back(r.stress[i]);
      sc[b].push_back(r.culled[i]);
    }
  }
  return out;
}

// Per bone, whether its section params, head and axis are the memo's (place_same) and which of
// its sections' stress or culling changed (entry_changed; all_same: none).
void compare_with_memo(const BoneProfiles& prof, const Analyzer::Impl::VertexStressMemo& memo,
                       const std::vector<Vec3>& heads, const std::vector<Vec3>& axis,
                       std::vector<std::uint8_t>& place_same, std::vector<std::uint8_t>& all_same,
                       std::vector<std::vector<std::uint8_t>>& entry_changed) {
  const auto& sp = prof.param;
  const auto& ss = prof.stress;
  const auto& sc = prof.culled;
  for (std::size_t b = 0; b < place_same.size(); ++b) {
    place_same[b] = same_bits(sp[b], memo.param[b]) &&
                    std::memcmp(heads[b].data(), memo.heads[b].data(), sizeof(Vec3)) == 0 &&
                    std::memcmp(axis[b].data(), memo.axis[b].data(), sizeof(Vec3)) == 0;
    if (!place_same[b]) continue;
    entry_changed[b].resize(sp[b].size());
    bool any = false;
    for (std::size_t j = 0; j < sp[b].size(); ++j) {
      entry_changed[b][j] = std::memcmp(&ss[b][j], &memo.stress[b][j], sizeof(double)) != 0 ||
                            sc[b][j] != memo.culled[b][j];
      any |= entry_changed[b][j] != 0;
    }
    all_same[b] = !any;
  }
}

// The vertices of the bones that changed or whose place or sections did not stay (`start`,
// `list`: each bone's vertices), into `work`.
void list_work(const std::vector<std::uint8_t>& changed,
               const std::vector<std::uint8_t>& place_same,
               const std::vector<std::uint8_t>& all_same, const std::vector<Index>& start,
               const std::vector<std::int32_t>& list, std::vector<std::int32_t>& work) {
  work.clear();
  for (std::size_t b = 0; b < changed.size(); ++b)
    if (changed[b] || !place_same[b] || !all_same[b])
      work.insert(work.end(), list.begin() + start[b], list.begin() + start[b + 1]);
}

}  // namespace

void Analyzer::Impl::compute_vertex_stress(RunState& run, AnalysisResult& r) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const std::vector<int>& vertex_bone = run.vertex_bone;
  const int nb = num_bones;
  BoneProfiles prof = bone_profiles(specs, states, r, nb);
  const auto& sp = prof.param;
  const auto& ss = prof.stress;
  const auto& sc = prof.culled;
  run.check_cancel();
  // Loose pieces (found with the moment-arm index) carry no load: their vertices stay at 0.
  r.loose_pieces = loose;
  const bool any_loose = !loose.empty();
  // Live mode (VertexStressMemo): per bone, whether its params, head and axis are the last run's
  // (place_same) and which of its sections' stress or culling changed (entry_changed).
  VertexStressMemo& memo = stress_memo;
  const std::uint8_t* moved = nullptr;
  std::vector<std::uint8_t> place_same(nb, 0), all_same(nb, 0);
  std::vector<std::vector<std::uint8_t>> entry_changed(nb);
  if (run.moved != nullptr && memo.valid &&
      memo.vertex_stress.size() == std::size_t(num_vertices) &&
      (any_loose ? same_bits(memo.loose_vertex, loose_vertex) : memo.loose_vertex.empty())) {
    moved = run.moved->data();
    compare_with_memo(prof, memo, sk.heads, run.axis, place_same, all_same, entry_changed);
    r.vertex_stress.swap(memo.vertex_stress);  // the last values; changed ones are overwritten
    r.vertex_culled.swap(memo.vertex_culled);
  } else {
    r.vertex_stress.assign(num_vertices, 0.0);
    r.vertex_culled.assign(num_vertices, 0);
  }
  // Only a reused Analyzer (live mode: the last run's vertices known) keeps what the next run
  // compares with; a one-off analysis pays nothing for it.
  const bool keep = run.moved != nullptr;
  if (keep) {
    memo.vertex_param.resize(num_vertices);
    memo.vertex_slab.resize(num_vertices);
  }
  const int* last_bone = moved != nullptr ? memo.vertex_bone.data() : nullptr;
  double* vparam = keep ? memo.vertex_param.data() : nullptr;
  std::int32_t* vslab = keep ? memo.vertex_slab.data() : nullptr;
  // Live mode: only the vertices of bones with a moved vertex, another frame or changed
  // sections are visited (every other vertex keeps its value, as the test below would decide).
  const std::int32_t* work = nullptr;
  Index count = num_vertices;
  if (moved != nullptr && !run.bone_changed.empty() && same_bits(memo.vertex_bone, vertex_bone)) {
    list_work(run.bone_changed, place_same, all_same, bone_vertex_start, bone_vertex_list,
              memo.work);
    work = memo.work.data();
    count = static_cast<Index>(memo.work.size());
  }
  const Index block = 8192;
  detail::parallel_for(
      static_cast<long>((count + block - 1) / block), options.threads, [&](long chunk, int) {
        run.check_cancel();
        const Index end = std::min(count, (chunk + 1) * block);
        for (Index k = chunk * block; k < end; ++k) {
          const Index v = work != nullptr ? work[k] : k;
          const int b = vertex_bone[v];
          const auto& p = sp[b];
          if (p.empty() || (any_loose && loose_vertex[v])) {
            r.vertex_stress[v] = 0.0;
            r.vertex_culled[v] = 0;
            continue;
          }
          double t;
          std::size_t j;
          if (moved != nullptr && !moved[v] && last_bone[v] == b && place_same[b]) {
            if (all_same[b]) continue;
            t = vparam[v];
            j = static_cast<std::size_t>(vslab[v]);
            const std::uint8_t* changed = entry_changed[b].data();
            if (!changed[j == 0 ? 0 : j - 1] && !changed[j == p.size() ? j - 1 : j]) continue;
          } else {
            t = (mesh.vertex(v) - sk.heads[b]).dot(run.axis[b]);
            j = detail::upper_index(p, t);
            if (vparam != nullptr) {
              vparam[v] = t;
              vslab[v] = static_cast<std::int32_t>(j);
            }
          }
          if (j == 0) {
            r.vertex_stress[v] = ss[b][0];
            r.vertex_culled[v] = sc[b][0];
          } else if (j == p.size()) {
            r.vertex_stress[v] = ss[b].back();
            r.vertex_culled[v] = sc[b].back();
          } else {
            const double w = (t - p[j - 1]) / (p[j] - p[j - 1]);
            r.vertex_stress[v] = (1 - w) * ss[b][j - 1] + w * ss[b][j];
            r.vertex_culled[v] = sc[b][j - 1] && sc[b][j];
          }
        }
      });
  memo.valid = false;
  if (!keep) {
    // Nothing reads the run's vertex bones after this stage: moved, not copied (4 bytes per
    // vertex written to fresh pages on the calling thread, 3 MB on cow x64).
    r.vertex_bone = std::move(run.vertex_bone);
    return;
  }
  r.vertex_bone = vertex_bone;
  // What the next run compares with (copies: the result owns its arrays).
  memo.param = std::move(prof.param);
  memo.stress = std::move(prof.stress);
  memo.culled = std::move(prof.culled);
  memo.heads.assign(sk.heads.begin(), sk.heads.begin() + nb);
  memo.axis.assign(run.axis.begin(), run.axis.begin() + nb);
  if (!same_bits(memo.vertex_bone, vertex_bone)) memo.vertex_bone = vertex_bone;
  if (any_loose)
    memo.loose_vertex = loose_vertex;
  else
    memo.loose_vertex.clear();
  memo.vertex_stress = r.vertex_stress;
  memo.vertex_culled = r.vertex_culled;
  memo.valid = true;
}

}  // namespace osteon
