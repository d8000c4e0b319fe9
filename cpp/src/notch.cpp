// Stress concentration at a change of section (issue 33, docs/notch.md).
#include "notch.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "notch_reuse.hpp"
#include "parallel.hpp"

namespace osteon {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Roark 7th ed. Table 17.1, square shoulder with fillet in a circular shaft, bending; C_i = a +
// b sqrt(h/r) + c h/r for 0.25 <= h/r <= 2 (first four rows) and 2 <= h/r <= 20 (last four).
constexpr std::array<std::array<double, 3>, 8> kShoulderBending = {{
    {0.927, 1.149, -0.086},
    {0.015, -3.281, 0.837},
    {0.847, 1.716, -0.506},
    {-0.790, 0.417, -0.246},
    {1.225, 0.831, -0.010},
    {-3.790, 0.958, -0.257},
    {7.374, -4.834, 0.862},
    {-3.809, 3.046, -0.595},
}};

// The fit inside its range (h/r in [0.25, 20], t = 2h/D).
double fit_kt(double h_over_r, double t) {
  const int first = h_over_r <= 2.0 ? 0 : 4;
  const double s = std::sqrt(h_over_r);
  double kt = 0.0, power = 1.0;
  for (int i = 0; i < 4; ++i) {
    const auto& c = kShoulderBending[first + i];
    kt += (c[0] + c[1] * s + c[2] * h_over_r) * power;
    power *= t;
  }
  return kt;
}

// Roark's fit for one D/d at one r/d, clamped to its h/r range on the safe side.
double roark_kt_at(double step, double r_over_d) {
  const double h_over_r = (step - 1.0) / (2.0 * r_over_d);
  const double t = 1.0 - 1.0 / step;  // 2h / D
  if (h_over_r <= 20.0) return std::max(1.0, fit_kt(std::max(h_over_r, 0.25), t));
  // Sharper than the fit: Neuber, Kt - 1 ~ sqrt(depth / radius), continued from h/r = 20.
  const double at_edge = std::max(1.0, fit_kt(20.0, t));
  return 1.0 + (at_edge - 1.0) * std::sqrt(h_over_r / 20.0);
}

// Tipton, Sorem & Rolovic, "Updated stress concentration factors for filleted shafts in bending
// and tension", ASME J. Mech. Design 118 (1996) 321-327: a fit of their finite-element Kt (the
// largest principal stress over 32 M / (pi d^3)), Kt = 0.632 + 0.377 (D/d)^-4.4 + sqrt(a / b) /
// sqrt(r/d), a = -0.14 - 0.363 (D/d)^2 + 0.503 (D/d)^4, b = 1 - 2.39 (D/d)^2 + 3.368 (D/d)^4.
// (a = 0 at D = d, where Kt = 1.009.)
double tipton_kt_at(double step, double r_over_d) {
  const double s2 = step * step, s4 = s2 * s2;
  const double a = std::max(0.0, -0.14 - 0.363 * s2 + 0.503 * s4);
  const double b = 1.0 - 2.39 * s2 + 3.368 * s4;
  return 0.632 + 0.377 * std::pow(step, -4.4) + std::sqrt(a / b / r_over_d);
}

// Kt for one D/d at one r/d: the larger of the two published fits (safe side). Roark's fit of
// the photoelastic charts reads under Tipton et al.'s FEM at sharp fillets (docs/notch.md).
double kt_at(double step, double r_over_d) {
  return std::max(roark_kt_at(step, r_over_d), tipton_kt_at(step, r_over_d));
}

// The faces near one corner and their vertices' normals, weighted by the face angle at the
// vertex (Thuermer & Wuethrich 1998: a vertex on a sharp edge gets the bisector whatever the
// faces' sizes). Every face touching a vertex inside the searched region is among them (a face
// lies in a grid cell whose box holds it), so those vertices' normals are complete. Per vertex,
// flat arrays (structure of arrays, written once while gathering): its position about the axis
// (from the region's point: axial a, radial vector and distance t), and whether it can be a
// candidate (`need`: only those get a normal).
struct LocalMesh {
  // (Buffers, not zero-filled: written once while gathering.)
  std::unique_ptr<std::int32_t[]> faces;     // 3 per face, mesh vertex indices
  std::unique_ptr<int[]> corners;            // 3 per face, entries of `vertices` (no slot lookup)
  std::unique_ptr<std::int32_t[]> vertices;  // distinct vertices of `faces`
  std::size_t num_corners = 0, num_vertices = 0;  // 3 x faces, vertices
  std::vector<Vec3> normals;       // per entry of `vertices`, unit; set where `need` only
  std::unique_ptr<double[]> a, t;  // per entry: axial and radial distance from the point, mm
  std::vector<Vec3> radial;        // per entry: its offset from the axis, mm
  std::vector<char> need;          // per entry: may be a candidate (its normal is summed)
};

// The angle atan2(s, c) in [0, pi] between two edges, s = |e1 x e2| >= 0 and c = e1 . e2 (the
// angle weights below, most of the search's cost with libm's atan2): the octant reduced to
// x = tan in [0, 1], the half-angle identity atan x = 2 atan(x / (1 + sqrt(1 + x^2))) applied
// twice (x <= tan(pi/16) = 0.199), then the Taylor series to x^17 (truncation < 2.4e-15).
double corner_angle(double s, double c) {
  const double ac = std::abs(c);
  if (!(s > 0) && !(ac > 0)) return 0.0;
  const bool steep = s > ac;
  double x = steep ? ac / s : s / ac;
  x = x / (1.0 + std::sqrt(1.0 + x * x));
  x = x / (1.0 + std::sqrt(1.0 + x * x));
  const double x2 = x * x;
  double series = 1.0 / 17.0;
  for (int k = 7; k >= 0; --k) series = (k % 2 ? -1.0 : 1.0) / (2 * k + 1) + x2 * series;
  double angle = 4.0 * x * series;
  if (steep) angle = 0.5 * kPi - angle;
  return c < 0 ? kPi - angle : angle;
}

// Faces of the cells the slab lo <= u.x <= hi and the region reach that have a vertex inside
// both (the only ones a candidate's normal and neighbours need), their distinct vertices and
// each face's corners as entries of those (`slot`: V scratch, all -1 before and after).
void gather_faces(const FaceGrid& grid, const Vec3& u, double lo, double hi,
                  const CutRegion& region, std::vector<int>& slot, bool canonical, LocalMesh& m) {
  const double r2 = region.radius * region.radius;
  auto inside = [&](const Vec3& p) {
    const double a = u.dot(p);
    if (a < lo || a > hi) return false;
    Vec3 d = p - region.point;
    d -= d.dot(u) * u;
    return d.squaredNorm() <= r2;
  };
  // Each cell's distinct vertices (its entries, bit-exact copies) are tested once, and a face
  // reads its corners' verdicts (a vertex is shared by ~6 faces).
  // The blocks and cells are first tested against the ball around the slab's piece of the
  // cylinder (the cylinder alone runs through the whole model).
  CutRegion ball;
  ball.point = region.point + (0.5 * (lo + hi) - u.dot(region.point)) * u;
  ball.radius = std::hypot(region.radius, 0.5 * (hi - lo));
  // The cells first, so that the lists are sized once for their faces and vertices at most (no
  // reallocation and copy while they grow).
  std::vector<Index> cells;
  std::size_t max_faces = 0, max_vertices = 0;
  for (Index k = 0; k < grid.num_blocks(); ++k) {
    if (!grid.block_near(k, ball)) continue;
    for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c) {
      if (!grid.near(c, ball) || !grid.meets(c, u, lo, hi, &region)) continue;
      cells.push_back(c);
      max_faces += grid.end(c) - grid.begin(c);
      max_vertices += grid.vertex_end(c) - grid.vertex_begin(c);
    }
  }
  // Written through pointers into buffers sized for the most (a face's vertices are entries of
  // its cell) and not zero-filled (the cells hold several times the faces kept).
  m.faces.reset(new std::int32_t[3 * max_faces]);
  m.vertices.reset(new std::int32_t[max_vertices]);
  m.corners.reset(new int[3 * max_faces]);
  std::int32_t *face_out = m.faces.get(), *vertex_out = m.vertices.get();
  int* corner_out = m.corners.get();
  int nv = 0;
  std::vector<char> in;
  for (Index c : cells) {
    const Index e0 = grid.vertex_begin(c), e1 = grid.vertex_end(c);
    in.assign(e1 - e0, 0);
    bool any = false;
    for (Index e = e0; e < e1; ++e) {
      in[e - e0] = inside(Vec3(grid.entry_x()[e], grid.entry_y()[e], grid.entry_z()[e]));
      any = any || in[e - e0];
    }
    if (!any) continue;
    for (Index t = grid.begin(c); t < grid.end(c); ++t) {
      const std::int32_t* fe = grid.face_entries() + 3 * t;
      if (!in[fe[0] - e0] && !in[fe[1] - e0] && !in[fe[2] - e0]) continue;
      const std::int32_t* f = grid.faces() + 3 * t;
      for (int j = 0; j < 3; ++j) {
        *face_out++ = f[j];
        int& s = slot[f[j]];
        if (s < 0) {
          s = nv;
          vertex_out[nv++] = f[j];
        }
        *corner_out++ = s;
      }
    }
  }
  m.num_corners = static_cast<std::size_t>(face_out - m.faces.get());
  m.num_vertices = static_cast<std::size_t>(nv);
  // `canonical` (live mode, notch_reuse.hpp): the faces in an order of their own, not the grid's
  // cells', so that the sums below do not depend on the grid's layout and a corner no moved
  // triangle reaches measures the same bit for bit.
  if (canonical) {
    std::vector<std::int32_t> faces(m.faces.get(), m.faces.get() + m.num_corners),
        vertices(m.vertices.get(), m.vertices.get() + m.num_vertices);
    canonical_face_order(faces, vertices, slot);
    std::copy(faces.begin(), faces.end(), m.faces.get());
    std::copy(vertices.begin(), vertices.end(), m.vertices.get());
    for (std::size_t i = 0; i < m.num_corners; ++i) m.corners[i] = slot[m.faces[i]];
  }
  for (std::size_t k = 0; k < m.num_vertices; ++k) slot[m.vertices[k]] = -1;
}

