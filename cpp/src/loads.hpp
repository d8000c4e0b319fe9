// Load analysis (paper §4.4): the skeleton re-rooted at the held bone, and moment arms.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/skeleton.hpp"

namespace osteon {

/// The skeleton as a tree rooted at the held point. Bones are joined to their parent where their
/// head projects onto it; extra root bones (IK, props) are joined to the nearest bone of the main
/// tree. Moving away from the hold, every bone is entered at `entry_param` (mm from its head).
struct LoadTree {
  int held_bone = 0;                ///< bone the object is held by (at its head)
  std::vector<int> parent;          ///< B re-rooted parent, -1 for the held bone
  std::vector<double> entry_param;  ///< B where each bone is entered from the root side, mm
  std::vector<std::vector<std::pair<int, double>>> children;  ///< B lists (child, attach param mm)
  std::vector<int> order;           ///< bones in breadth-first order from the held bone
  std::vector<int> attached_roots;  ///< extra root bones joined to the main tree
};

/// Builds the load tree. held_bone = -1 holds the main root's head (the root whose tree has most
/// vertices); vertex_count_per_bone gives the vertices bound to each bone (may be empty).
LoadTree build_load_tree(const Skeleton& skeleton, int held_bone,
                         const std::vector<Index>& vertex_count_per_bone);

/// Moment arms by best-first branch and bound over (bone, slab) point groups: the farthest
/// downstream mesh point from a section centroid, exact. Each bone's slabs sit under a binary
/// tree of boxes, so one query visits O(log n) boxes of a bone with n slabs instead of n (the
/// cost per section stays flat as the section count grows).
class MomentArmIndex {
 public:
  /// vertex_bone: #V bone of each vertex; slab_params[b]: sorted section params along bone b (mm).
  /// skip (optional, #V): vertices that carry no load (loose pieces that fall off the print) are
  /// never a load point.
  MomentArmIndex(const MeshView& mesh, const Skeleton& skeleton, const LoadTree& tree,
                 const std::vector<int>& vertex_bone,
                 const std::vector<std::vector<double>>& slab_params,
                 const std::vector<std::uint8_t>* skip = nullptr);
  /// An empty index (build() before farthest()).
  MomentArmIndex() = default;
  /// (Re)builds the index, as the constructor; the storage of an earlier build is reused (an
  /// index kept across live runs allocates nothing once the mesh size is steady). `tree` and
  /// the mesh's vertices must outlive the index's use (farthest() reads them).
  /// `moved` (optional, #V): which vertices moved since the last build (live mode); a vertex
  /// that did not, on the same bone, whose bone's head, axis and slabs are bitwise the same,
  /// keeps its slab and angle from then (the same numbers: the index is the same).
  /// `moved_list` (with `moved`: the moved vertices, each once): when every vertex keeps its bone
  /// and every bone its number of slabs and of buckets per slab, a bone with no moved vertex
  /// whose head, axis and slabs are the last build's keeps its part of the index as it is (the
  /// same bits: bone_kept) and only the other bones' vertices are grouped and packed again.
  /// `threads` (0 = all cores): a full build of kVerticesPerPass vertices or more is split over
  /// that many workers (the same index).
  void build(const MeshView& mesh, const Skeleton& skeleton, const LoadTree& tree,
             const std::vector<int>& vertex_bone,
             const std::vector<std::vector<double>>& slab_params,
             const std::vector<std::uint8_t>* skip = nullptr,
             const std::vector<std::uint8_t>* moved = nullptr,
             const std::vector<std::int32_t>* moved_list = nullptr, int threads = 1);
  /// The next build computes every vertex's slab anew (its inputs are not the last build's).
  void forget_slabs() {
    slabs_known_ = false;
    region_kept_.clear();
  }
  /// Whether this build kept bone b's part of the index and that of every bone beyond it in the
  /// tree, the tree unchanged: any farthest() query of b gives the last build's answer.
  bool region_kept(int bone) const {
    return bone < static_cast<int>(region_kept_.size()) && region_kept_[bone] != 0;
  }

  /// Farthest downstream vertex from `center` (mm) for a section of `bone` at slab boundary
  /// `boundary` (index into slab_params[bone]); downstream is the far side (plus = beyond the
  /// param). Returns (distance mm, vertex index or -1 when nothing is downstream); of vertices at
  /// the same distance, the smallest index.
  std::pair<double, Index> farthest(int bone, int boundary, bool plus_side,
                                    const Vec3& center) const;

