// Stages 1-2 of a run: each vertex's bone, then the plan of sections (Analyzer::Impl).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "analysis_impl.hpp"

namespace osteon {
namespace {

// Number of interior planes k*h strictly inside a bone of length L (not limited).
double interior_planes(double length, double interval) {
  const double n = std::ceil(length / interval * (1.0 - 1e-12)) - 1.0;
  return n > 0 ? n : 0.0;
}

// The same, for a plan: at most 10^6 on one bone.
int interior_count(double length, double interval) {
  const double n = interior_planes(length, interval);
  if (n > 1e6)
    throw std::invalid_argument("interval too small: more than 10^6 sections on one bone");
  return static_cast<int>(n);
}

// How far (a fraction of the bone's length) a free head's section moves into the bone.
constexpr double kCapNudge = 1e-7;

struct Endpoint {
  int bone;
  bool tail;
  Vec3 position;
};

// Bone ends (2 per bone: head, tail) clustered into joints: ends closer than 1e-6 of the
// longest bone are one joint. Each joint lists its members (indices into `ends`).
std::vector<std::vector<int>> cluster_joints(const Skeleton& sk, std::vector<Endpoint>& ends) {
  const int nb = sk.num_bones();
  double extent = 0.0;
  for (int b = 0; b < nb; ++b) extent = std::max(extent, sk.length(b));
  const double tol = 1e-6 * extent;
  ends.clear();
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
  return joints;
}

}  // namespace

std::int64_t count_sections(const Skeleton& sk, double interval) {
  if (!(interval > 0) || !std::isfinite(interval))
    throw std::invalid_argument("interval must be a positive finite length in mm");
  double interior = 0.0;
  for (int b = 0; b < sk.num_bones(); ++b) interior += interior_planes(sk.length(b), interval);
  if (interior > 9e18) return std::numeric_limits<std::int64_t>::max();
  std::int64_t n = static_cast<std::int64_t>(interior);
  std::vector<Endpoint> ends;
  // As plan_sections: a lone end is one section, a joint one per pair of different bones.
  for (const auto& members : cluster_joints(sk, ends)) {
    if (members.size() == 1) {
      ++n;
      continue;
    }
    for (std::size_t i = 0; i < members.size(); ++i)
      for (std::size_t j = i + 1; j < members.size(); ++j)
        n += ends[members[i]].bone != ends[members[j]].bone;
  }
  return n;
}

void Analyzer::Impl::assign_vertex_bones(RunState& run) {
  const MeshView& mesh = run.mesh;
  const Skeleton& sk = run.sk;
  const int threads = options.threads;
  std::vector<int>& vertex_bone = run.vertex_bone;
  if (has_weights) {
    vertex_bone = dominant;
    // Vertices no bone weighs (an unweighted eye or prop) take their nearest bone: only they
    // are measured (each vertex's nearest bone does not depend on the others).
    std::vector<double>& xyz = unweighted_xyz;
    xyz.clear();
    const auto first = std::find(vertex_bone.begin(), vertex_bone.end(), -1);
    for (Index v = first - vertex_bone.begin(); v < num_vertices; ++v)
      if (vertex_bone[v] < 0)
        xyz.insert(xyz.end(), mesh.vertices + 3 * v, mesh.vertices + 3 * v + 3);
    if (!xyz.empty()) {
      const MeshView some{xyz.data(), static_cast<Index>(xyz.size() / 3), nullptr, 0};
      const std::vector<int> nearest = nearest_bones(some, sk, threads);
      Index k = 0;
      for (Index v = 0; v < num_vertices; ++v)
        if (vertex_bone[v] < 0) vertex_bone[v] = nearest[k++];
    }
  } else {
    vertex_bone = nearest_bones(mesh, sk, threads);
  }
  run.per_bone.assign(num_bones, 0);
  for (int b : vertex_bone) ++run.per_bone[b];
}

void Analyzer::Impl::plan_sections(RunState& run) {
  const Skeleton& sk = run.sk;
  const int nb = num_bones;
  const double h = options.interval;
  run.partial = run.dirty != nullptr && !specs.empty();
  // Live mode: keep the last run's sections to reuse the ones nothing has changed.
  run.may_reuse = !run.partial && options.reuse_sections && !specs.empty() &&
                  last_vertices.size() == static_cast<std::size_t>(3 * num_vertices) &&
                  last_parents == sk.parents;
  if (run.may_reuse) {
    run.prev_specs = specs;
    // Moved, not copied (with outlines a section holds its loops): a reusing run is a full one,
    // and below `states` is made anew for the new plan.
    run.prev_states = std::move(states);
  }
  if (run.partial) return;  // the last run's plan stands
  tree = build_load_tree(sk, options.held_bone, run.per_bone);
  // Vertices downstream of each bone's entry, for choosing which bone owns a joint section.
  std::vector<Index> subtree_vertices(run.per_bone);
  for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it)
    if (tree.parent[*it] >= 0) subtree_vertices[tree.parent[*it]] += subtree_vertices[*it];

  // Interior planes per bone, then joints and free ends.
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
  const std::vector<std::vector<int>> joints = cluster_joints(sk, ends);
  auto add_single = [&](int bone, bool tail, const Vec3& normal, std::int8_t kind) {
    SectionSpec spec;
    spec.bone = bone;
    spec.kind = kind;
    spec.boundary = tail ? count[bone] + 1 : 0;
    const double param = tail ? sk.length(bone) : 0.0;
    spec.plus_side = param >= tree.entry_param[bone];
    spec.point = tail ? sk.tails[bone] : sk.heads[bone];
    // A free head sits where a bone usually starts: on the mesh's end cap. The slicer counts a
    // vertex on the plane as above it, so a plane exactly on the cap cuts nothing (the limit from
    // outside); nudged into the bone by kCapNudge of its length it cuts the cap's outline (the
    // limit from inside). A free tail already gets that limit, and a joint is inside the mesh.
    if (kind == kEnd && !tail) spec.point += kCapNudge * sk.length(bone) * sk.direction(bone);
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

}  // namespace osteon
