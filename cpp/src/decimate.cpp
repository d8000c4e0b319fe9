// Quadric edge-collapse decimation (Garland & Heckbert 1997) with the link condition, so a closed
// 2-manifold stays one (issue 35). See osteon/decimate.hpp.
#include "osteon/decimate.hpp"

#include <Eigen/LU>  // computeInverseAndDetWithCheck
#include <algorithm>
#include <array>
#include <iterator>
#include <queue>
#include <stdexcept>
#include <tuple>
#include <vector>

namespace osteon {
namespace {

using Face = std::array<std::int32_t, 3>;

/// Sum of squared distances to planes n·x + d = 0, each weighted by an area: x'Ax + 2b'x + c, mm⁴.
struct Quadric {
  Mat3 a = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  double c = 0.0;

  void add_plane(const Vec3& n, double d, double weight) {
    a += weight * n * n.transpose();
    b += weight * d * n;
    c += weight * d * d;
  }
  Quadric operator+(const Quadric& o) const {
    Quadric q;
    q.a = a + o.a;
    q.b = b + o.b;
    q.c = c + o.c;
    return q;
  }
  double error(const Vec3& p) const { return p.dot(a * p) + 2.0 * b.dot(p) + c; }
};

/// An edge's collapse, as priced when it was queued: stale once either end has changed (the
/// ends' stamps only grow, so their sum tells). Small, as the queue holds ~4 per face.
struct Candidate {
  double cost;
  std::int32_t a, b;
  std::uint32_t stamps;
};

/// Where a collapse puts the merged vertex, and its quadric error there, mm⁴.
struct Placement {
  double cost;
  Vec3 pos;
};

/// Orders the queue cheapest first, ties by vertex indices (deterministic).
struct Costlier {
  bool operator()(const Candidate& x, const Candidate& y) const {
    return std::tie(x.cost, x.a, x.b) > std::tie(y.cost, y.a, y.b);
  }
};

class Decimator {
 public:
  explicit Decimator(const MeshView& mesh);
  void run(Index target_faces);
  DecimatedMesh result() const;

 private:
  std::vector<Vec3> pos_;
  std::vector<Face> faces_;
  std::vector<std::uint8_t> face_alive_;
  std::vector<std::vector<std::int32_t>> vertex_faces_;  // may list dead faces (skipped)
  std::vector<Quadric> quadric_;
  std::vector<std::uint32_t> stamp_;
  std::vector<std::uint8_t> vertex_alive_, locked_;  // locked: on a boundary/non-manifold edge
  Index live_faces_ = 0;
  std::priority_queue<Candidate, std::vector<Candidate>, Costlier> queue_;

  void lock_open_edges();
  mutable std::vector<std::int32_t> ring_a_, ring_b_, common_;  // scratch (no allocation)

  void neighbours(std::int32_t v, std::vector<std::int32_t>& out) const;
  Placement place(std::int32_t a, std::int32_t b) const;
  Candidate price(std::int32_t a, std::int32_t b) const;
  bool keeps_topology(std::int32_t a, std::int32_t b) const;
  bool keeps_orientation(std::int32_t a, std::int32_t b, const Vec3& pos) const;
  void collapse(std::int32_t a, std::int32_t b, const Vec3& pos);
};

Decimator::Decimator(const MeshView& mesh)
    : pos_(mesh.num_vertices),
      vertex_faces_(mesh.num_vertices),
      quadric_(mesh.num_vertices),
      stamp_(mesh.num_vertices, 0),
      vertex_alive_(mesh.num_vertices, 0),
      locked_(mesh.num_vertices, 0) {
  for (Index i = 0; i < mesh.num_vertices; ++i) pos_[i] = mesh.vertex(i);
  for (Index f = 0; f < mesh.num_faces; ++f) {
    const Face t{mesh.faces[3 * f], mesh.faces[3 * f + 1], mesh.faces[3 * f + 2]};
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;  // no area, no orientation
    const auto id = static_cast<std::int32_t>(faces_.size());
    faces_.push_back(t);
    const Vec3 n = (pos_[t[1]] - pos_[t[0]]).cross(pos_[t[2]] - pos_[t[0]]);
    const double twice_area = n.norm();
    for (std::int32_t v : t) {
      vertex_faces_[v].push_back(id);
      vertex_alive_[v] = 1;
      if (twice_area > 0.0) {
        const Vec3 unit = n / twice_area;
        quadric_[v].add_plane(unit, -unit.dot(pos_[t[0]]), 0.5 * twice_area);
      }
    }
  }
  face_alive_.assign(faces_.size(), 1);
  live_faces_ = static_cast<Index>(faces_.size());
  lock_open_edges();
}

/// Locks both ends of every edge not shared by exactly two faces (a boundary or non-manifold
/// edge: collapsing next to one could change the topology the link condition assumes) and
/// queues every other edge.
void Decimator::lock_open_edges() {
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  edges.reserve(3 * faces_.size());
  for (const Face& t : faces_)
    for (int k = 0; k < 3; ++k)
      edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<std::int32_t, std::int32_t>> manifold;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 2)
      manifold.push_back(edges[i]);
    else
      locked_[edges[i].first] = locked_[edges[i].second] = 1;
    i = j;
  }
  std::vector<Candidate> all;
  all.reserve(manifold.size());
  for (const auto& [a, b] : manifold)
    if (!locked_[a] && !locked_[b]) all.push_back(price(a, b));
  queue_ = decltype(queue_)(Costlier(), std::move(all));  // heapified at once
}

