#include "loads.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <queue>
#include <stdexcept>
#include <string>

#include "parallel.hpp"
#include "prefetch.hpp"
#include "sorted_index.hpp"

namespace osteon {

LoadTree build_load_tree(const Skeleton& s, int held_bone,
                         const std::vector<Index>& vertex_count_per_bone) {
  const int nb = s.num_bones();
  if (held_bone < -1 || held_bone >= nb)
    throw std::invalid_argument("held bone index " + std::to_string(held_bone) +
                                " out of range for " + std::to_string(nb) + " bones");
  // Root of each bone's tree, and how many vertices/bones each tree carries.
  std::vector<int> tree_root(nb);
  for (int b = 0; b < nb; ++b) {
    int r = b;
    while (s.parents[r] >= 0) r = s.parents[r];
    tree_root[b] = r;
  }
  std::vector<double> tree_weight(nb, 0.0);
  for (int b = 0; b < nb; ++b) {
    const double verts = vertex_count_per_bone.empty() ? 0.0 : double(vertex_count_per_bone[b]);
    tree_weight[tree_root[b]] += verts * nb + 1.0;  // vertices first, then bone count
  }
  int main_root = held_bone >= 0 ? tree_root[held_bone] : -1;
  if (main_root < 0) {
    for (int r : root_bones(s))
      if (main_root < 0 || tree_weight[r] > tree_weight[main_root]) main_root = r;
  }
  const int held = held_bone >= 0 ? held_bone : main_root;

  // Undirected adjacency: (neighbour, connection param on this bone, param on the neighbour).
  struct Link {
    int other;
    double here, there;
  };
  std::vector<std::vector<Link>> links(nb);
  auto join = [&](int child, int parent) {
    const double on_parent = project_onto_bone(s, parent, s.heads[child]);
    links[parent].push_back({child, on_parent, 0.0});
    links[child].push_back({parent, 0.0, on_parent});
  };
  LoadTree tree;
  for (int b = 0; b < nb; ++b)
    if (s.parents[b] >= 0) join(b, s.parents[b]);
  // Extra roots (IK, props, the several root bones of joint-based rigs) join the main tree at
  // the bone nearest their head.
  for (int r : root_bones(s)) {
    if (r == main_root) continue;
    int nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int b = 0; b < nb; ++b) {
      if (tree_root[b] != main_root) continue;
      const double d = squared_distance_to_bone(s, b, s.heads[r]);
      if (d < best) {
        best = d;
        nearest = b;
      }
    }
    join(r, nearest);
    tree.attached_roots.push_back(r);
    // Later roots may attach to this tree too: treat it as part of the main tree from now on.
    for (int b = 0; b < nb; ++b)
      if (tree_root[b] == r) tree_root[b] = main_root;
  }

  tree.held_bone = held;
  tree.parent.assign(nb, -1);
  tree.entry_param.assign(nb, 0.0);
  tree.children.assign(nb, {});
  std::vector<std::uint8_t> seen(nb, 0);
  std::queue<int> queue;
  queue.push(held);
  seen[held] = 1;
  while (!queue.empty()) {
    const int b = queue.front();
    queue.pop();
    tree.order.push_back(b);
    for (const Link& l : links[b]) {
      if (seen[l.other]) continue;
      seen[l.other] = 1;
      tree.parent[l.other] = b;
      tree.entry_param[l.other] = l.there;
      tree.children[b].push_back({l.other, l.here});
      queue.push(l.other);
    }
  }
  return tree;
}

