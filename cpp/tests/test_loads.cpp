#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "loads.hpp"
#include "osteon/skeleton.hpp"
#include "sorted_index.hpp"

using namespace osteon;

namespace {
Skeleton tee() {
  Skeleton s;
  s.heads = {Vec3(0, 0, 0), Vec3(60, 0, 0), Vec3(30, 0, 0)};
  s.tails = {Vec3(60, 0, 0), Vec3(60, 40, 0), Vec3(30, -30, 0)};
  s.parents = {-1, 0, 0};
  return s;
}

// The farthest downstream vertex from c for the section of bone b at boundary i, by a scan of
// every vertex (largest squared distance, of those the smallest index; -1 when none), `skip`d
// vertices left out.
std::pair<double, Index> scan_farthest(const MeshView& mesh, const Skeleton& s,
                                       const LoadTree& tree, const std::vector<int>& vertex_bone,
                                       const std::vector<std::vector<double>>& params, int b, int i,
                                       bool plus, const Vec3& c,
                                       const std::vector<std::uint8_t>* skip = nullptr) {
  std::function<void(int, std::vector<std::uint8_t>&)> mark_subtree =
      [&](int bone, std::vector<std::uint8_t>& in) {
        in[bone] = 1;
        for (const auto& [child, param] : tree.children[bone]) mark_subtree(child, in);
      };
  const double split = params[b][i];
  std::vector<std::uint8_t> whole(s.num_bones(), 0);
  for (const auto& [child, param] : tree.children[b])
    if (plus ? param >= split : param <= split) mark_subtree(child, whole);
  double best = -1.0;
  Index best_v = -1;
  for (Index v = 0; v < mesh.num_vertices; ++v) {
    if (skip != nullptr && (*skip)[v]) continue;
    const int vb = vertex_bone[v];
    bool down = whole[vb] != 0;
    if (vb == b) {
      const double t = (mesh.vertex(v) - s.heads[b]).dot(s.direction(b));
      const auto& p = params[b];
      const long slab = std::upper_bound(p.begin(), p.end(), t) - p.begin();
      down = plus ? slab > i : slab <= i;
    }
    if (!down) continue;
    const double d2 = (mesh.vertex(v) - c).squaredNorm();
    if (d2 > best) {
      best = d2;
      best_v = v;
    }
  }
  return {best, best_v};
}

// Checks the index's farthest downstream vertex from c against the scan (arm and vertex; none:
// -1 and arm 0); `where` names the query in a failure. Returns whether a vertex was compared.
bool expect_farthest_as_scan(const MomentArmIndex& index, const MeshView& mesh, const Skeleton& s,
                             const LoadTree& tree, const std::vector<int>& vertex_bone,
                             const std::vector<std::vector<double>>& params, int b, int i,
                             bool plus, const Vec3& c, const std::vector<std::uint8_t>* skip,
                             const std::string& where) {
  const auto [best, best_v] =
      scan_farthest(mesh, s, tree, vertex_bone, params, b, i, plus, c, skip);
  const auto [arm, vertex] = index.farthest(b, i, plus, c);
  if (best_v < 0) {
    EXPECT_EQ(vertex, -1) << where;
    EXPECT_EQ(arm, 0.0) << where;
    return false;
  }
  EXPECT_EQ(arm, std::sqrt(best)) << where;
  EXPECT_EQ(vertex, best_v) << where;
  return true;
}

// Rings of integer points (12 per ring, radii 1-3 times 5) around each of the tee's bones, at
// every whole mm from 2 before its head to 2 past its tail, `copies` times over: many points at
// exactly the same distance from a centre on the axis. xyz (3 per point) and each point's bone.
void ring_points(const Skeleton& s, int copies, std::vector<double>& xyz,
                 std::vector<int>& vertex_bone) {
  const int ring[][2] = {{5, 0},  {4, 3},   {3, 4},   {0, 5},  {-3, 4}, {-4, 3},
                         {-5, 0}, {-4, -3}, {-3, -4}, {0, -5}, {3, -4}, {4, -3}};
  for (int copy = 0; copy < copies; ++copy)
    for (int b = 0; b < s.num_bones(); ++b) {
      const Vec3 d = s.direction(b);
      for (int t = -2; t <= static_cast<int>(s.length(b)) + 2; ++t)
        for (int r = 1; r <= 3; ++r)
          for (const auto& q : ring) {
            // Integer offsets in the two axes across the bone (bones run along x or y).
            const Vec3 off = d.x() != 0 ? Vec3(0, r * q[0], r * q[1]) : Vec3(r * q[0], 0, r * q[1]);
            const Vec3 p = s.heads[b] + static_cast<double>(t) * d + off;
            xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
            vertex_bone.push_back(b);
          }
    }
}
}  // namespace

