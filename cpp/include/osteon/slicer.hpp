// Plane-mesh slicing into closed loops, and the choice of the section around a bone
// (docs/method.md, Sections).
// Implemented in cpp/src/slicer_grid.cpp (FaceGrid, line_crossings), slicer_cut.cpp (PlaneFrame,
// cut_mesh, cut_mesh_parallel), slicer_loops.cpp (assemble_loops) and slicer.cpp
// (select_section, slice_section).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/section.hpp"

namespace osteon {

/// Per-section flags (bit mask) saying how a section was obtained; 0 = clean closed cut.
enum SectionFlag : std::uint32_t {
  kFlagGapClosed = 1u << 0,    ///< open polylines were joined across gaps <= the gap tolerance
  kFlagOpen = 1u << 1,         ///< an open polyline touches this section: it may be incomplete
  kFlagOutside = 1u << 2,      ///< the bone point lies in no material: the bone's own region used
  kFlagHollow = 1u << 3,       ///< the bone point lies in a real hole: the wall around it is used
  kFlagEmpty = 1u << 4,        ///< nothing usable was cut: section skipped (no stress)
  kFlagDegenerate = 1u << 5,   ///< zero area or singular second moment: section skipped
  kFlagNonManifold = 1u << 6,  ///< non-manifold edges were cut (more than two faces on an edge)
  kFlagUnreliable = 1u << 7,   ///< bone outside and no region tied to it: no number, left out
  kFlagTooThin = 1u << 8,   ///< thinner than the printable minimum: reported apart, not corrected
  kFlagJunction = 1u << 9,  ///< a side branch is cut: only the core that continues is counted
  kFlagNotch = 1u << 10,    ///< next to a concave corner: stress is the peak at it (Kt > 1)
};

/// An orthonormal plane frame: origin, unit normal and in-plane axes u, v (u x v = normal).
struct PlaneFrame {
  Vec3 origin = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  Vec3 u = Vec3::UnitX();
  Vec3 v = Vec3::UnitY();

