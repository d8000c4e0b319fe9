#include "loose_pieces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "line_triangle.hpp"

namespace osteon {
namespace {

int find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The ray of the inside tests: a fixed direction that mesh edges are unlikely to follow.
Vec3 inside_ray() { return Vec3(1.0, 0.3141592653589793, 0.2718281828459045).normalized(); }

// True when the inside ray from p crosses triangle t (3 vertex indices). (Inline: the inside
// tests call it per face.)
inline bool ray_crosses(const MeshView& mesh, const std::int32_t* t, const Vec3& p,
                        const Vec3& dir) {
  const Vec3 a = mesh.vertex(t[0]);
  const Vec3 e1 = mesh.vertex(t[1]) - a, e2 = mesh.vertex(t[2]) - a;
  double hit = 0.0;
  return detail::line_hits_triangle(p, dir, a, e1, e2, hit) && hit > 0.0;
}

// True when point p lies inside the closed triangle set `faces` (`corners` = 3 per face; parity
// of crossings of a ray).
bool inside_shell(const MeshView& mesh, const std::int32_t* faces, std::size_t corners,
                  const Vec3& p) {
  const Vec3 dir = inside_ray();
  int hits = 0;
  for (std::size_t k = 0; k < corners; k += 3) hits += ray_crosses(mesh, faces + k, p, dir);
  return hits % 2 == 1;
}

// inside_shell over the faces of one piece (shell_of: #V shell of each vertex of a face;
// piece_of_shell: the piece of each shell; a face belongs to its vertices' shell), visiting only
// the grid cells that the ray's line passes near: every face the line hits lies in such a cell, and
// each face is tested as inside_shell tests it, so the parity is the same (a live run's grid is
// there anyway; the whole held body is not scanned for each sampled vertex).
bool inside_piece(const MeshView& mesh, const FaceGrid& grid,
                  const std::vector<std::int32_t>& shell_of,
                  const std::vector<std::int32_t>& piece_of_shell, std::int32_t piece,
                  const Vec3& p) {
  const Vec3 dir = inside_ray();
  int hits = 0;
  grid.for_faces_near(CutRegion{p, dir, 0.0}, [&](const std::int32_t* t) {
    // a face of one vertex thrice, in no other face, is in no shell (-1): no triangle to cross
    const std::int32_t k = shell_of[t[0]];
    hits += k >= 0 && piece_of_shell[k] == piece && ray_crosses(mesh, t, p, dir);
  });
  return hits % 2 == 1;
}

// Squared distance (mm²) from p to the closed triangle (a, b, c): the closest point by its
// Voronoi region (vertex, edge or face), as in Ericson's Real-Time Collision Detection, 5.1.5.
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  const double denom = 1.0 / (va + vb + vc);
  return (ap - (vb * denom) * ab - (vc * denom) * ac).squaredNorm();
}

}  // namespace

std::vector<std::vector<std::int32_t>> loose_pieces(const MeshView& mesh,
                                                    const std::vector<int>& vertex_bone,
                                                    int held_bone, double contact_gap,
                                                    Index* face_shells) {
  return LoosePieceFinder().find(mesh, vertex_bone, held_bone, contact_gap, face_shells, false);
}

