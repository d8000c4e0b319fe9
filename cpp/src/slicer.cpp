#include "osteon/slicer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

#include "osteon/regions.hpp"
#include "parallel.hpp"

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

// Open-addressing table pairing the two segment endpoints ("occurrences") on each mesh edge.
struct EdgeTable {
  struct Slot {
    std::uint64_t key;
    std::int32_t first;
    std::uint32_t stamp;  // the slot is in use in this round only when stamp == round
  };
  std::vector<Slot> slots;
  std::uint64_t mask = 0;
  int bits = 0;
  std::uint32_t round = 0;

  // `keys` = distinct edges expected (at most); the table stays at most half full. Slots are
  // not cleared: a new round number empties them all at once (the table is reused per thread).
  void reset(std::size_t keys) {
    bits = 4;
    while ((std::size_t(1) << bits) < 2 * keys + 16) ++bits;
    const std::size_t size = std::size_t(1) << bits;
    mask = size - 1;
    if (slots.size() < size) slots.resize(size, Slot{0, -1, round});
    if (++round == 0) {  // wrapped: make every stamp stale again
      for (Slot& slot : slots) slot.stamp = 0;
      round = 1;
    }
  }
  // Pairs `occurrence` with the endpoint already on the edge (partner[] both ways); returns
  // false if the edge already had two endpoints (non-manifold).
  bool insert(std::uint64_t key, std::int32_t occurrence, std::vector<std::int32_t>& partner) {
    std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - bits);
    while (true) {
      Slot& slot = slots[h];
      if (slot.stamp != round) {
        slot = Slot{key, occurrence, round};
        return true;
      }
      if (slot.key == key) {
        if (slot.first < 0) return false;
        partner[slot.first] = occurrence;
        partner[occurrence] = slot.first;
        slot.first = -1;  // paired: a third endpoint is non-manifold
        return true;
      }
      h = (h + 1) & mask;
    }
  }
};

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

void FaceGrid::build(const MeshView& mesh, int faces_per_cell, int threads) {
  const Index nf = mesh.num_faces;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Index i = 0; i < mesh.num_vertices; ++i) {
    const Vec3 p = mesh.vertex(i);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 extent = (hi - lo).cwiseMax(Vec3::Constant(1e-12 * (1.0 + (hi - lo).norm())));
  // Boxes are widened by a few ulps of the coordinates so that a plane through a box's face is
  // never rounded out of it (the plane tests compute n.center +- |n|.half).
  const double slack = 64 * std::numeric_limits<double>::epsilon() *
                       std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
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
  constexpr int kBlock = 4;  // cells per block edge
  Eigen::Array3i dims;
  for (int k = 0; k < 3; ++k) {
    dims[k] = static_cast<int>(std::clamp(std::ceil(extent[k] / cell), 1.0, 256.0));
    dims[k] = (dims[k] + kBlock - 1) / kBlock * kBlock;
  }
  const Vec3 inv(dims[0] / extent.x(), dims[1] / extent.y(), dims[2] / extent.z());
  const Eigen::Array3i bdims = dims / kBlock;
  // Cell ids ordered block by block so that a block's cells are contiguous.
  auto cell_id = [&](const Vec3& c) {
    int x[3];
    for (int k = 0; k < 3; ++k)
      x[k] = std::clamp(static_cast<int>((c[k] - lo[k]) * inv[k]), 0, dims[k] - 1);
    const Index block =
        (Index(x[0] / kBlock) * bdims[1] + x[1] / kBlock) * bdims[2] + x[2] / kBlock;
    const Index inner = ((x[0] % kBlock) * kBlock + x[1] % kBlock) * kBlock + x[2] % kBlock;
    return block * (kBlock * kBlock * kBlock) + inner;
  };
  const Index total = Index(dims[0]) * dims[1] * dims[2];
  // One pass over the triangles (split over the workers): cell of the centroid, and how far each
  // cell's triangles stick out of it (so that a cell's box = its grid box widened by that,
  // without a second pass).
  const int parts = detail::worker_count(threads, static_cast<long>(nf / 16384 + 1));
  std::vector<std::int32_t> cell_of(nf);
  std::vector<std::vector<Index>> part_count(parts, std::vector<Index>(total, 0));
  std::vector<std::vector<float>> part_overhang(parts, std::vector<float>(total, 0.0f));
  const Vec3 size(extent.x() / dims[0], extent.y() / dims[1], extent.z() / dims[2]);
  auto part_range = [&](long part) {
    return std::make_pair(nf * part / parts, nf * (part + 1) / parts);
  };
  detail::parallel_for(parts, parts, [&](long part, int) {
    auto& count = part_count[part];
    auto& overhang = part_overhang[part];
    const auto [begin, end] = part_range(part);
    for (Index f = begin; f < end; ++f) {
      const std::int32_t* t = mesh.faces + 3 * f;
      const Vec3 a = mesh.vertex(t[0]), b = mesh.vertex(t[1]), c = mesh.vertex(t[2]);
      const Vec3 centroid = (a + b + c) / 3.0;
      const Index id = cell_id(centroid);
      cell_of[f] = static_cast<std::int32_t>(id);
      ++count[id];
      const double reach =
          std::max({(a - centroid).cwiseAbs().maxCoeff(), (b - centroid).cwiseAbs().maxCoeff(),
                    (c - centroid).cwiseAbs().maxCoeff()});
      overhang[id] = std::max(overhang[id], static_cast<float>(reach * (1 + 1e-6)));
    }
  });
  // Cell starts, and where each part writes its triangles of a cell: after the earlier parts', so
  // the order is the sequential one whatever the number of workers.
  std::vector<Index> count(total + 1, 0);
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
  faces_.resize(3 * nf);
  detail::parallel_for(parts, parts, [&](long part, int) {
    auto& fill = part_count[part];
    const auto [begin, end] = part_range(part);
    for (Index f = begin; f < end; ++f) {
      const Index k = fill[cell_of[f]]++;
      faces_[3 * k] = mesh.faces[3 * f];
      faces_[3 * k + 1] = mesh.faces[3 * f + 1];
      faces_[3 * k + 2] = mesh.faces[3 * f + 2];
    }
  });
  // Keep the non-empty cells only, each with its grid box widened by its triangles' overhang
  // (centroids lie inside the grid box), and the non-empty blocks with the box of their cells.
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
  start_.push_back(nf);
  block_start_.push_back(static_cast<Index>(center_.size()));
}