 private:
  struct Group {
    Vec3 lo, hi;
    Index begin = 0, end = 0;
  };
  const LoadTree* tree_ = nullptr;
  std::vector<std::vector<double>> slab_params_;
  std::vector<Index> group_offset_;  // B+1: first group of each bone
  std::vector<Group> groups_;        // slabs of every bone
  // Per bone b with m groups, a bottom-up binary tree over them: node i in [1, 2m) at
  // node_lo_/node_hi_[2 * group_offset_[b] + i]; leaves m + j are group j, node i < m the box of
  // nodes 2i and 2i+1.
  std::vector<Vec3> node_lo_, node_hi_;
  std::vector<Vec3> subtree_lo_, subtree_hi_;
  // Each slab's vertices in buckets of ~16 (sectors around the bone axis: a slab's skin is a
  // ring, a sector a short arc with a small box), under the same kind of tree: group g with k
  // buckets has node i in [1, 2k) at bucket_lo_/bucket_hi_[2 * bucket_offset_[g] + i].
  std::vector<Index> bucket_offset_;  // G+1: first bucket of each group
  std::vector<Group> buckets_;        // packed vertex ranges [begin, end) and boxes
  std::vector<Vec3> bucket_lo_, bucket_hi_;
  // The vertices grouped by (bone, slab) and bucket: each one's index into the mesh of the last
  // build, whose coordinates (vertices_, xyz interleaved, mm) the queries read. (No packed copy
  // of the coordinates: on a 1.5M-face mesh that was 18 MB of fresh pages per one-off analysis
  // for a few hundred queries.) Written in full by build(), so left uninitialized on allocation.
  const double* vertices_ = nullptr;
  std::unique_ptr<std::int32_t[]> packed_index_;
  Index packed_capacity_ = 0;  // vertices packed_index_ has room for
  // The steps of build(): vertices into groups (slabs), groups into buckets, the box trees.
  void group_vertices(const MeshView& mesh, const Skeleton& skeleton,
                      const std::vector<int>& vertex_bone, const std::vector<std::uint8_t>* skip,
                      const std::uint8_t* moved, bool keep_slabs, int chunks);
  void pack_buckets(const MeshView& mesh, const std::vector<std::uint8_t>* skip, int chunks);
  void build_box_trees(const LoadTree& tree, int chunks);
  // A bone's frame for placing its vertices, computed once per build: its head and axis, two
  // perpendiculars (the pseudo-angle's u, v) and its slab params with the search's constants.
  struct BoneFrame {
    Vec3 head, axis, u, v;
    const double* params = nullptr;  // slab_params_[b]
    Index count = 0;                 // its size
    double first = 0, last = 0;      // params[0], params[count - 1]
    double scale = 0;                // (count - 1) / (last - first): the search's first guess
  };
  void set_frames(const Skeleton& skeleton);
  Index place_vertex(const MeshView& mesh, Index v, int b);
  void pack_vertex(const MeshView& mesh, Index v, Group& bucket, Index k);
  void bucket_tree(Index g);
  void bone_tree(int b);
  // Scratch of build(), kept for its storage.
  std::unique_ptr<std::int32_t[]> vertex_group_;  // (32 bits: less memory to stream)
  std::unique_ptr<float[]> vertex_angle_;
  Index vertex_capacity_ = 0;  // vertices vertex_group_ and vertex_angle_ have room for
  std::vector<Index> group_count_, bucket_fill_;
  std::vector<std::vector<Index>> chunk_count_;  // per chunk of vertices: group or bucket counts
  std::vector<BoneFrame> frames_;
  // Each kept vertex's slab (group) and what it was computed from, kept for the next build
  // (builds with `moved`, live mode: a one-off build neither allocates nor writes the slabs).
  std::unique_ptr<std::int32_t[]> vertex_slab_;
  Index slab_capacity_ = 0;
  bool slabs_known_ = false;
  std::vector<int> last_bone_;
  std::vector<Vec3> last_head_, last_axis_;
  std::vector<std::vector<double>> last_slab_params_;
  std::vector<std::uint8_t> last_skip_;
  // Per bone, whether the last build's slabs of its unmoved vertices still hold.
  std::vector<std::uint8_t> bone_same_;
  // Live builds: each bone's kept vertices in vertex order (CSR over last_bone_), the last
  // build's slab count per bone (group_offset_), its tree, and which bones (and regions) this
  // build kept.
  std::vector<Index> bone_vertex_start_, last_group_offset_;
  std::vector<std::int32_t> bone_vertices_;
  std::vector<std::vector<std::pair<int, double>>> last_children_;
  std::vector<std::uint8_t> bone_kept_, region_kept_;
  bool rebuild_moved_bones(const MeshView& mesh, const Skeleton& skeleton,
                           const std::uint8_t* moved, const std::vector<std::int32_t>& moved_list);
  void regroup_bone(const MeshView& mesh, int b, const std::uint8_t* moved);
  void repack_bone(const MeshView& mesh, int b);
  void move_buckets();
  std::vector<Index> next_bucket_offset_;  // scratch of rebuild_moved_bones
  std::vector<Group> next_buckets_;
  std::vector<Vec3> next_lo_, next_hi_;
  void subtree_boxes(const LoadTree& tree);
  void mark_kept_regions(const LoadTree& tree);
  bool compare_with_last_build(const Skeleton& skeleton, const std::vector<std::uint8_t>* skip);
  void remember_build(const Skeleton& skeleton, const std::vector<int>& vertex_bone,
                      const std::vector<std::uint8_t>* skip, bool kept);
};

}  // namespace osteon