namespace {
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Buckets of a slab with `count` vertices: ~16 vertices each (fewer, wider buckets cost more
// scanning, more cost heap work).
constexpr Index kBucket = 16;
// The first vertex (or bucket) of chunk c of `chunks` over n.
inline Index chunk_end(Index n, long c, int chunks) {
  return n * c / chunks;  // n * chunks stays far below 2^63
}

inline Index buckets_for(Index count) {
  return std::max<Index>(1, (count + kBucket - 1) / kBucket);
}

// The bucket (of k) of a vertex at pseudo-angle `angle` in [0, 4].
inline Index bucket_at(double angle, Index k) {
  const double q = angle * (0.25 * static_cast<double>(k));
  return q > 0 ? (q < static_cast<double>(k) ? static_cast<Index>(q) : k - 1) : 0;
}

// A bottom-up tree of boxes over m leaves (each with .lo, .hi): node i in [1, 2m) at lo/hi[i],
// leaves m + j, node i < m the box of nodes 2i and 2i+1.
template <class Leaf>
void box_tree(const Leaf* leaves, Index m, Vec3* lo, Vec3* hi) {
  for (Index j = 0; j < m; ++j) {
    lo[m + j] = leaves[j].lo;
    hi[m + j] = leaves[j].hi;
  }
  for (Index i = m - 1; i >= 1; --i) {
    lo[i] = lo[2 * i].cwiseMin(lo[2 * i + 1]);
    hi[i] = hi[2 * i].cwiseMax(hi[2 * i + 1]);
  }
}
}  // namespace

MomentArmIndex::MomentArmIndex(const MeshView& mesh, const Skeleton& s, const LoadTree& tree,
                               const std::vector<int>& vertex_bone,
                               const std::vector<std::vector<double>>& slab_params,
                               const std::vector<std::uint8_t>* skip) {
  build(mesh, s, tree, vertex_bone, slab_params, skip);
}

void MomentArmIndex::build(const MeshView& mesh, const Skeleton& s, const LoadTree& tree,
                           const std::vector<int>& vertex_bone,
                           const std::vector<std::vector<double>>& slab_params,
                           const std::vector<std::uint8_t>* skip,
                           const std::vector<std::uint8_t>* moved,
                           const std::vector<std::int32_t>* moved_list, int threads) {
  tree_ = &tree;
  vertices_ = mesh.vertices;
  last_slab_params_.swap(slab_params_);
  slab_params_ = slab_params;
  const int nb = s.num_bones();
  // Slab j of bone b holds the vertices with params in [p[j-1], p[j]) (slab 0: below p[0],
  // last slab: at or above the last param); a section at boundary i splits slabs <= i from > i.
  last_group_offset_.swap(group_offset_);
  group_offset_.assign(nb + 1, 0);
  for (int b = 0; b < nb; ++b)
    group_offset_[b + 1] = group_offset_[b] + static_cast<Index>(slab_params_[b].size()) + 1;
  const bool reuse = moved != nullptr && slabs_known_ &&
                     static_cast<Index>(moved->size()) == mesh.num_vertices &&
                     static_cast<Index>(last_bone_.size()) == mesh.num_vertices &&
                     vertex_capacity_ >= mesh.num_vertices && slab_capacity_ >= mesh.num_vertices;
  const bool same_skip = reuse && compare_with_last_build(s, skip);
  // The same vertices per bone, slabs per bone and tree: only the moved bones are built again.
  const bool same_layout =
      same_skip && moved_list != nullptr && group_offset_ == last_group_offset_ &&
      static_cast<int>(bone_vertex_start_.size()) == nb + 1 && same_bits(vertex_bone, last_bone_);
  const bool kept = same_layout && rebuild_moved_bones(mesh, s, moved->data(), *moved_list);
  if (kept) {
    subtree_boxes(tree);
  } else {
    bone_kept_.assign(nb, 0);
    // From kVerticesPerPass vertices up, one chunk of vertices per worker.
    const int chunks = mesh.num_vertices >= detail::kVerticesPerPass
                           ? detail::worker_count(threads, mesh.num_vertices)
                           : 1;
    group_vertices(mesh, s, vertex_bone, skip, reuse ? moved->data() : nullptr,
                   /*keep_slabs=*/moved != nullptr, chunks);
    pack_buckets(mesh, skip, chunks);
    build_box_trees(tree, chunks);
  }
  // Only an index that is rebuilt with `moved` (live mode) keeps its inputs for the next build.
  if (moved != nullptr) {
    remember_build(s, vertex_bone, skip, kept);
    mark_kept_regions(tree);
    last_children_ = tree.children;
  } else {
    slabs_known_ = false;
    region_kept_.clear();
  }
}

// bone_same_[b]: bone b's head, axis and slab params are bitwise the last build's (and the
// vertices left out are the same), so an unmoved vertex of b lies in the same slab at the same
// angle.
bool MomentArmIndex::compare_with_last_build(const Skeleton& s,
                                             const std::vector<std::uint8_t>* skip) {
  const int nb = s.num_bones();
  bone_same_.assign(nb, 0);
  const bool same_skip = skip == nullptr ? last_skip_.empty() : same_bits(*skip, last_skip_);
  if (!same_skip || static_cast<int>(last_head_.size()) != nb ||
      static_cast<int>(last_slab_params_.size()) != nb)
    return false;
  for (int b = 0; b < nb; ++b) {
    const Vec3 axis = s.direction(b);
    bone_same_[b] = std::memcmp(s.heads[b].data(), last_head_[b].data(), sizeof(Vec3)) == 0 &&
                    std::memcmp(axis.data(), last_axis_[b].data(), sizeof(Vec3)) == 0 &&
                    same_bits(slab_params_[b], last_slab_params_[b]);
  }
  return true;
}

void MomentArmIndex::remember_build(const Skeleton& s, const std::vector<int>& vertex_bone,
                                    const std::vector<std::uint8_t>* skip, bool kept) {
  last_head_.assign(s.heads.begin(), s.heads.begin() + s.num_bones());
  last_axis_.resize(frames_.size());
  for (std::size_t b = 0; b < frames_.size(); ++b) last_axis_[b] = frames_[b].axis;
  slabs_known_ = true;
  if (kept) return;  // the same vertices of each bone as the last build's
  last_bone_ = vertex_bone;
  if (skip != nullptr)
    last_skip_ = *skip;
  else
    last_skip_.clear();
  // Each bone's kept vertices in vertex order.
  const int nb = s.num_bones();
  const Index nv = static_cast<Index>(vertex_bone.size());
  bone_vertex_start_.assign(nb + 1, 0);
  for (Index v = 0; v < nv; ++v)
    if (skip == nullptr || !(*skip)[v]) ++bone_vertex_start_[vertex_bone[v] + 1];
  for (int b = 0; b < nb; ++b) bone_vertex_start_[b + 1] += bone_vertex_start_[b];
  bone_vertices_.resize(bone_vertex_start_[nb]);
  std::vector<Index> fill(bone_vertex_start_.begin(), bone_vertex_start_.end() - 1);
  for (Index v = 0; v < nv; ++v)
    if (skip == nullptr || !(*skip)[v])
      bone_vertices_[fill[vertex_bone[v]]++] = static_cast<std::int32_t>(v);
}

// Each bone's frame (frames_): its head, axis and the pseudo-angle's perpendiculars, and its slab
// params with the constants of the slab search.
void MomentArmIndex::set_frames(const Skeleton& s) {
  const int nb = s.num_bones();
  frames_.resize(nb);
  for (int b = 0; b < nb; ++b) {
    BoneFrame& f = frames_[b];
    f.head = s.heads[b];
    f.axis = s.direction(b);
    f.u = f.axis.unitOrthogonal();
    f.v = f.axis.cross(f.u);
    const std::vector<double>& p = slab_params_[b];
    f.params = p.data();
    f.count = static_cast<Index>(p.size());
    f.first = p.empty() ? 0.0 : p.front();
    f.last = p.empty() ? 0.0 : p.back();
    f.scale = f.count > 1 && f.last > f.first
                  ? static_cast<double>(f.count - 1) / (f.last - f.first)
                  : 0.0;
  }
}

namespace {
// detail::upper_index(params, t) (the first param above t) with the bone's constants: any first
// guess in [1, count - 1] walks to the same index (it is unique in sorted params), so the guess
// multiplies by the precomputed scale instead of dividing.
template <class Frame>
inline Index slab_of(const Frame& f, double t) {
  const double* p = f.params;
  const Index n = f.count;
  if (n == 0 || t < f.first) return 0;
  if (!(t >= f.first)) return std::upper_bound(p, p + n, t) - p;  // NaN
  if (t >= f.last) return n;
  // first <= t < last: the answer lies in [1, n - 1] (and last > first, so scale > 0).
  const double guess = (t - f.first) * f.scale;
  Index j = guess < static_cast<double>(n - 1) ? static_cast<Index>(guess) : n - 1;
  if (j < 1) j = 1;
  while (p[j - 1] > t) --j;
  while (p[j] <= t) ++j;
  return j;
}
}  // namespace

// Bone b's vertex v: its slab within the bone (returned) and its pseudo-angle in [0, 4] around
// the bone axis (vertex_angle_: a monotone function of the angle in the bone's frame u, v: no
// atan; a float, as it only picks the vertex's bucket, and any bucket gives the same answers).
inline Index MomentArmIndex::place_vertex(const MeshView& mesh, Index v, int b) {
  const BoneFrame& f = frames_[b];
  const Vec3 d = mesh.vertex(v) - f.head;
  const Index slab = slab_of(f, d.dot(f.axis));
  const double du = d.dot(f.u), dv = d.dot(f.v);
  const double sum = std::abs(du) + std::abs(dv);
  const double r = sum > 0 ? du / sum : 1.0;
  vertex_angle_[v] = static_cast<float>(dv >= 0 ? 1.0 - r : 3.0 + r);
  return slab;
}

// Live builds: the bones with a moved vertex or another head, axis or slabs grouped, packed and
// boxed again in their part of the index, the others kept (bone_kept_).
bool MomentArmIndex::rebuild_moved_bones(const MeshView& mesh, const Skeleton& s,
                                         const std::uint8_t* moved,
                                         const std::vector<std::int32_t>& moved_list) {
  const int nb = s.num_bones();
  bone_kept_.assign(bone_same_.begin(), bone_same_.end());
  for (std::int32_t v : moved_list) bone_kept_[last_bone_[v]] = 0;
  set_frames(s);
  for (int b = 0; b < nb; ++b)
    if (!bone_kept_[b]) regroup_bone(mesh, b, moved);
  // Each slab's buckets: the kept bones' as they are, the others' for their new counts.
  std::vector<Index>& offset = next_bucket_offset_;
  offset.assign(group_offset_[nb] + 1, 0);
  for (int b = 0; b < nb; ++b)
    for (Index g = group_offset_[b]; g < group_offset_[b + 1]; ++g)
      offset[g + 1] = offset[g] + (bone_kept_[b] ? bucket_offset_[g + 1] - bucket_offset_[g]
                                                 : buckets_for(group_count_[g]));
  if (offset != bucket_offset_) move_buckets();
  if (bucket_fill_.size() < static_cast<std::size_t>(bucket_offset_.back()))
    bucket_fill_.resize(bucket_offset_.back());
  for (int b = 0; b < nb; ++b)
    if (!bone_kept_[b]) repack_bone(mesh, b);
  return true;
}

// The bucket arrays laid out for next_bucket_offset_: the kept bones' buckets and bucket boxes
// copied to their new places (their packed vertices stay: each bone's lie after the bones
// before it), the others' left empty for repack_bone.
void MomentArmIndex::move_buckets() {
  const int nb = static_cast<int>(group_offset_.size()) - 1;
  const std::vector<Index>& offset = next_bucket_offset_;
  const Index nbuckets = offset.back();
  const double inf = std::numeric_limits<double>::infinity();
  next_buckets_.assign(nbuckets, Group{});
  next_lo_.assign(2 * nbuckets, Vec3::Constant(inf));
  next_hi_.assign(2 * nbuckets, Vec3::Constant(-inf));
  for (int b = 0; b < nb; ++b) {
    if (!bone_kept_[b]) continue;
    const Index from = bucket_offset_[group_offset_[b]], to = offset[group_offset_[b]];
    const Index n = bucket_offset_[group_offset_[b + 1]] - from;
    std::copy(buckets_.begin() + from, buckets_.begin() + from + n, next_buckets_.begin() + to);
    std::copy(bucket_lo_.begin() + 2 * from, bucket_lo_.begin() + 2 * (from + n),
              next_lo_.begin() + 2 * to);
    std::copy(bucket_hi_.begin() + 2 * from, bucket_hi_.begin() + 2 * (from + n),
              next_hi_.begin() + 2 * to);
  }
  buckets_.swap(next_buckets_);
  bucket_lo_.swap(next_lo_);
  bucket_hi_.swap(next_hi_);
  bucket_offset_.swap(next_bucket_offset_);
}

// Bone b's vertices into its groups (as group_vertices: an unmoved vertex of a bone whose head,
// axis and slabs are the same keeps its slab and angle).
void MomentArmIndex::regroup_bone(const MeshView& mesh, int b, const std::uint8_t* moved) {
  const Index g0 = group_offset_[b];
  std::fill(group_count_.begin() + g0, group_count_.begin() + group_offset_[b + 1], 0);
  const bool same = bone_same_[b] != 0;
  for (Index k = bone_vertex_start_[b]; k < bone_vertex_start_[b + 1]; ++k) {
    const Index v = bone_vertices_[k];
    if (!same || moved[v]) vertex_slab_[v] = static_cast<std::int32_t>(place_vertex(mesh, v, b));
    const Index g = g0 + vertex_slab_[v];
    vertex_group_[v] = static_cast<std::int32_t>(g);
    ++group_count_[g];
  }
}

// Bone b's vertices into its buckets, packed in its part of packed_index_ (the same place: the
// same vertices before it), and its boxes: as pack_buckets and build_box_trees for this bone.
void MomentArmIndex::repack_bone(const MeshView& mesh, int b) {
  const Index g0 = group_offset_[b], g1 = group_offset_[b + 1];
  const Index k0 = bucket_offset_[g0], k1 = bucket_offset_[g1];
  std::int32_t* const vertex_group = vertex_group_.get();
  std::vector<Index>& fill = bucket_fill_;
  std::fill(fill.begin() + k0, fill.begin() + k1, 0);
  const Index first = bone_vertex_start_[b], last = bone_vertex_start_[b + 1];
  for (Index i = first; i < last; ++i) {
    const Index v = bone_vertices_[i], g = vertex_group[v];
    vertex_group[v] =
        bucket_offset_[g] + bucket_at(vertex_angle_[v], bucket_offset_[g + 1] - bucket_offset_[g]);
    ++fill[vertex_group[v]];
  }
  const double inf = std::numeric_limits<double>::infinity();
  Index at = bone_vertex_start_[b];  // the kept vertices of the bones before b come first
  for (Index k = k0; k < k1; ++k) {
    const Index n = fill[k];
    buckets_[k].begin = fill[k] = at;
    buckets_[k].end = at += n;
    buckets_[k].lo = Vec3::Constant(inf);
    buckets_[k].hi = Vec3::Constant(-inf);
  }
  for (Index i = first; i < last; ++i) {
    const Index v = bone_vertices_[i];
    pack_vertex(mesh, v, buckets_[vertex_group[v]], fill[vertex_group[v]]++);
  }
  for (Index g = g0; g < g1; ++g) bucket_tree(g);
  bone_tree(b);
}

// Each kept vertex's group (vertex_group_; its slab within its bone: vertex_slab_) and its
// pseudo-angle in [0, 4] around the bone axis
// (vertex_angle_: a monotone function of the angle in the bone's frame u, v: no atan); the
// vertices per group (group_count_). One job per chunk of vertices.
void MomentArmIndex::group_vertices(const MeshView& mesh, const Skeleton& s,
                                    const std::vector<int>& vertex_bone,
                                    const std::vector<std::uint8_t>* skip,
                                    const std::uint8_t* moved, bool keep_slabs, int chunks) {
  const int nb = s.num_bones();
  const Index ngroups = group_offset_[nb];
  // (Scratch arrays left uninitialised: every kept vertex's entry is written before it is read.)
  if (vertex_capacity_ < mesh.num_vertices) {
    vertex_group_.reset(new std::int32_t[mesh.num_vertices]);
    vertex_angle_.reset(new float[mesh.num_vertices]);
    vertex_capacity_ = mesh.num_vertices;
    moved = nullptr;  // nothing kept
  }
  // The slabs are kept for the next build in live mode only (a one-off build writes none).
  if (keep_slabs && slab_capacity_ < mesh.num_vertices) {
    vertex_slab_.reset(new std::int32_t[mesh.num_vertices]);
    slab_capacity_ = mesh.num_vertices;
    moved = nullptr;
  }
  std::int32_t* const vertex_group = vertex_group_.get();
  std::int32_t* const vertex_slab = vertex_slab_.get();  // the slab within its bone (kept)
  set_frames(s);
  const std::uint8_t* bone_same = bone_same_.data();
  const int* last_bone = last_bone_.data();
  chunk_count_.resize(chunks);
  detail::parallel_for(chunks, chunks, [&](long c, int) {
    chunk_count_[c].assign(ngroups, 0);
    Index* const group_count = chunk_count_[c].data();
    const Index v1 = chunk_end(mesh.num_vertices, c + 1, chunks);
    for (Index v = chunk_end(mesh.num_vertices, c, chunks); v < v1; ++v) {
      if (skip != nullptr && (*skip)[v] != 0) continue;
      const int b = vertex_bone[v];
      // An unmoved vertex on the same bone keeps the last build's slab and angle.
      Index slab;
      if (moved == nullptr || moved[v] || last_bone[v] != b || !bone_same[b]) {
        slab = place_vertex(mesh, v, b);
        if (keep_slabs) vertex_slab[v] = static_cast<std::int32_t>(slab);
      } else {
        slab = vertex_slab[v];
      }
      const Index g = group_offset_[b] + slab;
      vertex_group[v] = static_cast<std::int32_t>(g);
      ++group_count[g];
    }
  });
  group_count_.swap(chunk_count_[0]);
  for (int c = 1; c < chunks; ++c)
    for (Index g = 0; g < ngroups; ++g) group_count_[g] += chunk_count_[c][g];
}

// The vertices in buckets of ~16 per group (sectors around the bone axis), packed by bucket
// (packed_index_) in vertex order within each bucket (so the same index whatever
// the chunks: chunk c's vertices of a bucket come after chunk c - 1's). One job per chunk.
void MomentArmIndex::pack_buckets(const MeshView& mesh, const std::vector<std::uint8_t>* skip,
                                  int chunks) {
  const Index ngroups = group_offset_.back();
  std::int32_t* const vertex_group = vertex_group_.get();
  const float* const vertex_angle = vertex_angle_.get();
  const Index nv = mesh.num_vertices;
  auto skipped = [&](Index v) { return skip != nullptr && (*skip)[v] != 0; };
  bucket_offset_.assign(ngroups + 1, 0);
  for (Index g = 0; g < ngroups; ++g)
    bucket_offset_[g + 1] = bucket_offset_[g] + buckets_for(group_count_[g]);
  const Index nbuckets = bucket_offset_[ngroups];
  chunk_count_.resize(chunks);
  detail::parallel_for(chunks, chunks, [&](long c, int) {
    chunk_count_[c].assign(nbuckets, 0);
    Index* const count = chunk_count_[c].data();
    const Index v1 = chunk_end(nv, c + 1, chunks);
    for (Index v = chunk_end(nv, c, chunks); v < v1; ++v) {
      if (skipped(v)) continue;
      const Index g = vertex_group[v];
      // From here on: the vertex's bucket.
      vertex_group[v] =
          bucket_offset_[g] + bucket_at(vertex_angle[v], bucket_offset_[g + 1] - bucket_offset_[g]);
      ++count[vertex_group[v]];
    }
  });
  // Each bucket's range, and within it each chunk's first place (chunk_count_ from here on).
  const double inf = std::numeric_limits<double>::infinity();
  buckets_.resize(nbuckets);
  Index at = 0;
  for (Index k = 0; k < nbuckets; ++k) {
    Group& bucket = buckets_[k];
    bucket.begin = at;
    for (int c = 0; c < chunks; ++c) {
      const Index n = chunk_count_[c][k];
      chunk_count_[c][k] = at;
      at += n;
    }
    bucket.end = at;
    bucket.lo = Vec3::Constant(inf);
    bucket.hi = Vec3::Constant(-inf);
  }
  if (packed_capacity_ < at) {
    packed_index_.reset(new std::int32_t[at]);
    packed_capacity_ = at;
  }
  std::int32_t* const index = packed_index_.get();
  detail::parallel_for(chunks, chunks, [&](long c, int) {
    Index* const fill = chunk_count_[c].data();
    const Index v1 = chunk_end(nv, c + 1, chunks);
    for (Index v = chunk_end(nv, c, chunks); v < v1; ++v) {
      if (skipped(v)) continue;
      index[fill[vertex_group[v]]++] = static_cast<std::int32_t>(v);
    }
  });
}

// Vertex v at place k of packed_index_, in `bucket` (its box grown).
void MomentArmIndex::pack_vertex(const MeshView& mesh, Index v, Group& bucket, Index k) {
  const Vec3 p = mesh.vertex(v);
  packed_index_[k] = static_cast<std::int32_t>(v);
  bucket.lo = bucket.lo.cwiseMin(p);
  bucket.hi = bucket.hi.cwiseMax(p);
}

// The box trees: over each group's buckets, over each bone's slabs, and each bone's subtree box
// (the bone and every bone beyond it in `tree`). Each bucket's box from its packed vertices, in
// their order (as pack_vertex grows it), and its group's tree: one job per chunk of groups with
// about as many buckets.
void MomentArmIndex::build_box_trees(const LoadTree& tree, int chunks) {
  const Index ngroups = group_offset_.back();
  const int nb = static_cast<int>(group_offset_.size()) - 1;
  const Index nbuckets = bucket_offset_[ngroups];
  const double inf = std::numeric_limits<double>::infinity();
  groups_.resize(ngroups);
  // Each group's tree writes its nodes [1, 2k) (node 0 is never read): no fill first (a serial
  // pass that touched 4.5 MB of fresh pages on a 1.5M-face mesh), the pages are touched by the
  // workers that write them.
  bucket_lo_.resize(2 * nbuckets);
  bucket_hi_.resize(2 * nbuckets);
  const double* const xyz = vertices_;
  const std::int32_t* const index = packed_index_.get();
  const Index last = nbuckets > 0 ? std::max<Index>(0, buckets_[nbuckets - 1].end - 1) : 0;
  const bool ahead = last + 1 >= detail::kVerticesPerPass;  // a large mesh (prefetch pays)
  auto group_at = [&](Index k) {  // the first group whose buckets start at or after bucket k
    return std::lower_bound(bucket_offset_.begin(), bucket_offset_.end(), k) -
           bucket_offset_.begin();
  };
  detail::parallel_for(chunks, chunks, [&](long c, int) {
    const Index g1 = group_at(chunk_end(nbuckets, c + 1, chunks));
    for (Index g = group_at(chunk_end(nbuckets, c, chunks)); g < g1; ++g) {
      for (Index k = bucket_offset_[g]; k < bucket_offset_[g + 1]; ++k) {
        Group& bucket = buckets_[k];
        for (Index i = bucket.begin; i < bucket.end; ++i) {
          // A gather from the mesh (on a large one, the vertex 8 places on fetched ahead).
          if (ahead) detail::prefetch(xyz + 3 * static_cast<Index>(index[std::min(i + 8, last)]));
          const double* q = xyz + 3 * static_cast<Index>(index[i]);
          const Vec3 p(q[0], q[1], q[2]);
          bucket.lo = bucket.lo.cwiseMin(p);
          bucket.hi = bucket.hi.cwiseMax(p);
        }
      }
      bucket_tree(g);
    }
  });
  node_lo_.assign(2 * ngroups, Vec3::Constant(inf));
  node_hi_.assign(2 * ngroups, Vec3::Constant(-inf));
  for (int b = 0; b < nb; ++b) bone_tree(b);
  subtree_boxes(tree);
}

// A bottom-up tree over the buckets of group g (leaves k + j, parents i = (k + j) / 2, ...); its
// root (or single leaf) is the group's box.
void MomentArmIndex::bucket_tree(Index g) {
  const Index first = bucket_offset_[g], k = bucket_offset_[g + 1] - first;
  Vec3* lo = bucket_lo_.data() + 2 * first;
  Vec3* hi = bucket_hi_.data() + 2 * first;
  box_tree(buckets_.data() + first, k, lo, hi);
  groups_[g].begin = buckets_[first].begin;
  groups_[g].end = buckets_[first + k - 1].end;
  groups_[g].lo = lo[1];
  groups_[g].hi = hi[1];
}

// Bone b's tree of slab boxes (leaves m + j, parents i = (m + j) / 2, ...).
void MomentArmIndex::bone_tree(int b) {
  const Index first = group_offset_[b], m = group_offset_[b + 1] - first;
  box_tree(groups_.data() + first, m, node_lo_.data() + 2 * first, node_hi_.data() + 2 * first);
}

// Each bone's subtree box (the bone and every bone beyond it in `tree`), leaves first (reverse
// breadth-first order).
void MomentArmIndex::subtree_boxes(const LoadTree& tree) {
  const int nb = static_cast<int>(group_offset_.size()) - 1;
  const double inf = std::numeric_limits<double>::infinity();
  subtree_lo_.assign(nb, Vec3::Constant(inf));
  subtree_hi_.assign(nb, Vec3::Constant(-inf));
  for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it) {
    const int b = *it;
    for (Index g = group_offset_[b]; g < group_offset_[b + 1]; ++g) {
      subtree_lo_[b] = subtree_lo_[b].cwiseMin(groups_[g].lo);
      subtree_hi_[b] = subtree_hi_[b].cwiseMax(groups_[g].hi);
    }
    for (const auto& [child, param] : tree.children[b]) {
      (void)param;
      subtree_lo_[b] = subtree_lo_[b].cwiseMin(subtree_lo_[child]);
      subtree_hi_[b] = subtree_hi_[b].cwiseMax(subtree_hi_[child]);
    }
  }
}

