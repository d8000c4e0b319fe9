// Skinning weights, stored sparse by vertex (CSR) so large meshes never need dense V x B memory.
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/skeleton.hpp"

namespace osteon {

/// Sparse V x B skinning weights in compressed-row form (rows = vertices, columns = bones).
struct BoneWeights {
  Index num_vertices = 0;
  int num_bones = 0;
  std::vector<Index> row_start;  ///< #V+1 offsets into bone/weight
  std::vector<int> bone;         ///< nnz bone index per stored weight
  std::vector<double> weight;    ///< nnz weight (>= 0, unitless; rows are normalised by their sum)

  /// Builds from a dense row-major #V by #B array, keeping the non-zero entries.
  static BoneWeights from_dense(const double* dense, Index num_vertices, int num_bones);
  /// Builds from CSR arrays (indptr #V+1, indices nnz, data nnz), e.g. scipy.sparse.csr_matrix.
  static BoneWeights from_csr(const Index* indptr, const Index* indices, const double* data,
                              Index num_vertices, int num_bones);
  /// Sum of the weights of vertex v.
  double row_sum(Index v) const;
};

/// Throws std::invalid_argument if the shape does not match the mesh/skeleton, a bone index is out
/// of range, or a weight is negative or not finite.
void validate_weights(const BoneWeights& weights, Index num_vertices, int num_bones);

/// Dominant (largest-weight) bone of every vertex; -1 where a row is all zero.
std::vector<int> dominant_bones(const BoneWeights& weights);

/// The same straight from CSR arrays (indptr #V+1, indices nnz, data nnz), checking them in the
/// same pass (index range, finite, not below -1e-6) without copying the weights; `threads` as
/// in AnalysisOptions (0 = all cores).
std::vector<int> dominant_bones_csr(const Index* indptr, const Index* indices, const double* data,
                                    Index num_vertices, int num_bones, int threads = 0);
/// The same with 32-bit bone indices (SciPy's usual index type), read without a conversion.
std::vector<int> dominant_bones_csr(const Index* indptr, const std::int32_t* indices,
                                    const double* data, Index num_vertices, int num_bones,
                                    int threads = 0);

/// Nearest bone (by distance to the bone segment) of every vertex; rows listed in `only` if given.
std::vector<int> nearest_bones(const MeshView& mesh, const Skeleton& skeleton, int threads = 0);

/// Rigid binding: every vertex gets weight 1 on its nearest bone.
BoneWeights nearest_bone_weights(const MeshView& mesh, const Skeleton& skeleton, int threads = 0);

}  // namespace osteon
