#include "osteon/analysis.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "analysis_impl.hpp"
#include "osteon/regions.hpp"
#include "parallel.hpp"

namespace osteon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Number of interior planes k*h strictly inside a bone of length L.
int interior_count(double length, double interval) {
  const double n = std::ceil(length / interval * (1.0 - 1e-12)) - 1.0;
  if (n <= 0) return 0;
  if (n > 1e6)
    throw std::invalid_argument("interval too small: more than 10^6 sections on one bone");
  return static_cast<int>(n);
}

// Does the plane (point, normal) pass through the box?
bool plane_crosses_box(const Vec3& point, const Vec3& normal, const Box3& box) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? box.hi.x() : box.lo.x(), (c & 2) ? box.hi.y() : box.lo.y(),
                      (c & 4) ? box.hi.z() : box.lo.z());
    const double s = (corner - point).dot(normal);
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  return lo <= 0.0 && hi >= 0.0;
}

// Stage timer: OSTEON_PROFILE=1 prints the time of each stage of a run to stderr.
struct StageTimer {
  bool on = std::getenv("OSTEON_PROFILE") != nullptr;
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  void lap(const char* stage) {
    if (!on) return;
    const auto now = std::chrono::steady_clock::now();
    std::fprintf(stderr, "osteon %-14s %8.3f ms\n", stage,
                 std::chrono::duration<double, std::milli>(now - last).count());
    last = now;
  }
};

struct Endpoint {
  int bone;
  bool tail;
  Vec3 position;
};

}  // namespace

void validate_options(const AnalysisOptions& o, const Skeleton& skeleton) {
  if (!(o.force > 0) || !std::isfinite(o.force))
    throw std::invalid_argument("force must be a positive finite number of newtons");
  if (!(o.allowable_stress > 0) || !std::isfinite(o.allowable_stress))
    throw std::invalid_argument("allowable_stress must be a positive finite stress in MPa");
  if (!(o.interval > 0) || !std::isfinite(o.interval))
    throw std::invalid_argument("interval must be a positive finite length in mm");
  if (o.held_bone < -1 || o.held_bone >= skeleton.num_bones())
    throw std::invalid_argument("root (held bone) index " + std::to_string(o.held_bone) +
                                " out of range for " + std::to_string(skeleton.num_bones()) +
                                " bones");
  if (std::isnan(o.gap_tolerance)) throw std::invalid_argument("gap_tolerance must not be NaN");
}

Analyzer::Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
                   const BoneWeights* weights, int num_bones, const AnalysisOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  s.num_vertices = num_vertices;
  s.num_bones = num_bones;
  if (num_vertices <= 0) throw std::invalid_argument("empty mesh: vertices has no rows");
  if (num_faces <= 0 || faces == nullptr)
    throw std::invalid_argument("empty mesh: faces has no rows");
  if (num_bones <= 0) throw std::invalid_argument("skeleton has no bones");
  s.faces.assign(faces, faces + 3 * num_faces);
  MeshView probe{nullptr, num_vertices, s.faces.data(), num_faces};
  for (Index i = 0; i < 3 * num_faces; ++i) {
    const std::int32_t f = s.faces[i];
    if (f < 0 || f >= num_vertices)
      throw std::invalid_argument("face index out of range: faces[" + std::to_string(i / 3) +
                                  "] refers to vertex " + std::to_string(f) + " but there are " +
                                  std::to_string(num_vertices) + " vertices");
  }
  (void)probe;
  if (weights != nullptr) {
    validate_weights(*weights, num_vertices, num_bones);
    s.has_weights = true;
    s.dominant = dominant_bones(*weights);  // all the analysis needs of the weights
  }
}

