// The plane cut: plane frames and the segments where planes cross the mesh's triangles
// (see osteon/slicer.hpp).
#include <algorithm>
#include <cmath>
#include <vector>

#include "osteon/slicer.hpp"

namespace osteon {
namespace {

inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const std::uint32_t lo = static_cast<std::uint32_t>(std::min(a, b));
  const std::uint32_t hi = static_cast<std::uint32_t>(std::max(a, b));
  return (static_cast<std::uint64_t>(lo) << 32) | hi;
}

// Cut of triangle (a, b, c) given per-vertex "above" flags and signed heights (height 0 = plane).
// Exactly two edges change side; each gives an endpoint at linear interpolation of the heights.
// The segment keeps the face's orientation: it runs from the edge that goes down (above to below
// in the face's winding) to the edge that goes up, so that a closed outward-facing surface gives
// counter-clockwise loops in (u, v) and an inward-facing one clockwise loops.
inline void emit_segment(const MeshView& mesh, const PlaneFrame& plane, const std::int32_t* f,
                         const bool above[3], const double height[3], CutSegment& seg) {
  for (int e = 0; e < 3; ++e) {
    const int i = e, j = (e + 1) % 3;
    if (above[i] == above[j]) continue;
    const int n = above[i] ? 0 : 1;
    const double denom = height[j] - height[i];
    double lambda = denom != 0.0 ? -height[i] / denom : 0.5;
    lambda = std::clamp(lambda, 0.0, 1.0);
    const double* pi = mesh.vertices + 3 * static_cast<Index>(f[i]);
    const double* pj = mesh.vertices + 3 * static_cast<Index>(f[j]);
    const Vec3 p(pi[0] + lambda * (pj[0] - pi[0]), pi[1] + lambda * (pj[1] - pi[1]),
                 pi[2] + lambda * (pj[2] - pi[2]));
    seg.edge[n] = edge_key(f[i], f[j]);
    seg.point[n] = plane.to_plane(p);
  }
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

// Calls cell_fn(c) for each cell meeting a slab (and the region, and not near `exclude`), in the
// grid's order.
template <class Fn>
void for_cells_in_slab(const FaceGrid& grid, const Vec3& n, double lo, double hi,
                       const CutRegion* region, const CutRegion* exclude, Fn&& cell_fn) {
  for (Index k = 0; k < grid.num_blocks(); ++k) {
    if (!grid.block_meets(k, n, lo, hi, region)) continue;
    // A cell was visited by the `exclude` cut when both its block and itself are near `exclude`
    // (the two tests are not nested: a cell's bounding sphere may stick out of its block's).
    const bool block_excluded = exclude != nullptr && grid.block_near(k, *exclude);
    if (block_excluded && grid.block_within(k, *exclude)) continue;
    for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c) {
      if (!grid.meets(c, n, lo, hi, region)) continue;
      if (block_excluded && grid.near(c, *exclude)) continue;
      cell_fn(c);
    }
  }
}

// Visits the triangles (vertex index triples) of the cells meeting a slab (and the region, and
// not near `exclude`), or all triangles.
template <class Fn>
void for_faces_in_slab(const MeshView& mesh, const FaceGrid* grid, const Vec3& n, double lo,
                       double hi, const CutRegion* region, const CutRegion* exclude, Fn&& fn) {
  if (grid == nullptr) {
    for (Index f = 0; f < mesh.num_faces; ++f) fn(mesh.faces + 3 * f);
    return;
  }
  for_cells_in_slab(*grid, n, lo, hi, region, exclude, [&](Index c) {
    const std::int32_t* t = grid->faces() + 3 * grid->begin(c);
    for (Index f = grid->begin(c); f < grid->end(c); ++f, t += 3) fn(t);
  });
}

}  // namespace