namespace {

// Visits the triangles (vertex index triples) of the cells meeting a slab (and the region, and
// not near `exclude`), or all triangles.
template <class Fn>
void for_faces_in_slab(const MeshView& mesh, const FaceGrid* grid, const Vec3& n, double lo,
                       double hi, const CutRegion* region, const CutRegion* exclude, Fn&& fn) {
  if (grid == nullptr) {
    for (Index f = 0; f < mesh.num_faces; ++f) fn(mesh.faces + 3 * f);
    return;
  }
  for (Index k = 0; k < grid->num_blocks(); ++k) {
    if (!grid->block_meets(k, n, lo, hi, region)) continue;
    // A cell was visited by the `exclude` cut when both its block and itself are near `exclude`
    // (the two tests are not nested: a cell's bounding sphere may stick out of its block's).
    const bool block_excluded = exclude != nullptr && grid->block_near(k, *exclude);
    if (block_excluded && grid->block_within(k, *exclude)) continue;
    for (Index c = grid->block_begin(k); c < grid->block_end(k); ++c) {
      if (!grid->meets(c, n, lo, hi, region)) continue;
      if (block_excluded && grid->near(c, *exclude)) continue;
      const std::int32_t* t = grid->faces() + 3 * grid->begin(c);
      for (Index f = grid->begin(c); f < grid->end(c); ++f, t += 3) fn(t);
    }
  }
}

}  // namespace