void LoosePieceFinder::find_shells(const MeshView& mesh) {
  const Index nv = mesh.num_vertices, nf = mesh.num_faces;
  std::vector<std::int32_t>& parent = parent_;
  parent.resize(nv);
  for (Index v = 0; v < nv; ++v) parent[v] = static_cast<std::int32_t>(v);
  // A set's root is its smallest vertex (the larger root always joins the smaller one).
  auto join_roots = [&](std::int32_t a, std::int32_t b) {
    if (a == b) return a;
    if (a > b) std::swap(a, b);
    parent[b] = a;
    return a;
  };
  std::vector<std::uint8_t> used(nv, 0);
  for (Index f = 0; f < nf; ++f) {
    const std::int32_t* t = mesh.faces + 3 * f;
    // Most faces join nothing new: their vertices already point at one root (so an earlier
    // face marked them used; only a face of one vertex thrice, no triangle, marks nothing).
    const std::int32_t p0 = parent[t[0]];
    if (parent[t[1]] == p0 && parent[t[2]] == p0 && parent[p0] == p0) continue;
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
    const std::int32_t r = join_roots(find_root(parent, t[0]), find_root(parent, t[1]));
    join_roots(r, find_root(parent, t[2]));
  }
  // Shells numbered by their smallest vertex (a root comes before the rest of its set). A vertex
  // of no face is not printed: it is no shell (a stray vertex of a modelled figurine would
  // otherwise make it two shells and send every live run through the search).
  std::int32_t shells = 0;  // the roots of used vertices
  for (Index v = 0; v < nv; ++v) shells += used[v] && parent[v] == v;
  shells_ = shells;
  have_shells_ = true;
  shell_of_.assign(nv, -1);  // (its size tells the next call which mesh the shells are of)
  if (shells <= 1) return;   // no loose piece whatever the positions: nothing more to keep
  shells = 0;
  for (Index v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    const std::int32_t r = find_root(parent, static_cast<std::int32_t>(v));
    shell_of_[v] = r == v ? shells++ : shell_of_[r];
  }
  // Each shell's vertices (ascending) and faces (as in the mesh), and the largest shell.
  shell_vstart_.assign(shells + 1, 0);
  shell_fstart_.assign(shells + 1, 0);
  for (Index v = 0; v < nv; ++v)
    if (shell_of_[v] >= 0) ++shell_vstart_[shell_of_[v] + 1];
  // A face of one vertex thrice whose vertex is in no other face is no triangle and in no shell
  // (its vertex was never marked used): it is left out of the face lists.
  for (Index f = 0; f < nf; ++f)
    if (const std::int32_t k = shell_of_[mesh.faces[3 * f]]; k >= 0) ++shell_fstart_[k + 1];
  largest_ = 0;
  for (std::int32_t k = 0; k < shells; ++k)
    if (shell_vstart_[k + 1] > shell_vstart_[largest_ + 1]) largest_ = k;
  for (std::int32_t k = 0; k < shells; ++k) {
    shell_vstart_[k + 1] += shell_vstart_[k];
    shell_fstart_[k + 1] += shell_fstart_[k];
  }
  shell_vertices_.resize(shell_vstart_[shells]);
  shell_faces_.resize(3 * shell_fstart_[shells]);
  other_vertices_.clear();
  std::vector<Index> fill(shell_vstart_.begin(), shell_vstart_.end() - 1);
  for (Index v = 0; v < nv; ++v) {
    const std::int32_t k = shell_of_[v];
    if (k < 0) continue;
    shell_vertices_[fill[k]++] = static_cast<std::int32_t>(v);
    if (k != largest_) other_vertices_.push_back(static_cast<std::int32_t>(v));
  }
  fill.assign(shell_fstart_.begin(), shell_fstart_.end() - 1);
  for (Index f = 0; f < nf; ++f) {
    const std::int32_t* t = mesh.faces + 3 * f;
    if (const std::int32_t k = shell_of_[t[0]]; k >= 0)
      std::copy(t, t + 3, shell_faces_.begin() + 3 * fill[k]++);
  }
}

namespace detail {

// A piece's vertices or faces (3 indices per face): a shell's own list or a merged one.
struct IndexSpan {
  const std::int32_t* first = nullptr;
  std::size_t count = 0;
  const std::int32_t* begin() const { return first; }
  const std::int32_t* end() const { return first + count; }
  std::size_t size() const { return count; }
  bool empty() const { return count == 0; }
  std::int32_t operator[](std::size_t k) const { return first[k]; }
};

struct PieceSet {
  std::vector<IndexSpan> verts, faces;  // per piece
  std::vector<Vec3> lo, hi;             // per piece: the box of its vertices, mm
};

}  // namespace detail