// Each vertex's position about the axis and whether it can be a candidate: the candidate's own
// window (fillet_points) with a margin, so the normals it reads are summed from the same faces
// in the same order as for every vertex (bit for bit). `unit`: the unit radial direction where
// needed (keep_turning).
void place_vertices(const MeshView& mesh, const Vec3& u, double lo, double hi,
                    const CutRegion& region, double min_t, LocalMesh& m, std::vector<Vec3>& unit) {
  const double margin = 1e-9 * region.radius;
  const std::size_t nv = m.num_vertices;
  m.need.resize(nv);
  m.a.reset(new double[nv]);  // every entry written below: no zero fill
  m.t.reset(new double[nv]);
  m.radial.resize(nv);  // Vec3: no zero fill
  unit.resize(nv);
  for (std::size_t k = 0; k < nv; ++k) {
    const Vec3 p = mesh.vertex(m.vertices[k]);
    const Vec3 d = p - region.point;
    const double a = u.dot(p);
    const double along = d.dot(u);
    const Vec3 r = d - along * u;
    const double t = r.norm();
    m.a[k] = along;
    m.t[k] = t;
    m.radial[k] = r;
    m.need[k] =
        a >= lo - margin && a <= hi + margin && t >= min_t - margin && t <= region.radius + margin;
    unit[k] = m.need[k] && t > 0 ? Vec3(r / t) : Vec3::Zero();
  }
}

