// The face grid: triangles bucketed into cells and blocks (spatial index), and line queries
// through it (see osteon/slicer.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "line_triangle.hpp"
#include "osteon/slicer.hpp"
#include "parallel.hpp"
#include "prefetch.hpp"

namespace osteon {

namespace {

constexpr int kBlock = 4;  // cells per block edge

// bin_faces: faces per chunk (the cells of a chunk's faces found, then counted), from 131 072
// vertices on (where it prefetches; below, one plain loop: cow x4 10.5 -> 9.1 M instructions).
constexpr Index kBinChunk = 256;

// How many faces (corners, entries) ahead the loops of the build prefetch what they will gather:
// 24 from 131 072 vertices on (3 MB of coordinates: cow x16 29.7 against 37.6 CPU ms per grid,
// cow x64 111 against 208), never below (cow x4's 46k vertices stay in the caches: the same time,
// and the prefetches would be ~6 M more instructions). "Never": a distance no index reaches.
inline Index prefetch_distance(const MeshView& mesh) {
  return mesh.num_vertices >= 131072 ? Index(24) : Index(1) << 60;
}

// Prefetches the coordinates of vertex v (24 bytes: up to two cache lines).
inline void prefetch_vertex(const MeshView& mesh, std::int32_t v) {
  const double* p = mesh.vertices + 3 * static_cast<Index>(v);
  detail::prefetch(p);
  detail::prefetch(p + 2);
}

}  // namespace

// The grid's box, cell size and numbering: cells of about `faces_per_cell` triangles, ordered
// block by block (kBlock^3 cells) so that a block's cells are contiguous.
struct FaceGrid::Layout {
  Vec3 lo, hi;                 // the mesh's box, mm
  Vec3 inv;                    // cells per mm along each axis
  Vec3 size;                   // a cell's edges, mm
  Eigen::Array3i dims, bdims;  // cells and blocks along each axis
  Index total = 0;             // cells
  // id = (block index) * kBlock^3 + (index inside the block), a sum of one term per axis.
  std::vector<Index> axis_term[3];
  // The cell of `raw`, the truncated grid coordinates (c[k] - lo[k]) * inv[k] of a point c.
  Index cell_id(const int raw[3]) const {
    return axis_term[0][std::clamp(raw[0], 0, dims[0] - 1)] +
           axis_term[1][std::clamp(raw[1], 0, dims[1] - 1)] +
           axis_term[2][std::clamp(raw[2], 0, dims[2] - 1)];
  }
};

FaceGrid::Layout FaceGrid::layout(const MeshView& mesh, int faces_per_cell, int parts,
                                  double box_margin) const {
  const Index nf = mesh.num_faces;
  Layout grid;
  Vec3& lo = grid.lo;
  Vec3& hi = grid.hi;
  lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  hi = -lo;
  // The box over `parts` workers (large meshes only: see kVerticesPerPass): a minimum and
  // maximum per axis, the same bits in any order.
  if (mesh.num_vertices < detail::kVerticesPerPass) parts = 1;
  std::vector<Vec3> part_lo(parts, lo), part_hi(parts, hi);
  detail::parallel_for(parts, parts, [&](long part, int) {
    const Index begin = mesh.num_vertices * part / parts;
    const Index end = mesh.num_vertices * (part + 1) / parts;
    Vec3 l = part_lo[part], h = part_hi[part];
    for (Index i = begin; i < end; ++i) {
      const Vec3 p = mesh.vertex(i);
      l = l.cwiseMin(p);
      h = h.cwiseMax(p);
    }
    part_lo[part] = l;
    part_hi[part] = h;
  });
  for (int p = 0; p < parts; ++p) {
    lo = lo.cwiseMin(part_lo[p]);
    hi = hi.cwiseMax(part_hi[p]);
  }
  if (box_margin > 0) {  // live rebuilds: room for the next poses (see build())
    const Vec3 pad = box_margin * (hi - lo);
    lo -= pad;
    hi += pad;
  }
  const Vec3 extent = (hi - lo).cwiseMax(Vec3::Constant(1e-12 * (1.0 + (hi - lo).norm())));
  // A surface fills few cells of a volume grid: size cells from the triangles' mean area (a
  // sample) so that a non-empty cell holds about faces_per_cell triangles.
  const Index step = std::max<Index>(1, nf / 2048);
  double area = 0.0;
  Index sampled = 0;
  for (Index f = 0; f < nf; f += step, ++sampled) {
    const std::int32_t* t = mesh.faces + 3 * f;
    area +=
        0.5 *
        (mesh.vertex(t[1]) - mesh.vertex(t[0])).cross(mesh.vertex(t[2]) - mesh.vertex(t[0])).norm();
  }
  const double mean_area = area / std::max<Index>(1, sampled);
  double cell = std::sqrt(std::max(mean_area, 1e-300) * faces_per_cell);
  cell = std::max(cell, extent.maxCoeff() / 256.0);
  // Never more (volume) cells than a quarter of the faces, so the counting arrays stay small.
  cell = std::max(cell, std::cbrt(extent.prod() / (0.25 * double(std::max<Index>(nf, 4)))));
  if (!(cell > 0) || !std::isfinite(cell)) cell = extent.maxCoeff();
  Eigen::Array3i& dims = grid.dims;
  for (int k = 0; k < 3; ++k) {
    dims[k] = static_cast<int>(std::clamp(std::ceil(extent[k] / cell), 1.0, 256.0));
    dims[k] = (dims[k] + kBlock - 1) / kBlock * kBlock;
  }
  grid.inv = Vec3(dims[0] / extent.x(), dims[1] / extent.y(), dims[2] / extent.z());
  grid.bdims = dims / kBlock;
  const Eigen::Array3i& bdims = grid.bdims;
  const Index per_block = kBlock * kBlock * kBlock;
  const Index block_step[3] = {Index(bdims[1]) * bdims[2] * per_block, Index(bdims[2]) * per_block,
                               per_block};
  const Index inner_step[3] = {kBlock * kBlock, kBlock, 1};
  for (int k = 0; k < 3; ++k) {
    grid.axis_term[k].resize(dims[k]);
    for (int x = 0; x < dims[k]; ++x)
      grid.axis_term[k][x] = (x / kBlock) * block_step[k] + (x % kBlock) * inner_step[k];
  }
  grid.total = Index(dims[0]) * dims[1] * dims[2];
  grid.size = Vec3(extent.x() / dims[0], extent.y() / dims[1], extent.z() / dims[2]);
  return grid;
}

// Face f's cell (the cell of its centroid) and how far it sticks out of its centroid (`reach`,
// widened by 1e-6 relative, as a float), mm.
inline Index FaceGrid::file_face(const MeshView& mesh, const Layout& grid, const std::int32_t* t,
                                 float& reach_out) {
  const Vec3& lo = grid.lo;
  const Vec3& inv = grid.inv;
#if defined(__SSE2__)
  const __m128d lo_xy = _mm_loadu_pd(lo.data()), inv_xy = _mm_loadu_pd(inv.data());
  const __m128d kThree = _mm_set1_pd(3.0);
  const __m128d kAbs = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
#endif
  int raw[3];
  double reach;
#if defined(__SSE2__)
  // x and y as a pair, z alone: the same operations lane by lane as the Eigen code below
  // ((a + b + c) / 3.0, the truncations, the absolute values); reach is the largest of the
  // nine absolute offsets, which does not depend on the order (finite coordinates).
  const double *pa = mesh.vertices + 3 * static_cast<Index>(t[0]),
               *pb = mesh.vertices + 3 * static_cast<Index>(t[1]),
               *pc = mesh.vertices + 3 * static_cast<Index>(t[2]);
  const __m128d axy = _mm_loadu_pd(pa), bxy = _mm_loadu_pd(pb), cxy = _mm_loadu_pd(pc);
  const __m128d mxy = _mm_div_pd(_mm_add_pd(_mm_add_pd(axy, bxy), cxy), kThree);
  const double mz = (pa[2] + pb[2] + pc[2]) / 3.0;
  const __m128i ixy = _mm_cvttpd_epi32(_mm_mul_pd(_mm_sub_pd(mxy, lo_xy), inv_xy));
  raw[0] = _mm_cvtsi128_si32(ixy);
  raw[1] = _mm_cvtsi128_si32(_mm_shuffle_epi32(ixy, 1));
  raw[2] = static_cast<int>((mz - lo.z()) * inv.z());
  const __m128d dxy = _mm_max_pd(
      _mm_max_pd(_mm_and_pd(_mm_sub_pd(axy, mxy), kAbs), _mm_and_pd(_mm_sub_pd(bxy, mxy), kAbs)),
      _mm_and_pd(_mm_sub_pd(cxy, mxy), kAbs));
  const double dz =
      std::max(std::max(std::abs(pa[2] - mz), std::abs(pb[2] - mz)), std::abs(pc[2] - mz));
  reach = std::max(std::max(_mm_cvtsd_f64(dxy), _mm_cvtsd_f64(_mm_unpackhi_pd(dxy, dxy))), dz);
#else
  const Vec3 a = mesh.vertex(t[0]), b = mesh.vertex(t[1]), c = mesh.vertex(t[2]);
  const Vec3 centroid = (a + b + c) / 3.0;
  for (int k = 0; k < 3; ++k) raw[k] = static_cast<int>((centroid[k] - lo[k]) * inv[k]);
  reach = std::max({(a - centroid).cwiseAbs().maxCoeff(), (b - centroid).cwiseAbs().maxCoeff(),
                    (c - centroid).cwiseAbs().maxCoeff()});
#endif
  reach_out = static_cast<float>(reach * (1 + 1e-6));
  return grid.cell_id(raw);
}

void FaceGrid::build(const MeshView& mesh, int faces_per_cell, int threads, double box_margin) {
  const Index nf = mesh.num_faces;
  const int parts = detail::worker_count(threads, static_cast<long>(nf / 16384 + 1));
  auto grid = std::make_shared<Layout>(layout(mesh, faces_per_cell, parts, box_margin));
  // Boxes are widened by a few ulps of the coordinates so that a plane through a box's face is
  // never rounded out of it (the plane tests compute n.center +- |n|.half).
  slack_ = 64 * std::numeric_limits<double>::epsilon() *
           std::max(grid->lo.cwiseAbs().maxCoeff(), grid->hi.cwiseAbs().maxCoeff());
  kept_faces_ = -1;  // until the faces are filed
  bin_faces(mesh, *grid, parts);
  kept_layout_ = std::move(grid);
  kept_faces_ = nf;
  finish_build(mesh, *kept_layout_, parts);
}

// The steps after the binning (build and refile): the faces sorted by cell, the cells and blocks
// with their boxes, the vertex entries.
void FaceGrid::finish_build(const MeshView& mesh, const Layout& grid, int parts) {
  tight_on_ = false;
  sort_faces_by_cell(mesh, grid.total, parts);
  collect_cells(grid);
  start_.push_back(mesh.num_faces);
  block_start_.push_back(static_cast<Index>(center_.size()));
  build_entries(mesh, parts);
}

bool FaceGrid::refile(const MeshView& mesh, const std::int32_t* moved, Index count, int threads) {
  const Index nf = mesh.num_faces;
  if (kept_layout_ == nullptr || kept_faces_ != nf || 4 * count > nf) return false;
  const Layout& grid = *kept_layout_;
  // The faces that did not move lie in the box (they did when filed); a moved one must too, or
  // its centroid would be clamped into a cell whose box does not hold it.
  for (Index i = 0; i < count; ++i) {
    const std::int32_t* t = mesh.faces + 3 * static_cast<Index>(moved[i]);
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = mesh.vertex(t[k]);
      if (!((p.array() >= grid.lo.array()).all() && (p.array() <= grid.hi.array()).all()))
        return false;
    }
  }
  std::int32_t* cell_of = cell_of_.get();
  float* reach = face_reach_.get();
  // The first cell (in the numbering) a moved face leaves or enters: every cell before it keeps
  // its faces, their places in faces(), its vertex entries and its box.
  Index first = grid.total;
  old_cell_.resize(count);
  for (Index i = 0; i < count; ++i) {
    const Index f = moved[i];
    old_cell_[i] = cell_of[f];
    cell_of[f] = static_cast<std::int32_t>(file_face(mesh, grid, mesh.faces + 3 * f, reach[f]));
    first = std::min<Index>(first, std::min(old_cell_[i], cell_of[f]));
  }
  const int parts = detail::worker_count(threads, static_cast<long>(nf / 16384 + 1));
  if (parts == 1 || 2 * (nf - cell_start_[first]) <= nf) {
    refile_from(mesh, grid, first, moved, count);
    return true;
  }
  // The faces per cell and part and the cells' overhangs, from the kept cells and overhangs.
  if (static_cast<int>(part_count_.size()) < parts) {
    part_count_.resize(parts);
    part_overhang_.resize(parts);
  }
  detail::parallel_for(parts, parts, [&](long part, int) {
    std::vector<Index>& n = part_count_[part];
    std::vector<float>& overhang = part_overhang_[part];
    n.assign(grid.total, 0);
    overhang.assign(grid.total, 0.0f);
    for (Index f = nf * part / parts, end = nf * (part + 1) / parts; f < end; ++f) {
      const std::int32_t id = cell_of[f];
      ++n[id];
      overhang[id] = std::max(overhang[id], reach[f]);
    }
  });
  finish_build(mesh, grid, parts);
  return true;
}