namespace {

using detail::PieceSet;

// Fills the pieces' boxes; returns the held piece: the one with the most vertices of
// `held_bone`, else (ties) the one with the most vertices, else the first.
std::size_t box_pieces_and_find_held(const MeshView& mesh, const std::vector<int>& vertex_bone,
                                     int held_bone, const std::vector<std::int32_t>& shell_of,
                                     const std::vector<std::int32_t>& piece_of_shell,
                                     PieceSet& pieces) {
  const std::size_t np = pieces.verts.size();
  std::vector<Vec3>& lo = pieces.lo;
  std::vector<Vec3>& hi = pieces.hi;
  lo.assign(np, Vec3::Constant(std::numeric_limits<double>::infinity()));
  hi.assign(np, Vec3::Constant(-std::numeric_limits<double>::infinity()));
  std::vector<Index> held_count(np, 0);
  for (Index v = 0; v < mesh.num_vertices; ++v) {
    const std::int32_t k = shell_of[v];
    if (k < 0) continue;
    const int p = piece_of_shell[k];
    lo[p] = lo[p].cwiseMin(mesh.vertex(v));
    hi[p] = hi[p].cwiseMax(mesh.vertex(v));
    held_count[p] += vertex_bone[v] == held_bone;
  }
  std::size_t held = 0;
  for (std::size_t p = 1; p < np; ++p)
    if (held_count[p] > held_count[held] ||
        (held_count[p] == held_count[held] && pieces.verts[p].size() > pieces.verts[held].size()))
      held = p;
  return held;
}

// Whether two pieces touch or overlap for the printer (see loose_pieces in loose_pieces.hpp).
class PieceContact {
 public:
  PieceContact(const MeshView& mesh, const PieceSet& pieces, double gap, const FaceGrid* grid,
               const std::vector<std::int32_t>& shell_of,
               const std::vector<std::int32_t>& piece_of_shell)
      : mesh_(mesh),
        verts_(pieces.verts),
        faces_(pieces.faces),
        lo_(pieces.lo),
        hi_(pieces.hi),
        gap_(gap),
        grid_(grid),
        shell_of_(shell_of),
        piece_of_shell_(piece_of_shell) {}

  bool overlap(std::size_t a, std::size_t b) const {
    const double gap = gap_;
    const auto& lo = lo_;
    const auto& hi = hi_;
    if ((lo[a].array() > hi[b].array() + gap).any() || (lo[b].array() > hi[a].array() + gap).any())
      return false;
    if ((lo[a].array() > hi[b].array()).any() || (lo[b].array() > hi[a].array()).any())
      return within_gap(a, b);
    if (some_vertex_inside(a, b) || some_vertex_inside(b, a)) return true;
    return surfaces_cross(a, b);
  }

 private:
  // Pieces closer than the gap (a vertex of one within `gap` of a face of the other) touch for
  // the printer. Only the parts inside the common box widened by the gap are visited; past a
  // work cap they count as attached (doubt keeps a piece held).
  bool within_gap(std::size_t a, std::size_t b) const {
    const double gap = gap_;
    const MeshView& mesh = mesh_;
    const auto& lo = lo_;
    const auto& hi = hi_;
    const auto& verts = verts_;
    const auto& faces = faces_;
    if (gap <= 0) return false;
    const Vec3 clo = (lo[a].cwiseMax(lo[b]).array() - gap).matrix();
    const Vec3 chi = (hi[a].cwiseMin(hi[b]).array() + gap).matrix();
    auto in_box = [&](const Vec3& p) {
      return !((p.array() < clo.array()).any() || (p.array() > chi.array()).any());
    };
    auto near_vertices = [&](std::size_t piece) {
      std::vector<std::int32_t> out;
      for (std::int32_t v : verts[piece])
        if (in_box(mesh.vertex(v))) out.push_back(v);
      return out;
    };
    auto near_faces = [&](std::size_t piece) {
      std::vector<std::int32_t> out;
      const auto& fs = faces[piece];
      for (std::size_t k = 0; k < fs.size(); k += 3) {
        const Vec3 p = mesh.vertex(fs[k]), q = mesh.vertex(fs[k + 1]), r = mesh.vertex(fs[k + 2]);
        const Vec3 l = p.cwiseMin(q).cwiseMin(r), h = p.cwiseMax(q).cwiseMax(r);
        if (!((l.array() > chi.array()).any() || (h.array() < clo.array()).any()))
          out.insert(out.end(), fs.begin() + k, fs.begin() + k + 3);
      }
      return out;
    };
    const double gap2 = gap * gap;
    auto vertex_near_face = [&](const std::vector<std::int32_t>& vs,
                                const std::vector<std::int32_t>& fs) {
      if (static_cast<double>(vs.size()) * static_cast<double>(fs.size()) > 3e7) return true;
      for (std::int32_t v : vs) {
        const Vec3 p = mesh.vertex(v);
        for (std::size_t k = 0; k < fs.size(); k += 3)
          if (point_triangle_distance2(p, mesh.vertex(fs[k]), mesh.vertex(fs[k + 1]),
                                       mesh.vertex(fs[k + 2])) <= gap2)
            return true;
      }
      return false;
    };
    return vertex_near_face(near_vertices(a), near_faces(b)) ||
           vertex_near_face(near_vertices(b), near_faces(a));
  }