// A candidate's normal, in its meridian plane (radial x, towards the thin side y), turns 8..82
// degrees from radial (measure_corner). The angle-weighted normal is a positive combination of
// its faces' normals, and so is its meridian projection: when every face's projection lies
// below the 8-degree line (or every one above the 82-degree line), so does the vertex's, and it
// is no candidate. Such vertices are dropped from `need` before their angle weights (atan2) are
// computed; a margin of 1e-9 (unit normals) keeps every vertex the exact test could take.
void keep_turning(const MeshView& mesh, LocalMesh& m, const Vec3& u,
                  const std::vector<Vec3>& radial) {
  const double c8 = std::cos(8.0 * kPi / 180.0), s8 = std::sin(8.0 * kPi / 180.0);
  const double c82 = std::cos(82.0 * kPi / 180.0), s82 = std::sin(82.0 * kPi / 180.0);
  constexpr double kMargin = 1e-9;
  std::vector<char>& need = m.need;
  // bit 1: a face at/above 8 degrees, bit 2: a face at/below 82; a vertex with both is kept
  // whatever its other faces say, so they are not looked at (nor a face with no other vertex).
  // bit 4: needed. Pending: needed, not both seen (4, 5 or 6: one load and one compare).
  std::vector<unsigned char> seen(m.num_vertices);
  for (std::size_t k = 0; k < need.size(); ++k) seen[k] = need[k] ? 4 : 0;
  auto pending = [&](int k) { return static_cast<unsigned char>(seen[k] - 4) < 3; };
  for (std::size_t f = 0; f < m.num_corners; f += 3) {
    const int* at = &m.corners[f];
    if (!pending(at[0]) && !pending(at[1]) && !pending(at[2])) continue;
    const Vec3 p0 = mesh.vertex(m.faces[f]);
    const Vec3 n = (mesh.vertex(m.faces[f + 1]) - p0).cross(mesh.vertex(m.faces[f + 2]) - p0);
    const double len = n.norm();
    if (!(len > 0)) continue;
    const double ny = -n.dot(u) / len;
    for (int k = 0; k < 3; ++k) {
      if (!pending(at[k])) continue;
      const double nx = n.dot(radial[at[k]]) / len;
      if (c8 * ny - s8 * nx >= -kMargin) seen[at[k]] |= 1;
      if (c82 * ny - s82 * nx <= kMargin) seen[at[k]] |= 2;
    }
  }
  for (std::size_t k = 0; k < need.size(); ++k) need[k] = seen[k] == 7;
}

// The faces near the slab lo <= u.x <= hi within the region (gather_faces), and the normals of
// their vertices at least `min_t` from the axis that can be candidates (others stay 0).
LocalMesh local_mesh(const MeshView& mesh, const FaceGrid& grid, const Vec3& u, double lo,
                     double hi, const CutRegion& region, double min_t, std::vector<int>& slot,
                     bool canonical = false) {
  LocalMesh m;
  gather_faces(grid, u, lo, hi, region, slot, canonical, m);
  // Only a vertex that can be a candidate needs its normal (a neighbour's position is enough),
  // and the angle weights (atan2, most of the search's cost) of the other vertices are not
  // computed.
  std::vector<Vec3> unit;
  place_vertices(mesh, u, lo, hi, region, min_t, m, unit);
  keep_turning(mesh, m, u, unit);
  const std::vector<char>& need = m.need;
  m.normals.resize(m.num_vertices);  // Vec3: no zero fill; only the needed ones are summed
  for (std::size_t k = 0; k < m.num_vertices; ++k)
    if (need[k]) m.normals[k].setZero();
  for (std::size_t f = 0; f < m.num_corners; f += 3) {
    const int* at = &m.corners[f];
    if (!need[at[0]] && !need[at[1]] && !need[at[2]]) continue;
    const std::int32_t* fv = &m.faces[f];
    const Vec3 p[3] = {mesh.vertex(fv[0]), mesh.vertex(fv[1]), mesh.vertex(fv[2])};
    const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
    const double len = n.norm();
    if (!(len > 0)) continue;
    for (int k = 0; k < 3; ++k) {
      if (!need[at[k]]) continue;
      const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      m.normals[at[k]] += corner_angle(len, e1.dot(e2)) / len * n;
    }
  }
  for (std::size_t k = 0; k < m.normals.size(); ++k) {
    Vec3& n = m.normals[k];
    if (need[k] && n.norm() > 0) n.normalize();
  }
  return m;
}

// One concave corner measured on the mesh.
struct Corner {
  bool found = false;
  double radius = 0.0;  // fillet radius of the sharpest sector, mm (0: a sharp edge)
  double axial = 0.0;   // where the fillet meets the thin side, along the axis from the plane, mm
};

// Smallest moment arm / equivalent radius of a thin side the fit is applied to.
constexpr double kMinSlenderness = 2.0;

// A thin side that is the body itself, not a shaft entering it (docs/notch.md "Cost"): its
// equivalent radius at least kBodySized of the model's largest section's (its search cylinder,
// 2.5 r, would span that whole section) and its load within two of its own diameters (moment
// arm < kShaftSlenderness r: no length of shaft beyond the fillet's disturbance, Saint-Venant;
// the charts' and the study's bars are loaded 10 r away). No search from it.
constexpr double kBodySized = 0.4;
constexpr double kShaftSlenderness = 4.0;

// A plane inside the fillet: the nominal (thin) radius is at most this fraction below the cut's
// equivalent radius (nominal_radius). Judgement, not a source: a bound on what a noisy profile
// can do, about twice the drop of the study's training shape (D/d 3, r/d 0.3: 3.18 -> 3 mm).
constexpr double kMaxNominalDrop = 0.1;

// A sharp edge's ring spreads axially by less than this fraction of the local mesh edge length
// (the median in the meridian at the fillet points; docs/notch.md: a fillet the mesh resolves
// spreads by at least 0.13 of it).
constexpr double kSharpEdge = 0.1;

// Smallest turn of the surface at a corner that counts as a shoulder (docs/notch.md).
constexpr double kMinTurn = 45.0 * kPi / 180.0;

// Fillet points grouped in angular sectors around the axis: axial position a, distance t from
// the axis and the normal's axial component n_a of each point (mm, unit), and the lengths of
// their mesh edges in the meridian plane (mm).
constexpr int kSectors = 8;
struct SectorSums {
  std::size_t n = 0;                          // points
  double ma = 0, mt = 0, mn = 0;              // sums, then means, of a, t and n_a
  double saa = 0, stt = 0, snn = 0, san = 0;  // sums of the deviations' products
  double* lengths = nullptr;                  // their mesh edges' squared lengths (a buffer's run)
  std::size_t num_lengths = 0;
  double turn = 0;  // the largest normal turn from radial, radians
};