  /// Frame with the given origin and (not necessarily unit) normal; u, v chosen deterministically.
  static PlaneFrame make(const Vec3& origin, const Vec3& normal);
  /// 2D coordinates (mm) of a 3D point, relative to the origin.
  Vec2 to_plane(const Vec3& p) const { return Vec2((p - origin).dot(u), (p - origin).dot(v)); }
  /// 3D point of 2D plane coordinates.
  Vec3 to_world(const Vec2& q) const { return origin + q.x() * u + q.y() * v; }
};

/// One triangle's cut: two endpoints, each on a mesh edge identified by its vertex pair.
struct CutSegment {
  std::uint64_t edge[2];  ///< (min vertex << 32) | max vertex of the edge each endpoint lies on
  Vec2 point[2];  ///< endpoints in plane coordinates, mm; point[0] -> point[1] keeps the face's
                  ///< orientation (outward-facing surfaces give counter-clockwise loops)
};

/// The closed loops (and leftover open polylines) of one plane cut, in plane coordinates.
struct PlaneCut {
  std::vector<std::vector<Vec2>> loops;        ///< closed loops (last point joins the first)
  std::vector<std::vector<Vec2>> open_chains;  ///< polylines that could not be closed
  std::uint32_t flags = 0;                     ///< kFlagGapClosed, kFlagNonManifold
};

/// A section's material region and how it was found.
struct SectionGeometry {
  SectionPolygon polygon;   ///< outer boundary + holes, plane coordinates (mm)
  std::uint32_t flags = 0;  ///< SectionFlag bits
  bool found = false;       ///< false when the section had to be skipped
  int containing = 0;       ///< number of closed loops around the bone point
};

/// A region (mm) a cut may be restricted to: the cylinder of `radius` around the line through
/// `point` along unit `axis`, or the ball of `radius` around `point` when `axis` is zero.
struct CutRegion {
  Vec3 point = Vec3::Zero();
  Vec3 axis = Vec3::Zero();
  double radius = 0.0;
  /// True when a box (center, half extents) may reach into the region.
  bool meets_box(const Vec3& center, const Vec3& half) const {
    Vec3 d = center - point;
    d -= d.dot(axis) * axis;
    const double reach = radius + half.norm();
    return d.squaredNorm() <= reach * reach;
  }
  /// True when a box (center, half extents) lies wholly inside the region.
  bool holds_box(const Vec3& center, const Vec3& half) const {
    Vec3 d = center - point;
    d -= d.dot(axis) * axis;
    return d.norm() + half.norm() <= radius;
  }
};

/// Triangles bucketed into a uniform grid of cells, each with the bounding box of its triangles,
/// so that a plane (or a slab of parallel planes) visits only the cells it passes through.
class FaceGrid {
 public:
  /// Buckets the faces of `mesh` (about faces_per_cell triangles per non-empty cell) on up to
  /// `threads` workers (0 = all cores); the result does not depend on the number of workers.
  /// `box_margin` > 0 widens the grid's box by that fraction of the mesh's extent on each side
  /// of each axis (live mode: later poses that move a limb a little further stay inside it, so
  /// that refile() can keep the layout).
  void build(const MeshView& mesh, int faces_per_cell = 12, int threads = 0,
             double box_margin = 0.0);
  /// Live mode: the grid keeps the layout (box, cells) of its last build() and re-files only the
  /// faces listed in `moved` (indices into mesh.faces, the faces of the last build, at most one
  /// entry each; every other face's vertices must be bitwise those the grid last filed). The
  /// result is what build() gives with that layout, not with this mesh's own (a query may take
  /// its faces in another order than a fresh build's). The cells before the first one a moved
  /// face leaves or enters (in the grid's numbering) keep their faces, boxes and vertex entries
  /// as they are; the later ones are redone. Returns false, leaving the grid as it
  /// was, when it cannot: no layout kept, another face count, a moved face's vertex outside the
  /// kept box, or more than a quarter of the faces moved (then call build()).
  bool refile(const MeshView& mesh, const std::int32_t* moved, Index count, int threads = 0);
  /// Number of non-empty cells.
  Index num_cells() const { return static_cast<Index>(center_.size()); }
  /// Cell c's faces are faces()[3*begin(c) .. 3*end(c)) (vertex indices, reordered copy).
  Index begin(Index c) const { return start_[c]; }
  Index end(Index c) const { return start_[c + 1]; }
  const std::int32_t* faces() const { return faces_.get(); }
  /// Cell c's distinct vertices ("entries", a vertex shared by k cells has k) are entries
  /// vertex_begin(c) .. vertex_end(c): mesh vertex entry_vertex()[e], coordinates (mm)
  /// entry_x()[e], entry_y()[e], entry_z()[e] (bit-exact copies, laid out so that a cut computes
  /// the heights of a cell's vertices in one contiguous, vectorized pass).
  Index vertex_begin(Index c) const { return vstart_[c]; }
  Index vertex_end(Index c) const { return vstart_[c + 1]; }
  /// Number of entries (#entries; between #V used and 3 #F).
  Index num_entries() const { return vstart_.empty() ? 0 : vstart_.back(); }
  /// Mesh vertex index of each entry (#entries).
  const std::int32_t* entry_vertex() const { return entry_vertex_.get(); }
  /// x, y, z coordinate of each entry (#entries each), mm.
  const double* entry_x() const { return entry_x_.get(); }
  const double* entry_y() const { return entry_y_.get(); }
  const double* entry_z() const { return entry_z_.get(); }
  /// Corner k of faces() (3 #F) as an entry of its cell: entry_vertex()[face_entries()[k]] ==
  /// faces()[k].
  const std::int32_t* face_entries() const { return face_entries_.get(); }
  /// Cell c's box (centre and half extents, mm): its grid box widened by its triangles' overhang.
  const Vec3& cell_center(Index c) const { return center_[c]; }
  const Vec3& cell_half(Index c) const { return half_[c]; }
  /// True when cell c's box meets the slab lo <= dot(n, x) <= hi (and the region, if any).
  bool meets(Index c, const Vec3& n, double lo, double hi,
             const CutRegion* region = nullptr) const {
    const double mid = n.dot(center_[c]);
    const double r = n.cwiseAbs().dot(half_[c]);
    if (mid + r < lo || mid - r > hi) return false;
    return region == nullptr || region->meets_box(center_[c], half_[c]);
  }
  /// True when cell c's box may be touched by the region.
  bool near(Index c, const CutRegion& region) const {
    return region.meets_box(center_[c], half_[c]);
  }
  /// Blocks group neighbouring cells: block k holds cells block_begin(k) .. block_end(k).
  Index num_blocks() const { return static_cast<Index>(block_center_.size()); }
  Index block_begin(Index k) const { return block_start_[k]; }
  Index block_end(Index k) const { return block_start_[k + 1]; }
  /// Block k's box (centre and half extents, mm): the box of its cells' boxes.
  const Vec3& block_center(Index k) const { return block_center_[k]; }
  const Vec3& block_half(Index k) const { return block_half_[k]; }
  /// True when block k's box may be touched by the region.
  bool block_near(Index k, const CutRegion& region) const {
    return region.meets_box(block_center_[k], block_half_[k]);
  }
  /// True when block k's box (and so each of its cells) lies wholly inside the region.
  bool block_within(Index k, const CutRegion& region) const {
    return region.holds_box(block_center_[k], block_half_[k]);
  }
  /// Calls fn(t) with the 3 vertex indices of each face of the cells whose box may reach into
  /// `region` (block by block, cell by cell): every face that meets the region is among them.
  template <class Fn>
  void for_faces_near(const CutRegion& region, Fn&& fn) const {
    for (Index k = 0; k < num_blocks(); ++k) {
      if (!block_near(k, region)) continue;
      for (Index c = block_begin(k); c < block_end(k); ++c) {
        if (!near(c, region)) continue;
        const std::int32_t* t = faces() + 3 * begin(c);
        for (Index f = begin(c); f < end(c); ++f, t += 3) fn(t);
      }
    }
  }
  /// True when block k's box meets the slab lo <= dot(n, x) <= hi (and the region, if any).
  bool block_meets(Index k, const Vec3& n, double lo, double hi,
                   const CutRegion* region = nullptr) const {
    const double mid = n.dot(block_center_[k]);
    const double r = n.cwiseAbs().dot(block_half_[k]);
    if (mid + r < lo || mid - r > hi) return false;
    return region == nullptr || region->meets_box(block_center_[k], block_half_[k]);
  }