// refile() from cell `first` on (one thread): the kept counts, overhangs and entries of the
// earlier cells stand; the later cells are counted, sorted, bounded and given their vertex
// entries as finish_build() would (the same arrays, bit for bit).
void FaceGrid::refile_from(const MeshView& mesh, const Layout& grid, Index first,
                           const std::int32_t* moved, Index count) {
  const Index nf = mesh.num_faces, total = grid.total;
  const std::int32_t* cell_of = cell_of_.get();
  Index* start = cell_start_.get();  // the kept cell starts (total + 1)
  std::vector<Index>& fill = part_count_[0];
  std::vector<float>& overhang = part_overhang_[0];  // the kept overhangs (merged)
  fill.resize(total);
  for (Index c = first; c < total; ++c) fill[c] = start[c + 1] - start[c];
  for (Index i = 0; i < count; ++i) {
    --fill[old_cell_[i]];
    ++fill[cell_of[moved[i]]];
  }
  for (Index c = first; c < total; ++c) {
    const Index n = fill[c];
    fill[c] = start[c];
    start[c + 1] = start[c] + n;
  }
  // The faces of those cells in order, and each cell's overhang (the largest reach of its faces).
  const float* reach = face_reach_.get();
  std::fill(overhang.begin() + first, overhang.end(), 0.0f);
  for (Index f = 0; f < nf; ++f) {
    const Index c = cell_of[f];
    if (c < first) continue;
    const Index k = fill[c]++;
    faces_[3 * k] = mesh.faces[3 * f];
    faces_[3 * k + 1] = mesh.faces[3 * f + 1];
    faces_[3 * k + 2] = mesh.faces[3 * f + 2];
    overhang[c] = std::max(overhang[c], reach[f]);
  }
  tight_on_ = false;
  collect_cells(grid);
  start_.push_back(nf);
  block_start_.push_back(static_cast<Index>(center_.size()));
  // The non-empty cells before `first` are the kept ones, with their entries.
  const Index cells = num_cells();
  const Index k0 =
      std::lower_bound(start_.begin(), start_.begin() + cells, start[first]) - start_.begin();
  entries_from(mesh, k0);
}

