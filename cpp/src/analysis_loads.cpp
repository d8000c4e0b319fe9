// Stage 4 of a run: the load of every section (paper §4.4) and its stress (Analyzer::Impl).
#include <algorithm>
#include <limits>
#include <vector>

#include "analysis_impl.hpp"
#include "parallel.hpp"

namespace osteon {

AnalysisResult Analyzer::Impl::compute_loads(RunState& run) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const MeshView& mesh = run.mesh;
  // Farthest downstream point of every section, then stress.
  const int ns = static_cast<int>(specs.size());
  AnalysisResult r;
  r.held_bone = tree.held_bone;
  r.section_bone.resize(ns);
  r.section_kind.resize(ns);
  r.section_param.resize(ns);
  r.section_point.resize(ns);
  r.section_center.resize(ns);
  r.section_normal.resize(ns);
  r.load_point.resize(ns);
  r.section_area.resize(ns);
  r.section_modulus.resize(ns);
  r.section_thin_axis.resize(ns);
  r.section_aspect.resize(ns);
  r.moment_arm.resize(ns);
  r.moment.resize(ns);
  r.stress.resize(ns);
  r.culled.assign(ns, 0);
  r.weak.assign(ns, 0);
  r.section_flags.resize(ns);
  run.timer.lap("moment index");
  const MomentArmIndex& arms = *run.arms;
  detail::parallel_for((ns + 63) / 64, options.threads, [&](long chunk, int) {
    const int end = std::min(ns, static_cast<int>(chunk + 1) * 64);
    for (int i = static_cast<int>(chunk) * 64; i < end; ++i) {
      const SectionSpec& spec = specs[i];
      const SectionState& st = states[i];
      r.section_bone[i] = spec.bone;
      r.section_kind[i] = spec.kind;
      r.section_param[i] = slab_params[spec.bone][spec.boundary];
      r.section_point[i] = spec.point;
      r.section_normal[i] = spec.normal;
      r.section_flags[i] = st.flags;
      const Vec3 center = st.found ? st.center : spec.point;
      r.section_center[i] = center;
      const auto [arm, vertex] = arms.farthest(spec.bone, spec.boundary, spec.plus_side, center);
      r.moment_arm[i] = arm;
      r.load_point[i] = vertex >= 0 ? mesh.vertex(vertex) : center;
      r.moment[i] = options.force * arm;
      r.section_area[i] = st.found ? st.area : 0.0;
      r.section_modulus[i] = st.found ? st.modulus : kNaN;
      r.section_thin_axis[i] = st.found ? st.thin_axis : Vec3(kNaN, kNaN, kNaN);
      r.section_aspect[i] = st.found ? st.aspect : kNaN;
      r.stress[i] = st.found ? r.moment[i] / st.modulus : kNaN;
    }
  });
  for (int i = 0; i < ns; ++i) {
    if (!states[i].found) continue;
    r.max_moment = std::max(r.max_moment, r.moment[i]);
    if (r.weakest_section < 0 || r.stress[i] > r.max_stress) {
      r.max_stress = r.stress[i];
      r.weakest_section = i;
    }
  }
  r.safe_modulus = r.max_moment / options.allowable_stress;
  for (int i = 0; i < ns; ++i) {
    if (!states[i].found) continue;
    r.culled[i] = r.section_modulus[i] > r.safe_modulus;
    r.weak[i] = r.stress[i] > options.allowable_stress;
  }
  return r;
}

}  // namespace osteon
