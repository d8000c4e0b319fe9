// Stage 3 of a run: cutting the section planes, locally first (phase 1), then wider or whole
// where the local cut is not provably right (phase 2) (Analyzer::Impl).
//
// Cuts are first made locally, inside a cylinder (joints: a ball) around the bone that holds
// the bone's own vertices; the local section is used only when it is provably the one the whole
// plane gives: no open polyline, and the loops around the bone point agree in parity with a 3D
// inside test along the bone's axis (so no far loop, e.g. a hollow body's wall, encloses it).
// Otherwise the whole plane is cut.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "analysis_impl.hpp"
#include "parallel.hpp"
#include "region_choice.hpp"
#include "thickness.hpp"

namespace osteon {
namespace {

// Why a section is queued for phase 2.
enum Retry : std::uint8_t { kNone = 0, kGrowFamily = 1, kWholePlane = 2, kGrowJoint = 3 };

// Is the point at `param` along bone b's axis inside the mesh (odd number of crossings beyond)?
bool inside_at(const RunState& run, int b, double param) {
  const auto& c = run.crossings[b];
  return (c.end() - std::upper_bound(c.begin(), c.end(), param)) % 2 == 1;
}

// A loop clipped by the region (an open polyline here) cannot lie inside a closed local loop
// (the region is convex), so it can only matter if it reaches the chosen outer boundary's box
// (a hole of it) or encloses the point (then the parity test fails or it comes with a partner).
// A section flagged open (an open polyline's box meets the region's box) is not proven either:
// the flag would be the clip's, not the mesh's (the whole plane's cut says which).
bool local_ok(RunState& run, const PlaneCut& cut, const SectionGeometry& geom, bool inside) {
  bool ok = !(cut.flags & kFlagNonManifold) && geom.found && !(geom.flags & kFlagOpen) &&
            geom.containing >= 1 && (geom.containing % 2 == 1) == inside;
  if (ok && !cut.open_chains.empty()) {
    Vec2 lo = geom.polygon.outer[0], hi = lo;
    for (const Vec2& p : geom.polygon.outer) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    for (const auto& chain : cut.open_chains)
      for (const Vec2& p : chain)
        if (p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() && p.y() <= hi.y()) ok = false;
  }
  ++(ok ? run.local_used : run.local_failed);
  return ok;
}

// Section state of a found (or skipped) section geometry; region null: the whole plane was cut.
// With `ro.keep`, the region's loops are kept in 3D (AnalysisOptions::keep_outlines).
SectionState finish(const PlaneFrame& frame, const SectionGeometry& geom, const CutRegion* region,
                    const RegionOptions& ro) {
  SectionState st;
  st.flags = geom.flags;
  st.whole_plane = region == nullptr;
  if (region != nullptr) st.region = *region;
  if (geom.found) {
    if (set_section_region(st, frame, geom.polygon, ro)) {
      st.found = true;
      st.frame = frame;
      st.cut = geom.polygon;
      st.cut_area = st.area;
      st.cut_modulus = st.modulus;
    } else {
      st.flags |= kFlagDegenerate;
    }
  }
  return st;
}

// The whole-plane section from all of a plane's segments (gaps closed: nothing is clipped). A
// bone outside the mesh takes the region cut from its own skinning domain (vertex_bone, #V).
SectionState finish_whole(const PlaneFrame& frame, const std::vector<CutSegment>& segs, double gap,
                          const int* vertex_bone, int bone, const RegionOptions& ro) {
  const BoneDomain domain{&segs, vertex_bone, bone};
  SectionGeometry geom = select_region(assemble_loops(segs, gap), &domain);
  if (segs.empty()) geom.flags |= kFlagEmpty;
  return finish(frame, geom, nullptr, ro);
}

}  // namespace

bool set_section_region(SectionState& st, const PlaneFrame& frame, const SectionPolygon& polygon,
                        const RegionOptions& ro) {
  const SectionProperties props = section_properties(polygon);
  if (!props.valid) return false;
  PrintedSection printed;
  if (ro.print != nullptr) {
    const Vec2 build(ro.build.dot(frame.u), ro.build.dot(frame.v));
    printed =
        printed_section(polygon, props, build, ro.build.dot(frame.normal), *ro.print, ro.keep);
    if (!printed.valid) return false;
  }
  st.area = props.area;
  st.solid_modulus = props.modulus;
  st.modulus = ro.print != nullptr ? printed.modulus : props.modulus;
  st.wall_area = printed.wall_area;
  st.skin_area = printed.skin_area;
  st.infill_area = printed.infill_area;
  st.center = frame.to_world(props.centroid);
  // Principal second moments: the smaller one is across the thinnest direction (a b x t
  // rectangle has b^3 t / 12 and b t^3 / 12, so the aspect is b / t).
  const Eigen::SelfAdjointEigenSolver<Mat2> eig(props.second_moment);
  const Vec2 thin = eig.eigenvectors().col(0);
  st.thin_axis = (thin.x() * frame.u + thin.y() * frame.v).normalized();
  const double lo = std::max(eig.eigenvalues()(0), 0.0), hi = eig.eigenvalues()(1);
  st.aspect = lo > 0 ? std::sqrt(hi / lo) : std::numeric_limits<double>::infinity();
  // Thickness costs a convex hull per section; only a too_thin check or a reader needs it.
  st.thickness = std::numeric_limits<double>::quiet_NaN();
  st.thickness_bound = region_thickness_lower_bound(props.area, lo);
  st.analysed = std::make_shared<const SectionPolygon>(polygon);
  st.loops.clear();
  if (ro.keep) {
    auto to_world = [&](const std::vector<Vec2>& loop) {
      std::vector<Vec3> out(loop.size());
      for (std::size_t k = 0; k < loop.size(); ++k) out[k] = frame.to_world(loop[k]);
      return out;
    };
    st.loops.push_back(to_world(polygon.outer));
    for (const auto& hole : polygon.holes) st.loops.push_back(to_world(hole));
    st.infill_loops.clear();
    for (const auto& loop : printed.sparse) st.infill_loops.push_back(to_world(loop));
  }
  return true;
}

double section_thickness_at(SectionState& st) {
  if (std::isnan(st.thickness) && st.analysed) st.thickness = region_thickness(*st.analysed);
  return st.thickness;
}

void Analyzer::Impl::prepare_cuts(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const int nb = num_bones;
  const int threads = options.threads;
  const double h = options.interval;
  const long jobs = static_cast<long>(job_bone.size());
  run.workers = detail::worker_count(threads, jobs);
  if (std::find(run.job_dirty.begin(), run.job_dirty.end(), 1) != run.job_dirty.end())
    run.build_grid(threads);
  run.timer.lap("grid");
  run.reach.assign(nb, 0.0);
  run.axis.resize(nb);
  std::vector<double>& reach = run.reach;
  for (int b = 0; b < nb; ++b) run.axis[b] = sk.direction(b);
  bone_reach2(run);
  for (int b = 0; b < nb; ++b) reach[b] = 2.5 * std::sqrt(last_reach2[b]) + 2.0 * h;
  run.crossings.assign(nb, {});
  std::vector<std::uint8_t> need_crossings(nb, 0);
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (run.job_dirty[specs[i].job]) need_crossings[specs[i].bone] = 1;
  detail::parallel_for(nb, threads, [&](long b, int) {
    if (options.local_cuts && need_crossings[b])
      run.crossings[b] = line_crossings(mesh, run.grid, sk.heads[b], sk.direction(b));
  });
  run.family_segments.assign(run.workers, {});
  run.single_segments.assign(run.workers, {});
  // Segments of a section whose local cut was not enough: a wider cut only adds the triangles
  // the narrower one left out (cut_mesh's `exclude`), so no triangle is cut twice.
  run.kept.assign(specs.size(), {});
  run.retry.assign(specs.size(), kNone);
}

// Each bone's farthest vertex from its axis (squared, mm^2: last_reach2): a maximum, so the same
// bits in any order. Live mode: a bone with no moved vertex and the same head and tail keeps the
// last run's, the others pass over their own vertices; else over chunks of all vertices on all
// workers (large meshes only: see kVerticesPerPass).
void Analyzer::Impl::bone_reach2(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const int nb = num_bones;
  auto far2 = [&](Index v, int b) {
    const Vec3 rel = mesh.vertex(v) - sk.heads[b];
    const Vec3& d = run.axis[b];
    return (rel - rel.dot(d) * d).squaredNorm();
  };
  if (!run.bone_changed.empty() && static_cast<int>(last_reach2.size()) == nb) {
    for (int b = 0; b < nb; ++b) {
      if (!run.bone_changed[b]) continue;
      double far = 0.0;
      for (Index k = bone_vertex_start[b]; k < bone_vertex_start[b + 1]; ++k)
        far = std::max(far, far2(bone_vertex_list[k], b));
      last_reach2[b] = far;
    }
    return;
  }
  const Index block = detail::kVerticesPerPass;
  const long chunks = static_cast<long>((num_vertices + block - 1) / block);
  std::vector<std::vector<double>> chunk_reach(chunks, std::vector<double>(nb, 0.0));
  detail::parallel_for(chunks, options.threads, [&](long chunk, int) {
    std::vector<double>& far = chunk_reach[chunk];
    for (Index v = chunk * block, end = std::min(num_vertices, (chunk + 1) * block); v < end; ++v) {
      const int b = run.vertex_bone[v];
      far[b] = std::max(far[b], far2(v, b));
    }
  });
  last_reach2.assign(nb, 0.0);
  for (const std::vector<double>& far : chunk_reach)
    for (int b = 0; b < nb; ++b) last_reach2[b] = std::max(last_reach2[b], far[b]);
}

void Analyzer::Impl::cut_local(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const double h = options.interval;
  const long jobs = static_cast<long>(job_bone.size());
  const RegionOptions ro(options);
  // Phase 1 (parallel over bones and joints): one local cut per family of parallel planes.
  // Sections whose local cut is not provably right, and all joints, are queued for phase 2.
  detail::parallel_for(jobs, options.threads, [&](long job, int worker) {
    if (!run.job_dirty[job]) return;
    run.check_cancel();
    const int first = job_section[job];
    const int b = job_bone[job];
    if (b < 0) {
      run.retry[first] = options.local_cuts ? kGrowJoint : kWholePlane;
      return;
    }
    const PlaneFrame base = PlaneFrame::make(sk.heads[b], sk.direction(b));
    const int n = static_cast<int>(slab_params[b].size()) - 2;
    auto& segs = run.family_segments[worker];
    const CutRegion region{sk.heads[b], sk.direction(b), run.reach[b]};
    const bool local = options.local_cuts;
    // The family is cut `chunk` planes at a time (the same planes, bit for bit): a long bone's
    // segments never all sit in memory at once, and a cancel waits for one chunk's pass only.
    // (At most 64 passes per bone: each pass costs O(n) bookkeeping besides its planes.)
    const int chunk = std::max(512, (n + 63) / 64);
    std::vector<std::uint8_t> wanted(n, 0);
    for (int k = 1; k <= n; ++k) {
      const int si = first + k - 1;
      if ((k - 1) % chunk == 0) {
        run.check_cancel();
        for (int j = std::max(1, k - chunk); j < k; ++j) {
          wanted[j - 1] = 0;
          std::vector<CutSegment>().swap(segs[j - 1]);  // the last chunk's buffers
        }
        const int end = std::min(n, k + chunk - 1);
        for (int j = k; j <= end; ++j) wanted[j - 1] = run.section_dirty[first + j - 1];
        cut_mesh_parallel(mesh, base, h, n, segs, &run.grid, local ? &region : nullptr,
                          wanted.data());
      }
      if (!run.section_dirty[si]) continue;
      run.check_cancel();
      PlaneFrame frame = base;
      frame.origin = specs[si].point;
      if (!local) {
        states[si] = finish_whole(frame, segs[k - 1], run.gap, run.vertex_bone.data(), b, ro);
        run.sections_done();
        continue;
      }
      const PlaneCut cut = assemble_loops(segs[k - 1], 0.0);
      const SectionGeometry geom = select_region(cut, nullptr);
      if (local_ok(run, cut, geom, inside_at(run, b, k * h))) {
        states[si] = finish(frame, geom, &region, ro);
        run.sections_done();
        continue;
      }
      run.retry[si] = geom.found ? kWholePlane : kGrowFamily;
      run.kept[si] = std::move(segs[k - 1]);
    }
  });
}

void Analyzer::Impl::cut_retries(RunState& run) {
  const std::vector<int> units = retry_units(run);
  // Joints' and whole planes' cuts skip the cells and runs of faces whose triangles' own box the
  // plane misses (FaceGrid::enable_tight_bounds: the same segments, in the same order).
  if (!units.empty() && run.grid_built) run.grid.enable_tight_bounds();
  // The loose pieces and the moment-arm index (stage 4) need no section: they are one more
  // unit, third in line, so that it fills a core while the other cuts.
  const long index_unit = std::min<long>(2, static_cast<long>(units.size()));
  detail::parallel_for(static_cast<long>(units.size()) + 1, options.threads,
                       [&](long u, int worker) {
                         if (u == index_unit) {
                           find_loose_pieces_and_arms(run);
                           return;
                         }
                         run.check_cancel();
                         const int job = units[u > index_unit ? u - 1 : u];
                         if (job_bone[job] < 0)
                           retry_joint(run, job, worker);
                         else
                           retry_family(run, job, worker);
                       });
  if (run.timer.on) {
    std::fprintf(stderr, "local cuts used %d, whole planes %d\n", int(run.local_used),
                 int(run.local_failed));
    std::fprintf(stderr, "sections retried %ld\n", run.retried);
  }
}

// Phase 2 units: a family's queued planes are re-cut together in masked passes (a cylinder
// three times wider, then the whole plane); a joint grows a ball around its point, then cuts
// the whole plane. Families first: they are the larger units, joints balance the cores last.
std::vector<int> Analyzer::Impl::retry_units(RunState& run) {
  const long jobs = static_cast<long>(job_bone.size());
  const std::vector<std::uint8_t>& retry = run.retry;
  std::vector<int> units;
  for (long job = 0; job < jobs; ++job) {
    const int first = job_section[job];
    const int n = job_bone[job] >= 0 ? static_cast<int>(slab_params[job_bone[job]].size()) - 2 : 1;
    bool any = false;
    for (int i = first; i < first + n; ++i) {
      any |= retry[i] != kNone;
      run.retried += retry[i] != kNone;
    }
    if (any) units.push_back(static_cast<int>(job));
  }
  std::stable_partition(units.begin(), units.end(), [&](int job) { return job_bone[job] >= 0; });
  return units;
}

// The loose pieces and, over the vertices of the attached ones, the moment-arm index.
void Analyzer::Impl::find_loose_pieces_and_arms(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const auto start = std::chrono::steady_clock::now();
  // Loose pieces fall off the print: their vertices are no load point (full runs; the
  // correction's partial re-cuts move no piece apart, so they keep the last run's).
  if (!run.partial) {
    // A gap under half the minimum printable thickness is fused by the printer.
    loose = face_shells == 1
                ? std::vector<std::vector<std::int32_t>>{}
                : loose_finder.find(mesh, run.vertex_bone, tree.held_bone,
                                    0.5 * options.min_thickness, &face_shells,
                                    /*same_faces=*/true, run.grid_built ? &run.grid : nullptr);
    // Per vertex, loose or not: read only where a piece is loose (no pass over the vertices
    // otherwise).
    loose_vertex.clear();
    if (!loose.empty()) loose_vertex.assign(num_vertices, 0);
    for (const auto& piece : loose)
      for (std::int32_t v : piece) loose_vertex[v] = 1;
  }
  const auto indexed = std::chrono::steady_clock::now();
  arm_index.build(mesh, sk, tree, run.vertex_bone, slab_params,
                  loose.empty() ? nullptr : &loose_vertex, run.moved,
                  run.moved != nullptr ? &moved_vertices : nullptr, options.threads);
  run.arms = &arm_index;
  if (run.timer.on)
    std::fprintf(
        stderr, "loose pieces %.3f ms, moment-arm index %.3f ms wall (in phase 2)\n",
        std::chrono::duration<double, std::milli>(indexed - start).count(),
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - indexed)
            .count());
}