// build_entries() from non-empty cell k0 on (one thread), the entries before it kept.
void FaceGrid::entries_from(const MeshView& mesh, Index k0) {
  const Index cells = num_cells();
  std::vector<std::int32_t>& slot = part_slots_[0];  // v's latest entry (stale below k0)
  if (static_cast<Index>(slot.size()) != mesh.num_vertices ||
      k0 >= static_cast<Index>(vstart_.size())) {
    build_entries(mesh, 1);
    return;
  }
  const Index base = vstart_[k0];  // entries of the cells before k0, unchanged
  vstart_.resize(cells + 1);
  for (Index k = 3 * start_[k0], stop = 3 * start_[cells]; k < stop; ++k) slot[faces_[k]] = -1;
  std::int32_t* list = part_lists_[0].reserve(3 * (start_[cells] - start_[k0]) + 1);
  std::int32_t* corner = face_entries_.get();
  Index n = base;
  for (Index c = k0; c < cells; ++c) {
    const Index cell_first = n;
    vstart_[c] = cell_first;
    for (Index k = 3 * start_[c], stop = 3 * start_[c + 1]; k < stop; ++k) {
      const std::int32_t v = faces_[k];
      std::int32_t e = slot[v];
      if (e < cell_first) {
        e = static_cast<std::int32_t>(n++);
        slot[v] = e;
        list[e - base] = v;
      }
      corner[k] = e;
    }
  }
  vstart_[cells] = n;
  entry_vertex_.grow(n, base);
  entry_x_.grow(n, base);
  entry_y_.grow(n, base);
  entry_z_.grow(n, base);
  write_entries(mesh, list, base, n);
}