// A sector's verdict "sharp edge" at axial position `at` (always true).
bool sharp_edge(double& rho, double& axial, double at) {
  rho = 0.0;
  axial = at;
  return true;
}

// The fillet radius of one sector: a fillet of radius rho tangent to a thin part and a shoulder
// normal to the axis is a circle whose points satisfy a = c_a - rho n_a (the outward normal
// points to the circle's centre), whatever the section's shape: rho = -cov(a, n_a) / var(n_a).
// Returns false when the sector says nothing (under two points, a straight taper, a convex
// turn). `t`: the points' distances from the axis; `lengths`: their mesh edge lengths (mm), what
// the mesh can resolve there.
bool sector_radius(const SectorSums& sums, double scale, double& rho, double& axial) {
  const std::size_t n = sums.n;
  // One point tells neither a ring (a sharp edge) nor a curve (a fillet): a lone point's zero
  // spread would read as a sharp edge, the worst Kt, from noise (a symmetric rig's two thighs
  // got radii 1.9 and 0.2 mm).
  if (n < 2) return false;
  const double ma = sums.ma, mn = sums.mn, san = sums.san, snn = sums.snn;
  const double saa = sums.saa, stt = sums.stt;
  const double sd_a = std::sqrt(saa / n), sd_t = std::sqrt(stt / n), sd_n = std::sqrt(snn / n);
  // Every fillet point on one ring: a sharp edge. A ring may wander axially (a crease on a
  // shoulder that is not quite flat), so up to 0.02 r it is a ring; but a fillet the mesh
  // resolves (two candidate rings or more) spreads by at least 0.13 of the mesh's own edge
  // length h there, however narrow it is, along the axis and (the arc's other half) radially
  // (docs/notch.md): a ring spreads by under kSharpEdge h along one of them; points spread by
  // more along both are measured as a fillet first, and read as a ring only when they make none.
  // h: the median edge length (the long edges of a flat face next to a fillet do not count).
  double* const lengths = sums.lengths;
  double* const mid = lengths + sums.num_lengths / 2;
  std::nth_element(lengths, mid, lengths + sums.num_lengths);
  // (The lengths are kept squared: sqrt is monotone and correctly rounded, so the square root of
  // the squares' median is the lengths' median, bit for bit, with one square root.)
  const double h = sums.num_lengths == 0 ? 0.0 : std::sqrt(*mid);
  const bool ring = sd_a < 0.02 * scale;
  if (ring && std::min(sd_a, sd_t) < kSharpEdge * h) return sharp_edge(rho, axial, ma);
  // One normal direction along a length: a straight taper (or a wandering ring).
  if (sd_n < 0.05) return ring && sharp_edge(rho, axial, ma);
  rho = -san / snn;
  // The surface turns the other way: no inside corner (or a ring).
  if (!(rho > 0)) return ring && sharp_edge(rho, axial, ma);
  axial = ma + rho * mn;  // the circle's centre: where the fillet leaves the thin side
  return true;
}

// Meridian coordinates of a vertex about the axis (origin, u): axial a, radial t, and its
// normal's axial and radial components.
struct Meridian {
  double a = 0, t = 0, na = 0, nr = 0;
};

// A fillet point's normal: mostly in the meridian plane, turned 8..82 degrees from radial
// towards the thin side (the shoulder face, at 90 degrees, and the thin part, at 0, left out).
// The signs and a squared test first, with a margin of 1e-9 (far above the rounding of either),
// reject the vertices clearly outside (no normal, the thin part, the shoulder face: about half of
// those in the window on cow x4) without the hypot; the exact test decides the rest as before.
// `meridian`: the normal's length in the meridian plane (set where true: fillet_points reuses it).
bool fillet_turn(const Meridian& m, double& meridian) {
  const double lo_sin = std::sin(8.0 * kPi / 180.0), hi_sin = std::sin(82.0 * kPi / 180.0);
  if (m.nr <= 0 || !(m.na < 0)) return false;  // turn <= 0: no hypot needed
  constexpr double kLoose = 1e-9;
  const double q = m.na * m.na + m.nr * m.nr, na2 = m.na * m.na;
  if (q < 0.49 * (1 - kLoose) || na2 < lo_sin * lo_sin * q * (1 - kLoose) ||
      na2 > hi_sin * hi_sin * q * (1 + kLoose))
    return false;
  meridian = std::hypot(m.na, m.nr);
  if (meridian < 0.7) return false;
  const double turn = -m.na / meridian;  // sin of the angle from radial towards the thin side
  return turn >= lo_sin && turn <= hi_sin;
}

// A vertex of a concave fillet: axial position a from the thin plane (mm), the axial component
// na of its unit meridian normal, the normal's turn from radial towards the thin side (radians)
// and its unit radial direction (x, y) in a frame of the plane.
struct FilletPoint {
  double a = 0, na = 0, turn = 0, x = 0, y = 0;
  double t = 0;                              // distance from the axis, mm
  std::size_t edge_begin = 0, edge_end = 0;  // its edges' squared lengths in FilletPoints::edges
};

// The fillet points of a corner and the squared lengths of their mesh edges in the meridian
// plane (mm^2), one run per point.
struct FilletPoints {
  std::vector<FilletPoint> points;
  std::unique_ptr<double[]> edges;
};

