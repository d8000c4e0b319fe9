// Stage 3d of a run: the effective section at junctions (docs/method.md, Sections;
// docs/junctions.md) (Analyzer::Impl).
//
// Where a side branch grows out of a bone, the plane through the junction also cuts the stub of
// the branch, and beam theory would count it. By Saint-Venant's principle a stub shorter than
// about its own width is not engaged: only the material that continues through the plane, a
// bone's width before and after it, carries the load. A cheap detector picks the candidates (a
// cut whose area exceeds 1.5 x its bone's median); for these only, two parallel planes at
// +-delta (delta = 1.25 x the bone's equivalent radius sqrt(A_median / pi): the slab between
// them is a little longer than the bone is wide) are cut and the section is trimmed to what both
// neighbours' regions (widened a little) also cover: the core. Trimmed pieces that are nowhere
// wider than 0.6 equivalent radii (a taper's rim, a tilted bone's crescent) stay in the core.
// The bone's own sections inside the slab that are narrower than both neighbours (a neck) are
// neighbours too. The core is used only where the trimmed material sticks out of it by at least
// 1.25 core radii (a branch); a shallower swelling (a joint's flare, a bulge) is the bone's own.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "analysis_impl.hpp"
#include "clipper2/clipper.h"
#include "junction_core.hpp"
#include "parallel.hpp"
#include "region_choice.hpp"
#include "simplify_path.hpp"

namespace osteon {
namespace {

constexpr double kCandidateArea = 1.5;  // candidate: whole cut area > this x the bone's median
constexpr double kDelta = 1.25;         // neighbour planes at +-this x the bone's equivalent radius
constexpr double kMargin = 0.05;        // neighbour regions widened by this x the radius (wobble)
constexpr double kOpening = 0.3;    // trimmed pieces nowhere wider than 2 x this x radius go back
constexpr double kMaterial = 0.95;  // the core is used when its area < this x the cut's
constexpr double kContinues = 0.5;  // ... and >= this x the bone's median area
constexpr double kReach = 1.25;     // ... and the cut reaches >= this x the core's radius beyond it
// The branch test asked early, of a region inside the core, at this x its reach: a "no" there is
// a "no" for the core (see find_junction_cores); the 10 % cover the branch test's thinning
// (1 % of the reach, of either region's loops) many times over.
constexpr double kSureNo = 0.9;

// Area of a region (outer boundary minus its holes), mm^2.
double region_area(const SectionPolygon& p) {
  double a = std::abs(signed_area(p.outer));
  for (const auto& h : p.holes) a -= std::abs(signed_area(h));
  return a;
}

// Squared distance from q to the segment a-b, mm^2.
double segment_distance2(const Vec2& q, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (q - (a + t * ab)).squaredNorm();
}

// True when some vertex of `cut`'s outer boundary lies farther than `reach` (mm) from the box
// [lo, hi] (mm).
bool reaches_beyond_box(const SectionPolygon& cut, const Vec2& lo, const Vec2& hi, double reach) {
  const double r2 = reach * reach;
  for (const Vec2& q : cut.outer) {
    const double dx = std::max({lo.x() - q.x(), 0.0, q.x() - hi.x()});
    const double dy = std::max({lo.y() - q.y(), 0.0, q.y() - hi.y()});
    if (dx * dx + dy * dy > r2) return true;
  }
  return false;
}

// True when some vertex of `cut`'s outer boundary lies farther than `reach` (mm) from every
// boundary loop of `core` (core is a part of cut, so its vertices outside the core are the
// trimmed material): the trimmed material sticks out of the core at least that far.
bool reaches_beyond(const SectionPolygon& cut, const SectionPolygon& core, double reach) {
  const double r2 = reach * reach;
  // A vertex farther than `reach` from the core's box is farther from all of the core: a stub
  // usually has one, and the answer costs one pass.
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec2& p : core.outer) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (reaches_beyond_box(cut, lo, hi, reach)) return true;
  // Otherwise every vertex against the core's loops, thinned to within 1 % of `reach` (Clipper2
  // SimplifyPath: a few dozen segments instead of hundreds; the distances move by no more).
  std::vector<std::pair<Vec2, Vec2>> segments;
  auto add = [&](const std::vector<Vec2>& loop) {
    Clipper2Lib::PathD path;
    path.reserve(loop.size());
    for (const Vec2& p : loop) path.emplace_back(p.x(), p.y());
    path = detail::simplify_closed(path, 0.01 * reach);
    for (std::size_t k = 0, n = path.size(); k < n; ++k) {
      const auto& a = path[k];
      const auto& b = path[k + 1 == n ? 0 : k + 1];
      segments.emplace_back(Vec2(a.x, a.y), Vec2(b.x, b.y));
    }
  };
  add(core.outer);
  for (const auto& hole : core.holes) add(hole);
  // Consecutive vertices of the cut are usually near the same segment: the search for a near one
  // starts at the last one found (the answer is whether there is one).
  const std::size_t m = segments.size();
  std::size_t last = 0;
  for (const Vec2& q : cut.outer) {
    bool near = false;
    for (std::size_t j = 0; !near && j < m; ++j) {
      const std::size_t k = last + j < m ? last + j : last + j - m;
      near = segment_distance2(q, segments[k].first, segments[k].second) < r2;
      if (near) last = k;
    }
    if (!near) return true;
  }
  return false;
}

// Back to the whole cut (a section that was a junction core but is no longer a candidate).
void restore_whole(SectionState& st, const RegionOptions& ro) {
  if (!(st.flags & kFlagJunction)) return;
  set_section_region(st, st.frame, st.cut, ro);
  st.flags &= ~kFlagJunction;
  st.cut_loops.clear();
}

}  // namespace

