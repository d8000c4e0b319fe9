// The plane cut: plane frames and the segments where planes cross the mesh's triangles
// (see osteon/slicer.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <type_traits>
#include <vector>

#include "cell_cut.hpp"
#include "osteon/slicer.hpp"

namespace osteon {
namespace {

using detail::emit_segment;

// True when the segment a-b (mm) comes within the region's radius of its axis line (a ball: of
// its point). One formula for every cut, so whether a triangle's segment counts depends on the
// segment alone (not on the grid cell it was filed in), and is monotone in the radius: a
// segment that meets a region meets every wider one around the same axis.
inline bool segment_meets(const CutRegion& region, const Vec3& a, const Vec3& b) {
  Vec3 p = a - region.point, q = b - region.point;
  p -= p.dot(region.axis) * region.axis;
  q -= q.dot(region.axis) * region.axis;
  const double r2 = region.radius * region.radius;
  if (p.squaredNorm() <= r2 || q.squaredNorm() <= r2) return true;
  const Vec3 d = q - p;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp(-p.dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p + t * d).squaredNorm() <= r2;
}

// Which segments a cut keeps: those meeting `region` (if any) and not `exclude` (if any).
struct SegmentFilter {
  const CutRegion* region;
  const CutRegion* exclude;
  bool keeps(const Vec3 world[2]) const {
    return (region == nullptr || segment_meets(*region, world[0], world[1])) &&
           (exclude == nullptr || !segment_meets(*exclude, world[0], world[1]));
  }
};

// How far (mm) the cells' tests widen a region (and narrow `exclude`): more than the rounding
// of segment_meets and of the segments' points, so that a cell the grid skips holds no segment
// the filter would keep.
inline double region_slack(const CutRegion& region) {
  return 1e-9 * (region.radius + region.point.cwiseAbs().maxCoeff());
}

}  // namespace

PlaneFrame PlaneFrame::make(const Vec3& origin, const Vec3& normal) {
  PlaneFrame f;
  f.origin = origin;
  f.normal = normal.normalized();
  // Pick the world axis least aligned with the normal to build u deterministically.
  Vec3 helper = Vec3::UnitX();
  const Vec3 a = f.normal.cwiseAbs();
  if (a.x() <= a.y() && a.x() <= a.z())
    helper = Vec3::UnitX();
  else if (a.y() <= a.z())
    helper = Vec3::UnitY();
  else
    helper = Vec3::UnitZ();
  f.u = (helper - helper.dot(f.normal) * f.normal).normalized();
  f.v = f.normal.cross(f.u);
  return f;
}

namespace {

// False only when the box (center, half extents, mm) surely misses the region; a box that
// overflowed (NaN: coordinates near the double range, where a float overhang is infinite) may
// meet it. The box's test must never drop a cell that holds a segment the filter keeps.
bool box_may_meet(const CutRegion& region, const Vec3& center, const Vec3& half) {
  Vec3 d = center - region.point;
  d -= d.dot(region.axis) * region.axis;
  const double reach = region.radius + half.norm();
  return !(d.squaredNorm() > reach * reach);
}

// Calls cell_fn(c) for each cell meeting a slab that may hold a triangle the region filter
// keeps, in the grid's order. `per_segment` (cut_mesh's region test per segment): the cells
// whose box may reach into `region` and does not lie wholly inside `exclude` -- which cells
// these are depends on the grid's layout, the segments kept do not (SegmentFilter decides each
// one). Otherwise the cells themselves are the filter: those whose box may reach into `region`
// and not into `exclude`.
template <class Fn>
void for_cells_in_slab(const FaceGrid& grid, const Vec3& n, double lo, double hi,
                       const CutRegion* region, const CutRegion* exclude, bool per_segment,
                       Fn&& cell_fn) {
  if (!per_segment) {
    for (Index k = 0; k < grid.num_blocks(); ++k) {
      if (!grid.block_meets(k, n, lo, hi, region)) continue;
      // A cell was visited by the `exclude` cut when both its block and itself are near
      // `exclude` (the two tests are not nested: a cell's bounding sphere may stick out of its
      // block's).
      const bool block_excluded = exclude != nullptr && grid.block_near(k, *exclude);
      if (block_excluded && grid.block_within(k, *exclude)) continue;
      for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c) {
        if (!grid.meets(c, n, lo, hi, region)) continue;
        if (block_excluded && grid.near(c, *exclude)) continue;
        cell_fn(c);
      }
    }
    return;
  }
  CutRegion wider, narrower;
  if (region != nullptr) {
    wider = *region;
    wider.radius += region_slack(*region);
  }
  if (exclude != nullptr) {
    narrower = *exclude;
    narrower.radius -= region_slack(*exclude);
  }
  for (Index k = 0; k < grid.num_blocks(); ++k) {
    if (!grid.block_meets(k, n, lo, hi)) continue;
    if (region != nullptr && !box_may_meet(wider, grid.block_center(k), grid.block_half(k)))
      continue;
    if (exclude != nullptr && grid.block_within(k, narrower)) continue;
    for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c) {
      if (!grid.meets(c, n, lo, hi)) continue;
      if (region != nullptr && !box_may_meet(wider, grid.cell_center(c), grid.cell_half(c)))
        continue;
      if (exclude != nullptr && narrower.holds_box(grid.cell_center(c), grid.cell_half(c)))
        continue;
      cell_fn(c);
    }
  }
}

