// Stage 5 of a run: per-vertex stress, linear along the vertex's bone between its sections
// (Analyzer::Impl).
#include <algorithm>
#include <cmath>
#include <vector>

#include "analysis_impl.hpp"
#include "parallel.hpp"
#include "sorted_index.hpp"

namespace osteon {

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
  r.vertex_stress.assign(num_vertices, 0.0);
  r.vertex_culled.assign(num_vertices, 0);
  r.vertex_bone = vertex_bone;
  run.check_cancel();
  // Loose pieces (found with the moment-arm index) carry no load: their vertices stay at 0.
  r.loose_pieces = loose;
  const bool any_loose = !loose.empty();
  const Index block = 8192;
  detail::parallel_for(
      static_cast<long>((num_vertices + block - 1) / block), options.threads, [&](long chunk, int) {
        run.check_cancel();
        const Index end = std::min(num_vertices, (chunk + 1) * block);
        for (Index v = chunk * block; v < end; ++v) {
          const int b = vertex_bone[v];
          const auto& p = sp[b];
          if (p.empty() || (any_loose && loose_vertex[v])) continue;
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
}

}  // namespace osteon