  /// Tight bounds (for cut_mesh): a cell's box above holds its triangles with room to spare (the
  /// grid box widened by the farthest overhang), so a plane meets many cells whose triangles it
  /// does not cross. With tight bounds on, the first cut that visits a cell also records the
  /// bounding box of its triangles' vertices, and of each run of kGroup consecutive faces of the
  /// cell (widened by the same few ulps as the cell boxes), and every cut skips a cell or a run
  /// whose tight box the plane misses: none of its faces would give a segment, so the segments and
  /// their order are those of the face-by-face visit (which cells are visited, by the slab and the
  /// regions, does not change). Safe with concurrent cuts; the boxes are those of the mesh the grid
  /// was built from (as every cut assumes). Off until enable_tight_bounds(); build() turns them
  /// off.
  static constexpr Index kGroup = 4;
  /// Turns tight bounds on (allocation only: nothing is computed until a cut visits a cell).
  void enable_tight_bounds();
  /// True when enable_tight_bounds() ran after the last build().
  bool tight_bounds() const { return tight_on_; }
  /// Cell c's tight boxes (tight bounds on): `cell` (center, half extents) and its groups' (cell
  /// c's faces begin(c) + kGroup * j .. : group j; group_center[j], group_half[j]), mm.
  struct TightBoxes {
    Vec3* cell = nullptr;  // [2]: center, half extents
    Vec3* group_center = nullptr;
    Vec3* group_half = nullptr;
  };
  /// kReady: cell c's boxes are there (read them); kMine: the caller is the first to visit c and
  /// must compute them (bound_cell); kBusy: another thread is computing them (visit the faces
  /// one by one).
  enum class Tight { kReady, kMine, kBusy };
  /// (Inline: every cell a cut visits calls it.)
  Tight tight_boxes(Index c, TightBoxes& boxes) const {
    TightData& t = tight_;
    boxes.cell = &t.cell_box[2 * c];
    boxes.group_center = t.group_center.data() + t.group_start[c];
    boxes.group_half = t.group_half.data() + t.group_start[c];
    std::atomic<std::uint8_t>& state = tight_state_[c];
    if (state.load(std::memory_order_acquire) == 2) return Tight::kReady;
    std::uint8_t none = 0;
    return state.compare_exchange_strong(none, 1, std::memory_order_acq_rel) ? Tight::kMine
                                                                             : Tight::kBusy;
  }
  /// Writes cell c's boxes (from its entries: copies of `mesh`, the grid's mesh) and makes them
  /// visible to every cut; only the thread that got kMine for c.
  void bound_cell(Index c, const MeshView& mesh, const TightBoxes& boxes) const;