TEST(LoadTree, ChildrenAttachWhereTheirHeadProjects) {
  const LoadTree t = build_load_tree(tee(), -1, {});
  EXPECT_EQ(t.held_bone, 0);
  ASSERT_EQ(t.children[0].size(), 2u);
  for (const auto& [child, param] : t.children[0])
    EXPECT_NEAR(param, child == 1 ? 60.0 : 30.0, 1e-12);
  EXPECT_EQ(t.entry_param[1], 0.0);
}

TEST(LoadTree, HoldingAChildReversesThePath) {
  const LoadTree t = build_load_tree(tee(), 1, {});
  EXPECT_EQ(t.held_bone, 1);
  EXPECT_EQ(t.parent[0], 1);
  EXPECT_NEAR(t.entry_param[0], 60.0, 1e-12);  // the trunk is entered at its tail
  EXPECT_EQ(t.parent[2], 0);
}

TEST(LoadTree, ExtraRootsJoinTheNearestBone) {
  Skeleton s = tee();
  s.parents = {-1, -1, -1};
  const LoadTree t = build_load_tree(s, -1, {100, 10, 10});
  EXPECT_EQ(t.held_bone, 0);
  EXPECT_EQ(t.attached_roots.size(), 2u);
  EXPECT_EQ(t.parent[1], 0);
  EXPECT_EQ(t.parent[2], 0);
}

TEST(LoadTree, BadHeldBoneThrows) {
  EXPECT_THROW(build_load_tree(tee(), 7, {}), std::invalid_argument);
}

TEST(Skeleton, ValidationNamesTheProblem) {
  Skeleton s = tee();
  s.parents = {2, 0, 1};
  try {
    validate_skeleton(s);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos);
  }
  s = tee();
  s.tails[1] = s.heads[1];
  EXPECT_THROW(validate_skeleton(s), std::invalid_argument);
}

TEST(MomentArmIndex, FarthestDownstreamPointMatchesBruteForce) {
  // Many slabs per bone (the slab trees are deep and not powers of two): every section's
  // farthest downstream point equals a scan of the downstream vertices (same distance; of
  // vertices at the same distance the smallest index).
  const Skeleton s = tee();
  const std::vector<Index> per_bone;  // the held bone is the main root
  const LoadTree tree = build_load_tree(s, -1, per_bone);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz;
  std::vector<int> vertex_bone;
  for (int b = 0; b < s.num_bones(); ++b) {
    const Vec3 d = s.direction(b);
    for (int k = 0; k < 700; ++k) {
      const double t = (0.5 * (u(rng) + 1.0)) * s.length(b);
      const Vec3 p = s.heads[b] + t * d + Vec3(u(rng), u(rng), u(rng)) * 4.0;
      xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
      vertex_bone.push_back(b);
    }
  }
  // Two vertices at the same place: the smaller index must win the tie.
  xyz.insert(xyz.end(), {xyz[0], xyz[1], xyz[2]});
  vertex_bone.push_back(vertex_bone[0]);
  const MeshView mesh{xyz.data(), static_cast<Index>(vertex_bone.size()), nullptr, 0};
  std::vector<std::vector<double>> params(s.num_bones());
  const int counts[] = {97, 250, 3};
  for (int b = 0; b < s.num_bones(); ++b) {
    const double h = s.length(b) / (counts[b] + 1);
    params[b].push_back(0.0);
    for (int k = 1; k <= counts[b]; ++k) params[b].push_back(k * h);
    params[b].push_back(s.length(b));
  }
  const MomentArmIndex index(mesh, s, tree, vertex_bone, params);
  int checked = 0;
  for (int b = 0; b < s.num_bones(); ++b) {
    for (int i = 0; i < static_cast<int>(params[b].size()); ++i) {
      for (const bool plus : {true, false}) {
        const Vec3 c = s.heads[b] + params[b][i] * s.direction(b) + Vec3(0.3, -0.2, 0.1);
        checked += expect_farthest_as_scan(
            index, mesh, s, tree, vertex_bone, params, b, i, plus, c, nullptr,
            "bone " + std::to_string(b) + " boundary " + std::to_string(i));
      }
    }
  }
  EXPECT_GT(checked, 600);
}