/// The vertices sharing a live face with v (ascending, each once), into out.
void Decimator::neighbours(std::int32_t v, std::vector<std::int32_t>& out) const {
  out.clear();
  for (std::int32_t f : vertex_faces_[v]) {
    if (!face_alive_[f]) continue;
    for (std::int32_t w : faces_[f])
      if (w != v) out.push_back(w);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

/// The position of least quadric error for merging a and b: the planes' common point when they
/// fix one near the edge, else the better of the ends and the midpoint.
Placement Decimator::place(std::int32_t a, std::int32_t b) const {
  const Quadric q = quadric_[a] + quadric_[b];
  const Vec3 mid = 0.5 * (pos_[a] + pos_[b]);
  Vec3 best = mid;
  double cost = q.error(mid);
  for (const Vec3& p : {pos_[a], pos_[b]}) {
    const double e = q.error(p);
    if (e < cost) cost = e, best = p;
  }
  Mat3 inverse;
  double det = 0.0;
  bool invertible = false;
  const double scale = q.a.trace();  // |det| of a well-posed A is about (trace / 3)^3
  q.a.computeInverseAndDetWithCheck(inverse, det, invertible, 1e-9 * scale * scale * scale);
  if (invertible) {  // the planes fix a point: use it when it stays near the edge
    const Vec3 p = -(inverse * q.b);
    const double e = q.error(p);
    if (p.allFinite() && (p - mid).norm() <= (pos_[a] - pos_[b]).norm() && e < cost)
      cost = e, best = p;
  }
  return Placement{std::max(cost, 0.0), best};
}

/// The queue entry of edge a-b (a < b or not).
Candidate Decimator::price(std::int32_t a, std::int32_t b) const {
  const std::int32_t lo = std::min(a, b), hi = std::max(a, b);
  return Candidate{place(lo, hi).cost, lo, hi, stamp_[lo] + stamp_[hi]};
}

/// The link condition on a closed manifold: a and b share exactly the two neighbours opposite
/// their edge (the edge has two live faces), and the piece keeps more than a tetrahedron.
bool Decimator::keeps_topology(std::int32_t a, std::int32_t b) const {
  neighbours(a, ring_a_);
  neighbours(b, ring_b_);
  common_.clear();
  std::set_intersection(ring_a_.begin(), ring_a_.end(), ring_b_.begin(), ring_b_.end(),
                        std::back_inserter(common_));
  if (common_.size() != 2) return false;
  int shared_faces = 0;
  for (std::int32_t f : vertex_faces_[a]) {
    if (!face_alive_[f]) continue;
    const Face& t = faces_[f];
    if (t[0] == b || t[1] == b || t[2] == b) ++shared_faces;
  }
  if (shared_faces != 2) return false;
  // a, b and at least three others (the union less the two in common): not a tetrahedron
  return ring_a_.size() + ring_b_.size() - common_.size() >= 5;
}

/// No face left by the collapse turns by more than 78° (cos 0.2), over, or to a line when a
/// and b move to pos: a sliver folded into its neighbours would pinch the surface.
bool Decimator::keeps_orientation(std::int32_t a, std::int32_t b, const Vec3& pos) const {
  for (std::int32_t v : {a, b}) {
    for (std::int32_t f : vertex_faces_[v]) {
      if (!face_alive_[f]) continue;
      const Face& t = faces_[f];
      const bool has_a = t[0] == a || t[1] == a || t[2] == a;
      const bool has_b = t[0] == b || t[1] == b || t[2] == b;
      if (has_a && has_b) continue;  // removed by the collapse
      std::array<Vec3, 3> p{pos_[t[0]], pos_[t[1]], pos_[t[2]]};
      const Vec3 before = (p[1] - p[0]).cross(p[2] - p[0]);
      for (int k = 0; k < 3; ++k)
        if (t[k] == v) p[k] = pos;
      const Vec3 after = (p[1] - p[0]).cross(p[2] - p[0]);
      if (after.dot(before) <= 0.2 * after.norm() * before.norm()) return false;
    }
  }
  return true;
}

/// Merges b into a at pos and requeues a's edges.
void Decimator::collapse(std::int32_t a, std::int32_t b, const Vec3& pos) {
  for (std::int32_t f : vertex_faces_[b]) {
    if (!face_alive_[f]) continue;
    Face& t = faces_[f];
    if (t[0] == a || t[1] == a || t[2] == a) {
      face_alive_[f] = 0;
      --live_faces_;
      continue;
    }
    for (std::int32_t& w : t)
      if (w == b) w = a;
    vertex_faces_[a].push_back(f);
  }
  std::vector<std::int32_t>& fa = vertex_faces_[a];
  fa.erase(std::remove_if(fa.begin(), fa.end(), [&](std::int32_t f) { return !face_alive_[f]; }),
           fa.end());
  vertex_faces_[b].clear();
  vertex_alive_[b] = 0;
  pos_[a] = pos;
  quadric_[a] = quadric_[a] + quadric_[b];
  ++stamp_[a];
  ++stamp_[b];
  neighbours(a, ring_a_);
  for (std::int32_t n : ring_a_)
    if (!locked_[n]) queue_.push(price(a, n));
}

void Decimator::run(Index target_faces) {
  while (live_faces_ > target_faces && !queue_.empty()) {
    const Candidate c = queue_.top();
    queue_.pop();
    if (!vertex_alive_[c.a] || !vertex_alive_[c.b]) continue;
    if (stamp_[c.a] + stamp_[c.b] != c.stamps) continue;  // requeued since
    if (!keeps_topology(c.a, c.b)) continue;
    const Vec3 pos = place(c.a, c.b).pos;  // (the same quadrics as when it was queued)
    if (keeps_orientation(c.a, c.b, pos)) collapse(c.a, c.b, pos);
  }
}

DecimatedMesh Decimator::result() const {
  std::vector<std::int32_t> index(pos_.size(), -1);
  DecimatedMesh out;
  for (std::size_t f = 0; f < faces_.size(); ++f)
    if (face_alive_[f])
      for (std::int32_t v : faces_[f]) index[v] = 0;
  std::int32_t next = 0;
  for (std::size_t v = 0; v < pos_.size(); ++v) {
    if (index[v] < 0) continue;
    index[v] = next++;
    out.vertices.insert(out.vertices.end(), pos_[v].data(), pos_[v].data() + 3);
  }
  for (std::size_t f = 0; f < faces_.size(); ++f)
    if (face_alive_[f])
      for (std::int32_t v : faces_[f]) out.faces.push_back(index[v]);
  return out;
}

}  // namespace

DecimatedMesh decimate_mesh(const MeshView& mesh, Index target_faces) {
  validate_mesh(mesh);
  if (target_faces < 0) throw std::invalid_argument("target_faces must not be negative");
  Decimator d(mesh);
  d.run(target_faces);
  return d.result();
}

}  // namespace osteon