// region_kept_: the bone and every bone beyond it kept, with the last build's children (the
// same bones joined at the same params).
void MomentArmIndex::mark_kept_regions(const LoadTree& tree) {
  region_kept_.assign(bone_kept_.size(), 0);
  if (last_children_.size() != tree.children.size()) return;
  for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it) {
    const int b = *it;
    bool kept = bone_kept_[b] != 0 && tree.children[b] == last_children_[b];
    for (const auto& [child, param] : tree.children[b]) {
      (void)param;
      kept = kept && region_kept_[child] != 0;
    }
    region_kept_[b] = kept;
  }
}

namespace {
// Largest squared distance from c to any point of the box (its farthest corner); -1 if empty.
inline double farthest_corner2(const Vec3& c, const Vec3& lo, const Vec3& hi) {
  if (lo.x() > hi.x()) return -1.0;
  double d = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double a = c[k] - lo[k], b = hi[k] - c[k];
    d += std::max(a * a, b * b);
  }
  return d;
}
}  // namespace

std::pair<double, Index> MomentArmIndex::farthest(int bone, int boundary, bool plus_side,
                                                  const Vec3& c) const {
  // Best-first branch and bound. Items (id < 0: bone -1 - id): node >= 1 of a bone's slab tree
  // (a leaf: one slab), or node 0: the bone's whole downstream subtree (its slabs and its
  // children's subtrees); (id >= 0: group id) node >= 1 of a slab's bucket tree.
  struct Item {
    double ub;  // squared distance to the box's farthest corner, mm^2
    std::int32_t id, node;
    bool operator<(const Item& o) const { return ub < o.ub; }
  };
  std::priority_queue<Item> heap;
  auto push_node = [&](int b, Index i) {
    const Index at = 2 * group_offset_[b] + i;
    const double ub = farthest_corner2(c, node_lo_[at], node_hi_[at]);
    if (ub >= 0) heap.push({ub, -1 - b, static_cast<std::int32_t>(i)});
  };
  auto push_subtree = [&](int b) {
    const double ub = farthest_corner2(c, subtree_lo_[b], subtree_hi_[b]);
    if (ub >= 0) heap.push({ub, -1 - b, 0});
  };
  const auto& params = slab_params_[bone];
  const double split = params[boundary];
  const Index slabs = group_offset_[bone + 1] - group_offset_[bone];
  // The downstream slabs [l, r) of this bone, as O(log n) disjoint tree nodes.
  Index l = plus_side ? boundary + 1 : 0, r = plus_side ? slabs : boundary + 1;
  for (l += slabs, r += slabs; l < r; l >>= 1, r >>= 1) {
    if (l & 1) push_node(bone, l++);
    if (r & 1) push_node(bone, --r);
  }
  for (const auto& [child, param] : tree_->children[bone]) {
    if (plus_side ? param >= split : param <= split) push_subtree(child);
  }
  double best = -1.0;
  Index best_vertex = -1;
  // Node i of group g's bucket tree, its bound passed: down to a bucket through the child with
  // the larger bound (the other one queued), then its vertices. A box whose bound is below the
  // best so far holds no vertex as far (nor one as far with a smaller index).
  auto descend = [&](Index g, Index i) {
    const Index first = bucket_offset_[g], k = bucket_offset_[g + 1] - first;
    const Vec3* lo = bucket_lo_.data() + 2 * first;
    const Vec3* hi = bucket_hi_.data() + 2 * first;
    while (i < k) {
      Index near = 2 * i, far = 2 * i + 1;
      double un = farthest_corner2(c, lo[near], hi[near]);
      double uf = farthest_corner2(c, lo[far], hi[far]);
      if (uf > un) {
        std::swap(near, far);
        std::swap(un, uf);
      }
      if (uf >= 0 && !(uf < best))
        heap.push({uf, static_cast<std::int32_t>(g), static_cast<std::int32_t>(far)});
      if (un < 0 || un < best) return;
      i = near;
    }
    const Group& bucket = buckets_[first + i - k];
    for (Index v = bucket.begin; v < bucket.end; ++v) {
      const double* p = vertices_ + 3 * static_cast<Index>(packed_index_[v]);
      const double dx = p[0] - c.x(), dy = p[1] - c.y(), dz = p[2] - c.z();
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 > best || (d2 == best && packed_index_[v] < best_vertex)) {
        best = d2;
        best_vertex = packed_index_[v];
      }
    }
  };
  while (!heap.empty()) {
    const Item item = heap.top();
    heap.pop();
    if (item.ub < best) break;  // (equal: it may hold a vertex of smaller index at the same d)
    if (item.id >= 0) {
      descend(item.id, item.node);
      continue;
    }
    const int b = -1 - item.id;
    const Index m = group_offset_[b + 1] - group_offset_[b];
    if (item.node == 0) {
      push_node(b, 1);
      for (const auto& [child, param] : tree_->children[b]) {
        (void)param;
        push_subtree(child);
      }
    } else if (item.node < m) {
      push_node(b, 2 * item.node);
      push_node(b, 2 * item.node + 1);
    } else {
      // A slab: its bucket tree's root has the slab's box (the bound just passed).
      descend(group_offset_[b] + item.node - m, 1);
    }
  }
  if (best_vertex < 0) return {0.0, -1};
  return {std::sqrt(best), best_vertex};
}

}  // namespace osteon