void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out,
              const FaceGrid* grid, const CutRegion* region, const CutRegion* exclude) {
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  for_faces_in_slab(mesh, grid, plane.normal, offset, offset, region, exclude,
                    [&](const std::int32_t* f) {
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

std::vector<double> line_crossings(const MeshView& mesh, const FaceGrid& grid, const Vec3& point,
                                   const Vec3& dir) {
  std::vector<double> hits;
  const CutRegion line{point, dir, 0.0};
  for (Index c = 0, k = 0; k < grid.num_blocks(); ++k) {
    if (!grid.block_near(k, line)) continue;
    for (c = grid.block_begin(k); c < grid.block_end(k); ++c) {
      if (!grid.near(c, line)) continue;
      const std::int32_t* t = grid.faces() + 3 * grid.begin(c);
      for (Index f = grid.begin(c); f < grid.end(c); ++f, t += 3) {
        // Moller-Trumbore for the infinite line.
        const Vec3 a = mesh.vertex(t[0]);
        const Vec3 e1 = mesh.vertex(t[1]) - a, e2 = mesh.vertex(t[2]) - a;
        const Vec3 p = dir.cross(e2);
        const double det = e1.dot(p);
        if (det == 0.0) continue;
        const double inv = 1.0 / det;
        const Vec3 s = point - a;
        const double u = s.dot(p) * inv;
        if (u < 0.0 || u > 1.0) continue;
        const Vec3 q = s.cross(e1);
        const double v = dir.dot(q) * inv;
        if (v < 0.0 || u + v > 1.0) continue;
        hits.push_back(e2.dot(q) * inv);
      }
    }
  }
  std::sort(hits.begin(), hits.end());
  return hits;
}

namespace {
// Unordered pair of the two edge keys of a segment: identical for a doubled triangle.
std::pair<std::uint64_t, std::uint64_t> segment_key(const CutSegment& s) {
  return s.edge[0] < s.edge[1] ? std::make_pair(s.edge[0], s.edge[1])
                               : std::make_pair(s.edge[1], s.edge[0]);
}
}  // namespace

PlaneCut assemble_loops(const std::vector<CutSegment>& input, double gap_tolerance) {
  PlaneCut cut;
  if (input.empty()) return cut;
  // Pair the two endpoints that lie on the same mesh edge; orientation-agnostic so that
  // inconsistently wound meshes still give loops. An edge with more than two endpoints is first
  // explained by exact duplicate segments (doubled triangles), which are dropped; whatever is
  // still non-manifold after that is flagged.
  const std::vector<CutSegment>* source = &input;
  std::vector<CutSegment> deduplicated;
  thread_local EdgeTable table;
  thread_local std::vector<std::int32_t> partner;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::vector<CutSegment>& segs = *source;
    const std::size_t count = segs.size();
    table.reset(2 * count);  // 2*count endpoints: at most that many distinct edges
    partner.assign(2 * count, -1);
    bool crowded = false;
    for (std::size_t s = 0; s < count; ++s)
      for (int e = 0; e < 2; ++e)
        if (!table.insert(segs[s].edge[e], static_cast<std::int32_t>(2 * s + e), partner))
          crowded = true;
    if (crowded && attempt == 0) {
      deduplicated = input;
      std::sort(
          deduplicated.begin(), deduplicated.end(),
          [](const CutSegment& x, const CutSegment& y) { return segment_key(x) < segment_key(y); });
      const auto last = std::unique(deduplicated.begin(), deduplicated.end(),
                                    [](const CutSegment& x, const CutSegment& y) {
                                      return segment_key(x) == segment_key(y);
                                    });
      if (last != deduplicated.end()) {
        deduplicated.erase(last, deduplicated.end());
        source = &deduplicated;
        continue;
      }
    }
    if (crowded) cut.flags |= kFlagNonManifold;
    break;
  }
  const std::vector<CutSegment>& segments = *source;
  const std::size_t m = segments.size();
  thread_local std::vector<std::uint8_t> used;
  used.assign(m, 0);
  std::vector<Vec2> forward, backward;
  for (std::size_t s0 = 0; s0 < m; ++s0) {
    if (used[s0]) continue;
    forward.clear();
    backward.clear();
    bool closed = false;
    // Walk forward: enter s at endpoint `in`, leave through the other endpoint.
    std::size_t cur = s0;
    int in = 0;
    while (true) {
      used[cur] = 1;
      forward.push_back(segments[cur].point[in]);
      const std::int32_t next = partner[2 * cur + (1 - in)];
      if (next < 0) {
        forward.push_back(segments[cur].point[1 - in]);
        break;
      }
      const std::size_t ns = static_cast<std::size_t>(next / 2);
      if (ns == s0) {
        closed = true;
        break;
      }
      if (used[ns]) {
        forward.push_back(segments[cur].point[1 - in]);
        break;
      }
      cur = ns;
      in = next % 2;
    }
    if (!closed) {
      // Walk backward from s0's entry endpoint to find the chain's true start.
      std::int32_t prev = partner[2 * s0 + 0];
      while (prev >= 0) {
        const std::size_t ps = static_cast<std::size_t>(prev / 2);
        if (used[ps]) break;
        used[ps] = 1;
        const int out_end = prev % 2;  // we reach ps through this endpoint: it is ps's exit
        backward.push_back(segments[ps].point[1 - out_end]);
        prev = partner[2 * ps + (1 - out_end)];
      }
      std::vector<Vec2> chain(backward.rbegin(), backward.rend());
      chain.insert(chain.end(), forward.begin(), forward.end());
      cut.open_chains.push_back(std::move(chain));
    } else {
      cut.loops.push_back(std::move(forward));
      forward = {};
    }
  }
  // Close small gaps: join open ends closer than the tolerance, closest pairs first (a chain's
  // own two ends close it into a loop). Ends are bucketed on a grid of the tolerance's size, so
  // this stays linear even for triangle soups where every triangle is its own chain.
  auto& chains = cut.open_chains;
  if (!chains.empty() && gap_tolerance > 0) {
    const std::size_t c = chains.size();
    // End 2i is chain i's front, 2i+1 its back.
    auto end_point = [&](std::size_t end) -> const Vec2& {
      return end % 2 == 0 ? chains[end / 2].front() : chains[end / 2].back();
    };
    const double cell = gap_tolerance;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> buckets;
    auto cell_of = [&](const Vec2& p, int dx, int dy) {
      const std::int64_t x = static_cast<std::int64_t>(std::floor(p.x() / cell)) + dx;
      const std::int64_t y = static_cast<std::int64_t>(std::floor(p.y() / cell)) + dy;
      return (static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull) ^
             static_cast<std::uint64_t>(y);
    };
    for (std::size_t end = 0; end < 2 * c; ++end)
      buckets[cell_of(end_point(end), 0, 0)].push_back(static_cast<std::uint32_t>(end));
    struct Pair {
      double d2;
      std::uint32_t a, b;
    };
    std::vector<Pair> pairs;
    const double tol2 = gap_tolerance * gap_tolerance;
    for (std::size_t end = 0; end < 2 * c; ++end) {
      const Vec2& p = end_point(end);
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy) {
          auto it = buckets.find(cell_of(p, dx, dy));
          if (it == buckets.end()) continue;
          for (std::uint32_t other : it->second) {
            if (other <= end) continue;
            const double d2 = (end_point(other) - p).squaredNorm();
            if (d2 <= tol2) pairs.push_back({d2, static_cast<std::uint32_t>(end), other});
          }
        }
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
      return x.d2 < y.d2 || (x.d2 == y.d2 && (x.a < y.a || (x.a == y.a && x.b < y.b)));
    });
    // Join ends greedily; `link[end]` is the end it is joined to. Chains then form paths and
    // cycles of chains; a cycle is a closed loop.
    std::vector<std::int64_t> link(2 * c, -1);
    std::vector<std::size_t> group(c);
    for (std::size_t i = 0; i < c; ++i) group[i] = i;
    auto root = [&](std::size_t i) {
      while (group[i] != i) i = group[i] = group[group[i]];
      return i;
    };
    std::vector<std::uint8_t> closed_group(c, 0);
    for (const Pair& pr : pairs) {
      if (link[pr.a] >= 0 || link[pr.b] >= 0) continue;
      const std::size_t ra = root(pr.a / 2), rb = root(pr.b / 2);
      if (ra == rb) {
        if (closed_group[ra]) continue;
        closed_group[ra] = 1;  // joining the two free ends of one path closes it
      } else {
        group[ra] = rb;
        closed_group[rb] = closed_group[ra] || closed_group[rb];
      }
      link[pr.a] = pr.b;
      link[pr.b] = pr.a;
      cut.flags |= kFlagGapClosed;
    }
    // Walk each joined group from a free end (paths) or any end (cycles).
    std::vector<std::uint8_t> done(c, 0);
    std::vector<std::vector<Vec2>> remaining;
    auto walk = [&](std::size_t start_end, bool cycle) {
      std::vector<Vec2> pts;
      std::size_t end = start_end;
      while (true) {
        const std::size_t chain = end / 2;
        if (done[chain]) break;
        done[chain] = 1;
        // Enter the chain at `end`, traverse to its other end.
        if (end % 2 == 0)
          pts.insert(pts.end(), chains[chain].begin(), chains[chain].end());
        else
          pts.insert(pts.end(), chains[chain].rbegin(), chains[chain].rend());
        const std::size_t exit_end = end ^ 1u;
        if (link[exit_end] < 0) break;
        end = static_cast<std::size_t>(link[exit_end]);
      }
      if (cycle) {
        if (pts.size() >= 3) cut.loops.push_back(std::move(pts));
      } else {
        remaining.push_back(std::move(pts));
      }
    };
    for (std::size_t i = 0; i < c; ++i) {
      if (done[i]) continue;
      // Find a free end of this group by walking backwards from chain i's front.
      std::size_t end = 2 * i;
      bool cycle = false;
      for (std::size_t steps = 0; steps <= 2 * c; ++steps) {
        if (link[end] < 0) break;
        end = static_cast<std::size_t>(link[end]) ^ 1u;  // the other end of the linked chain
        if (end == 2 * i) {
          cycle = true;
          break;
        }
      }
      walk(end, cycle);
    }
    chains.swap(remaining);
  }
  // Drop degenerate loops (fewer than three points cannot bound area).
  cut.loops.erase(std::remove_if(cut.loops.begin(), cut.loops.end(),
                                 [](const std::vector<Vec2>& l) { return l.size() < 3; }),
                  cut.loops.end());
  return cut;
}

SectionGeometry select_section(const PlaneCut& cut) { return select_region(cut, nullptr); }

SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance) {
  std::vector<CutSegment> segments;
  cut_mesh(mesh, plane, segments, nullptr);
  return select_section(assemble_loops(segments, gap_tolerance));
}

}  // namespace osteon
