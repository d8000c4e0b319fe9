// Stage 4 of a run: the load of every section (paper §4.4) and its stress (Analyzer::Impl).
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "analysis_impl.hpp"
#include "notch.hpp"
#include "parallel.hpp"
#include "thickness.hpp"

namespace osteon {
namespace {

// Packs the loops `member` of the sections that `take` (AnalysisResult's outline_* layout):
// section i owns loops section_start[i] .. section_start[i + 1], loop l the points
// loop_start[l] .. loop_start[l + 1].
template <class Take>
void pack_loops(const std::vector<SectionState>& states,
                std::vector<std::vector<Vec3>> SectionState::*member, const Take& take,
                std::vector<Vec3>& points, std::vector<std::int64_t>& loop_start,
                std::vector<std::int64_t>& section_start) {
  const int ns = static_cast<int>(states.size());
  section_start.reserve(ns + 1);
  loop_start.push_back(0);
  for (int i = 0; i < ns; ++i) {
    section_start.push_back(static_cast<std::int64_t>(loop_start.size()) - 1);
    if (!take(i)) continue;
    for (const auto& loop : states[i].*member) {
      points.insert(points.end(), loop.begin(), loop.end());
      loop_start.push_back(static_cast<std::int64_t>(points.size()));
    }
  }
  section_start.push_back(static_cast<std::int64_t>(loop_start.size()) - 1);
}

}  // namespace

AnalysisResult Analyzer::Impl::compute_loads(RunState& run) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const int ns = static_cast<int>(specs.size());
  AnalysisResult r = section_loads(run);
  // Stress concentration at corners (notch.hpp, docs/notch.md): `stress` becomes the governing
  // stress, the peak at the corner next to the section; the beam stress stays as nominal_stress.
  run.timer.lap("loads");
  r.nominal_stress = r.stress;
  const auto grid = [&]() -> const FaceGrid& {
    run.build_grid(options.threads);
    return run.grid;
  };
  // Live mode: corners no moved triangle reaches keep the last run's measurement (exact).
  MeshChange change;
  change.known = run.moved != nullptr;
  change.lo = run.changed.lo;
  change.hi = run.changed.hi;
  // (A partial run, the correction's, disarms it: its final full run searches as before.)
  if (run.partial) corner_memo.forget();
  NotchField notch = find_notches(
      run.mesh, grid, r, options.min_notch_radius, options.notch_sensitivity, options.threads,
      options.reuse_sections && !run.partial ? &corner_memo : nullptr, change);
  for (int i = 0; i < ns; ++i) {
    if (!(notch.kt[i] > 1.0) || !std::isfinite(r.stress[i])) continue;
    r.stress[i] *= notch.effective[i] * notch.arm_ratio[i];
    r.section_flags[i] |= kFlagNotch;
  }
  r.stress_concentration = notch.kt;
  r.notch_radius = notch.radius;
  r.notch_step = notch.step;
  run.timer.lap("notches");
  // Direction-dependent allowable (FDM layers, osteon/layers.hpp): exactly allowable_stress
  // when isotropic.
  section_allowables(r.section_normal, options.build_direction, options.allowable_stress,
                     options.layer_strength_ratio, r.section_allowable, r.across_layers);
  r.stress_ratio.assign(ns, kNaN);
  const std::vector<std::uint8_t> usable = usable_sections(r);
  for (int i = 0; i < ns; ++i) {
    if (!(r.section_flags[i] & kFlagUnreliable) || !(notch.kt[i] > 1.0)) continue;
    r.nominal_stress[i] = r.notch_radius[i] = r.notch_step[i] = kNaN;  // an unreliable sliver
    r.stress_concentration[i] = notch.effective[i] = notch.arm_ratio[i] = 1.0;
    r.section_flags[i] &= ~static_cast<std::uint32_t>(kFlagNotch);
  }
  // Thickness not needed so far: the regions, for complete_section_thickness().
  if (options.defer_thickness) {
    for (int i = 0; i < ns; ++i) {
      const SectionState& st = states[i];
      if (!st.found || !st.analysed || !std::isnan(st.thickness) ||
          (r.section_flags[i] & kFlagUnreliable))
        continue;
      if (r.thickness_pending.empty()) r.thickness_pending.resize(ns);
      r.thickness_pending[i] = st.analysed;
    }
  }
  for (int i = 0; i < ns; ++i) {
    if (!usable[i]) continue;
    // The moment at a notch section's corner counts (the bound below stays a bound).
    r.max_moment = std::max(r.max_moment, r.moment[i] * notch.arm_ratio[i]);
    r.max_stress = std::max(r.max_stress, r.stress[i]);
    if (r.weakest_section < 0 || r.stress_ratio[i] > r.max_stress_ratio) {
      r.max_stress_ratio = r.stress_ratio[i];
      r.weakest_section = i;
    }
  }
  r.safe_modulus = r.max_moment / options.allowable_stress;
  for (int i = 0; i < ns; ++i) {
    if (!usable[i]) continue;
    // Safe for sure even with its corner: (1 + q (Kt - 1)) M_max / W below the allowable.
    r.culled[i] = r.section_modulus[i] > notch.effective[i] * r.max_moment / r.section_allowable[i];
    r.weak[i] = r.stress[i] > r.section_allowable[i];
  }
  run.check_cancel();
  if (options.keep_outlines) pack_outlines(r);
  return r;
}