// Entries [begin, end): vertex list[e - begin] and its coordinates (storage already sized).
void FaceGrid::write_entries(const MeshView& mesh, const std::int32_t* list, Index begin,
                             Index end) {
  const Index ahead = prefetch_distance(mesh);
  for (Index e = begin; e < end; ++e) {
    if (e + ahead < end) prefetch_vertex(mesh, list[e + ahead - begin]);
    const std::int32_t v = list[e - begin];
    const double* p = mesh.vertices + 3 * static_cast<Index>(v);
    entry_vertex_[e] = v;
    entry_x_[e] = p[0];
    entry_y_[e] = p[1];
    entry_z_[e] = p[2];
  }
}

// One pass over the triangles (split over `parts` workers): cell of the centroid (cell_of_), the
// faces per cell and part (part_count_), and how far each cell's triangles stick out of it
// (part_overhang_; so that a cell's box = its grid box widened by that, without a second pass).
void FaceGrid::bin_faces(const MeshView& mesh, const Layout& grid, int parts) {
  const Index ahead = prefetch_distance(mesh);
  const Index nf = mesh.num_faces, total = grid.total;
  std::int32_t* cell_of = cell_of_.reserve(nf);
  float* face_reach = face_reach_.reserve(nf);
  auto& part_count = part_count_;
  auto& part_overhang = part_overhang_;
  if (static_cast<int>(part_count.size()) < parts) {
    part_count.resize(parts);
    part_overhang.resize(parts);
  }
  for (int p = 0; p < parts; ++p) {
    part_count[p].assign(total, 0);
    part_overhang[p].assign(total, 0.0f);
  }
  detail::parallel_for(parts, parts, [&](long part, int) {
    auto& count = part_count[part];
    auto& overhang = part_overhang[part];
    const Index begin = nf * part / parts, end = nf * (part + 1) / parts;
    if (ahead >= nf) {  // no prefetch (the vertices stay in the caches): one plain loop
      for (Index f = begin; f < end; ++f) {
        float r;
        const Index id = file_face(mesh, grid, mesh.faces + 3 * f, r);
        cell_of[f] = static_cast<std::int32_t>(id);
        face_reach[f] = r;
        ++count[id];
        overhang[id] = std::max(overhang[id], r);
      }
      return;
    }
    for (Index c0 = begin; c0 < end; c0 += kBinChunk) {
      const Index c1 = std::min(end, c0 + kBinChunk);
      for (Index f = c0; f < c1; ++f) {
        if (f + ahead < end)
          for (int k = 0; k < 3; ++k) prefetch_vertex(mesh, mesh.faces[3 * (f + ahead) + k]);
        cell_of[f] =
            static_cast<std::int32_t>(file_face(mesh, grid, mesh.faces + 3 * f, face_reach[f]));
      }
      for (Index f = c0; f < c1; ++f) {
        if (f + ahead < c1) {
          detail::prefetch(&count[cell_of[f + ahead]]);
          detail::prefetch(&overhang[cell_of[f + ahead]]);
        }
        const std::int32_t id = cell_of[f];
        ++count[id];
        overhang[id] = std::max(overhang[id], face_reach[f]);
      }
    }
  });
}

