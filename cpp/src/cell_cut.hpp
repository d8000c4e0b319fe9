// One grid cell's share of a plane cut, shared by the section cuts (slicer_cut.cpp) and the
// corner search's meridian profiles (notch.cpp): the faces the plane crosses, found with the
// grid's tight boxes, and the segment each gives. Engine-internal.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "osteon/slicer.hpp"

namespace osteon::detail {

// The key of mesh edge a-b in either order: (min << 32) | max (CutSegment::edge).
inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint32_t>(std::min(a, b));
  const auto hi = static_cast<std::uint32_t>(std::max(a, b));
  return (static_cast<std::uint64_t>(lo) << 32) | hi;
}

// Cut of triangle f given per-vertex "above" flags and signed heights (height 0 = plane).
// Exactly two edges change side; each gives an endpoint at linear interpolation of the heights.
// The segment keeps the face's orientation: it runs from the edge that goes down (above to below
// in the face's winding) to the edge that goes up, so that a closed outward-facing surface gives
// counter-clockwise loops in (u, v) and an inward-facing one clockwise loops.
// `world` (when not null) receives the endpoints in mesh coordinates (mm), for region tests.
inline void emit_segment(const MeshView& mesh, const PlaneFrame& plane, const std::int32_t* f,
                         const bool above[3], const double height[3], CutSegment& seg,
                         Vec3* world) {
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
    if (world != nullptr) world[n] = p;
  }
}

// The faces of grid cell c that may cross the plane n . x = offset (n unit, mm). With the grid's
// tight boxes (FaceGrid::enable_tight_bounds), a cell or a run of FaceGrid::kGroup of its faces
// whose tight box the plane misses, or that `skip_box(center, half)` rejects (a caller's own
// window: it must reject only boxes that hold no face it would keep), is passed over with one
// test: the segments and their order are those of the face-by-face visit. Calls
// `cut(f, height)` for every other face, in the grid's order: f its 3 vertex indices
// (grid.faces()), height[3] its corners' signed heights, computed in one vectorized pass per cell
// from the grid's entries (bit-exact copies of the mesh's vertices: the same bits as
// n . p - offset from the mesh). Without tight boxes (none, or another thread bounding the cell)
// every face is passed. `heights`: scratch.
template <class SkipBox, class Cut>
void cut_cell_faces(const MeshView& mesh, const FaceGrid& grid, Index c, const Vec3& n,
                    double offset, SkipBox&& skip_box, std::vector<double>& heights, Cut&& cut) {
  const double nx = n.x(), ny = n.y(), nz = n.z();
  const double ax = std::abs(nx), ay = std::abs(ny), az = std::abs(nz);
  auto skips = [&](const Vec3& center, const Vec3& half) {
    const double mid = nx * center.x() + ny * center.y() + nz * center.z();
    const double r = ax * half.x() + ay * half.y() + az * half.z();
    return mid + r < offset || mid - r > offset || skip_box(center, half);
  };
  FaceGrid::TightBoxes boxes;
  bool tight = false;
  if (grid.tight_bounds()) {
    const FaceGrid::Tight state = grid.tight_boxes(c, boxes);
    if (state == FaceGrid::Tight::kMine) grid.bound_cell(c, mesh, boxes);
    tight = state != FaceGrid::Tight::kBusy;
    if (tight && skips(boxes.cell[0], boxes.cell[1])) return;
  }
  const Index vb = grid.vertex_begin(c), nv = grid.vertex_end(c) - vb;
  const std::int32_t* entries = grid.face_entries();
  const std::int32_t* faces = grid.faces();
  // A plain pointer to the heights: each use of a thread_local vector would re-derive its
  // address (a __tls_get_addr call in a shared library).
  const double* hv = nullptr;
  const Index begin = grid.begin(c), end = grid.end(c);
  for (Index f0 = begin, g = 0; f0 < end; f0 += FaceGrid::kGroup, ++g) {
    if (tight && skips(boxes.group_center[g], boxes.group_half[g])) continue;
    if (hv == nullptr) {
      if (static_cast<Index>(heights.size()) < nv) heights.resize(nv);
      double* __restrict h = heights.data();
      const double* __restrict x = grid.entry_x() + vb;
      const double* __restrict y = grid.entry_y() + vb;
      const double* __restrict z = grid.entry_z() + vb;
      for (Index v = 0; v < nv; ++v) h[v] = x[v] * nx + y[v] * ny + z[v] * nz - offset;
      hv = h;
    }
    for (Index k = 3 * f0, stop = 3 * std::min(end, f0 + FaceGrid::kGroup); k < stop; k += 3) {
      const std::int32_t* e = entries + k;
      double height[3] = {hv[e[0] - vb], hv[e[1] - vb], hv[e[2] - vb]};
      cut(faces + k, height);
    }
  }
}

}  // namespace osteon::detail