void Analyzer::Impl::find_junction_cores(RunState& run) {
  const int ns = static_cast<int>(specs.size());
  const RegionOptions ro(options);
  if (!options.junctions) {
    for (SectionState& st : states) {
      restore_whole(st, ro);
      st.junction_delta = 0.0;
    }
    return;
  }
  std::vector<double> delta, median;
  typical_sections(delta, median);
  const std::vector<int> todo = junction_candidates(run, delta, median);
  run.junction_checks = static_cast<long>(todo.size());
  if (todo.empty()) return;
  run.build_grid(options.threads);
  // The neighbour planes' cuts skip the cells and runs of faces whose triangles' own box they
  // miss (FaceGrid::enable_tight_bounds: the same segments, in the same order).
  run.grid.enable_tight_bounds();
  // Which sections may serve as a neighbour (read while other candidates' flags change).
  std::vector<std::uint8_t> neighbour_ok(ns);
  for (int j = 0; j < ns; ++j)
    neighbour_ok[j] = states[j].found && !(states[j].flags & (kFlagOutside | kFlagOpen));
  const int workers = detail::worker_count(options.threads, static_cast<long>(todo.size()));
  std::vector<std::vector<CutSegment>> scratch(workers);
  detail::parallel_for(static_cast<long>(todo.size()), options.threads, [&](long t, int worker) {
    run.check_cancel();  // Esc reaches a run that is checking many candidates, too
    const int i = todo[t];
    const int b = specs[i].bone;
    check_junction(run, i, delta[b], median[b], neighbour_ok, scratch[worker]);
  });
  if (run.timer.on) std::fprintf(stderr, "junction checks %ld\n", run.junction_checks);
}

// Each bone's typical section: the median whole-cut area of its sections inside the mesh, and
// the distance delta (mm) of the neighbour planes from it.
void Analyzer::Impl::typical_sections(std::vector<double>& delta,
                                      std::vector<double>& median) const {
  const int ns = static_cast<int>(specs.size());
  std::vector<std::vector<double>> areas(num_bones);
  for (int i = 0; i < ns; ++i)
    if (states[i].found && !(states[i].flags & kFlagOutside))
      areas[specs[i].bone].push_back(states[i].cut_area);
  delta.assign(num_bones, 0.0);
  median.assign(num_bones, 0.0);
  for (int b = 0; b < num_bones; ++b) {
    auto& a = areas[b];
    if (a.empty()) continue;
    std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
    median[b] = a[a.size() / 2];
    delta[b] = kDelta * std::sqrt(median[b] / M_PI);
  }
}

// Along a bone, the family's own sections m intervals away serve as the neighbours when m * h
// is within [0.75, 1.5] delta: already cut, and in the same plane coordinates (u, v are shared
// and the origins lie on the bone's axis). Otherwise (m = 0 here) the two planes are cut.
Analyzer::Impl::JunctionFamily Analyzer::Impl::junction_family(int i, double d) const {
  const int job = specs[i].job;
  JunctionFamily fam{
      job_section[job],
      job_bone[job] >= 0 ? static_cast<int>(slab_params[specs[i].bone].size()) - 2 : 0,
      std::max(1, static_cast<int>(std::lround(d / options.interval)))};
  const double reach = fam.m * options.interval;
  if (!(fam.count > 0 && reach >= 0.75 * d && reach <= 1.5 * d && i - fam.m >= fam.first &&
        i + fam.m < fam.first + fam.count))
    fam.m = 0;
  return fam;
}