// Cell starts (cell_start_), and the faces sorted by cell (faces_): each part writes its
// triangles of a cell after the earlier parts', so the order is the sequential one whatever the
// number of workers. The parts' overhangs are merged into part_overhang_[0].
void FaceGrid::sort_faces_by_cell(const MeshView& mesh, Index total, int parts) {
  const Index ahead = prefetch_distance(mesh);
  const Index nf = mesh.num_faces;
  auto& part_count = part_count_;
  auto& part_overhang = part_overhang_;
  const std::int32_t* cell_of = cell_of_.get();
  // The cell starts; count[c + 1] is written at cell c (so no zero-fill).
  Index* count = cell_start_.reserve(total + 1);
  count[0] = 0;
  std::vector<float>& overhang = part_overhang[0];
  for (Index c = 0; c < total; ++c) {
    Index sum = count[c];
    for (int p = 0; p < parts; ++p) {
      const Index n = part_count[p][c];
      part_count[p][c] = sum;  // now: where part p starts writing in cell c
      sum += n;
      if (p > 0) overhang[c] = std::max(overhang[c], part_overhang[p][c]);
    }
    count[c + 1] = sum;
  }
  faces_.reserve(3 * nf);  // written in full below
  detail::parallel_for(parts, parts, [&](long part, int) {
    auto& fill = part_count[part];
    const Index begin = nf * part / parts, end = nf * (part + 1) / parts;
    for (Index f = begin; f < end; ++f) {
      if (f + 2 * ahead < end) detail::prefetch(&fill[cell_of[f + 2 * ahead]]);
      if (f + ahead < end) detail::prefetch(faces_.get() + 3 * fill[cell_of[f + ahead]]);
      const Index k = fill[cell_of[f]]++;
      faces_[3 * k] = mesh.faces[3 * f];
      faces_[3 * k + 1] = mesh.faces[3 * f + 1];
      faces_[3 * k + 2] = mesh.faces[3 * f + 2];
    }
  });
}

