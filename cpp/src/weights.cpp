#include "osteon/weights.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "parallel.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace osteon {
namespace {

// Weights down to this are solver round-off (bounded biharmonic weights have ~-1e-9): read as 0.
constexpr double kNegativeTolerance = 1e-6;

std::invalid_argument bone_out_of_range(long long bone, int num_bones) {
  return std::invalid_argument("weights: bone (column) index " + std::to_string(bone) +
                               " out of range for " + std::to_string(num_bones) + " bones");
}

// CSR row offsets must start at 0 and never decrease.
void check_indptr(const Index* indptr, Index num_vertices) {
  if (indptr[0] != 0) throw std::invalid_argument("weights: CSR indptr must start at 0");
  for (Index v = 0; v < num_vertices; ++v)
    if (indptr[v + 1] < indptr[v])
      throw std::invalid_argument("weights: CSR indptr must not decrease");
}

// Throws for the first bad entry (not finite, negative beyond round-off, bone out of range).
template <class BoneIndex>
void check_entries(const BoneIndex* bones, const double* data, Index nnz, int num_bones) {
  for (Index k = 0; k < nnz; ++k) {
    const double w = data[k];
    if (!std::isfinite(w)) throw std::invalid_argument("weights contain NaN or infinity");
    if (w < -kNegativeTolerance) {
      std::ostringstream msg;
      msg << "weights must not be negative (found " << w << ")";
      throw std::invalid_argument(msg.str());
    }
    if (bones[k] < 0 || bones[k] >= num_bones) throw bone_out_of_range(bones[k], num_bones);
  }
}

// Bone of the largest weight in entries [begin, end), -1 when none is above round-off.
template <class BoneIndex>
int row_argmax(Index begin, Index end, const BoneIndex* bones, const double* data) {
  double best = 1e-12;  // round-off weights never make a bone dominant
  Index arg = -1;
  for (Index k = begin; k < end; ++k) {
    const bool larger = data[k] > best;  // branch-free: the loop carries only `best`
    best = larger ? data[k] : best;
    arg = larger ? k : arg;
  }
  return arg >= 0 ? static_cast<int>(bones[arg]) : -1;
}

}  // namespace

BoneWeights BoneWeights::from_dense(const double* dense, Index num_vertices, int num_bones) {
  BoneWeights w;
  w.num_vertices = num_vertices;
  w.num_bones = num_bones;
  w.row_start.resize(num_vertices + 1);
  w.row_start[0] = 0;
  for (Index v = 0; v < num_vertices; ++v) {
    const double* row = dense + v * num_bones;
    for (int b = 0; b < num_bones; ++b) {
      if (row[b] != 0.0) {
        w.bone.push_back(b);
        w.weight.push_back(row[b]);
      }
    }
    w.row_start[v + 1] = static_cast<Index>(w.bone.size());
  }
  return w;
}

BoneWeights BoneWeights::from_csr(const Index* indptr, const Index* indices, const double* data,
                                  Index num_vertices, int num_bones) {
  BoneWeights w;
  w.num_vertices = num_vertices;
  w.num_bones = num_bones;
  check_indptr(indptr, num_vertices);
  const Index nnz = indptr[num_vertices];
  w.row_start.assign(indptr, indptr + num_vertices + 1);
  w.bone.resize(nnz);
  w.weight.assign(data, data + nnz);
  for (Index k = 0; k < nnz; ++k) {
    if (indices[k] < 0 || indices[k] >= num_bones) throw bone_out_of_range(indices[k], num_bones);
    w.bone[k] = static_cast<int>(indices[k]);
  }
  return w;
}

double BoneWeights::row_sum(Index v) const {
  double s = 0.0;
  for (Index k = row_start[v]; k < row_start[v + 1]; ++k) s += weight[k];
  return s;
}

void validate_weights(const BoneWeights& w, Index num_vertices, int num_bones) {
  if (w.num_vertices != num_vertices)
    throw std::invalid_argument("weights have " + std::to_string(w.num_vertices) +
                                " rows but the mesh has " + std::to_string(num_vertices) +
                                " vertices");
  if (w.num_bones != num_bones)
    throw std::invalid_argument("weights have " + std::to_string(w.num_bones) +
                                " columns but the skeleton has " + std::to_string(num_bones) +
                                " bones");
  if (static_cast<Index>(w.row_start.size()) != num_vertices + 1)
    throw std::invalid_argument("weights: row offsets do not match the vertex count");
  if (w.bone.size() != w.weight.size() ||
      w.row_start[num_vertices] != static_cast<Index>(w.weight.size()))
    throw std::invalid_argument("weights: row offsets do not match the entries");
  check_entries(w.bone.data(), w.weight.data(), static_cast<Index>(w.weight.size()), num_bones);
}

std::vector<int> dominant_bones(const BoneWeights& w) {
  std::vector<int> dom(w.num_vertices);
  for (Index v = 0; v < w.num_vertices; ++v)
    dom[v] = row_argmax(w.row_start[v], w.row_start[v + 1], w.bone.data(), w.weight.data());
  return dom;
}