TEST(MomentArmIndex, BucketsKeepTiesAndSkippedVerticesLikeAScan) {
  // Vertices on rings around the bones (integer coordinates: many at exactly the same distance
  // from a centre on the axis, in different buckets of a slab), some exactly on a slab boundary
  // or beyond the last one, unevenly spaced boundaries with a repeated one, and skipped
  // vertices: the farthest downstream vertex equals a scan (largest distance, then smallest
  // index).
  const Skeleton s = tee();
  const LoadTree tree = build_load_tree(s, -1, {});
  std::vector<std::vector<double>> params = {
      {0, 1, 2, 2, 5, 6, 7, 11, 12, 13, 20, 30, 31, 50}, {0, 4, 8, 12, 16, 20, 24, 28, 32}, {10}};
  std::vector<double> xyz;
  std::vector<int> vertex_bone;
  ring_points(s, 1, xyz, vertex_bone);
  const Index nv = static_cast<Index>(vertex_bone.size());
  const MeshView mesh{xyz.data(), nv, nullptr, 0};
  std::vector<std::uint8_t> skip(nv, 0);
  for (Index v = 0; v < nv; v += 7) skip[v] = 1;
  int checked = 0;
  for (const bool use_skip : {false, true}) {
    const std::vector<std::uint8_t>* skipped = use_skip ? &skip : nullptr;
    const MomentArmIndex index(mesh, s, tree, vertex_bone, params, skipped);
    for (int b = 0; b < s.num_bones(); ++b) {
      for (int i = 0; i < static_cast<int>(params[b].size()); ++i) {
        for (const bool plus : {true, false}) {
          for (int c_kind = 0; c_kind < 3; ++c_kind) {
            // On the axis (ties everywhere), off it by integers, off it by fractions.
            const Vec3 off =
                c_kind == 0 ? Vec3::Zero() : (c_kind == 1 ? Vec3(1, 2, -1) : Vec3(0.3, -0.2, 0.1));
            const Vec3 c = s.heads[b] + params[b][i] * s.direction(b) + off;
            checked += expect_farthest_as_scan(
                index, mesh, s, tree, vertex_bone, params, b, i, plus, c, skipped,
                "bone " + std::to_string(b) + " boundary " + std::to_string(i) + " c " +
                    std::to_string(c_kind));
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(SortedIndex, UpperIndexIsUpperBound) {
  // Evenly and unevenly spaced values, repeated values, queries on, between and beyond them,
  // and NaN: the same index as std::upper_bound.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = trial % 13;
    std::vector<double> p;
    for (int k = 0; k < n; ++k) {
      const double step = trial % 3 == 0 ? 2.0 : (trial % 3 == 1 ? u(rng) * 5.0 : 0.0);
      p.push_back(p.empty() ? u(rng) * 10.0 - 5.0 : p.back() + (u(rng) < 0.2 ? 0.0 : step));
    }
    std::vector<double> queries = {-1e300, 1e300, -std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::quiet_NaN()};
    for (const double v : p)
      queries.insert(queries.end(), {v, std::nextafter(v, -1e9), std::nextafter(v, 1e9)});
    for (int k = 0; k < 20; ++k) queries.push_back(u(rng) * 40.0 - 10.0);
    for (const double t : queries) {
      const auto expected =
          static_cast<std::size_t>(std::upper_bound(p.begin(), p.end(), t) - p.begin());
      EXPECT_EQ(detail::upper_index(p, t), expected) << "n " << n << " t " << t;
      ++checked;
    }
  }
  EXPECT_GT(checked, 5000);
}

TEST(MomentArmIndex, RebuiltIndexAnswersAsAFreshOne) {
  // One index rebuilt for meshes of different sizes, slab counts and skipped vertices (live
  // mode keeps one across runs): every answer equals that of an index built fresh.
  const Skeleton s = tee();
  const LoadTree tree = build_load_tree(s, -1, {});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  MomentArmIndex kept;
  int checked = 0;
  for (const int per_bone : {900, 150, 400}) {
    std::vector<double> xyz;
    std::vector<int> vertex_bone;
    for (int b = 0; b < s.num_bones(); ++b)
      for (int k = 0; k < per_bone; ++k) {
        const double t = (0.5 * (u(rng) + 1.0)) * s.length(b);
        const Vec3 p = s.heads[b] + t * s.direction(b) + Vec3(u(rng), u(rng), u(rng)) * 3.0;
        xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
        vertex_bone.push_back(b);
      }
    const Index nv = static_cast<Index>(vertex_bone.size());
    const MeshView mesh{xyz.data(), nv, nullptr, 0};
    std::vector<std::vector<double>> params(s.num_bones());
    for (int b = 0; b < s.num_bones(); ++b) {
      const int count = per_bone / 50 + b;
      for (int k = 0; k <= count + 1; ++k) params[b].push_back(k * s.length(b) / (count + 1));
    }
    std::vector<std::uint8_t> skip(nv, 0);
    for (Index v = per_bone % 3; v < nv; v += 5) skip[v] = 1;
    const std::vector<std::uint8_t>* skipped = per_bone == 150 ? &skip : nullptr;
    kept.build(mesh, s, tree, vertex_bone, params, skipped);
    const MomentArmIndex fresh(mesh, s, tree, vertex_bone, params, skipped);
    for (int b = 0; b < s.num_bones(); ++b)
      for (int i = 0; i < static_cast<int>(params[b].size()); ++i)
        for (const bool plus : {true, false}) {
          const Vec3 c = s.heads[b] + params[b][i] * s.direction(b) + Vec3(0.2, 0.1, -0.3);
          EXPECT_EQ(kept.farthest(b, i, plus, c), fresh.farthest(b, i, plus, c))
              << "mesh of " << nv << " bone " << b << " boundary " << i;
          ++checked;
        }
  }
  EXPECT_GT(checked, 100);
}

TEST(MomentArmIndex, BuildSplitOverWorkersAnswersAsAScan) {
  // From kVerticesPerPass vertices up the full build is split into one chunk of vertices per
  // worker. Rings of integer points around the bones (ties at equal distances) repeated 26
  // times (135 720 vertices: every point has copies in every chunk, exact ties whose smallest
  // index must win), every 7th vertex skipped; built with 1, 2 and 3 workers (uneven chunks):
  // each answer equals a scan of the downstream vertices.
  const Skeleton s = tee();
  const LoadTree tree = build_load_tree(s, -1, {});
  const std::vector<std::vector<double>> params = {
      {0, 1, 2, 2, 5, 11, 20, 31, 50}, {0, 8, 16, 24, 32}, {10}};
  std::vector<double> xyz;
  std::vector<int> vertex_bone;
  ring_points(s, 26, xyz, vertex_bone);
  const Index nv = static_cast<Index>(vertex_bone.size());
  ASSERT_GE(nv, 131072);
  const MeshView mesh{xyz.data(), nv, nullptr, 0};
  std::vector<std::uint8_t> skip(nv, 0);
  for (Index v = 3; v < nv; v += 7) skip[v] = 1;
  MomentArmIndex index;
  int checked = 0;
  for (const int threads : {1, 2, 3}) {
    index.build(mesh, s, tree, vertex_bone, params, &skip, nullptr, nullptr, threads);
    for (int b = 0; b < s.num_bones(); ++b)
      for (int i = 0; i < static_cast<int>(params[b].size()); ++i)
        for (const bool plus : {true, false})
          for (const Vec3& off : {Vec3(0, 0, 0), Vec3(0.3, -0.2, 0.1)}) {
            const Vec3 c = s.heads[b] + params[b][i] * s.direction(b) + off;
            checked += expect_farthest_as_scan(index, mesh, s, tree, vertex_bone, params, b, i,
                                               plus, c, &skip,
                                               "threads " + std::to_string(threads) + " bone " +
                                                   std::to_string(b) + " at " + std::to_string(i));
          }
  }
  EXPECT_GT(checked, 100);
}

TEST(MomentArmIndex, LiveRebuildReadsTheNewVertexArray) {
  // The index keeps no copy of the coordinates: its queries read the vertex array of its last
  // build. A live rebuild (`moved` given) on a new array in which one bone's vertices moved keeps
  // the other bones' part of the index (region_kept) and must answer from the new array: the old
  // one is overwritten with NaN before the queries. Every answer equals a scan and a fresh index.
  const Skeleton s = tee();
  const LoadTree tree = build_load_tree(s, -1, {});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xyz;
  std::vector<int> vertex_bone;
  for (int b = 0; b < s.num_bones(); ++b)
    for (int k = 0; k < 600; ++k) {
      const double t = (0.5 * (u(rng) + 1.0)) * s.length(b);
      const Vec3 p = s.heads[b] + t * s.direction(b) + Vec3(u(rng), u(rng), u(rng)) * 4.0;
      xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
      vertex_bone.push_back(b);
    }
  const Index nv = static_cast<Index>(vertex_bone.size());
  std::vector<std::vector<double>> params(s.num_bones());
  for (int b = 0; b < s.num_bones(); ++b)
    for (int k = 0; k <= 8 + b; ++k) params[b].push_back(k * s.length(b) / (9 + b));
  MomentArmIndex kept;
  std::vector<std::uint8_t> moved(nv, 0);
  std::vector<std::int32_t> moved_list;
  kept.build(MeshView{xyz.data(), nv, nullptr, 0}, s, tree, vertex_bone, params, nullptr, &moved,
             &moved_list);
  // Bone 1's vertices move (1 mm away from its axis) in a copy of the array.
  std::vector<double> next = xyz;
  for (Index v = 0; v < nv; ++v)
    if (vertex_bone[v] == 1) {
      next[3 * v + 2] += 1.0;
      moved[v] = 1;
      moved_list.push_back(static_cast<std::int32_t>(v));
    }
  const MeshView mesh{next.data(), nv, nullptr, 0};
  kept.build(mesh, s, tree, vertex_bone, params, nullptr, &moved, &moved_list);
  EXPECT_TRUE(kept.region_kept(2));   // bone 2 (a leaf, unmoved): its part kept
  EXPECT_FALSE(kept.region_kept(1));  // bone 1 moved
  std::fill(xyz.begin(), xyz.end(), std::numeric_limits<double>::quiet_NaN());
  const MomentArmIndex fresh(mesh, s, tree, vertex_bone, params);
  int checked = 0;
  for (int b = 0; b < s.num_bones(); ++b)
    for (int i = 0; i < static_cast<int>(params[b].size()); ++i)
      for (const bool plus : {true, false}) {
        const Vec3 c = s.heads[b] + params[b][i] * s.direction(b) + Vec3(0.3, -0.1, 0.2);
        EXPECT_EQ(kept.farthest(b, i, plus, c), fresh.farthest(b, i, plus, c))
            << "bone " << b << " boundary " << i;
        checked += expect_farthest_as_scan(kept, mesh, s, tree, vertex_bone, params, b, i, plus, c,
                                           nullptr, "bone " + std::to_string(b));
      }
  EXPECT_GT(checked, 30);
}
