#include "osteon/correction.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "analysis_impl.hpp"
#include "osteon/skinning.hpp"

namespace osteon {
namespace {

// The bone whose skinning domain holds a section: the largest weight sum over the vertices in a
// thin slab around the section plane, near its centre (paper §5: the domain of the weakest
// section). A junction section (docs/junctions.md) is its own bone's core, the member that
// continues along the bone through the plane; the vertices around it belong mostly to the stub
// or the body it grows from, which scaling would thicken without touching the core: its own bone
// is the domain when any vertex there carries weight on it.
int domain_bone(const MeshView& mesh, const BoneWeights& w, const AnalysisResult& a, int section,
                double interval) {
  const Vec3 c = a.section_center[section];
  const Vec3 n = a.section_normal[section];
  const double radius = 2.0 * std::sqrt(std::max(a.section_area[section], 0.0) / M_PI) + interval;
  const double half = 0.5 * interval;
  std::vector<double> sum(w.num_bones, 0.0);
  bool any = false;
  for (Index v = 0; v < mesh.num_vertices; ++v) {
    const Vec3 p = mesh.vertex(v) - c;
    if (std::abs(p.dot(n)) > half || p.squaredNorm() > radius * radius) continue;
    const double total = w.row_sum(v);
    if (!(total > 0)) continue;
    for (Index k = w.row_start[v]; k < w.row_start[v + 1]; ++k) {
      sum[w.bone[k]] += w.weight[k] / total;
      any = true;
    }
  }
  const int own = a.section_bone[section];
  if (!any) return own;
  if ((a.section_flags[section] & kFlagJunction) && own >= 0 && own < w.num_bones && sum[own] > 0)
    return own;
  return static_cast<int>(std::max_element(sum.begin(), sum.end()) - sum.begin());
}

}  // namespace

double enclosed_volume(const MeshView& mesh) {
  double six_v = 0.0;
  for (Index f = 0; f < mesh.num_faces; ++f) {
    const Vec3 a = mesh.vertex(mesh.faces[3 * f]);
    const Vec3 b = mesh.vertex(mesh.faces[3 * f + 1]);
    const Vec3 c = mesh.vertex(mesh.faces[3 * f + 2]);
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

namespace {

void check_correction_options(const CorrectionOptions& co, int nb) {
  if (!(co.max_scale >= 1.0) || !std::isfinite(co.max_scale))
    throw std::invalid_argument("max_scale must be a finite number >= 1");
  if (co.max_rounds < 0) throw std::invalid_argument("max_rounds must be >= 0");
  if (!(co.target_ratio > 0 && co.target_ratio <= 1.0))
    throw std::invalid_argument("target_ratio must be in (0, 1]");
  if (!(co.flat_aspect >= 1.0)) throw std::invalid_argument("flat_aspect must be >= 1");
  if (!co.bone_x_axes.empty() && static_cast<int>(co.bone_x_axes.size()) != nb)
    throw std::invalid_argument("bone_x_axes must have one axis per bone");
  if (!co.bone_long_axes.empty() && static_cast<int>(co.bone_long_axes.size()) != nb)
    throw std::invalid_argument("bone_long_axes must have one axis per bone");
}

// Why scaling a bone left a section's stress where it was. At a corner (Kt > 1) under blended
// joint weights the section thickens little, and what it does lowers D/d but also r/d (the
// fillet does not grow with it), so the peak barely falls (docs/notch.md "Correction"): say so,
// and what would lower it.
std::string stuck_reason(const AnalysisResult& a, std::size_t section) {
  const double kt = section < a.stress_concentration.size() ? a.stress_concentration[section] : 1.0;
  if (!(kt > 1.0)) return " (blended weights at a joint?)";
  std::ostringstream out;
  out.precision(3);
  out << " (a corner at a joint: Kt " << kt;
  const double r = section < a.notch_radius.size() ? a.notch_radius[section] : 0.0;
  if (std::isfinite(r)) out << " at a " << r << " mm fillet";
  out << "; a larger fillet there lowers the peak)";
  return out.str();
}

// The axis each bone scales across: its segment, or the given long axis (unit).
std::vector<Vec3> bone_long_axes(const Skeleton& sk, const CorrectionOptions& co) {
  const int nb = sk.num_bones();
  std::vector<Vec3> long_axis(nb);
  for (int b = 0; b < nb; ++b) {
    long_axis[b] = sk.direction(b);
    if (co.bone_long_axes.empty()) continue;
    const Vec3& l = co.bone_long_axes[b];
    if (!l.allFinite() || !(l.norm() > 1e-6))
      throw std::invalid_argument("bone_long_axes[" + std::to_string(b) +
                                  "] must be a finite non-zero vector");
    long_axis[b] = l.normalized();
  }
  return long_axis;
}

// Each bone's unit x axis across its long axis: the given one, or its plane frame's u.
std::vector<Vec3> bone_x_axes(const Skeleton& sk, const CorrectionOptions& co,
                              const std::vector<Vec3>& long_axis) {
  const int nb = sk.num_bones();
  std::vector<Vec3> x_axis(nb);
  for (int b = 0; b < nb; ++b) {
    const Vec3 d = long_axis[b];
    Vec3 x = co.bone_x_axes.empty() ? PlaneFrame::make(sk.heads[b], d).u : co.bone_x_axes[b];
    x -= x.dot(d) * d;
    if (!x.allFinite() || !(x.norm() > 1e-6))
      throw std::invalid_argument("bone_x_axes[" + std::to_string(b) +
                                  "] must be a finite vector across the bone");
    x_axis[b] = x.normalized();
  }
  return x_axis;
}

// The weak section with the highest stress ratio that scaling may still fix, or -1;
// `any_weak`: whether any section is weak at all.
int weakest_fixable(const AnalysisResult& current, const std::vector<std::uint8_t>& unfixable,
                    bool& any_weak) {
  int worst = -1;
  any_weak = false;
  for (std::size_t i = 0; i < current.stress.size(); ++i) {
    if (!current.weak[i]) continue;
    any_weak = true;
    if (unfixable[i]) continue;
    if (worst < 0 || current.stress_ratio[i] > current.stress_ratio[worst])
      worst = static_cast<int>(i);
  }
  return worst;
}

// Which axes of `bone` to scale for section `worst`: 0 both (the paper), 1 x only, 2 z only
// (across a flat section's thickness; `trial`'s x axis of the bone may turn to it).
int scaling_axis(const AnalysisResult& current, int worst, int bone, const Vec3& long_axis,
                 const CorrectionOptions& co, const AxisScales& scales, AxisScales& trial) {
  if (!co.thin_direction || !(current.section_aspect[worst] >= co.flat_aspect)) return 0;
  const Vec3 d = long_axis;
  Vec3 thin = current.section_thin_axis[worst];
  thin -= thin.dot(d) * d;
  if (!(thin.norm() > 0.5)) return 0;  // the thin direction does not lie mostly across the bone
  thin.normalize();
  if (co.bone_x_axes.empty() && scales.x[bone] == scales.z[bone]) trial.x_axis[bone] = thin;
  const Vec3 x = trial.x_axis[bone], z = x.cross(d);
  const double cx = std::abs(thin.dot(x)), cz = std::abs(thin.dot(z));
  if (std::max(cx, cz) >= std::cos(M_PI / 6)) return cx >= cz ? 1 : 2;
  return 0;
}

// Box of every triangle touching a moved vertex, before and after: only planes through it can
// change (the paper's culling of unaffected domains). Smooth weights (e.g. bounded biharmonic)
// reach everywhere with ~1e-10: displacements below the tolerance (squared, mm^2) do not make a
// plane dirty (the final `after` is a full analysis). `moved`: scratch, #V.
Box3 moved_triangles_box(const MeshView& mesh, const std::vector<double>& before,
                         const std::vector<double>& after, double tolerance2,
                         std::vector<std::uint8_t>& moved) {
  Box3 dirty;
  for (Index v = 0; v < mesh.num_vertices; ++v) {
    const double dx = after[3 * v] - before[3 * v], dy = after[3 * v + 1] - before[3 * v + 1],
                 dz = after[3 * v + 2] - before[3 * v + 2];
    moved[v] = dx * dx + dy * dy + dz * dz > tolerance2;
  }
  for (Index f = 0; f < mesh.num_faces; ++f) {
    const std::int32_t* tri = mesh.faces + 3 * f;
    if (!moved[tri[0]] && !moved[tri[1]] && !moved[tri[2]]) continue;
    for (int k = 0; k < 3; ++k) {
      const Index v = tri[k];
      dirty.add(Vec3(after[3 * v], after[3 * v + 1], after[3 * v + 2]));
      dirty.add(Vec3(before[3 * v], before[3 * v + 1], before[3 * v + 2]));
    }
  }
  return dirty;
}

// The outcome once `after` is analysed: converged or the sections that stay weak (in the
// reason, with `why` each could not be fixed), the largest displacement and the volume change.
void summarise_correction(const MeshView& mesh, const Skeleton& sk,
                          const std::vector<std::string>& why, CorrectionResult& res) {
  res.converged = true;
  for (std::size_t i = 0; i < res.after.weak.size(); ++i) {
    if (!res.after.weak[i]) continue;
    res.converged = false;
    res.unfixed_sections.push_back(static_cast<int>(i));
  }
  if (!res.converged) {
    std::ostringstream msg;
    msg << res.reason << "; " << res.unfixed_sections.size() << " section(s) stay weak";
    for (std::size_t k = 0; k < std::min<std::size_t>(res.unfixed_sections.size(), 5); ++k) {
      const int i = res.unfixed_sections[k];
      msg << "; bone '" << sk.name(res.after.section_bone[i]) << "' at "
          << res.after.section_param[i] << " mm: " << res.after.stress[i] << " MPa";
      if (i < static_cast<int>(why.size()) && !why[i].empty()) msg << " (" << why[i] << ")";
    }
    res.reason = msg.str();
  }
  for (Index v = 0; v < mesh.num_vertices; ++v) {
    const Vec3 d(res.vertices[3 * v] - mesh.vertices[3 * v],
                 res.vertices[3 * v + 1] - mesh.vertices[3 * v + 1],
                 res.vertices[3 * v + 2] - mesh.vertices[3 * v + 2]);
    res.max_displacement = std::max(res.max_displacement, d.norm());
  }
  const double v0 = enclosed_volume(mesh);
  const MeshView out{res.vertices.data(), mesh.num_vertices, mesh.faces, mesh.num_faces};
  if (std::abs(v0) > 0)
    res.volume_change_percent = 100.0 * (enclosed_volume(out) - v0) / std::abs(v0);
}

}  // namespace

CorrectionResult correct(const MeshView& mesh, const Skeleton& sk, const BoneWeights& weights,
                         const AnalysisOptions& options, const CorrectionOptions& co,
                         Progress* progress) {
  validate_mesh(mesh);
  validate_skeleton(sk);
  const int nb = sk.num_bones();
  check_correction_options(co, nb);
  AxisScales scales{
      std::vector<double>(nb, 1.0), std::vector<double>(nb, 1.0), std::vector<Vec3>(nb), {}};
  const std::vector<Vec3> long_axis = bone_long_axes(sk, co);
  if (!co.bone_long_axes.empty()) scales.long_axis = long_axis;
  scales.x_axis = bone_x_axes(sk, co, long_axis);
  Analyzer analyzer(mesh.faces, mesh.num_faces, mesh.num_vertices, &weights, nb, options);
  Analyzer::Impl& impl = analyzer.internals();

  CorrectionResult res;
  res.bone_scale.assign(nb, 1.0);
  res.vertices.assign(mesh.vertices, mesh.vertices + 3 * mesh.num_vertices);
  res.before = impl.run(mesh.vertices, sk, nullptr, progress);
  AnalysisResult current = res.before;
  std::vector<std::uint8_t> unfixable(current.stress.size(), 0);
  std::vector<std::string> why(current.stress.size());
  std::vector<double> next(3 * mesh.num_vertices);
  std::vector<std::uint8_t> moved(mesh.num_vertices);
  const double move_tolerance2 = std::pow(1e-6 * bounding_diagonal(mesh), 2);
  res.reason = "max_rounds reached";
  for (int round = 0;; ++round) {
    bool any_weak = false;
    const int worst = weakest_fixable(current, unfixable, any_weak);
    if (!any_weak) {
      res.reason = "no weak section";
      break;
    }
    if (worst < 0) {
      res.reason = "the remaining weak sections cannot be fixed by scaling";
      break;
    }
    if (round >= co.max_rounds) break;
    if (progress != nullptr) progress->check();
    const MeshView current_mesh{res.vertices.data(), mesh.num_vertices, mesh.faces, mesh.num_faces};
    const int bone = domain_bone(current_mesh, weights, current, worst, options.interval);
    const double ratio =
        current.stress[worst] / (co.target_ratio * current.section_allowable[worst]);
    AxisScales trial = scales;
    const int axis = scaling_axis(current, worst, bone, long_axis[bone], co, scales, trial);
    const double want = axis == 0 ? std::cbrt(ratio) : std::sqrt(ratio);
    if (axis != 2) trial.x[bone] = std::min(scales.x[bone] * want, co.max_scale);
    if (axis != 1) trial.z[bone] = std::min(scales.z[bone] * want, co.max_scale);
    const double old_scale = axis == 2 ? scales.z[bone] : scales.x[bone];
    const double new_scale = axis == 2 ? trial.z[bone] : trial.x[bone];
    if (trial.x[bone] <= scales.x[bone] * (1.0 + 1e-9) &&
        trial.z[bone] <= scales.z[bone] * (1.0 + 1e-9)) {
      unfixable[worst] = 1;
      why[worst] = "bone '" + sk.name(bone) + "' already at max_scale";
      continue;
    }
    skin_axis_scales(mesh.vertices, mesh.num_vertices, sk, weights, trial, next.data());
    const Box3 dirty = moved_triangles_box(mesh, res.vertices, next, move_tolerance2, moved);
    const double before_stress = current.stress[worst];
    res.vertices.swap(next);
    scales = trial;
    current = dirty.empty() ? current : impl.run(res.vertices.data(), sk, &dirty, progress);
    res.rounds.push_back({bone, new_scale / old_scale, current.max_stress, axis});
    // No progress on this section: its domain is not this bone's alone (blended joint weights).
    if (!(current.stress[worst] < before_stress * 0.995)) {
      unfixable[worst] = 1;
      why[worst] = "scaling bone '" + sk.name(bone) + "' does not thicken it" +
                   stuck_reason(current, static_cast<std::size_t>(worst));
    }
  }
  res.bone_scale_x = scales.x;
  res.bone_scale_z = scales.z;
  res.bone_x_axis = scales.x_axis;
  for (int b = 0; b < nb; ++b)
    res.bone_scale[b] =
        scales.x[b] == scales.z[b] ? scales.x[b] : std::sqrt(scales.x[b] * scales.z[b]);
  res.after = impl.run(res.vertices.data(), sk, nullptr, progress);
  summarise_correction(mesh, sk, why, res);
  return res;
}

}  // namespace osteon