  // Vertices of `from` (16 sampled) inside `into` (ray parity; along the grid when there is one).
  bool some_vertex_inside(std::size_t from, std::size_t into) const {
    const MeshView& mesh = mesh_;
    const auto& verts = verts_;
    const auto& faces = faces_;
    const FaceGrid* grid = grid_;
    if (faces[into].empty()) return false;
    const std::size_t n = verts[from].size(), step = std::max<std::size_t>(1, n / 16);
    for (std::size_t k = 0; k < n; k += step)
      if (grid != nullptr
              ? inside_piece(mesh, *grid, shell_of_, piece_of_shell_,
                             static_cast<std::int32_t>(into), mesh.vertex(verts[from][k]))
              : inside_shell(mesh, faces[into].begin(), faces[into].size(),
                             mesh.vertex(verts[from][k])))
        return true;
    return false;
  }

  // Surfaces that pass through each other (a wing plate through a body): an edge of one
  // crosses a face of the other, inside the boxes' common part. Past a work cap the pieces
  // count as attached: calling a piece loose drops its load, so doubt keeps it held.
  bool surfaces_cross(std::size_t a, std::size_t b) const {
    const MeshView& mesh = mesh_;
    const auto& faces = faces_;
    const Vec3 clo = lo_[a].cwiseMax(lo_[b]), chi = hi_[a].cwiseMin(hi_[b]);
    auto in_common = [&](const Vec3& p, const Vec3& q, const Vec3& r) {
      const Vec3 l = p.cwiseMin(q).cwiseMin(r), h = p.cwiseMax(q).cwiseMax(r);
      return !((l.array() > chi.array()).any() || (h.array() < clo.array()).any());
    };
    std::vector<std::int32_t> fa, fb;
    for (int side = 0; side < 2; ++side) {
      auto& out = side == 0 ? fa : fb;
      const auto& fs = faces[side == 0 ? a : b];
      for (std::size_t k = 0; k < fs.size(); k += 3)
        if (in_common(mesh.vertex(fs[k]), mesh.vertex(fs[k + 1]), mesh.vertex(fs[k + 2])))
          out.insert(out.end(), fs.begin() + k, fs.begin() + k + 3);
    }
    if (fa.empty() || fb.empty()) return within_gap(a, b);
    if (static_cast<double>(fa.size()) * static_cast<double>(fb.size()) > 9e7) return true;
    return edges_cross(fa, fb) || edges_cross(fb, fa) || within_gap(a, b);
  }

  // An edge of a triangle of `edges_of` crosses a triangle of `faces_of` (3 indices each).
  bool edges_cross(const std::vector<std::int32_t>& edges_of,
                   const std::vector<std::int32_t>& faces_of) const {
    const MeshView& mesh = mesh_;
    for (std::size_t k = 0; k < edges_of.size(); k += 3)
      for (int e = 0; e < 3; ++e) {
        const Vec3 p = mesh.vertex(edges_of[k + e]);
        const Vec3 d = mesh.vertex(edges_of[k + (e + 1) % 3]) - p;
        for (std::size_t m = 0; m < faces_of.size(); m += 3) {
          const Vec3 t0 = mesh.vertex(faces_of[m]);
          double t = 0.0;
          if (detail::line_hits_triangle(p, d, t0, mesh.vertex(faces_of[m + 1]) - t0,
                                         mesh.vertex(faces_of[m + 2]) - t0, t) &&
              t >= 0.0 && t <= 1.0)
            return true;
        }
      }
    return false;
  }