// Visits the triangles (vertex index triples) of the cells for_cells_in_slab visits, or all
// triangles.
template <class Fn>
void for_faces_in_slab(const MeshView& mesh, const FaceGrid* grid, const Vec3& n, double lo,
                       double hi, const CutRegion* region, const CutRegion* exclude,
                       bool per_segment, Fn&& fn) {
  if (grid == nullptr) {
    for (Index f = 0; f < mesh.num_faces; ++f) fn(mesh.faces + 3 * f);
    return;
  }
  for_cells_in_slab(*grid, n, lo, hi, region, exclude, per_segment, [&](Index c) {
    const std::int32_t* t = grid->faces() + 3 * grid->begin(c);
    for (Index f = grid->begin(c); f < grid->end(c); ++f, t += 3) fn(t);
  });
}

}  // namespace

void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out,
              const FaceGrid* grid, const CutRegion* region, const CutRegion* exclude,
              bool per_segment) {
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  const SegmentFilter filter{region, exclude};
  // Without a grid a region is always decided per segment (there are no cells to decide by).
  per_segment = per_segment || grid == nullptr;
  const bool filtered = per_segment && (region != nullptr || exclude != nullptr);
  // Face f given its corners' heights.
  auto cut_face_at = [&](const std::int32_t* f, double height[3]) {
    const bool above[3] = {height[0] >= 0.0, height[1] >= 0.0, height[2] >= 0.0};
    if (above[0] == above[1] && above[1] == above[2]) return;
    if (!filtered) {  // written in place: no copy, no mesh-coordinate endpoints
      emit_segment(mesh, plane, f, above, height, out.emplace_back(), nullptr);
      return;
    }
    CutSegment seg;
    Vec3 world[2];
    emit_segment(mesh, plane, f, above, height, seg, world);
    if (filter.keeps(world)) out.push_back(seg);
  };
  auto cut_face = [&](const std::int32_t* f) {
    double height[3];
    for (int k = 0; k < 3; ++k) {
      const double* p = mesh.vertices + 3 * static_cast<Index>(f[k]);
      height[k] = p[0] * nx + p[1] * ny + p[2] * nz - offset;
    }
    cut_face_at(f, height);
  };
  if (grid == nullptr || !grid->tight_bounds()) {
    for_faces_in_slab(mesh, grid, plane.normal, offset, offset, region, exclude, per_segment,
                      cut_face);
    return;
  }
  // The same cells, but a cell or a run of its faces whose tight box the plane misses is skipped
  // with one test: none of its faces would give a segment (FaceGrid::enable_tight_bounds).
  thread_local std::vector<double> cell_heights;
  std::vector<double>& heights = cell_heights;
  auto no_window = [](const Vec3&, const Vec3&) { return false; };
  for_cells_in_slab(*grid, plane.normal, offset, offset, region, exclude, per_segment,
                    [&](Index c) {
                      detail::cut_cell_faces(mesh, *grid, c, plane.normal, offset, no_window,
                                             heights, cut_face_at);
                    });
}