// Keeps the non-empty cells only, each with its grid box widened by its triangles' overhang
// (centroids lie inside the grid box), and the non-empty blocks with the box of their cells.
void FaceGrid::collect_cells(const Layout& grid) {
  const Index total = grid.total;
  const Vec3& lo = grid.lo;
  const Vec3& size = grid.size;
  const Eigen::Array3i& bdims = grid.bdims;
  const Index* count = cell_start_.get();
  const std::vector<float>& overhang = part_overhang_[0];
  const double slack = slack_;
  center_.clear();
  half_.clear();
  start_.clear();
  block_center_.clear();
  block_half_.clear();
  block_start_.clear();
  const Index per_block = kBlock * kBlock * kBlock;
  const double inf = std::numeric_limits<double>::infinity();
  for (Index b0 = 0; b0 < total; b0 += per_block) {
    Vec3 klo = Vec3::Constant(inf), khi = -klo;
    const Index cells_before = static_cast<Index>(center_.size());
    const Index block = b0 / per_block;
    const int bx = static_cast<int>(block / (Index(bdims[1]) * bdims[2]));
    const int by = static_cast<int>((block / bdims[2]) % bdims[1]);
    const int bz = static_cast<int>(block % bdims[2]);
    for (Index c = b0; c < b0 + per_block; ++c) {
      if (count[c + 1] == count[c]) continue;
      const Index inner = c - b0;
      const int ix = bx * kBlock + static_cast<int>(inner / (kBlock * kBlock));
      const int iy = by * kBlock + static_cast<int>((inner / kBlock) % kBlock);
      const int iz = bz * kBlock + static_cast<int>(inner % kBlock);
      const Vec3 clo = lo + Vec3(ix * size.x(), iy * size.y(), iz * size.z());
      const Vec3 half = 0.5 * size + Vec3::Constant(double(overhang[c]) + slack);
      const Vec3 center = clo + 0.5 * size;
      center_.push_back(center);
      half_.push_back(half);
      start_.push_back(count[c]);
      klo = klo.cwiseMin(center - half);
      khi = khi.cwiseMax(center + half);
    }
    if (static_cast<Index>(center_.size()) == cells_before) continue;
    block_center_.push_back(0.5 * (klo + khi));
    block_half_.push_back(0.5 * (khi - klo) + Vec3::Constant(slack));
    block_start_.push_back(cells_before);
  }
}