// The fillet points of the concave corner between a thin section (bone point `origin`,
// equivalent radius r_thin) and the thick side along unit axis `u` (thin -> thick), within
// axial [lo, hi] of the thin section's plane, in the mesh's order. A point's test does not
// depend on the window beyond its own a (its normal and neighbours come from all its faces),
// so the points of a narrower window are exactly those of this list inside it.
FilletPoints fillet_points(const MeshView& mesh, const FaceGrid& grid, std::vector<int>& slot,
                           const Vec3& origin, const Vec3& u, double r_thin, double lo, double hi,
                           bool canonical = false) {
  const Vec3 e1 = u.unitOrthogonal(), e2 = u.cross(e1);
  CutRegion region;  // the cylinder t <= 2.5 r_thin around the axis
  region.point = origin;
  region.axis = u;
  region.radius = 2.5 * r_thin;
  const double at = u.dot(origin);
  const LocalMesh local =
      local_mesh(mesh, grid, u, at + lo, at + hi, region, 0.5 * r_thin, slot, canonical);
  const std::size_t nv = local.num_vertices;
  // The normals' meridian components, of the vertices in the window only (a neighbour's a and t
  // are enough) and, of the candidates, its length in that plane; every one read below is
  // written (no zero fill first).
  const std::unique_ptr<double[]> na(new double[nv]), nr(new double[nv]), meridian(new double[nv]);
  std::vector<char> candidate(nv, 0);
  for (std::size_t k = 0; k < nv; ++k) {
    if (!local.need[k]) continue;  // outside the window or turning too little or too much
    Meridian m;
    m.a = local.a[k];
    m.t = local.t[k];
    if (m.a < lo || m.a > hi || m.t < 0.5 * r_thin || m.t > 2.5 * r_thin) continue;
    m.na = local.normals[k].dot(u);
    m.nr = m.t > 0 ? local.normals[k].dot(local.radial[k]) / m.t : 0.0;
    na[k] = m.na;
    nr[k] = m.nr;
    candidate[k] = fillet_turn(m, meridian[k]);
  }
  // Concave in the meridian only: the neighbours lie on the outer side of the tangent line of
  // the meridian, (a_q - a_p) n_a + (t_q - t_p) n_r > 0 summed (the outer, convex edge of a
  // shoulder has the same normal turn and is left out by this).
  const std::unique_ptr<double[]> bend(new double[nv]());  // zero-filled
  // The candidates' edges in the meridian plane (the plane a fillet curves in): their lengths
  // there are what the mesh resolves of a fillet (a ring's own edges count ~0).
  // (One run per candidate in one array: two per face at the candidate.)
  // The faces at a candidate are listed while the runs are counted (one pass over all faces).
  const int* const corners = local.corners.get();
  std::vector<std::size_t> next(nv + 1, 0);
  std::vector<std::size_t> at_candidate;
  for (std::size_t f = 0; f < local.num_corners; f += 3) {
    const int* slots = &corners[f];
    if (!candidate[slots[0]] && !candidate[slots[1]] && !candidate[slots[2]]) continue;
    at_candidate.push_back(f);
    for (int j = 0; j < 3; ++j)
      if (candidate[slots[j]]) next[slots[j] + 1] += 2;
  }
  for (std::size_t k = 0; k < nv; ++k) next[k + 1] += next[k];
  FilletPoints out;
  // Every slot is written exactly once below (the runs' counts): no zero fill first.
  out.edges.reset(new double[next.back()]);
  const std::vector<std::size_t> first(next.begin(), next.end() - 1);
  const double *a = local.a.get(), *t = local.t.get();
  for (std::size_t f : at_candidate) {
    const int* slots = &corners[f];
    for (int j = 0; j < 3; ++j) {
      const int p = slots[j];
      if (!candidate[p]) continue;
      // p's sums in registers (the edges' array could alias them), added in the same order
      const double ap = a[p], tp = t[p], nap = na[p], nrp = nr[p];
      double b = bend[p];
      std::size_t e = next[p];
      for (int k = 1; k < 3; ++k) {
        const int q = slots[(j + k) % 3];
        const double da = a[q] - ap, dt = t[q] - tp;
        b += da * nap + dt * nrp;
        out.edges[e++] = da * da + dt * dt;  // squared (FilletPoints)
      }
      bend[p] = b;
      next[p] = e;
    }
  }
  for (std::size_t k = 0; k < nv; ++k) {
    if (!candidate[k] || !(bend[k] > 1e-9 * r_thin)) continue;
    const Vec3& radial = local.radial[k];
    FilletPoint p;
    p.a = local.a[k];
    p.na = na[k] / meridian[k];  // hypot(na, nr), from fillet_turn
    p.turn = std::atan2(-na[k], nr[k]);
    p.t = local.t[k];
    p.edge_begin = first[k];
    p.edge_end = next[k];
    const double t = std::hypot(radial.dot(e1), radial.dot(e2));
    p.x = t > 0 ? radial.dot(e1) / t : 1.0;
    p.y = t > 0 ? radial.dot(e2) / t : 0.0;
    out.points.push_back(p);
  }
  return out;
}

// Octant 0..7 of the direction (x, y), counter-clockwise from (1, 0).
int octant(double x, double y) {
  if (y >= 0) return x > 0 ? (y < x ? 0 : 1) : (y > -x ? 2 : 3);
  return x < 0 ? (-y < -x ? 4 : 5) : (-y > x ? 6 : 7);
}

// Where the sectors start, as a unit direction (c, s) in the points' frame: taken from the
// points themselves, so that it turns with the model. Their directions' resultant of order k,
// sum (x + i y)^k, fixes an angle modulo 360/k degrees, a multiple of 45 for k = 1, 2, 4, 8, so
// each gives one partition into 45-degree sectors whatever the branch; the order with the
// largest resultant (the clearest: a one-sided corner k = 1, a two-sided one k = 2, ...) is
// used. A ring with none (a round bar's even ring) fits alike in every sector.
std::pair<double, double> sector_start(const std::vector<const FilletPoint*>& pts) {
  std::array<std::complex<double>, 4> sum{};  // k = 1, 2, 4, 8
  for (const FilletPoint* p : pts) {
    std::complex<double> z(p->x, p->y);
    for (auto& s : sum) {
      s += z;
      z *= z;
    }
  }
  int best = 0;
  for (int j = 1; j < 4; ++j)
    if (std::abs(sum[j]) > std::abs(sum[best])) best = j;
  if (!(std::abs(sum[best]) > 0)) return {1.0, 0.0};
  const double phi = std::arg(sum[best]) / (1 << best);
  return {std::cos(phi), std::sin(phi)};
}