// The sections to check: found, inside the mesh and much larger than their bone's typical
// section, and not checked with the same delta since nothing they read changed. The others get
// their whole cut back.
std::vector<int> Analyzer::Impl::junction_candidates(RunState& run,
                                                     const std::vector<double>& delta,
                                                     const std::vector<double>& median) {
  const int ns = static_cast<int>(specs.size());
  const RegionOptions ro(options);
  std::vector<int> todo;
  for (int i = 0; i < ns; ++i) {
    SectionState& st = states[i];
    if (!st.found) continue;
    const int b = specs[i].bone;
    const bool candidate =
        !(st.flags & kFlagOutside) && delta[b] > 0 && st.cut_area > kCandidateArea * median[b];
    if (!candidate) {
      restore_whole(st, ro);
      st.junction_delta = 0.0;
      continue;
    }
    // A check made with the same delta stays right unless the section was re-cut or a change
    // reaches its neighbour planes. Where the bone's own sections serve as the neighbours (and
    // necks), those are the planes: the check reads nothing but their cuts, and stays right
    // unless one of them was re-cut.
    bool fresh = run.section_dirty[i] || run.all_changed || st.junction_delta != delta[b];
    if (!fresh && !run.changed.empty()) {
      const JunctionFamily fam = junction_family(i, delta[b]);
      if (fam.m > 0) {
        for (int j = i - fam.m; !fresh && j <= i + fam.m; ++j)
          fresh = j >= fam.first && j < fam.first + fam.count && run.section_dirty[j];
      } else {
        fresh = run.changed.meets_slab(specs[i].point, specs[i].normal, 1.5 * delta[b]);
      }
    }
    if (fresh) todo.push_back(i);
  }
  return todo;
}

// The two planes at -delta and +delta cut inside a ball around the bone point three times the
// section's reach: a neighbour whose region around the bone point leaves that ball (its loop is
// clipped open there) is far larger than the section and covers it (counted in `sides`, no
// region). The regions found go to `regions` and `neighbours`. False when a side has no
// material of its own (nothing continues through the plane).
bool Analyzer::Impl::cut_neighbour_planes(RunState& run, int i, double delta,
                                          std::vector<CutSegment>& segs,
                                          SectionPolygon (&regions)[2],
                                          std::vector<const SectionPolygon*>& neighbours,
                                          int& sides) const {
  const SectionState& st = states[i];
  const JunctionFamily fam = junction_family(i, delta);
  double extent = 0.0;
  for (const Vec2& q : st.cut.outer) extent = std::max(extent, q.norm());
  // The side towards the bone's nearer end first: where one side has no material of its
  // own it is usually that one, and the other plane need not be cut.
  const bool far_first = fam.count > 0 && 2 * (i - fam.first) >= fam.count;
  for (int k = 0; k < 2; ++k) {
    const int side = far_first ? 1 - k : k;
    PlaneFrame frame = st.frame;
    frame.origin += (side == 0 ? -delta : delta) * frame.normal;
    const CutRegion ball{frame.origin, Vec3::Zero(), 3.0 * extent + delta};
    segs.clear();
    // Per segment: the loop is clipped where it leaves the ball, whatever the grid's cells.
    cut_mesh(run.mesh, frame, segs, &run.grid, &ball, nullptr, /*per_segment=*/true);
    const PlaneCut cut = assemble_loops(segs, 0.0);
    SectionGeometry geom = select_region(cut, nullptr);
    if (geom.found && !(geom.flags & kFlagOutside)) {
      regions[side] = std::move(geom.polygon);
      neighbours.push_back(&regions[side]);
      ++sides;
    } else if (!geom.found && !cut.open_chains.empty() && (geom.flags & kFlagOpen)) {
      ++sides;  // clipped around the bone point: a far larger member, covering the section
    } else {
      return false;
    }
  }
  return true;
}