// Farthest downstream point of every section, then its moment and stress (the result's
// per-section arrays; the allowable and the ratio come later).
AnalysisResult Analyzer::Impl::section_loads(RunState& run) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const MeshView& mesh = run.mesh;
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
  r.section_thickness.resize(ns);
  r.section_cut_area.resize(ns);
  r.section_cut_modulus.resize(ns);
  r.section_solid_modulus.resize(ns);
  r.section_wall_area.resize(ns);
  r.section_skin_area.resize(ns);
  r.section_infill_area.resize(ns);
  r.moment_arm.resize(ns);
  r.moment.resize(ns);
  r.stress.resize(ns);
  r.culled.assign(ns, 0);
  r.weak.assign(ns, 0);
  r.section_flags.resize(ns);
  run.timer.lap("moment index");
  const MomentArmIndex& arms = *run.arms;
  const bool recall = run.moved != nullptr && load_memo.size() == static_cast<std::size_t>(ns);
  if (!recall) load_memo.assign(ns, LoadMemo{});
  detail::parallel_for((ns + 63) / 64, options.threads, [&](long chunk, int) {
    run.check_cancel();
    const int end = std::min(ns, static_cast<int>(chunk + 1) * 64);
    for (int i = static_cast<int>(chunk) * 64; i < end; ++i) {
      const SectionSpec& spec = specs[i];
      SectionState& st = states[i];
      if (st.found && !options.defer_thickness) section_thickness_at(st);
      r.section_bone[i] = spec.bone;
      r.section_kind[i] = spec.kind;
      r.section_param[i] = slab_params[spec.bone][spec.boundary];
      r.section_point[i] = spec.point;
      r.section_normal[i] = spec.normal;
      r.section_flags[i] = st.flags;
      const Vec3 center = st.found ? st.center : spec.point;
      r.section_center[i] = center;
      // Live mode: the last run's load point when the query and every point it could take are
      // the last run's (the same answer, bit for bit).
      LoadMemo& memo = load_memo[i];
      if (!(recall && memo.bone == spec.bone && memo.boundary == spec.boundary &&
            memo.plus_side == spec.plus_side && memo.center == center &&
            arms.region_kept(spec.bone))) {
        std::tie(memo.arm, memo.vertex) =
            arms.farthest(spec.bone, spec.boundary, spec.plus_side, center);
        memo.bone = spec.bone;
        memo.boundary = spec.boundary;
        memo.plus_side = spec.plus_side;
        memo.center = center;
      }
      const double arm = memo.arm;
      const Index vertex = memo.vertex;
      r.moment_arm[i] = arm;
      r.load_point[i] = vertex >= 0 ? mesh.vertex(vertex) : center;
      r.moment[i] = options.force * arm;
      r.section_area[i] = st.found ? st.area : 0.0;
      r.section_modulus[i] = st.found ? st.modulus : kNaN;
      r.section_thin_axis[i] = st.found ? st.thin_axis : Vec3(kNaN, kNaN, kNaN);
      r.section_aspect[i] = st.found ? st.aspect : kNaN;
      r.section_thickness[i] = st.found ? st.thickness : kNaN;
      r.section_cut_area[i] = st.found ? st.cut_area : 0.0;
      r.section_cut_modulus[i] = st.found ? st.cut_modulus : kNaN;
      r.section_solid_modulus[i] = st.found ? st.solid_modulus : kNaN;
      r.section_wall_area[i] = st.found ? st.wall_area : 0.0;
      r.section_skin_area[i] = st.found ? st.skin_area : 0.0;
      r.section_infill_area[i] = st.found ? st.infill_area : 0.0;
      r.stress[i] = st.found ? r.moment[i] / st.modulus : kNaN;
    }
  });
  return r;
}