// A joint's queued section: a ball grown around its point (twice, three times wider each), then
// the whole plane.
void Analyzer::Impl::retry_joint(RunState& run, int job, int worker) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const double diag = run.diag;
  const std::vector<std::uint8_t>& retry = run.retry;
  const std::vector<double>& reach = run.reach;
  const RegionOptions ro(options);
  const int first = job_section[job];
  const SectionSpec& spec = specs[first];
  const int bone = spec.bone;
  const PlaneFrame frame = PlaneFrame::make(spec.point, spec.normal);
  auto& segs = run.single_segments[worker];
  segs.clear();
  CutRegion ball{spec.point, Vec3::Zero(), reach[bone]};
  if (sk.parents[bone] >= 0) ball.radius = std::max(ball.radius, reach[sk.parents[bone]]);
  const CutRegion* done = nullptr;  // the region already cut
  CutRegion previous;
  if (retry[first] == kGrowJoint) {
    const bool inside = inside_at(run, bone, slab_params[bone][spec.boundary]);
    for (int step = 0; step < 2 && ball.radius < diag; ++step, ball.radius *= 3.0) {
      cut_mesh(mesh, frame, segs, &run.grid, &ball, done);
      const PlaneCut cut = assemble_loops(segs, 0.0);
      const SectionGeometry geom = select_region(cut, nullptr);
      previous = ball;
      done = &previous;
      if (local_ok(run, cut, geom, inside)) {
        states[first] = finish(frame, geom, &ball, ro);
        run.sections_done();
        return;
      }
      if (geom.found) break;  // found but not provably right: cut the whole plane
    }
  }
  cut_mesh(mesh, frame, segs, &run.grid, nullptr, done);
  states[first] = finish_whole(frame, segs, run.gap, run.vertex_bone.data(), bone, ro);
  run.sections_done();
}