// One candidate: the regions around the bone point on the planes at -delta and +delta (a side
// with no region of its own there -- past a free end, bone outside the mesh, open cut -- ends
// the check), the necks between them, the core, and the tests that make it the section's
// region (flag kFlagJunction).
void Analyzer::Impl::check_junction(RunState& run, int i, double delta, double median,
                                    const std::vector<std::uint8_t>& neighbour_ok,
                                    std::vector<CutSegment>& scratch) {
  const RegionOptions ro(options);
  SectionState& st = states[i];
  restore_whole(st, ro);
  st.junction_delta = delta;
  SectionPolygon regions[2];
  std::vector<const SectionPolygon*> neighbours;
  // The family's own sections m intervals away, or the two planes cut (see junction_family).
  const JunctionFamily fam = junction_family(i, delta);
  const int first = fam.first, count = fam.count, m = fam.m;
  auto usable = [&](int j) { return neighbour_ok[j] != 0; };
  int sides = 0;
  if (m > 0) {
    if (!usable(i - m) || !usable(i + m)) return;  // a side without material of its own
    neighbours.push_back(&states[i - m].cut);
    neighbours.push_back(&states[i + m].cut);
    sides = 2;
  } else if (!cut_neighbour_planes(run, i, delta, scratch, regions, neighbours, sides)) {
    return;
  }
  // Material continues through the plane only if there is material on both sides.
  if (sides < 2 || neighbours.empty()) return;
  // A neck between the section and a neighbour plane: the bone's own sections strictly inside
  // the slab that are smaller than every neighbour region are neighbours too (the core is what
  // passes through the whole slab, so it passes through the neck).
  double neck = median;
  if (count > 0 && i >= first && i < first + count) {
    double smallest = std::numeric_limits<double>::infinity();
    for (const SectionPolygon* p : neighbours) smallest = std::min(smallest, region_area(*p));
    for (int k = 1; k * options.interval < delta; ++k)
      for (const int j : {i - k, i + k})
        if (j >= first && j < first + count && usable(j) && states[j].cut_area < smallest) {
          neighbours.push_back(&states[j].cut);
          neck = std::min(neck, states[j].cut_area);
        }
  }
  // The branch test (below) first on a region inside the core (`inner`, before the costly
  // widening and trimming): the core holds it, so the core's area is no smaller and each vertex
  // of the cut is no farther from the core than from it. When no vertex of the cut reaches
  // 0.9 x inner's own radius beyond it, none reaches the core's radius beyond the core: the
  // section would fail the branch test, and is left whole now. (A limb's top running inside
  // the body: the cut is the body, nearly all of it core.)
  auto may_branch = [&](const SectionPolygon& inner) {
    return reaches_beyond(st.cut, inner, kSureNo * kReach * std::sqrt(region_area(inner) / M_PI));
  };
  // No region inside a box of area A reaches farther than 0.9 x 1.25 x sqrt(A / pi): when a
  // vertex of the cut lies farther than that from the box, may_branch says yes for every one
  // (its first pass, against the region's box, which lies inside) and is not asked.
  auto may_fail = [&](const Vec2& lo, const Vec2& hi) {
    const double area = (hi.x() - lo.x()) * (hi.y() - lo.y()) * (1 + 1e-9);
    return !reaches_beyond_box(st.cut, lo, hi, kSureNo * kReach * std::sqrt(area / M_PI));
  };
  const SectionGeometry core = junction_core(st.cut, neighbours, kMargin / kDelta * delta,
                                             kOpening / kDelta * delta, may_branch, may_fail);
  if (!core.found) return;
  const SectionProperties props = section_properties(core.polygon);
  if (!props.valid || !(props.area < kMaterial * st.cut_area)) return;
  // A core far smaller than the bone's typical section (or than the neck it passes through) is
  // not the bone's member passing through (the planes landed in other parts: a bend, a flare,
  // a bone end): whole cut kept.
  if (props.area < kContinues * neck) return;
  // A side branch sticks out of the member: the trimmed material must reach at least
  // kReach x the core's equivalent radius beyond the core. Shallower material (a joint's flare,
  // a taper, a bulge) is the bone's own: by Saint-Venant a feature of depth t is engaged within
  // about t of the plane, inside the slab, so the whole cut carries the load.
  if (!reaches_beyond(st.cut, core.polygon, kReach * std::sqrt(props.area / M_PI))) return;
  if (ro.keep) st.cut_loops = st.loops;
  if (set_section_region(st, st.frame, core.polygon, ro)) st.flags |= kFlagJunction;
}

}  // namespace osteon