 private:
  // Lazily computed tight boxes (see enable_tight_bounds).
  struct TightData {
    std::vector<Index> group_start;  // cell c's groups: group_start[c] .. group_start[c + 1]
    std::vector<Vec3> cell_box, group_center, group_half;  // cell_box: 2 per cell
  };
  /// An array written in full before it is read (so never zero-filled) whose storage outlives a
  /// build: a grid rebuilt on every live update reuses it instead of touching fresh pages.
  template <class T>
  struct Buffer {
    std::unique_ptr<T[]> data;
    std::size_t capacity = 0;
    /// Room for n elements (contents unspecified).
    T* reserve(std::size_t n) {
      if (n > capacity) {
        data.reset(new T[n]);
        capacity = n;
      }
      return data.get();
    }
    T* get() const { return data.get(); }
    T& operator[](std::size_t i) const { return data[i]; }
    /// Room for n elements, the first `keep` kept.
    T* grow(std::size_t n, std::size_t keep) {
      if (n > capacity) {
        std::unique_ptr<T[]> bigger(new T[n]);
        std::copy(data.get(), data.get() + keep, bigger.get());
        data = std::move(bigger);
        capacity = n;
      }
      return data.get();
    }
  };
  // Tight boxes: storage kept across builds, valid while tight_on_ (filled lazily by const cuts).
  mutable TightData tight_;
  Buffer<std::atomic<std::uint8_t>> tight_state_;
  bool tight_on_ = false;
  double slack_ = 0.0;  // mm: how far every box is widened (a few ulps of the coordinates)
  std::vector<Vec3> center_, half_;
  std::vector<Index> start_;
  Buffer<std::int32_t> faces_;  // 3 #F
  std::vector<Index> vstart_;   // cell c's entries: vstart_[c] .. [c + 1]
  Buffer<std::int32_t> entry_vertex_, face_entries_;
  Buffer<double> entry_x_, entry_y_, entry_z_;
  // The steps of build() (slicer_grid.cpp): the grid's size and cell numbering, each face into
  // the cell of its centroid (per worker part), the faces sorted by cell, the non-empty cells and
  // blocks with their boxes, and each cell's vertex entries.
  struct Layout;
  Layout layout(const MeshView& mesh, int faces_per_cell, int parts, double box_margin) const;
  void bin_faces(const MeshView& mesh, const Layout& grid, int parts);
  void sort_faces_by_cell(const MeshView& mesh, Index total, int parts);
  void collect_cells(const Layout& grid);
  void build_entries(const MeshView& mesh, int parts);
  void finish_build(const MeshView& mesh, const Layout& grid, int parts);
  static Index file_face(const MeshView& mesh, const Layout& grid, const std::int32_t* corners,
                         float& reach);
  void refile_from(const MeshView& mesh, const Layout& grid, Index first, const std::int32_t* moved,
                   Index count);
  void entries_from(const MeshView& mesh, Index k0);
  // Entries [begin, end) from the vertex list (their coordinates from mesh).
  void write_entries(const MeshView& mesh, const std::int32_t* list, Index begin, Index end);
  // The last build's layout (refile keeps it) and each face's cell (cell_of_) and overhang.
  std::shared_ptr<const Layout> kept_layout_;
  Index kept_faces_ = -1;
  Buffer<float> face_reach_;
  std::vector<Vec3> block_center_, block_half_;
  std::vector<Index> block_start_;
  // Scratch of build() and build_entries(), kept for its storage.
  Buffer<std::int32_t> cell_of_;
  std::vector<std::int32_t> old_cell_;  // refile(): each moved face's cell before
  std::vector<std::vector<Index>> part_count_;
  std::vector<std::vector<float>> part_overhang_;
  Buffer<Index> cell_start_;
  std::vector<Buffer<std::int32_t>> part_lists_;
  std::vector<std::vector<std::int32_t>> part_slots_;
};

/// Cuts every triangle of the mesh that crosses the plane; appends to `out`. With a grid only
/// the cells the plane passes through are visited; with a region only cells near it; with
/// `exclude` (grid only) not the cells near that region, so that a cut grown from `exclude` to
/// `region` adds exactly the triangles the smaller cut left out. With `per_segment` (and always
/// without a grid) the region is decided per triangle instead: a triangle is cut when its own
/// segment comes within the region's radius of its axis or point (and not within `exclude`'s),
/// so which triangles are cut -- where a loop around the region's point is clipped open -- does
/// not depend on the grid's layout. (A cut and its grown cuts must use the same mode.)
void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out,
              const FaceGrid* grid = nullptr, const CutRegion* region = nullptr,
              const CutRegion* exclude = nullptr, bool per_segment = false);