  const MeshView& mesh_;
  const std::vector<detail::IndexSpan>& verts_;
  const std::vector<detail::IndexSpan>& faces_;
  const std::vector<Vec3>& lo_;
  const std::vector<Vec3>& hi_;
  double gap_;
  const FaceGrid* grid_;
  const std::vector<std::int32_t>& shell_of_;
  const std::vector<std::int32_t>& piece_of_shell_;
};

}  // namespace

// Shells touching at exactly the same position (unwelded meshes) are one piece: a union-find
// over the shells, whose root is its smallest shell (so the pieces are numbered, below, by
// their smallest vertex, as shells are). Positions shared within one shell change nothing, so
// only the vertices outside the largest shell are sorted; each vertex of the largest shell
// inside their box looks its position up among them (a figurine with a small separate part:
// no sort of the whole mesh on every live run).
void LoosePieceFinder::join_touching_shells(const MeshView& mesh) {
  const auto shells = static_cast<std::int32_t>(shells_);
  std::vector<std::int32_t>& parent = parent_;
  parent.resize(shells);
  for (std::int32_t k = 0; k < shells; ++k) parent[k] = k;
  auto join = [&](std::int32_t u, std::int32_t v) {
    std::int32_t a = find_root(parent, shell_of_[u]), b = find_root(parent, shell_of_[v]);
    if (a == b) return;
    if (a > b) std::swap(a, b);
    parent[b] = a;
  };
  std::vector<std::int32_t>& order = order_;
  order.assign(other_vertices_.begin(), other_vertices_.end());
  Vec3 others_lo = Vec3::Constant(std::numeric_limits<double>::infinity()), others_hi = -others_lo;
  for (std::int32_t v : order) {
    others_lo = others_lo.cwiseMin(mesh.vertex(v));
    others_hi = others_hi.cwiseMax(mesh.vertex(v));
  }
  auto less = [&](std::int32_t a, std::int32_t b) {
    const double* p = mesh.vertices + 3 * static_cast<Index>(a);
    const double* q = mesh.vertices + 3 * static_cast<Index>(b);
    return std::lexicographical_compare(p, p + 3, q, q + 3);
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < order.size(); ++k)
    if (!less(order[k - 1], order[k])) join(order[k - 1], order[k]);
  for (Index k = shell_vstart_[largest_], e = shell_vstart_[largest_ + 1]; k < e; ++k) {
    const std::int32_t u = shell_vertices_[k];
    const Vec3 p = mesh.vertex(u);
    if ((p.array() < others_lo.array()).any() || (p.array() > others_hi.array()).any()) continue;
    const auto it = std::lower_bound(order.begin(), order.end(), u, less);
    if (it != order.end() && !less(u, *it)) join(u, *it);
  }
}

std::size_t LoosePieceFinder::number_pieces() {
  const auto shells = static_cast<std::int32_t>(shells_);
  std::vector<std::int32_t>& parent = parent_;
  std::vector<std::int32_t>& piece_of_shell = piece_of_shell_;
  piece_of_shell.assign(shells, -1);
  std::size_t np = 0;
  for (std::int32_t k = 0; k < shells; ++k) {
    const std::int32_t r = find_root(parent, k);
    if (piece_of_shell[r] < 0) piece_of_shell[r] = static_cast<std::int32_t>(np++);
    piece_of_shell[k] = piece_of_shell[r];
  }
  return np;
}