namespace {

// Whether any value of data[begin, end) is bad (NaN, infinite, negative beyond round-off): no
// branch and no early exit. The compiler does not vectorise a floating-point comparison that
// NaN makes unordered, so on SSE2 two lanes are tested at a time (cmpnge / cmpnle: true for NaN);
// on cow x64's 6.2M entries the scalar test was half of the dominant-bone pass.
bool any_bad_weight(const double* data, Index begin, Index end) {
  const double lo = -kNegativeTolerance, hi = std::numeric_limits<double>::max();
  Index k = begin;
  bool bad = false;
#if defined(__SSE2__)
  const __m128d vlo = _mm_set1_pd(lo), vhi = _mm_set1_pd(hi);
  __m128d acc = _mm_setzero_pd();
  for (; k + 4 <= end; k += 4) {
    const __m128d a = _mm_loadu_pd(data + k), b = _mm_loadu_pd(data + k + 2);
    acc = _mm_or_pd(acc, _mm_or_pd(_mm_cmpnge_pd(a, vlo), _mm_cmpnle_pd(a, vhi)));
    acc = _mm_or_pd(acc, _mm_or_pd(_mm_cmpnge_pd(b, vlo), _mm_cmpnle_pd(b, vhi)));
  }
  bad = _mm_movemask_pd(acc) != 0;
#endif
  for (; k < end; ++k) bad |= !(data[k] >= lo) | !(data[k] <= hi);
  return bad;
}

// Whether any bone of bones[begin, end) is out of range (one unsigned comparison: a negative bone
// is above the limit); this loop vectorises.
template <class BoneIndex>
bool any_bad_bone(const BoneIndex* bones, Index begin, Index end, int num_bones) {
  using Unsigned = std::make_unsigned_t<BoneIndex>;
  const Unsigned limit = static_cast<Unsigned>(num_bones);
  Unsigned bad = 0;
  for (Index k = begin; k < end; ++k) bad |= static_cast<Unsigned>(bones[k]) >= limit;
  return bad != 0;
}

template <class BoneIndex>
std::vector<int> dominant_bones_of_csr(const Index* indptr, const BoneIndex* indices,
                                       const double* data, Index num_vertices, int num_bones,
                                       int threads) {
  check_indptr(indptr, num_vertices);
  // Check all entries first in a branch-free pass (it vectorises); check_entries names the
  // first bad one only when there is one.
  const Index nnz = indptr[num_vertices];
  const Index block = 8192;
  const long chunks = static_cast<long>((num_vertices + block - 1) / block);
  std::vector<std::uint8_t> chunk_bad(chunks, 0);
  std::vector<int> dom(num_vertices, -1);
  detail::parallel_for(chunks, threads, [&](long chunk, int) {
    const Index v0 = chunk * block, v1 = std::min(num_vertices, v0 + block);
    const bool bad = any_bad_weight(data, indptr[v0], indptr[v1]) |
                     any_bad_bone(indices, indptr[v0], indptr[v1], num_bones);
    chunk_bad[chunk] = bad;
    if (bad) return;
    for (Index v = v0; v < v1; ++v) dom[v] = row_argmax(indptr[v], indptr[v + 1], indices, data);
  });
  if (std::find(chunk_bad.begin(), chunk_bad.end(), 1) != chunk_bad.end())
    check_entries(indices, data, nnz, num_bones);
  return dom;
}

}  // namespace

std::vector<int> dominant_bones_csr(const Index* indptr, const Index* indices, const double* data,
                                    Index num_vertices, int num_bones, int threads) {
  return dominant_bones_of_csr(indptr, indices, data, num_vertices, num_bones, threads);
}

std::vector<int> dominant_bones_csr(const Index* indptr, const std::int32_t* indices,
                                    const double* data, Index num_vertices, int num_bones,
                                    int threads) {
  return dominant_bones_of_csr(indptr, indices, data, num_vertices, num_bones, threads);
}

std::vector<int> nearest_bones(const MeshView& mesh, const Skeleton& s, int threads) {
  const int nb = s.num_bones();
  std::vector<int> nearest(mesh.num_vertices, 0);
  // Per-bone constants; the inner loop is branch-light so it vectorises.
  std::vector<Vec3> head(nb), axis(nb);
  std::vector<double> len(nb);
  for (int b = 0; b < nb; ++b) {
    head[b] = s.heads[b];
    len[b] = s.length(b);
    axis[b] = (s.tails[b] - s.heads[b]) / len[b];
  }
  const Index block = 4096;
  const long jobs = static_cast<long>((mesh.num_vertices + block - 1) / block);
  detail::parallel_for(jobs, threads, [&](long job, int) {
    const Index begin = job * block;
    const Index end = std::min(mesh.num_vertices, begin + block);
    std::vector<double> best(end - begin, std::numeric_limits<double>::infinity());
    for (int b = 0; b < nb; ++b) {
      const double hx = head[b].x(), hy = head[b].y(), hz = head[b].z();
      const double ax = axis[b].x(), ay = axis[b].y(), az = axis[b].z(), L = len[b];
      for (Index v = begin; v < end; ++v) {
        const double* p = mesh.vertices + 3 * v;
        const double dx = p[0] - hx, dy = p[1] - hy, dz = p[2] - hz;
        double t = dx * ax + dy * ay + dz * az;
        t = t < 0.0 ? 0.0 : (t > L ? L : t);
        const double ex = dx - t * ax, ey = dy - t * ay, ez = dz - t * az;
        const double d2 = ex * ex + ey * ey + ez * ez;
        if (d2 < best[v - begin]) {
          best[v - begin] = d2;
          nearest[v] = b;
        }
      }
    }
  });
  return nearest;
}

BoneWeights nearest_bone_weights(const MeshView& mesh, const Skeleton& s, int threads) {
  const std::vector<int> nearest = nearest_bones(mesh, s, threads);
  BoneWeights w;
  w.num_vertices = mesh.num_vertices;
  w.num_bones = s.num_bones();
  w.row_start.resize(mesh.num_vertices + 1);
  for (Index v = 0; v <= mesh.num_vertices; ++v) w.row_start[v] = v;
  w.bone = nearest;
  w.weight.assign(mesh.num_vertices, 1.0);
  return w;
}

}  // namespace osteon