void FaceGrid::build_entries(const MeshView& mesh, int parts) {
  const Index ahead = prefetch_distance(mesh);
  // Part p lists the distinct vertices of cells cells * p / parts .. (first appearance order),
  // numbered from 0; the entries of the earlier parts are added afterwards (so the result does
  // not depend on the number of parts).
  const Index cells = num_cells();
  parts = static_cast<int>(std::clamp<Index>(cells, 1, parts));
  if (static_cast<int>(part_lists_.size()) < parts) {
    part_lists_.resize(parts);
    part_slots_.resize(parts);
  }
  std::vector<Index> shift(parts + 1, 0);
  vstart_.resize(cells + 1);
  face_entries_.reserve(3 * start_[cells]);
  auto cell_range = [&](long part) {
    return std::make_pair(cells * part / parts, cells * (part + 1) / parts);
  };
  detail::parallel_for(parts, parts, [&](long part, int) {
    const auto [c0, c1] = cell_range(part);
    // slot[v]: v's latest entry; v is already listed in cell c when that is c's or later.
    std::vector<std::int32_t>& slot = part_slots_[part];
    slot.assign(mesh.num_vertices, -1);
    std::int32_t* list = part_lists_[part].reserve(3 * (start_[c1] - start_[c0]));  // <= 1 a corner
    std::int32_t* corner = face_entries_.get();
    const Index last = 3 * start_[c1];
    std::int32_t n = 0;
    for (Index c = c0; c < c1; ++c) {
      const std::int32_t first = n;
      vstart_[c] = first;
      for (Index k = 3 * start_[c], stop = 3 * start_[c + 1]; k < stop; ++k) {
        if (k + ahead < last) detail::prefetch(&slot[faces_[k + ahead]]);
        const std::int32_t v = faces_[k];
        std::int32_t e = slot[v];
        if (e < first) {
          e = n++;
          slot[v] = e;
          list[e] = v;
        }
        corner[k] = e;
      }
    }
    shift[part + 1] = n;
  });
  for (int p = 0; p < parts; ++p) shift[p + 1] += shift[p];
  const Index total = shift[parts];
  vstart_[cells] = total;
  entry_vertex_.reserve(total);
  entry_x_.reserve(total);
  entry_y_.reserve(total);
  entry_z_.reserve(total);
  detail::parallel_for(parts, parts, [&](long part, int) {
    const auto [c0, c1] = cell_range(part);
    const Index base = shift[part];
    if (base != 0) {
      for (Index c = c0; c < c1; ++c) vstart_[c] += base;
      for (Index k = 3 * start_[c0], stop = 3 * start_[c1]; k < stop; ++k)
        face_entries_[k] += static_cast<std::int32_t>(base);
    }
    write_entries(mesh, part_lists_[part].get(), base, shift[part + 1]);
  });
}

