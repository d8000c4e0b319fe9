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

}  // namespace

void Analyzer::Impl::compute_vertex_stress(RunState& run, AnalysisResult& r) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const std::vector<int>& vertex_bone = run.vertex_bone;
  const int nb = num_bones;
  const int ns = static_cast<int>(specs.size());
  std::vector<std::vector<int>> bone_sections(nb);
  // Unreliable and too-thin sections are left out (they do not set the colour scale).
  for (int i = 0; i < ns; ++i)
    if (states[i].found && !(r.section_flags[i] & (kFlagUnreliable | kFlagTooThin)))
      bone_sections[specs[i].bone].push_back(i);
  std::vector<std::vector<double>> sp(nb), ss(nb);
  std::vector<std::vector<std::uint8_t>> sc(nb);
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
  r.vertex_bone = vertex_bone;
  run.check_cancel();
  // Loose pieces (found with the moment-arm index) carry no load: their vertices stay at 0.
  r.loose_pieces = loose;
  const bool any_loose = !loose.empty();
  // Live mode: a vertex keeps the last run's value when nothing its value is computed from
  // changed (its position and bone; the bone's head, axis and section profile, bit for bit).
  VertexStressMemo& memo = stress_memo;
  const std::uint8_t* moved = nullptr;
  std::vector<std::uint8_t> bone_same(nb, 0);
  if (run.moved != nullptr && memo.valid &&
      memo.vertex_stress.size() == std::size_t(num_vertices) &&
      (any_loose ? same_bits(memo.loose_vertex, loose_vertex) : memo.loose_vertex.empty())) {
    moved = run.moved->data();
    for (int b = 0; b < nb; ++b)
      bone_same[b] = same_bits(sp[b], memo.param[b]) && same_bits(ss[b], memo.stress[b]) &&
                     same_bits(sc[b], memo.culled[b]) &&
                     std::memcmp(sk.heads[b].data(), memo.heads[b].data(), sizeof(Vec3)) == 0 &&
                     std::memcmp(run.axis[b].data(), memo.axis[b].data(), sizeof(Vec3)) == 0;
    r.vertex_stress.swap(memo.vertex_stress);  // the last values; changed ones are overwritten
    r.vertex_culled.swap(memo.vertex_culled);
  } else {
    r.vertex_stress.assign(num_vertices, 0.0);
    r.vertex_culled.assign(num_vertices, 0);
  }
  const int* last_bone = moved != nullptr ? memo.vertex_bone.data() : nullptr;
  const Index block = 8192;
  detail::parallel_for(static_cast<long>((num_vertices + block - 1) / block), options.threads,
                       [&](long chunk, int) {
                         run.check_cancel();
                         const Index end = std::min(num_vertices, (chunk + 1) * block);
                         for (Index v = chunk * block; v < end; ++v) {
                           const int b = vertex_bone[v];
                           if (moved != nullptr && !moved[v] && last_bone[v] == b && bone_same[b])
                             continue;
                           const auto& p = sp[b];
                           if (p.empty() || (any_loose && loose_vertex[v])) {
                             r.vertex_stress[v] = 0.0;
                             r.vertex_culled[v] = 0;
                             continue;
                           }
                           const double t = (mesh.vertex(v) - sk.heads[b]).dot(run.axis[b]);
                           const std::size_t j = detail::upper_index(p, t);
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
  // What the next run compares with (copies: the result owns its arrays).
  memo.param = std::move(sp);
  memo.stress = std::move(ss);
  memo.culled = std::move(sc);
  memo.heads.assign(sk.heads.begin(), sk.heads.begin() + nb);
  memo.axis.assign(run.axis.begin(), run.axis.begin() + nb);
  memo.vertex_bone = vertex_bone;
  if (any_loose)
    memo.loose_vertex = loose_vertex;
  else
    memo.loose_vertex.clear();
  memo.vertex_stress = r.vertex_stress;
  memo.vertex_culled = r.vertex_culled;
  memo.valid = true;
}

}  // namespace osteon