/// Cuts the mesh by `count` parallel planes base + k*spacing*normal, k = 1..count, in one pass.
/// out[k-1] receives plane k's segments, in coordinates of the frame `plane` (whose origin is
/// base). With `wanted` (count flags) only the planes k with wanted[k-1] != 0 are cut; region and
/// exclude as for cut_mesh.
void cut_mesh_parallel(const MeshView& mesh, const PlaneFrame& plane, double spacing, int count,
                       std::vector<std::vector<CutSegment>>& out, const FaceGrid* grid = nullptr,
                       const CutRegion* region = nullptr, const std::uint8_t* wanted = nullptr,
                       const CutRegion* exclude = nullptr);

/// Sorted parameters s (mm) where the line point + s*dir (dir unit) crosses mesh triangles; a
/// point of the line is inside a closed mesh when an odd number of crossings lie beyond it.
std::vector<double> line_crossings(const MeshView& mesh, const FaceGrid& grid, const Vec3& point,
                                   const Vec3& dir);

/// Links cut segments into loops by shared mesh edges; joins open ends closer than gap_tolerance
/// (mm).
PlaneCut assemble_loops(const std::vector<CutSegment>& segments, double gap_tolerance);

/// The material region around the plane origin (the bone point; docs/method.md, Sections):
/// select_region (cpp/src/region_choice.hpp) without a bone domain (the non-zero-winding union
/// of the loops; a bone outside the mesh gets the nearest region, flagged kFlagOutside).
SectionGeometry select_section(const PlaneCut& cut);

/// Convenience: cut, assemble and select the section of one plane (origin = bone point).
SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance);

}  // namespace osteon