// Pieces: shells, or unions of shells (their vertices in ascending order, their faces in any:
// every test on a piece's faces asks whether some face does something).
void LoosePieceFinder::list_piece_elements(std::size_t np, detail::PieceSet& pieces) {
  const auto shells = static_cast<std::int32_t>(shells_);
  const std::vector<std::int32_t>& piece_of_shell = piece_of_shell_;
  std::vector<detail::IndexSpan>& verts = pieces.verts;
  std::vector<detail::IndexSpan>& faces = pieces.faces;
  verts.assign(np, {});
  faces.assign(np, {});
  std::vector<std::int32_t> piece_shells(np, 0), slot(np, -1);
  for (std::int32_t k = 0; k < shells; ++k) ++piece_shells[piece_of_shell[k]];
  std::size_t merged = 0;  // pieces of several shells: their lists are built in merged_
  for (std::int32_t k = 0; k < shells; ++k) {
    const std::size_t q = piece_of_shell[k];
    const Index v0 = shell_vstart_[k], v1 = shell_vstart_[k + 1];
    const Index f0 = 3 * shell_fstart_[k], f1 = 3 * shell_fstart_[k + 1];
    if (piece_shells[q] == 1) {
      verts[q] = {shell_vertices_.data() + v0, static_cast<std::size_t>(v1 - v0)};
      faces[q] = {shell_faces_.data() + f0, static_cast<std::size_t>(f1 - f0)};
      continue;
    }
    if (slot[q] < 0) {
      slot[q] = static_cast<std::int32_t>(merged++);
      if (merged_.size() < 2 * merged) merged_.resize(2 * merged);
      merged_[2 * slot[q]].clear();
      merged_[2 * slot[q] + 1].clear();
    }
    std::vector<std::int32_t>& vs = merged_[2 * slot[q]];
    std::vector<std::int32_t>& fs = merged_[2 * slot[q] + 1];
    vs.insert(vs.end(), shell_vertices_.begin() + v0, shell_vertices_.begin() + v1);
    fs.insert(fs.end(), shell_faces_.begin() + f0, shell_faces_.begin() + f1);
  }
  for (std::size_t q = 0; q < np; ++q) {
    if (slot[q] < 0) continue;
    std::vector<std::int32_t>& vs = merged_[2 * slot[q]];
    const std::vector<std::int32_t>& fs = merged_[2 * slot[q] + 1];
    std::sort(vs.begin(), vs.end());
    verts[q] = {vs.data(), vs.size()};
    faces[q] = {fs.data(), fs.size()};
  }
}

std::vector<std::vector<std::int32_t>> LoosePieceFinder::find(const MeshView& mesh,
                                                              const std::vector<int>& vertex_bone,
                                                              int held_bone, double contact_gap,
                                                              Index* face_shells, bool same_faces,
                                                              const FaceGrid* grid) {
  const Index nv = mesh.num_vertices;
  const double gap = std::isfinite(contact_gap) ? std::max(0.0, contact_gap) : 0.0;
  if (!same_faces || !have_shells_ || static_cast<Index>(shell_of_.size()) != nv) find_shells(mesh);
  if (face_shells != nullptr) *face_shells = shells_;
  if (shells_ <= 1) return {};
  join_touching_shells(mesh);
  const std::size_t np = number_pieces();
  if (np <= 1) return {};
  detail::PieceSet pieces;
  list_piece_elements(np, pieces);
  const std::size_t held =
      box_pieces_and_find_held(mesh, vertex_bone, held_bone, shell_of_, piece_of_shell_, pieces);
  // Pieces attached to the held one, directly or through other attached pieces.
  const PieceContact contact(mesh, pieces, gap, grid, shell_of_, piece_of_shell_);
  std::vector<std::uint8_t> attached(np, 0);
  std::vector<std::size_t> queue{held};
  attached[held] = 1;
  for (std::size_t q = 0; q < queue.size(); ++q)
    for (std::size_t p = 0; p < np; ++p)
      if (!attached[p] && contact.overlap(queue[q], p)) {
        attached[p] = 1;
        queue.push_back(p);
      }
  std::vector<std::vector<std::int32_t>> loose;
  for (std::size_t p = 0; p < np; ++p)
    if (!attached[p] && !pieces.faces[p].empty())
      loose.emplace_back(pieces.verts[p].begin(), pieces.verts[p].end());
  return loose;
}

}  // namespace osteon