void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out,
              const FaceGrid* grid, const CutRegion* region, const CutRegion* exclude) {
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  auto cut_face = [&](const std::int32_t* f) {
    double height[3];
    bool above[3];
    for (int k = 0; k < 3; ++k) {
      const double* p = mesh.vertices + 3 * static_cast<Index>(f[k]);
      height[k] = p[0] * nx + p[1] * ny + p[2] * nz - offset;
      above[k] = height[k] >= 0.0;
    }
    if (above[0] == above[1] && above[1] == above[2]) return;
    CutSegment seg;
    emit_segment(mesh, plane, f, above, height, seg);
    out.push_back(seg);
  };
  if (grid == nullptr || !grid->tight_bounds()) {
    for_faces_in_slab(mesh, grid, plane.normal, offset, offset, region, exclude, cut_face);
    return;
  }
  // The same cells, but a cell or a run of its faces whose tight box the plane misses is skipped
  // with one test: none of its faces would give a segment (FaceGrid::enable_tight_bounds).
  const double ax = std::abs(nx), ay = std::abs(ny), az = std::abs(nz);
  auto misses = [&](const Vec3& center, const Vec3& half) {
    const double mid = nx * center.x() + ny * center.y() + nz * center.z();
    const double r = ax * half.x() + ay * half.y() + az * half.z();
    return mid + r < offset || mid - r > offset;
  };
  const std::int32_t* faces = grid->faces();
  constexpr Index kGroup = FaceGrid::kGroup;
  for_cells_in_slab(*grid, plane.normal, offset, offset, region, exclude, [&](Index c) {
    FaceGrid::TightBoxes boxes;
    const Index begin = grid->begin(c), end = grid->end(c);
    const FaceGrid::Tight state = grid->tight_boxes(c, boxes);
    if (state == FaceGrid::Tight::kBusy) {
      for (Index f = begin; f < end; ++f) cut_face(faces + 3 * f);
      return;
    }
    if (state == FaceGrid::Tight::kMine) grid->bound_cell(c, mesh, boxes);
    if (misses(boxes.cell[0], boxes.cell[1])) return;
    for (Index f = begin, g = 0; f < end; f += kGroup, ++g) {
      if (misses(boxes.group_center[g], boxes.group_half[g])) continue;
      for (Index k = f, stop = std::min(end, f + kGroup); k < stop; ++k) cut_face(faces + 3 * k);
    }
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
  // Height and bucket of every vertex, once: the bucket is the number of planes at or below the
  // vertex (clamped to 0..count), so a triangle crosses plane k exactly when its vertices'
  // buckets straddle k, and most triangles are rejected with three integer loads.
  thread_local std::vector<double> height;
  thread_local std::vector<std::int32_t> bucket;
  const Index nv = mesh.num_vertices;
  height.resize(nv);
  bucket.resize(nv);
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  const double inv = 1.0 / spacing;
  const double top = static_cast<double>(count);
  const double* x = mesh.vertices;
  for (Index v = 0; v < nv; ++v) {
    const double t = x[3 * v] * nx + x[3 * v + 1] * ny + x[3 * v + 2] * nz - offset;
    height[v] = t;
    // Clamped first, so truncation is floor (and vectorizes, unlike std::floor without SSE4.1).
    const double q = t * inv;
    bucket[v] = static_cast<std::int32_t>(q < 0.0 ? 0.0 : (q > top ? top : q));
  }
  const std::int32_t* bk = bucket.data();
  const double* ht = height.data();
  for_faces_in_slab(mesh, grid, plane.normal, offset + first * spacing, offset + last * spacing,
                    region, exclude, [&](const std::int32_t* f) {
                      const std::int32_t b[3] = {bk[f[0]], bk[f[1]], bk[f[2]]};
                      const std::int32_t lo = std::max(std::min({b[0], b[1], b[2]}), first - 1);
                      const std::int32_t hi = std::min(std::max({b[0], b[1], b[2]}), last);
                      for (std::int32_t k = lo + 1; k <= hi; ++k) {
                        if (wanted != nullptr && !wanted[k - 1]) continue;
                        const double c = k * spacing;
                        bool above[3];
                        double h[3];
                        for (int j = 0; j < 3; ++j) {
                          above[j] = b[j] >= k;
                          h[j] = ht[f[j]] - c;
                        }
                        CutSegment seg;
                        emit_segment(mesh, plane, f, above, h, seg);
                        out[k - 1].push_back(seg);
                      }
                    });
}

}  // namespace osteon