void cut_mesh_parallel(const MeshView& mesh, const PlaneFrame& plane, double spacing, int count,
                       std::vector<std::vector<CutSegment>>& out, const FaceGrid* grid,
                       const CutRegion* region, const std::uint8_t* wanted,
                       const CutRegion* exclude) {
  out.resize(count);
  for (auto& o : out) o.clear();
  if (count <= 0) return;
  int first = 1, last = count;
  if (wanted != nullptr) {
    while (first <= count && !wanted[first - 1]) ++first;
    while (last >= first && !wanted[last - 1]) --last;
    if (first > last) return;
  }
  // Height and bucket of each vertex (with a grid: of each entry of the visited cells, a
  // vertex shared by cells once per cell; without: of every vertex): the bucket is the number of
  // planes at or below the vertex (clamped to 0..count), so a triangle crosses plane k exactly
  // when its vertices' buckets straddle k, and most triangles are rejected with three integer
  // loads. The same formula either way, so the same bits.
  // (Per-thread buffers, uninitialized: every entry read was written first in this call.)
  thread_local std::unique_ptr<double[]> height;
  thread_local std::unique_ptr<std::int32_t[]> bucket;
  thread_local Index capacity = 0;
  const Index size = grid != nullptr ? grid->num_entries() : mesh.num_vertices;
  if (capacity < size) {
    height.reset(new double[size]);
    bucket.reset(new std::int32_t[size]);
    capacity = size;
  }
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  const double inv = 1.0 / spacing;
  const double top = static_cast<double>(count);
  double* __restrict ht = height.get();
  std::int32_t* __restrict bk = bucket.get();
  // Heights and buckets of vertices begin .. end.
  auto heights = [&](const double* __restrict x, const double* __restrict y,
                     const double* __restrict z, Index begin, Index end, auto stride) {
    for (Index v = begin; v < end; ++v) {
      const double t = x[stride * v] * nx + y[stride * v] * ny + z[stride * v] * nz - offset;
      ht[v] = t;
      // Clamped first, so truncation is floor (and vectorizes, unlike std::floor without SSE4.1).
      const double q = t * inv;
      bk[v] = static_cast<std::int32_t>(q < 0.0 ? 0.0 : (q > top ? top : q));
    }
  };
  // Face f (mesh vertex indices) whose corners' heights are ht[e[0..2]].
  auto cut_face = [&](const std::int32_t* f, const std::int32_t* e) {
    const std::int32_t b[3] = {bk[e[0]], bk[e[1]], bk[e[2]]};
    // Most faces lie between two planes: one test, nothing else computed first.
    if (((b[0] ^ b[1]) | (b[1] ^ b[2])) == 0) return;
    const std::int32_t lo = std::max(std::min({b[0], b[1], b[2]}), first - 1);
    const std::int32_t hi = std::min(std::max({b[0], b[1], b[2]}), last);
    for (std::int32_t k = lo + 1; k <= hi; ++k) {
      if (wanted != nullptr && !wanted[k - 1]) continue;
      const double c = k * spacing;
      bool above[3];
      double h[3];
      for (int j = 0; j < 3; ++j) {
        above[j] = b[j] >= k;
        h[j] = ht[e[j]] - c;
      }
      // Written in place (no copy); the mesh-coordinate endpoints are not needed here.
      emit_segment(mesh, plane, f, above, h, out[k - 1].emplace_back(), nullptr);
    }
  };
  if (grid == nullptr) {
    const double* x = mesh.vertices;
    heights(x, x + 1, x + 2, 0, mesh.num_vertices, std::integral_constant<Index, 3>());
    for (Index f = 0; f < mesh.num_faces; ++f) cut_face(mesh.faces + 3 * f, mesh.faces + 3 * f);
    return;
  }
  // Only the visited cells' vertices, from the grid's contiguous copies: first the cells, then
  // the heights of each run of consecutive cells in one loop (vectorized; a cell alone has too
  // few vertices to pay for the loop's setup), then the faces.
  const double *gx = grid->entry_x(), *gy = grid->entry_y(), *gz = grid->entry_z();
  const std::int32_t* faces = grid->faces();
  const std::int32_t* entries = grid->face_entries();
  thread_local std::vector<Index> visited_cells;
  std::vector<Index>& visited = visited_cells;
  visited.clear();
  for_cells_in_slab(*grid, plane.normal, offset + first * spacing, offset + last * spacing, region,
                    exclude, false, [&](Index c) { visited.push_back(c); });
  for (std::size_t i = 0, j = 0; i < visited.size(); i = j) {
    for (j = i + 1; j < visited.size() && visited[j] == visited[j - 1] + 1;) ++j;
    heights(gx, gy, gz, grid->vertex_begin(visited[i]), grid->vertex_end(visited[j - 1]),
            std::integral_constant<Index, 1>());
  }
  for (const Index c : visited)
    for (Index k = 3 * grid->begin(c), stop = 3 * grid->end(c); k < stop; k += 3)
      cut_face(faces + k, entries + k);
}

}  // namespace osteon