// Sections that drive results: found, not doubted (unreliable), not too thin to print. An
// outside section far smaller than its bone's sections inside the mesh (below a tenth of their
// median area) is a sliver the bone only grazes: unreliable, no number. Too-thin sections keep
// their stress and ratio but drive neither the maximum, weak, culled nor the safe modulus.
std::vector<std::uint8_t> Analyzer::Impl::usable_sections(AnalysisResult& r) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const int ns = static_cast<int>(specs.size());
  std::vector<std::uint8_t> usable(ns, 0);
  const int nb = num_bones;
  std::vector<std::vector<double>> inner(nb);
  for (int i = 0; i < ns; ++i)
    if (states[i].found && !(states[i].flags & kFlagOutside))
      inner[specs[i].bone].push_back(states[i].area);
  std::vector<double> median(nb, 0.0);
  for (int b = 0; b < nb; ++b) {
    auto& a = inner[b];
    if (a.empty()) continue;
    std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
    median[b] = a[a.size() / 2];
  }
  for (int i = 0; i < ns; ++i) {
    if (!states[i].found) continue;
    std::uint32_t& flags = r.section_flags[i];
    if ((flags & kFlagOutside) && states[i].area < 0.1 * median[specs[i].bone]) {
      flags |= kFlagUnreliable;
      r.section_area[i] = r.section_cut_area[i] = 0.0;
      r.section_cut_modulus[i] = r.section_solid_modulus[i] = kNaN;
      r.section_wall_area[i] = r.section_skin_area[i] = r.section_infill_area[i] = 0.0;
      r.section_modulus[i] = r.stress[i] = r.section_aspect[i] = r.section_thickness[i] = kNaN;
      r.section_thin_axis[i] = Vec3(kNaN, kNaN, kNaN);
      continue;
    }
    // The exact thickness only for a section that is too thin (the check mostly decides
    // from a lower bound of the width and a search of the walls within the minimum).
    SectionState& st = states[i];
    const bool thin = std::isnan(st.thickness)
                          ? st.analysed && region_thinner_than(*st.analysed, options.min_thickness,
                                                               st.thickness_bound)
                          : st.thickness < options.min_thickness;
    if (thin) {
      r.section_thickness[i] = section_thickness_at(st);
      flags |= kFlagTooThin;
    }
    r.stress_ratio[i] = r.stress[i] / r.section_allowable[i];
    usable[i] = !(flags & kFlagTooThin);
  }
  return usable;
}

// Each analysed region's loops (outline_*), each junction's whole cut (cut_outline_*) and each
// region's sparse infill (infill_outline_*; none when the part is solid).
void Analyzer::Impl::pack_outlines(AnalysisResult& r) const {
  // Only regions analysed: not an unreliable sliver (no number, no outline).
  auto analysed = [&](int i) { return states[i].found && !(r.section_flags[i] & kFlagUnreliable); };
  pack_loops(states, &SectionState::loops, analysed, r.outline_points, r.outline_loop_start,
             r.outline_section_start);
  pack_loops(
      states, &SectionState::cut_loops,
      [&](int i) { return states[i].found && (r.section_flags[i] & kFlagJunction); },
      r.cut_outline_points, r.cut_outline_loop_start, r.cut_outline_section_start);
  pack_loops(states, &SectionState::infill_loops, analysed, r.infill_outline_points,
             r.infill_outline_loop_start, r.infill_outline_section_start);
}

}  // namespace osteon