// The corner's radius from the fillet points within axial [lo, hi]: fitted per 45-degree
// sector around the axis (the sectors start where sector_start says), the sharpest sector
// governs.
Corner corner_in(const FilletPoints& fillet, double r_thin, double lo, double hi) {
  std::vector<const FilletPoint*> inside;
  for (const FilletPoint& p : fillet.points)
    if (p.a >= lo && p.a <= hi) inside.push_back(&p);
  const auto [c0, s0] = sector_start(inside);
  // Each sector's sums over its points in their order (the order a sequential sum needs), and
  // its edges' lengths grouped in one buffer: no per-sector copies of the points.
  std::vector<int> sector_of(inside.size());
  std::array<SectorSums, kSectors> sums{};
  std::array<std::size_t, kSectors + 1> edge_at{};
  for (std::size_t i = 0; i < inside.size(); ++i) {
    const FilletPoint* p = inside[i];
    const int sector = octant(p->x * c0 + p->y * s0, p->y * c0 - p->x * s0);
    sector_of[i] = sector;
    SectorSums& q = sums[sector];
    ++q.n;
    q.ma += p->a;
    q.mn += p->na;
    q.mt += p->t;
    q.turn = std::max(q.turn, p->turn);
    edge_at[sector + 1] += p->edge_end - p->edge_begin;
  }
  for (int s = 0; s < kSectors; ++s) {
    edge_at[s + 1] += edge_at[s];
    SectorSums& q = sums[s];
    if (q.n == 0) continue;
    q.ma /= q.n;
    q.mn /= q.n;
    q.mt /= q.n;
  }
  const std::unique_ptr<double[]> lengths(new double[edge_at[kSectors]]);
  std::array<std::size_t, kSectors> edge_next{};
  for (int s = 0; s < kSectors; ++s) {
    edge_next[s] = edge_at[s];
    sums[s].lengths = lengths.get() + edge_at[s];
    sums[s].num_lengths = edge_at[s + 1] - edge_at[s];
  }
  for (std::size_t i = 0; i < inside.size(); ++i) {
    const FilletPoint* p = inside[i];
    SectorSums& q = sums[sector_of[i]];
    const double da = p->a - q.ma, dt = p->t - q.mt, dn = p->na - q.mn;
    q.saa += da * da;
    q.stt += dt * dt;
    q.snn += dn * dn;
    q.san += da * dn;
    std::copy(fillet.edges.get() + p->edge_begin, fillet.edges.get() + p->edge_end,
              lengths.get() + edge_next[sector_of[i]]);
    edge_next[sector_of[i]] += p->edge_end - p->edge_begin;
  }
  Corner c;
  for (int s = 0; s < kSectors; ++s) {
    double rho = 0, axial = 0;
    if (!sector_radius(sums[s], r_thin, rho, axial)) continue;
    // How far the surface turns at the corner: a sharp edge's normal is the bisector (half the
    // turn), a fillet's points reach the turn. The fit is for a shoulder (a 90-degree turn);
    // creases turning less than kMinTurn (tapers, facets of a low-poly mesh) are not counted:
    // their singularity is weaker (Williams 1952: stress ~ dist^-0.33 at a 45-degree turn
    // against dist^-0.46 at 90), and turns of 45..90 degrees take the shoulder's Kt (safe side).
    const double turn = rho == 0.0 ? 2.0 * sums[s].turn : sums[s].turn + 8.0 * kPi / 180.0;
    if (turn < kMinTurn) continue;
    if (!c.found || rho < c.radius) {  // the sharpest sector governs
      c.found = true;
      c.radius = rho;
      c.axial = axial;
    }
  }
  return c;
}

// Sections of each bone that have a region, in order along the bone.
std::vector<std::vector<int>> bone_profiles(const AnalysisResult& r) {
  int nb = 0;
  for (int b : r.section_bone) nb = std::max(nb, b + 1);
  std::vector<std::vector<int>> chains(nb);
  for (int i = 0; i < static_cast<int>(r.section_bone.size()); ++i)
    if (r.section_cut_area[i] > 0 && r.section_area[i] > 0 && std::isfinite(r.moment_arm[i]))
      chains[r.section_bone[i]].push_back(i);
  for (auto& c : chains)
    std::stable_sort(c.begin(), c.end(),
                     [&](int x, int y) { return r.section_param[x] < r.section_param[y]; });
  return chains;
}

double equivalent_radius(double area) { return std::sqrt(area / kPi); }

// One step of the equivalent radius along a bone, to be searched for its corner.
struct Step {
  int section = 0;            // the thin side's section
  Vec3 point = Vec3::Zero();  // its bone point, mm
  double r_thin = 0;          // its equivalent radius (its region), mm
  double r_big = 0;           // the thick side's largest equivalent radius near the step, mm
  double reach = 0;           // axial distance from the thin plane to the thick neighbour's, mm
  Vec3 u = Vec3::Zero();      // unit axis, thin -> thick (the thin section's normal or its reverse)
  double r_beyond = kNaN;     // the thin side's profile extrapolated to the thin plane, mm
};

// The thin side's profile beyond the thin section (chain[thin], the step towards +dir) carried
// back to its plane: the line through the next two sections' equivalent radii (their regions),
// or the next one's alone, never below the next one's; NaN if there is none. A shaft beyond a
// fillet gives its own radius; a taper about the thin section's own (then nothing changes).
double profile_beyond(const AnalysisResult& r, const std::vector<int>& chain, int thin, int dir) {
  const int n = static_cast<int>(chain.size()), j1 = thin - dir, j2 = thin - 2 * dir;
  if (j1 < 0 || j1 >= n) return kNaN;
  const double r1 = equivalent_radius(r.section_area[chain[j1]]);
  if (j2 < 0 || j2 >= n) return r1;
  const double r2 = equivalent_radius(r.section_area[chain[j2]]);
  const double p0 = r.section_param[chain[thin]], p1 = r.section_param[chain[j1]],
               p2 = r.section_param[chain[j2]];
  // Never below the next section itself (a bulge beyond, a hand or a paw, would tip the line).
  return p1 != p2 ? std::max(r1, r1 + (r1 - r2) * (p0 - p1) / (p1 - p2)) : r1;
}