void FaceGrid::enable_tight_bounds() {
  if (tight_on_) return;
  TightData& t = tight_;
  const Index cells = num_cells();
  t.group_start.resize(cells + 1);
  t.group_start[0] = 0;
  for (Index c = 0; c < cells; ++c)
    t.group_start[c + 1] = t.group_start[c] + (end(c) - begin(c) + kGroup - 1) / kGroup;
  t.cell_box.resize(2 * cells);
  t.group_center.resize(t.group_start[cells]);
  t.group_half.resize(t.group_start[cells]);
  tight_state_.reserve(cells);
  for (Index c = 0; c < cells; ++c) tight_state_[c].store(0, std::memory_order_relaxed);
  tight_on_ = true;
}

void FaceGrid::bound_cell(Index c, const MeshView& /*mesh*/, const TightBoxes& boxes) const {
  // The corners' coordinates from the cell's entries (bit-exact copies of the mesh's vertices,
  // a few contiguous cache lines per cell) instead of gathered from the mesh's vertex array (on
  // cow x64, 18 MB: a miss per vertex); the same values in the same order, so the same boxes.
  // x and y as a pair (one SIMD min and max per vertex where Eigen vectorizes), z alone.
  using Pair = Eigen::Array2d;
  const std::int32_t* corner = face_entries_.get();
  const double *ex = entry_x_.get(), *ey = entry_y_.get(), *ez = entry_z_.get();
  const double inf = std::numeric_limits<double>::infinity();
  Pair cell_lo = Pair::Constant(inf), cell_hi = Pair::Constant(-inf);
  double cell_zlo = inf, cell_zhi = -inf;
  const Pair slack = Pair::Constant(slack_);
  Index g = 0;
  for (Index f = begin(c), e = end(c); f < e; f += kGroup, ++g) {
    Pair lo = Pair::Constant(inf), hi = Pair::Constant(-inf);
    double zlo = inf, zhi = -inf;
    for (Index k = 3 * f, stop = 3 * std::min(e, f + kGroup); k < stop; ++k) {
      const Index entry = corner[k];
      const Pair xy(ex[entry], ey[entry]);
      lo = lo.min(xy);
      hi = hi.max(xy);
      zlo = std::min(zlo, ez[entry]);
      zhi = std::max(zhi, ez[entry]);
    }
    const Pair mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo) + slack;
    boxes.group_center[g] = Vec3(mid.x(), mid.y(), 0.5 * (zlo + zhi));
    boxes.group_half[g] = Vec3(half.x(), half.y(), 0.5 * (zhi - zlo) + slack_);
    cell_lo = cell_lo.min(lo);
    cell_hi = cell_hi.max(hi);
    cell_zlo = std::min(cell_zlo, zlo);
    cell_zhi = std::max(cell_zhi, zhi);
  }
  const Pair mid = 0.5 * (cell_lo + cell_hi), half = 0.5 * (cell_hi - cell_lo) + slack;
  boxes.cell[0] = Vec3(mid.x(), mid.y(), 0.5 * (cell_zlo + cell_zhi));
  boxes.cell[1] = Vec3(half.x(), half.y(), 0.5 * (cell_zhi - cell_zlo) + slack_);
  tight_state_[c].store(2, std::memory_order_release);
}

std::vector<double> line_crossings(const MeshView& mesh, const FaceGrid& grid, const Vec3& point,
                                   const Vec3& dir) {
  std::vector<double> hits;
  grid.for_faces_near(CutRegion{point, dir, 0.0}, [&](const std::int32_t* t) {
    const Vec3 a = mesh.vertex(t[0]);
    const Vec3 e1 = mesh.vertex(t[1]) - a, e2 = mesh.vertex(t[2]) - a;
    double hit = 0.0;
    if (detail::line_hits_triangle(point, dir, a, e1, e2, hit)) hits.push_back(hit);
  });
  std::sort(hits.begin(), hits.end());
  return hits;
}

}  // namespace osteon