Analyzer::Analyzer(const std::int32_t* faces, Index num_faces, Index num_vertices,
                   std::vector<int> vertex_bone, int num_bones, const AnalysisOptions& options)
    : Analyzer(faces, num_faces, num_vertices, nullptr, num_bones, options) {
  if (static_cast<Index>(vertex_bone.size()) != num_vertices)
    throw std::invalid_argument("vertex_bone must have one entry per vertex");
  for (int b : vertex_bone)
    if (b < -1 || b >= num_bones)
      throw std::invalid_argument("vertex_bone: bone index out of range");
  impl_->has_weights = true;
  impl_->dominant = std::move(vertex_bone);
}

Analyzer::~Analyzer() = default;

const AnalysisOptions& Analyzer::options() const { return impl_->options; }

AnalysisResult Analyzer::run(const double* vertices, const Skeleton& skeleton) {
  return impl_->run(vertices, skeleton, nullptr);
}

AnalysisResult Analyzer::Impl::run(const double* vertices, const Skeleton& sk, const Box3* dirty) {
  StageTimer timer;
  validate_skeleton(sk);
  if (sk.num_bones() != num_bones)
    throw std::invalid_argument("skeleton has " + std::to_string(sk.num_bones()) +
                                " bones but the analyzer was built for " +
                                std::to_string(num_bones));
  validate_options(options, sk);
  const MeshView mesh{vertices, num_vertices, faces.data(), static_cast<Index>(faces.size() / 3)};
  for (Index i = 0; i < 3 * num_vertices; ++i)
    if (!std::isfinite(vertices[i]))
      throw std::invalid_argument("vertices contain NaN or infinity (vertex " +
                                  std::to_string(i / 3) + ")");
  const int nb = num_bones;
  const int threads = options.threads;
  const double h = options.interval;
  const double diag = bounding_diagonal(mesh);
  const double gap = options.gap_tolerance >= 0 ? options.gap_tolerance : 0.01 * diag;

  timer.lap("validate");
  // 1. Which bone each vertex belongs to (dominant weight; nearest bone where it has none).
  std::vector<int> vertex_bone;
  if (has_weights) {
    vertex_bone = dominant;
    if (std::find(vertex_bone.begin(), vertex_bone.end(), -1) != vertex_bone.end()) {
      const std::vector<int> nearest = nearest_bones(mesh, sk, threads);
      for (Index v = 0; v < num_vertices; ++v)
        if (vertex_bone[v] < 0) vertex_bone[v] = nearest[v];
    }
  } else {
    vertex_bone = nearest_bones(mesh, sk, threads);
  }
  std::vector<Index> per_bone(nb, 0);
  for (int b : vertex_bone) ++per_bone[b];

  timer.lap("vertex bones");
  const bool partial = dirty != nullptr && !specs.empty();
  // Live mode: keep the last run's sections to reuse the ones nothing has changed.
  std::vector<SectionSpec> prev_specs;
  std::vector<SectionState> prev_states;
  const bool may_reuse = !partial && options.reuse_sections && !specs.empty() &&
                         last_vertices.size() == static_cast<std::size_t>(3 * num_vertices) &&
                         last_parents == sk.parents;
  if (may_reuse) {
    prev_specs = specs;
    prev_states = states;
  }
  if (!partial) {
    tree = build_load_tree(sk, options.held_bone, per_bone);
    // Vertices downstream of each bone's entry, for choosing which bone owns a joint section.
    std::vector<Index> subtree_vertices(per_bone);
    for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it)
      if (tree.parent[*it] >= 0) subtree_vertices[tree.parent[*it]] += subtree_vertices[*it];

    // 2. Sections: interior planes per bone, then joints and free ends.
    specs.clear();
    slab_params.assign(nb, {});
    job_bone.clear();
    job_section.clear();
    std::vector<int> count(nb);
    for (int b = 0; b < nb; ++b) {
      const double L = sk.length(b);
      count[b] = interior_count(L, h);
      auto& p = slab_params[b];
      p.push_back(0.0);
      for (int k = 1; k <= count[b]; ++k) p.push_back(k * h);
      p.push_back(L);
      if (count[b] == 0) continue;
      job_bone.push_back(b);
      job_section.push_back(static_cast<int>(specs.size()));
      const Vec3 d = sk.direction(b);
      for (int k = 1; k <= count[b]; ++k) {
        SectionSpec spec;
        spec.bone = b;
        spec.kind = kInterior;
        spec.boundary = k;
        spec.plus_side = k * h >= tree.entry_param[b];
        spec.point = sk.heads[b] + (k * h) * d;
        spec.normal = d;
        spec.job = static_cast<int>(job_bone.size()) - 1;
        specs.push_back(spec);
      }
    }
    // Cluster bone ends into joints.
    double extent = 0.0;
    for (int b = 0; b < nb; ++b) extent = std::max(extent, sk.length(b));
    const double tol = 1e-6 * extent;
    std::vector<Endpoint> ends;
    for (int b = 0; b < nb; ++b) {
      ends.push_back({b, false, sk.heads[b]});
      ends.push_back({b, true, sk.tails[b]});
    }
    std::vector<std::vector<int>> joints;
    std::vector<Vec3> joint_pos;
    for (int e = 0; e < static_cast<int>(ends.size()); ++e) {
      int found = -1;
      for (int j = 0; j < static_cast<int>(joints.size()); ++j)
        if ((joint_pos[j] - ends[e].position).norm() <= tol) {
          found = j;
          break;
        }
      if (found < 0) {
        joints.push_back({e});
        joint_pos.push_back(ends[e].position);
      } else {
        joints[found].push_back(e);
      }
    }
    auto add_single = [&](int bone, bool tail, const Vec3& normal, std::int8_t kind) {
      SectionSpec spec;
      spec.bone = bone;
      spec.kind = kind;
      spec.boundary = tail ? count[bone] + 1 : 0;
      const double param = tail ? sk.length(bone) : 0.0;
      spec.plus_side = param >= tree.entry_param[bone];
      spec.point = tail ? sk.tails[bone] : sk.heads[bone];
      const Vec3 unit = normal.normalized();
      spec.normal = unit.dot(sk.direction(bone)) < 0 ? Vec3(-unit) : unit;
      job_bone.push_back(-1);
      job_section.push_back(static_cast<int>(specs.size()));
      spec.job = static_cast<int>(job_bone.size()) - 1;
      specs.push_back(spec);
    };
    for (const auto& members : joints) {
      if (members.size() == 1) {
        const Endpoint& e = ends[members[0]];
        add_single(e.bone, e.tail, sk.direction(e.bone), kEnd);
        continue;
      }
      for (std::size_t i = 0; i < members.size(); ++i) {
        for (std::size_t j = i + 1; j < members.size(); ++j) {
          const Endpoint& a = ends[members[i]];
          const Endpoint& b = ends[members[j]];
          if (a.bone == b.bone) continue;
          // Mean direction of the path that enters the joint along a and leaves along b.
          const Vec3 in = a.tail ? sk.direction(a.bone) : Vec3(-sk.direction(a.bone));
          const Vec3 out = b.tail ? Vec3(-sk.direction(b.bone)) : sk.direction(b.bone);
          Vec3 n = in + out;
          if (n.norm() < 1e-6) n = out;
          // Owner: the bone entered from the root side at this joint; if both, the smaller branch.
          auto entered_here = [&](const Endpoint& e) {
            const double param = e.tail ? sk.length(e.bone) : 0.0;
            return std::abs(param - tree.entry_param[e.bone]) <= tol;
          };
          const bool ea = entered_here(a), eb = entered_here(b);
          const Endpoint* owner = &a;
          if (ea && eb) {
            if (subtree_vertices[b.bone] < subtree_vertices[a.bone] ||
                (subtree_vertices[b.bone] == subtree_vertices[a.bone] && b.bone > a.bone))
              owner = &b;
          } else if (eb) {
            owner = &b;
          }
          add_single(owner->bone, owner->tail, n, kJoint);
        }
      }
    }
    states.assign(specs.size(), SectionState{});
  }

  // 3. Cut the planes (jobs in parallel: one per bone's family of parallel planes, one per joint).
  const long jobs = static_cast<long>(job_bone.size());
  std::vector<std::uint8_t> job_dirty(jobs, 1);
  std::vector<std::uint8_t> section_dirty(specs.size(), 1);
  if (partial) {
    // A section changes only if the moved triangles cross its plane inside the region its cut
    // was proven in (and, for a ball, away from its bone's axis: the inside test uses that line).
    const Vec3 center = 0.5 * (dirty->lo + dirty->hi), half = 0.5 * (dirty->hi - dirty->lo);
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const SectionState& st = states[i];
      bool touched = plane_crosses_box(specs[i].point, specs[i].normal, *dirty);
      if (touched && !st.whole_plane) {
        const int b = specs[i].bone;
        const CutRegion axis_line{sk.heads[b], sk.direction(b), 0.0};
        touched = st.region.meets_box(center, half) || axis_line.meets_box(center, half);
      }
      section_dirty[i] = touched;
    }
    std::fill(job_dirty.begin(), job_dirty.end(), 0);
    for (std::size_t i = 0; i < specs.size(); ++i)
      if (section_dirty[i]) job_dirty[specs[i].job] = 1;
  }
  if (may_reuse && prev_specs.size() == specs.size()) {
    // Exact reuse: a section keeps its geometry when its bone, plane and downstream side are
    // bitwise the same and no moved triangle reaches the region its cut was proven in.
    Box3 moved_box;
    std::vector<std::uint8_t> moved(num_vertices, 0);
    bool any_moved = false;
    for (Index v = 0; v < num_vertices; ++v) {
      const double* a = vertices + 3 * v;
      const double* b = last_vertices.data() + 3 * v;
      moved[v] = a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
      any_moved |= moved[v] != 0;
    }
    if (any_moved) {
      for (std::size_t f = 0; f < faces.size(); f += 3) {
        if (!moved[faces[f]] && !moved[faces[f + 1]] && !moved[faces[f + 2]]) continue;
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
    std::fill(job_dirty.begin(), job_dirty.end(), 0);
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const SectionSpec& a = specs[i];
      const SectionSpec& b = prev_specs[i];
      const int bone = a.bone;
      bool same = a.bone == b.bone && a.kind == b.kind && a.boundary == b.boundary &&
                  a.plus_side == b.plus_side && a.point == b.point && a.normal == b.normal &&
                  sk.heads[bone] == last_heads[bone] && sk.tails[bone] == last_tails[bone] &&
                  !(prev_states[i].whole_plane && gap != last_gap);  // gap closing applies there
      if (same && any_moved && plane_crosses_box(a.point, a.normal, moved_box)) {
        const SectionState& st = prev_states[i];
        const CutRegion axis_line{sk.heads[bone], sk.direction(bone), 0.0};
        same = !st.whole_plane && !st.region.meets_box(center, half) &&
               !axis_line.meets_box(center, half);
      }
      if (same) {
        states[i] = prev_states[i];
        section_dirty[i] = 0;
      } else {
        section_dirty[i] = 1;
        job_dirty[a.job] = 1;
      }
    }
  }
  const int workers = detail::worker_count(threads, jobs);
  timer.lap("sections");
  FaceGrid grid;
  if (std::find(job_dirty.begin(), job_dirty.end(), 1) != job_dirty.end())
    grid.build(mesh, 12, threads);
  timer.lap("grid");
  // Cuts are first made locally, inside a cylinder (joints: a ball) around the bone that holds
  // the bone's own vertices; the local section is used only when it is provably the one the whole
  // plane gives: no open polyline, and the loops around the bone point agree in parity with a 3D
  // inside test along the bone's axis (so no far loop, e.g. a hollow body's wall, encloses it).
  // Otherwise the whole plane is cut.
  std::vector<double> reach(nb, 0.0);
  std::vector<Vec3> axis(nb);
  for (int b = 0; b < nb; ++b) axis[b] = sk.direction(b);
  for (Index v = 0; v < num_vertices; ++v) {
    const int b = vertex_bone[v];
    const Vec3 rel = mesh.vertex(v) - sk.heads[b];
    const Vec3& d = axis[b];
    reach[b] = std::max(reach[b], (rel - rel.dot(d) * d).squaredNorm());
  }
  for (int b = 0; b < nb; ++b) reach[b] = 2.5 * std::sqrt(reach[b]) + 2.0 * h;
  std::vector<std::vector<double>> crossings(nb);
  std::vector<std::uint8_t> need_crossings(nb, 0);
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (job_dirty[specs[i].job]) need_crossings[specs[i].bone] = 1;
  detail::parallel_for(nb, threads, [&](long b, int) {
    if (options.local_cuts && need_crossings[b])
      crossings[b] = line_crossings(mesh, grid, sk.heads[b], sk.direction(b));
  });
  timer.lap("reach+lines");
  auto inside_at = [&](int b, double param) {
    const auto& c = crossings[b];
    return (c.end() - std::upper_bound(c.begin(), c.end(), param)) % 2 == 1;
  };
  // A loop clipped by the region (an open polyline here) cannot lie inside a closed local loop
  // (the region is convex), so it can only matter if it reaches the chosen outer boundary's box
  // (a hole of it) or encloses the point (then the parity test fails or it comes with a partner).
  std::atomic<int> local_used{0}, local_failed{0};
  auto local_ok = [&](const PlaneCut& cut, const SectionGeometry& geom, bool inside) {
    bool ok = !(cut.flags & kFlagNonManifold) && geom.found && geom.containing >= 1 &&
              (geom.containing % 2 == 1) == inside;
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
    ++(ok ? local_used : local_failed);
    return ok;
  };
  std::vector<std::vector<std::vector<CutSegment>>> family_segments(workers);
  std::vector<std::vector<CutSegment>> single_segments(workers);
  // Segments of a section whose local cut was not enough: a wider cut only adds the triangles
  // the narrower one left out (cut_mesh's `exclude`), so no triangle is cut twice.
  std::vector<std::vector<CutSegment>> kept(specs.size());
  auto finish = [&](int si, const PlaneFrame& frame, const SectionGeometry& geom,
                    const CutRegion* region) {
    SectionState st;
    st.flags = geom.flags;
    st.whole_plane = region == nullptr;
    if (region != nullptr) st.region = *region;
    if (geom.found) {
      const SectionProperties props = section_properties(geom.polygon);
      if (props.valid) {
        st.found = true;
        st.area = props.area;
        st.modulus = props.modulus;
        st.center = frame.to_world(props.centroid);
        // Principal second moments: the smaller one is across the thinnest direction (a b x t
        // rectangle has b^3 t / 12 and b t^3 / 12, so the aspect is b / t).
        const Eigen::SelfAdjointEigenSolver<Mat2> eig(props.second_moment);
        const Vec2 thin = eig.eigenvectors().col(0);
        st.thin_axis = (thin.x() * frame.u + thin.y() * frame.v).normalized();
        const double lo = std::max(eig.eigenvalues()(0), 0.0), hi = eig.eigenvalues()(1);
        st.aspect = lo > 0 ? std::sqrt(hi / lo) : std::numeric_limits<double>::infinity();
        st.thickness = region_thickness(geom.polygon);
      } else {
        st.flags |= kFlagDegenerate;
      }
    }
    states[si] = st;
  };
  // The whole-plane section from all of a plane's segments (gaps closed: nothing is clipped).
  auto finish_whole = [&](int si, const PlaneFrame& frame, const std::vector<CutSegment>& segs) {
    // A bone outside the mesh takes the region cut from its own skinning domain.
    const BoneDomain domain{&segs, vertex_bone.data(), specs[si].bone};
    SectionGeometry geom = select_region(assemble_loops(segs, gap), &domain);
    if (segs.empty()) geom.flags |= kFlagEmpty;
    finish(si, frame, geom, nullptr);
  };
  // Phase 1 (parallel over bones and joints): one local cut per family of parallel planes.
  // Sections whose local cut is not provably right, and all joints, are queued for phase 2.
  enum Retry : std::uint8_t { kNone = 0, kGrowFamily = 1, kWholePlane = 2, kGrowJoint = 3 };
  std::vector<std::uint8_t> retry(specs.size(), kNone);
  detail::parallel_for(jobs, threads, [&](long job, int worker) {
    if (!job_dirty[job]) return;
    const int first = job_section[job];
    const int b = job_bone[job];
    if (b < 0) {
      retry[first] = options.local_cuts ? kGrowJoint : kWholePlane;
      return;
    }
    const PlaneFrame base = PlaneFrame::make(sk.heads[b], sk.direction(b));
    const int n = static_cast<int>(slab_params[b].size()) - 2;
    auto& segs = family_segments[worker];
    const CutRegion region{sk.heads[b], sk.direction(b), reach[b]};
    const bool local = options.local_cuts;
    cut_mesh_parallel(mesh, base, h, n, segs, &grid, local ? &region : nullptr,
                      section_dirty.data() + first);
    for (int k = 1; k <= n; ++k) {
      const int si = first + k - 1;
      if (!section_dirty[si]) continue;
      PlaneFrame frame = base;
      frame.origin = specs[si].point;
      if (!local) {
        finish_whole(si, frame, segs[k - 1]);
        continue;
      }
      const PlaneCut cut = assemble_loops(segs[k - 1], 0.0);
      const SectionGeometry geom = select_section(cut);
      if (local_ok(cut, geom, inside_at(b, k * h))) {
        finish(si, frame, geom, &region);
        continue;
      }
      retry[si] = geom.found ? kWholePlane : kGrowFamily;
      kept[si] = std::move(segs[k - 1]);
    }
  });
  timer.lap("slicing phase 1");
  // Phase 2 units: a family's queued planes are re-cut together in masked passes (a cylinder
  // three times wider, then the whole plane); a joint grows a ball around its point, then cuts
  // the whole plane. Families first: they are the larger units, joints balance the cores last.
  std::vector<int> units;
  long retried = 0;
  for (long job = 0; job < jobs; ++job) {
    const int first = job_section[job];
    const int n = job_bone[job] >= 0 ? static_cast<int>(slab_params[job_bone[job]].size()) - 2 : 1;
    bool any = false;
    for (int i = first; i < first + n; ++i) {
      any |= retry[i] != kNone;
      retried += retry[i] != kNone;
    }
    if (any) units.push_back(static_cast<int>(job));
  }
  std::stable_partition(units.begin(), units.end(), [&](int job) { return job_bone[job] >= 0; });
  // The moment-arm index (step 4) needs no section: it is built as one more unit, third in
  // line, so that it fills a core while the other cuts.
  std::unique_ptr<MomentArmIndex> arms;
  const long index_unit = std::min<long>(2, static_cast<long>(units.size()));
  detail::parallel_for(static_cast<long>(units.size()) + 1, threads, [&](long u, int worker) {
    if (u == index_unit) {
      arms = std::make_unique<MomentArmIndex>(mesh, sk, tree, vertex_bone, slab_params);
      return;
    }
    const int job = units[u > index_unit ? u - 1 : u];
    const int first = job_section[job];
    const int b = job_bone[job];
    if (b < 0) {
      const SectionSpec& spec = specs[first];
      const int bone = spec.bone;
      const PlaneFrame frame = PlaneFrame::make(spec.point, spec.normal);
      auto& segs = single_segments[worker];
      segs.clear();
      CutRegion ball{spec.point, Vec3::Zero(), reach[bone]};
      if (sk.parents[bone] >= 0) ball.radius = std::max(ball.radius, reach[sk.parents[bone]]);
      const CutRegion* done = nullptr;  // the region already cut
      CutRegion previous;
      if (retry[first] == kGrowJoint) {
        const bool inside = inside_at(bone, slab_params[bone][spec.boundary]);
        for (int step = 0; step < 2 && ball.radius < diag; ++step, ball.radius *= 3.0) {
          cut_mesh(mesh, frame, segs, &grid, &ball, done);
          const PlaneCut cut = assemble_loops(segs, 0.0);
          const SectionGeometry geom = select_section(cut);
          previous = ball;
          done = &previous;
          if (local_ok(cut, geom, inside)) {
            finish(first, frame, geom, &ball);
            return;
          }
          if (geom.found) break;  // found but not provably right: cut the whole plane
        }
      }
      cut_mesh(mesh, frame, segs, &grid, nullptr, done);
      finish_whole(first, frame, segs);
      return;
    }
    const PlaneFrame base = PlaneFrame::make(sk.heads[b], sk.direction(b));
    const int n = static_cast<int>(slab_params[b].size()) - 2;
    auto& segs = family_segments[worker];
    std::vector<std::uint8_t> wanted(n);
    for (int k = 1; k <= n; ++k) wanted[k - 1] = retry[first + k - 1] != kNone;
    auto frame_of = [&](int k) {
      PlaneFrame frame = base;
      frame.origin = specs[first + k - 1].point;
      return frame;
    };
    auto add_kept = [&](int k) {
      auto& all = kept[first + k - 1];
      all.insert(all.end(), segs[k - 1].begin(), segs[k - 1].end());
    };
    const CutRegion region{sk.heads[b], sk.direction(b), reach[b]};
    const CutRegion wide{sk.heads[b], sk.direction(b), 3.0 * reach[b]};
    const CutRegion* done = &region;
    bool grow = false;
    for (int k = 1; k <= n; ++k) grow |= retry[first + k - 1] == kGrowFamily;
    if (grow && wide.radius < diag) {
      cut_mesh_parallel(mesh, base, h, n, segs, &grid, &wide, wanted.data(), &region);
      done = &wide;
      for (int k = 1; k <= n; ++k) {
        if (!wanted[k - 1]) continue;
        add_kept(k);
        if (retry[first + k - 1] != kGrowFamily) continue;
        const PlaneCut cut = assemble_loops(kept[first + k - 1], 0.0);
        const SectionGeometry geom = select_section(cut);
        if (local_ok(cut, geom, inside_at(b, k * h))) {
          finish(first + k - 1, frame_of(k), geom, &wide);
          wanted[k - 1] = 0;
        }
      }
    }
    if (std::find(wanted.begin(), wanted.end(), 1) == wanted.end()) return;
    cut_mesh_parallel(mesh, base, h, n, segs, &grid, nullptr, wanted.data(), done);
    for (int k = 1; k <= n; ++k) {
      if (!wanted[k - 1]) continue;
      add_kept(k);
      finish_whole(first + k - 1, frame_of(k), kept[first + k - 1]);
    }
  });
  if (timer.on) {
    std::fprintf(stderr, "local cuts used %d, whole planes %d\n", int(local_used),
                 int(local_failed));
    std::fprintf(stderr, "sections retried %ld\n", retried);
  }
  timer.lap("slicing");
  // 4. Loads: farthest downstream point of every section (paper §4.4), then stress.
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
  r.moment_arm.resize(ns);
  r.moment.resize(ns);
  r.stress.resize(ns);
  r.culled.assign(ns, 0);
  r.weak.assign(ns, 0);
  r.section_flags.resize(ns);
  timer.lap("moment index");
  detail::parallel_for((ns + 63) / 64, threads, [&](long chunk, int) {
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
      const auto [arm, vertex] = arms->farthest(spec.bone, spec.boundary, spec.plus_side, center);
      r.moment_arm[i] = arm;
      r.load_point[i] = vertex >= 0 ? mesh.vertex(vertex) : center;
      r.moment[i] = options.force * arm;
      r.section_area[i] = st.found ? st.area : 0.0;
      r.section_modulus[i] = st.found ? st.modulus : kNaN;
      r.section_thin_axis[i] = st.found ? st.thin_axis : Vec3(kNaN, kNaN, kNaN);
      r.section_aspect[i] = st.found ? st.aspect : kNaN;
      r.section_thickness[i] = st.found ? st.thickness : kNaN;
      r.stress[i] = st.found ? r.moment[i] / st.modulus : kNaN;
    }
  });
  // Sections that drive results: found, not doubted (unreliable), not too thin to print. An
  // outside section far smaller than its bone's sections inside the mesh (below a tenth of their
  // median area) is a sliver the bone only grazes: unreliable, no number.
  std::vector<std::uint8_t> usable(ns, 0);
  {
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
        r.section_area[i] = 0.0;
        r.section_modulus[i] = r.stress[i] = r.section_aspect[i] = r.section_thickness[i] = kNaN;
        r.section_thin_axis[i] = Vec3(kNaN, kNaN, kNaN);
        continue;
      }
      if (options.min_thickness > 0 && states[i].thickness < options.min_thickness)
        flags |= kFlagTooThin;
      usable[i] = !(flags & kFlagTooThin);
    }
  }
  for (int i = 0; i < ns; ++i) {
    if (!usable[i]) continue;
    r.max_moment = std::max(r.max_moment, r.moment[i]);
    if (r.weakest_section < 0 || r.stress[i] > r.max_stress) {
      r.max_stress = r.stress[i];
      r.weakest_section = i;
    }
  }
  r.safe_modulus = r.max_moment / options.allowable_stress;
  for (int i = 0; i < ns; ++i) {
    if (!usable[i]) continue;
    r.culled[i] = r.section_modulus[i] > r.safe_modulus;
    r.weak[i] = r.stress[i] > options.allowable_stress;
  }

  timer.lap("moment arms");
  // 5. Per-vertex stress: linear along the vertex's bone between its sections.
  std::vector<std::vector<int>> bone_sections(nb);
  for (int i = 0; i < ns; ++i)
    if (usable[i]) bone_sections[specs[i].bone].push_back(i);
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
  // Loose pieces: full runs only (the correction's partial re-cuts move no piece apart).
  if (!partial) r.loose_pieces = loose_pieces(mesh, vertex_bone, tree.held_bone);
  const Index block = 8192;
  detail::parallel_for(
      static_cast<long>((num_vertices + block - 1) / block), threads, [&](long chunk, int) {
        const Index end = std::min(num_vertices, (chunk + 1) * block);
        for (Index v = chunk * block; v < end; ++v) {
          const int b = vertex_bone[v];
          const auto& p = sp[b];
          if (p.empty()) continue;
          const double t = (mesh.vertex(v) - sk.heads[b]).dot(axis[b]);
          const std::size_t j = std::upper_bound(p.begin(), p.end(), t) - p.begin();
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
  timer.lap("vertex stress");
  last_vertices.assign(vertices, vertices + 3 * num_vertices);
  last_heads = sk.heads;
  last_tails = sk.tails;
  last_parents = sk.parents;
  last_gap = gap;
  return r;
}

AnalysisResult analyze(const MeshView& mesh, const Skeleton& skeleton, const BoneWeights* weights,
                       const AnalysisOptions& options) {
  validate_mesh(mesh);
  validate_skeleton(skeleton);
  Analyzer analyzer(mesh.faces, mesh.num_faces, mesh.num_vertices, weights, skeleton.num_bones(),
                    options);
  return analyzer.run(mesh.vertices, skeleton);
}

}  // namespace osteon