// The steps along each bone (ratio >= kStepRatio between neighbours) whose thin side is slender,
// in the order of the bones' sections.
std::vector<Step> find_steps(const AnalysisResult& r) {
  std::vector<Step> steps;
  double r_model = 0;  // the model's largest section (whole cut), mm
  for (std::size_t i = 0; i < r.section_cut_area.size(); ++i)
    if (r.section_cut_area[i] > 0)
      r_model = std::max(r_model, equivalent_radius(r.section_cut_area[i]));
  for (const std::vector<int>& chain : bone_profiles(r)) {
    const int n = static_cast<int>(chain.size());
    auto radius_of = [&](int k) { return equivalent_radius(r.section_cut_area[chain[k]]); };
    for (int k = 0; k + 1 < n; ++k) {
      const double ra = radius_of(k), rb = radius_of(k + 1);
      if (std::max(ra, rb) < kStepRatio * std::min(ra, rb)) continue;
      const int dir = rb > ra ? 1 : -1;  // along the chain, thin -> thick
      int thin = rb > ra ? k : k + 1;
      const int thick = thin + dir;
      // A plane may cut the fillet itself: the thin side's smallest section within the largest
      // fillet the study covers (r = 0.3 d, i.e. 0.6 of the thin radius) is the thin one.
      const int first = thin;
      for (int j = thin - dir; j >= 0 && j < n; j -= dir) {
        if (radius_of(j) >= radius_of(thin)) break;
        if (std::abs(r.section_param[chain[j]] - r.section_param[chain[first]]) >
            0.6 * radius_of(first))
          break;
        thin = j;
      }
      Step st;
      st.section = chain[thin];
      const int i = st.section;
      st.point = r.section_point[i];
      st.r_thin = equivalent_radius(r.section_area[i]);
      st.r_beyond = profile_beyond(r, chain, thin, dir);
      // The fit is for a shaft, a beam: the thin part must be slender where it is loaded (arm
      // >= kMinSlenderness r, the FEM check's slenderness, docs/validation.md); a stubby or
      // body-sized section gets no Kt (and costs no search).
      if (r.moment_arm[i] < kMinSlenderness * st.r_thin) continue;
      // The body itself, not a shaft entering it (kBodySized).
      if (st.r_thin >= kBodySized * r_model && r.moment_arm[i] < kShaftSlenderness * st.r_thin)
        continue;
      const double gap = std::abs(r.section_param[chain[thick]] - r.section_param[i]);
      // The big dimension: the thick side's largest section within two thin radii of the step.
      for (int j = thick; j >= 0 && j < n; j += dir) {
        if (std::abs(r.section_param[chain[j]] - r.section_param[i]) > gap + 2 * st.r_thin) break;
        st.r_big = std::max(st.r_big, radius_of(j));
      }
      st.u = r.section_normal[i];
      const Vec3 towards = r.section_point[chain[thick]] - r.section_point[i];
      if (towards.dot(st.u) < 0) st.u = -st.u;
      st.reach = std::max(towards.dot(st.u), 0.0);
      steps.push_back(st);
    }
  }
  return steps;
}

// The corner of each step, measured on the mesh. The steps of one thin section towards one side
// (its neighbours 1, 2, 3 ... planes on, where the walk to the thinnest section joins them) are
// gathered once, over the widest window, and each step fitted on its own window's points.
std::vector<Corner> measure_corners(const MeshView& mesh,
                                    const std::function<const FaceGrid&()>& face_grid,
                                    const std::vector<Step>& steps, int threads,
                                    bool canonical = false) {
  std::vector<Corner> corners(steps.size());
  auto same_side = [&](std::size_t s, std::size_t t) {
    return steps[s].section == steps[t].section && steps[s].u == steps[t].u;
  };
  // One job per gathering: the first step of each thin section and side.
  std::vector<std::size_t> firsts;
  std::vector<char> taken(steps.size(), 0);
  for (std::size_t s = 0; s < steps.size(); ++s) {
    if (taken[s]) continue;
    firsts.push_back(s);
    for (std::size_t t = s; t < steps.size(); ++t)
      if (same_side(s, t)) taken[t] = 1;
  }
  if (firsts.empty()) return corners;
  const FaceGrid& grid = face_grid();  // built here, before the workers read it
  // The jobs are independent (each writes its own steps' corners): the same corners whatever
  // the number of workers. Each worker has its own scratch (all -1 between calls).
  const int workers = detail::worker_count(threads, static_cast<long>(firsts.size()));
  std::vector<std::vector<int>> slots(static_cast<std::size_t>(workers));
  detail::parallel_for(static_cast<long>(firsts.size()), workers, [&](long job, int worker) {
    const std::size_t s = firsts[static_cast<std::size_t>(job)];
    std::vector<int>& slot = slots[static_cast<std::size_t>(worker)];
    if (slot.empty()) slot.assign(mesh.num_vertices, -1);
    double reach = 0;
    for (std::size_t t = s; t < steps.size(); ++t)
      if (same_side(s, t)) reach = std::max(reach, steps[t].reach);
    const Step& st = steps[s];
    const FilletPoints points = fillet_points(mesh, grid, slot, st.point, st.u, st.r_thin,
                                              -0.25 * reach, 1.25 * reach, canonical);
    for (std::size_t t = s; t < steps.size(); ++t)
      if (same_side(s, t))
        corners[t] = corner_in(points, st.r_thin, -0.25 * steps[t].reach, 1.25 * steps[t].reach);
  });
  return corners;
}

// The thin diameter's radius that Kt and its nominal stress refer to (mm). A plane inside the
// fillet (the measured corner leaves the thin side beyond it: axial < 0) cuts a section larger
// than the thin part; the thin side's profile beyond the fillet, carried back to the plane
// (profile_beyond), says how much. The drop is taken from that profile, never more than the
// fillet can add at the plane (a fillet of radius rho tangent at e = -axial beyond the plane:
// rho - sqrt(rho^2 - e^2)), nor than kMaxNominalDrop of the radius (noisy meshes: the profile and
// the circle only bound each other).
double nominal_radius(const Step& st, const Corner& c) {
  if (!(c.axial < 0) || !(c.radius > 0) || !(st.r_beyond < st.r_thin)) return st.r_thin;
  const double e = std::min(-c.axial, c.radius);
  const double fillet_excess = c.radius - std::sqrt(c.radius * c.radius - e * e);
  return std::max({st.r_beyond, st.r_thin - fillet_excess, (1.0 - kMaxNominalDrop) * st.r_thin});
}

}  // namespace

