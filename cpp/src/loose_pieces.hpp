// Loose pieces of a mesh: shells that would fall off the printed model (docs/robustness.md).
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

namespace detail {
struct PieceSet;  // loose_pieces.cpp: the pieces' vertices, faces and boxes
}  // namespace detail

/// Loose pieces of a mesh: its shells (faces connected by shared vertices or by vertices at
/// exactly the same position) that neither touch nor overlap the held piece, directly or through
/// other attached shells. The held piece is the shell with the most vertices of `held_bone`
/// (vertex_bone, #V), else the largest. Two shells overlap when a vertex of one (16 sampled of
/// each) lies inside the other (ray parity) or an edge of one crosses a face of the other (in
/// the common part of their boxes; past ~1e8 edge-face pairs they count as attached), or when
/// they are closer than `contact_gap` mm (a vertex of either within that distance of a face of
/// the other): a printer fuses a gap narrower than it can print. Returns the vertex indices of
/// each loose piece. `face_shells`, when given, receives the number of shells the faces alone
/// make (shared vertex indices; positions not used; a vertex of no face is not printed and is no
/// shell, nor part of any piece): 1 means no loose piece whatever the vertices' positions, which
/// a caller with fixed faces (Analyzer) may keep.
std::vector<std::vector<std::int32_t>> loose_pieces(const MeshView& mesh,
                                                    const std::vector<int>& vertex_bone,
                                                    int held_bone, double contact_gap = 0.0,
                                                    Index* face_shells = nullptr);

/// loose_pieces() for repeated use (an Analyzer's live runs): the same answer, with the working
/// arrays kept from call to call (a live update allocates and frees no memory for it: freed
/// arrays go back to the system and their pages come back zero-filled, at a cost per page) and,
/// when `same_faces`, the faces' shells of the previous call reused (they do not depend on the
/// vertices' positions).
class LoosePieceFinder {
 public:
  /// As loose_pieces(mesh, vertex_bone, held_bone, contact_gap (mm), face_shells); same_faces:
  /// the mesh's faces and vertex count are those of the previous call; grid (optional): a face
  /// grid built from this mesh, which the inside tests walk along their ray instead of testing
  /// every face of a piece (the same answer).
  std::vector<std::vector<std::int32_t>> find(const MeshView& mesh,
                                              const std::vector<int>& vertex_bone, int held_bone,
                                              double contact_gap, Index* face_shells,
                                              bool same_faces, const FaceGrid* grid = nullptr);

 private:
  /// The faces' shells (they do not depend on the vertices' positions).
  void find_shells(const MeshView& mesh);
  /// Joins the shells that touch at exactly the same position (parent_: a union-find over the
  /// shells whose root is its smallest shell).
  void join_touching_shells(const MeshView& mesh);
  /// Numbers the pieces (piece_of_shell_) from the joined shells; returns their count.
  std::size_t number_pieces();
  /// Each piece's vertices (ascending) and faces (the shells' own lists, or for a piece of
  /// several shells their union, in merged_).
  void list_piece_elements(std::size_t np, detail::PieceSet& pieces);
  bool have_shells_ = false;
  Index shells_ = 0;                    // shells of the faces alone
  std::vector<std::int32_t> shell_of_;  // #V shell of each vertex (by smallest vertex; -1: no face)
  std::vector<Index> shell_vstart_, shell_fstart_;  // shell k: [start[k], start[k + 1])
  std::vector<std::int32_t> shell_vertices_;        // each shell's vertices, ascending
  std::vector<std::int32_t> shell_faces_;           // each shell's faces (3 per face), mesh order
  std::int32_t largest_ = 0;                        // the shell with the most vertices
  std::vector<std::int32_t> other_vertices_;        // vertices of the other shells, ascending
  // Scratch kept for its storage.
  std::vector<std::int32_t> parent_, order_, piece_of_shell_;
  std::vector<std::vector<std::int32_t>> merged_;  // lists of pieces of several shells
};

}  // namespace osteon