// A family's queued planes, re-cut together in masked passes: a cylinder three times wider
// (for the sections queued to grow), then the whole plane.
void Analyzer::Impl::retry_family(RunState& run, int job, int worker) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const double h = options.interval;
  const double diag = run.diag;
  const std::vector<std::uint8_t>& retry = run.retry;
  const std::vector<double>& reach = run.reach;
  const RegionOptions ro(options);
  const int first = job_section[job];
  const int b = job_bone[job];
  const PlaneFrame base = PlaneFrame::make(sk.heads[b], sk.direction(b));
  const int n = static_cast<int>(slab_params[b].size()) - 2;
  auto& segs = run.family_segments[worker];
  std::vector<std::uint8_t> wanted(n);
  for (int k = 1; k <= n; ++k) wanted[k - 1] = retry[first + k - 1] != kNone;
  auto frame_of = [&](int k) {
    PlaneFrame frame = base;
    frame.origin = specs[first + k - 1].point;
    return frame;
  };
  auto add_kept = [&](int k) {
    auto& all = run.kept[first + k - 1];
    all.insert(all.end(), segs[k - 1].begin(), segs[k - 1].end());
  };
  const CutRegion region{sk.heads[b], sk.direction(b), reach[b]};
  const CutRegion wide{sk.heads[b], sk.direction(b), 3.0 * reach[b]};
  const CutRegion* done = &region;
  bool grow = false;
  for (int k = 1; k <= n; ++k) grow |= retry[first + k - 1] == kGrowFamily;
  if (grow && wide.radius < diag) {
    cut_mesh_parallel(mesh, base, h, n, segs, &run.grid, &wide, wanted.data(), &region);
    done = &wide;
    for (int k = 1; k <= n; ++k) {
      if (!wanted[k - 1]) continue;
      add_kept(k);
      if (retry[first + k - 1] != kGrowFamily) continue;
      run.check_cancel();
      const PlaneCut cut = assemble_loops(run.kept[first + k - 1], 0.0);
      const SectionGeometry geom = select_region(cut, nullptr);
      if (local_ok(run, cut, geom, inside_at(run, b, k * h))) {
        states[first + k - 1] = finish(frame_of(k), geom, &wide, ro);
        run.sections_done();
        wanted[k - 1] = 0;
      }
    }
  }
  if (std::find(wanted.begin(), wanted.end(), 1) == wanted.end()) return;
  cut_mesh_parallel(mesh, base, h, n, segs, &run.grid, nullptr, wanted.data(), done);
  for (int k = 1; k <= n; ++k) {
    if (!wanted[k - 1]) continue;
    run.check_cancel();
    add_kept(k);
    states[first + k - 1] =
        finish_whole(frame_of(k), run.kept[first + k - 1], run.gap, run.vertex_bone.data(), b, ro);
    run.sections_done();
  }
}

}  // namespace osteon