double shoulder_fillet_kt(double big_diameter, double small_diameter, double radius) {
  if (!(std::isfinite(big_diameter) && std::isfinite(small_diameter) && std::isfinite(radius)) ||
      !(small_diameter > 0) || !(radius > 0) || !(big_diameter > small_diameter))
    return 1.0;
  const double step = std::min(big_diameter / small_diameter, kMaxStepRatio);
  const double r_over_d = radius / small_diameter;
  // The fit is not monotone in D/d at a large r/d: the largest Kt up to this step (safe side).
  double kt = kt_at(step, r_over_d);
  for (int k = 1; k < 16; ++k) kt = std::max(kt, kt_at(1.0 + (step - 1.0) * k / 16.0, r_over_d));
  return kt;
}

namespace {

// The corners of `steps` in a live update (notch_reuse.hpp): a gathering (the steps of one thin
// section towards one side) whose inputs are bitwise the last run's and whose searched region no
// moved triangle reaches is copied from `memo`, the others are searched in the canonical face
// order (whole gatherings: a gathering's window is its widest step's); `memo` then holds this
// run's.
std::vector<Corner> recall_or_measure(const MeshView& mesh,
                                      const std::function<const FaceGrid&()>& face_grid,
                                      const std::vector<Step>& steps, int threads, CornerMemo& memo,
                                      const MeshChange& change) {
  std::vector<CornerGroup> groups;
  std::vector<int> group_of(steps.size(), -1);
  for (std::size_t s = 0; s < steps.size(); ++s) {
    if (group_of[s] >= 0) continue;
    CornerGroup g;
    g.point = steps[s].point;
    g.u = steps[s].u;
    g.r_thin = steps[s].r_thin;
    for (std::size_t t = s; t < steps.size(); ++t)
      if (steps[t].section == steps[s].section && steps[t].u == steps[s].u) {
        group_of[t] = static_cast<int>(groups.size());
        g.reach.push_back(steps[t].reach);
      }
    groups.push_back(std::move(g));
  }
  std::vector<char> recalled(groups.size());
  for (std::size_t k = 0; k < groups.size(); ++k) recalled[k] = memo.recall(groups[k], change);
  std::vector<Step> todo;
  for (std::size_t s = 0; s < steps.size(); ++s)
    if (!recalled[group_of[s]]) todo.push_back(steps[s]);
  const std::vector<Corner> measured = measure_corners(mesh, face_grid, todo, threads, true);
  std::vector<Corner> corners(steps.size());
  std::vector<std::size_t> taken(groups.size(), 0);
  for (std::size_t s = 0, next = 0; s < steps.size(); ++s) {
    CornerGroup& g = groups[group_of[s]];
    if (recalled[group_of[s]]) {
      const CornerFit& f = g.corners[taken[group_of[s]]++];
      corners[s] = Corner{f.found, f.radius, f.axial};
    } else {
      corners[s] = measured[next++];
      g.corners.push_back(CornerFit{corners[s].found, corners[s].radius, corners[s].axial});
    }
  }
  memo.groups = std::move(groups);
  memo.valid = true;
  return corners;
}

}  // namespace

NotchField find_notches(const MeshView& mesh, const std::function<const FaceGrid&()>& face_grid,
                        const AnalysisResult& r, double min_radius, double sensitivity, int threads,
                        CornerMemo* memo, const MeshChange& change) {
  const int ns = static_cast<int>(r.section_bone.size());
  NotchField out;
  out.kt.assign(ns, 1.0);
  out.radius.assign(ns, kNaN);
  out.step.assign(ns, kNaN);
  out.effective.assign(ns, 1.0);
  out.arm_ratio.assign(ns, 1.0);
  std::vector<double> peak(ns, 1.0);  // Kt x modulus ratio x arm ratio of the corner taken
  const std::vector<Step> steps = find_steps(r);
  // Live updates (what moved is known, after a full run or another live update): the canonical
  // order, and the memo. Other runs (one-off, the first of a session, the correction's) search in
  // the grid's order, as they always did; a full one arms the memo for the next run.
  const bool live = memo != nullptr && change.known && memo->armed;
  if (memo != nullptr && !live) {
    memo->forget();
    memo->armed = true;
  }
  const std::vector<Corner> corners =
      live ? recall_or_measure(mesh, face_grid, steps, threads, *memo, change)
           : measure_corners(mesh, face_grid, steps, threads);
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const Step& st = steps[s];
    const Corner& c = corners[s];
    if (!c.found) continue;
    const int i = st.section;
    const double rho = std::max(c.radius, min_radius);
    const double kt = shoulder_fillet_kt(2 * st.r_big, 2 * st.r_thin, rho);
    // Nominal stress at the corner: the same load point, the centroid moved to the corner.
    const double shift = std::clamp(c.axial, 0.0, st.reach);
    const double arm_c = (r.load_point[i] - (r.section_center[i] + shift * st.u)).norm();
    // A plane inside the fillet: Kt refers to the thin diameter's beam stress where the fillet
    // meets the thin side (beyond the plane); the plane's own is lower by the moduli's ratio (a
    // round part: the cube of the radii), a little less by the moments'. 1 otherwise.
    double modulus_ratio = 1.0;
    const double r_nominal = nominal_radius(st, c);
    if (r_nominal < st.r_thin && arm_c > 0) {
      const Vec3 meet = r.section_center[i] + std::max(c.axial, -st.reach) * st.u;
      const double arm_t = (r.load_point[i] - meet).norm();
      modulus_ratio = std::max(1.0, std::pow(st.r_thin / r_nominal, 3) * arm_t / arm_c);
    }
    const double arm_ratio = r.moment_arm[i] > 0 ? std::max(1.0, arm_c / r.moment_arm[i]) : 1.0;
    const double effective = 1.0 + sensitivity * (kt * modulus_ratio - 1.0);
    if (kt * modulus_ratio * arm_ratio > peak[i]) {  // a corner on each side: the worse
      peak[i] = kt * modulus_ratio * arm_ratio;
      out.kt[i] = kt;
      out.radius[i] = rho;
      out.step[i] = st.r_big / st.r_thin;
      out.effective[i] = effective;
      out.arm_ratio[i] = arm_ratio;
    }
  }
  return out;
}

}  // namespace osteon
