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

#include "cell_cut.hpp"
#include "noinline.hpp"
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

// One concave corner measured on the mesh.
struct Corner {
  bool found = false;
  double radius = 0.0;  // fillet radius of the sharpest sector, mm (0: a sharp edge)
  double axial = 0.0;   // where the fillet meets the thin side, along the axis from the plane, mm
  double opening = kPi / 2;  // the most acute sector's opening, radians (acute_factor)
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

// An acute corner (docs/notch.md "Round 6"): the opening angle between the thin side's
// generatrix and the thick side's surface beyond the fillet, in a meridian half-plane, is pi
// less the largest turn of the profile's segments from radial over the concave run the fillet
// lies in (chain_runs: a run ends where the profile has turned convex by more than kRunBreak in
// total, the thick side's outer edge or a convex surface beyond). A 90-degree shoulder opens 90.
constexpr double kRunBreak = 5.0 * kPi / 180.0;
// Openings under 85 degrees raise Kt - 1 by a factor interpolated linearly in the opening
// between kAcuteTable's points (degrees, factor), continued below the last with the slope of
// the last two, down to kAcuteMin. Fitted on FEM, not taken from a source (no published law
// was found for it: docs/notch.md "Round 6"): CalculiX's peak in the acute corner of a junction
// tilted 30 and 45 degrees (round 6's training tilts, r/d 0.1) over the nominal stress there is
// a Kt whose excess over the stepped-bar fit's (the same D/d and true radius) is 2.29 x at 60
// degrees and 2.52 x at 45. At 85 degrees and over: 1 (judgement: a shoulder meshed with facets
// within 5 degrees of 90 keeps the stepped bar's Kt; the T's 90-degree junction, 1.43 x in FEM,
// reads on the safe side through its measured radius, docs/notch.md). kAcuteMin: judgement (a
// slot, not a corner, below it).
constexpr std::array<std::array<double, 2>, 3> kAcuteTable = {
    {{85.0, 1.0}, {60.0, 2.29}, {45.0, 2.52}}};
constexpr double kAcuteMin = 30.0;

// The factor on Kt - 1 of a corner opening `opening` radians (1 at and above 85 degrees).
double acute_factor(double opening) {
  const double deg = std::max(opening * 180.0 / kPi, kAcuteMin);
  if (!(deg < kAcuteTable[0][0])) return 1.0;
  std::size_t k = 1;
  while (k + 1 < kAcuteTable.size() && deg < kAcuteTable[k][0]) ++k;
  const auto &p0 = kAcuteTable[k - 1], &p1 = kAcuteTable[k];
  return p0[1] + (p1[1] - p0[1]) * (deg - p0[0]) / (p1[0] - p0[0]);
}

// Fillet points grouped in angular sectors around the axis: axial position a, distance t from
// the axis and the normal's axial component n_a of each point (mm, unit), and the lengths of
// their mesh edges in the meridian plane (mm).
// Meridian profiles (fillet_points): kHalfPlanes half-planes evenly around the axis; sector s
// holds the points of half-planes s .. s + kSectorSpan - 1 (90 degrees: two profiles, so that a
// sharp edge's ring gives a sector two points), every half-plane in kSectorSpan sectors.
constexpr int kHalfPlanes = 8;
constexpr int kSectorSpan = 2;
constexpr int kSectors = kHalfPlanes;
struct SectorSums {
  std::size_t n = 0;                          // points
  double ma = 0, mt = 0, mn = 0;              // sums, then means, of a, t and n_a
  double saa = 0, stt = 0, snn = 0, san = 0;  // sums of the deviations' products
  double* lengths = nullptr;                  // their mesh edges' squared lengths (a buffer's run)
  std::size_t num_lengths = 0;
  double turn = 0;   // the largest normal turn from radial, radians
  double flank = 0;  // the largest turn of the points' concave runs (the opening's complement)
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

// Meridian profiles (docs/notch.md "Round 5"): the surface near a corner is cut by kHalfPlanes
// half-planes through the thin section's axis, evenly spaced around it; each cut is a polyline
// (axial position a, distance t from the axis) whose segments' normals are exact for the mesh.
// The cost scales with the faces the planes cross (about the square root of the faces in the
// searched volume), not with the faces in that volume.
// Where the half-planes lie in their spacing, from the start direction (plane_start): off the
// start itself, so that a revolved mesh's columns (the start's ties) are not cut along an edge.
// Judgement (any fixed fraction keeps the planes turning with the model).
constexpr double kPlanePhase = 0.2874;

// A fillet point: a vertex of a concave meridian polyline. Axial position a from the thin plane
// (mm), the axial component na of its unit normal (the bisector of its two segments' normals),
// the normal's turn from radial towards the thin side (radians), its distance t from the axis
// (mm), and the sector (a group of neighbouring half-planes) its half-plane belongs to.
struct FilletPoint {
  double a = 0, na = 0, turn = 0, t = 0;
  double flank = 0;  // the largest segment turn of its concave run (chain_runs), radians
  int sector = 0;
  std::size_t edge_begin = 0, edge_end = 0;  // its segments' squared lengths in FilletPoints::edges
};

// Counts fillet point p into sector sums q, first pass: the sums and the largest turns (the
// deviations' products come in a second pass, from the means).
void add_point(SectorSums& q, const FilletPoint& p) {
  ++q.n;
  q.ma += p.a;
  q.mn += p.na;
  q.mt += p.t;
  q.turn = std::max(q.turn, p.turn);
  q.flank = std::max(q.flank, p.flank);
}

// The fillet points of a corner and the squared lengths of their polyline segments (mm^2), one
// run per point.
struct FilletPoints {
  std::vector<FilletPoint> points;
  std::vector<double> edges;
};

// The grid's blocks that may hold a face of the searched window (the slab lo <= a <= hi, a from
// the thin plane along u, within 2.5 r_thin of the axis: the ball around it), found once per
// search: each plane's cut visits only these (a face lies in a cell whose box holds it).
std::vector<Index> window_blocks(const FaceGrid& grid, const Vec3& origin, const Vec3& u,
                                 double r_thin, double lo, double hi) {
  CutRegion ball;
  ball.point = origin + 0.5 * (lo + hi) * u;
  ball.radius = std::hypot(2.5 * r_thin, 0.5 * (hi - lo));
  std::vector<Index> blocks;
  for (Index k = 0; k < grid.num_blocks(); ++k)
    if (grid.block_near(k, ball)) blocks.push_back(k);
  return blocks;
}

// The chains of one plane's cut (chains_of): chain j is items[starts[j]] .. items[starts[j + 1]]
// - 1; the other buffers are chains_of's own.
struct Chains {
  std::vector<int> by_start, next, items;
  std::vector<char> led, used;
  std::vector<std::size_t> starts;
  std::size_t size() const { return starts.size() - 1; }
};

// Scratch of the cuts, one per worker thread, reused from search to search (no allocation once
// its buffers have grown).
struct Scratch {
  std::vector<double> heights;
  std::vector<double> run_flank;      // a chain's concave runs' largest segment turn (chain_runs)
  std::vector<int> run_of;            // each segment's run (chain_runs)
  std::vector<std::size_t> run_best;  // each run's segment of largest turn (chain_runs)
  std::vector<std::size_t> point_at;  // a chain's fillet points' vertices (fillet_points)
  std::vector<CutSegment> segments;
  std::vector<std::pair<double, Index>> start_cells;  // plane_start's cells and their bounds
  Chains chains;
};

// A window in a plane's coordinates (lo <= x <= hi, t_lo <= y <= t_hi, mm): a cut keeps the
// segments with an end in it (fillet_points). A face with such an end lies in any box that holds
// the face, so a box wholly outside the window in either coordinate holds none of them. The
// plane's axes and their absolute values are held as scalars, so that the test (called for
// every block, cell and run of faces a half-plane meets) is inlined with no vector loads; it
// computes what (center - origin) . u and |u| . half give, in the same order.
struct Window {
  double lo, hi, t_lo, t_hi;
  double ox, oy, oz, ux, uy, uz, vx, vy, vz, aux, auy, auz, avx, avy, avz;
  Window(const PlaneFrame& plane, double lo_, double hi_, double t_lo_, double t_hi_)
      : lo(lo_),
        hi(hi_),
        t_lo(t_lo_),
        t_hi(t_hi_),
        ox(plane.origin.x()),
        oy(plane.origin.y()),
        oz(plane.origin.z()),
        ux(plane.u.x()),
        uy(plane.u.y()),
        uz(plane.u.z()),
        vx(plane.v.x()),
        vy(plane.v.y()),
        vz(plane.v.z()),
        aux(std::abs(ux)),
        auy(std::abs(uy)),
        auz(std::abs(uz)),
        avx(std::abs(vx)),
        avy(std::abs(vy)),
        avz(std::abs(vz)) {}
  bool outside(const Vec3& center, const Vec3& half) const {
    const double dx = center.x() - ox, dy = center.y() - oy, dz = center.z() - oz;
    const double hx = half.x(), hy = half.y(), hz = half.z();
    const double x = ux * dx + uy * dy + uz * dz, rx = aux * hx + auy * hy + auz * hz;
    if (x + rx < lo || x - rx > hi) return true;
    const double y = vx * dx + vy * dy + vz * dz, ry = avx * hx + avy * hy + avz * hz;
    return y + ry < t_lo || y - ry > t_hi;
  }
  // The square of an upper bound on the norm of the plane coordinates of the box's points: the
  // farthest corner of the box's extent along each axis (the same products as outside()).
  double reach2(const Vec3& center, const Vec3& half) const {
    const double dx = center.x() - ox, dy = center.y() - oy, dz = center.z() - oz;
    const double hx = half.x(), hy = half.y(), hz = half.z();
    const double x = std::abs(ux * dx + uy * dy + uz * dz) + (aux * hx + auy * hy + auz * hz);
    const double y = std::abs(vx * dx + vy * dy + vz * dz) + (avx * hx + avy * hy + avz * hz);
    return x * x + y * y;
  }
  // outside() for a box inside a box already tested (a run of a cell's faces), skipping the
  // coordinates in which that box lay wholly inside the window; `in_x`, `in_y` set for this box.
  bool outside(const Vec3& center, const Vec3& half, bool& in_x, bool& in_y) const {
    const double dx = center.x() - ox, dy = center.y() - oy, dz = center.z() - oz;
    const double hx = half.x(), hy = half.y(), hz = half.z();
    if (!in_x) {
      const double x = ux * dx + uy * dy + uz * dz, rx = aux * hx + auy * hy + auz * hz;
      if (x + rx < lo || x - rx > hi) return true;
      in_x = x - rx >= lo && x + rx <= hi;
    }
    if (!in_y) {
      const double y = vx * dx + vy * dy + vz * dz, ry = avx * hx + avy * hy + avz * hz;
      if (y + ry < t_lo || y - ry > t_hi) return true;
      in_y = y - ry >= t_lo && y + ry <= t_hi;
    }
    return false;
  }
  bool contains(const Vec2& p) const {
    return p.x() >= lo && p.x() <= hi && p.y() >= t_lo && p.y() <= t_hi;
  }
};
inline bool outside_window(const Window* window, const Vec3& center, const Vec3& half) {
  return window != nullptr && window->outside(center, half);
}

// A face of a cell cut (heights of its corners above the plane, mm): its segment appended to
// `out` when the plane crosses it and one end lies in the window (every end when none) — the
// step cut_cell and plane_start's start cut share.
inline void keep_crossing(const MeshView& mesh, const PlaneFrame& plane, const std::int32_t* f,
                          const double height[3], const Window* window,
                          std::vector<CutSegment>& out) {
  const bool above[3] = {height[0] >= 0.0, height[1] >= 0.0, height[2] >= 0.0};
  if (above[0] == above[1] && above[1] == above[2]) return;
  CutSegment seg;
  detail::emit_segment(mesh, plane, f, above, height, seg, nullptr);
  if (window == nullptr || window->contains(seg.point[0]) || window->contains(seg.point[1]))
    out.push_back(seg);
}

// Cell c's faces that the plane (normal n, offset n . origin) crosses, as segments (cut_cells),
// by the section cuts' own cell cut (cell_cut.hpp): a cell or a run of its faces whose tight box
// misses the plane or the window is skipped (none of its faces gives a kept segment). With a
// window, only the segments with an end in it are kept (in the grid's order, as a later filter
// would leave them).
void cut_cell(const MeshView& mesh, const FaceGrid& grid, Index c, const PlaneFrame& plane,
              double offset, const Window* window, std::vector<CutSegment>& out,
              std::vector<double>& heights) {
  // cut_cell_faces tests the cell's tight box first, then its runs' (each inside the cell's): a
  // run is not tested in a coordinate in which the cell's box lies wholly inside the window.
  bool in_x = window == nullptr, in_y = in_x;
  auto outside = [&](const Vec3& center, const Vec3& half) {
    return !(in_x && in_y) && window->outside(center, half, in_x, in_y);
  };
  detail::cut_cell_faces(mesh, grid, c, plane.normal, offset, outside, heights,
                         [&](const std::int32_t* f, const double height[3]) {
                           keep_crossing(mesh, plane, f, height, window, out);
                         });
}

// The segments of the faces that the plane crosses in the cells of `blocks` whose box may reach
// `region` (a ball), as cut_mesh makes them (each endpoint on a mesh edge, the face's
// orientation kept: an outward-facing surface gives counter-clockwise loops in (u, v)), from the
// grid's vertex entries (bit-exact copies of the mesh's). `heights`: scratch.
void cut_cells(const MeshView& mesh, const FaceGrid& grid, const std::vector<Index>& blocks,
               const PlaneFrame& plane, const CutRegion& region, std::vector<CutSegment>& out,
               Scratch& scratch, const Window* window = nullptr) {
  const Vec3& n = plane.normal;
  const double offset = n.dot(plane.origin);
  auto outside = [&](const Vec3& center, const Vec3& half) {
    return outside_window(window, center, half);
  };
  for (Index k : blocks) {
    // (A block's box holds its cells' boxes: the window test first, it needs no square root.)
    if (outside(grid.block_center(k), grid.block_half(k)) ||
        !grid.block_meets(k, n, offset, offset, &region))
      continue;
    // (In a block the plane test first: it rejects most of its cells, the window few.)
    // (With a window, a cell that meets the plane and the window's extent along both axes is
    // cut without the ball's test: it rejects few such cells, and only visits are saved by it.)
    for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c)
      if (grid.meets(c, n, offset, offset) && !outside(grid.cell_center(c), grid.cell_half(c)) &&
          (window != nullptr || region.meets_box(grid.cell_center(c), grid.cell_half(c))))
        cut_cell(mesh, grid, c, plane, offset, window, out, scratch.heights);
  }
}

// The unit direction, normal to u, from which the half-planes are placed: the point of the thin
// plane's cut within 1.5 r of the axis (the thin section's outline) farthest from it (ties: the
// smaller mesh edge), so that the planes turn with the model (a turned model cuts the same
// profiles). e1 if the cut is empty. The cells are cut farthest first (by a bound on the distance
// of their box from the origin), skipping the cells and runs of faces whose bound is below the
// best point so far: every point they hold lies nearer (the same point as a cut of them all).
Vec3 plane_start(const MeshView& mesh, const FaceGrid& grid, const std::vector<Index>& blocks,
                 const Vec3& origin, const Vec3& u, double r_thin, const Vec3& e1,
                 Scratch& scratch) {
  PlaneFrame frame = PlaneFrame::make(origin, u);
  CutRegion ball;
  ball.point = origin;
  ball.radius = 1.5 * r_thin;
  // Only points within the disk count, so only segments with an end in its square (widened far
  // beyond rounding: |x| and |y| exceed the norm by an ulp at most).
  const double square = ball.radius + 1e-9 * r_thin;
  const Window window(frame, -square, square, -square, square);
  const Vec3& n = frame.normal;
  const double offset = n.dot(frame.origin);
  // The cells the cut visits (cut_cells' tests), farthest first by a bound on their points' plane
  // coordinates (Window::reach2): a segment's end lies on a face edge inside the box (to a few
  // ulps, far below the margin). A cell, or a run of its faces (by its tight box), whose bound is
  // below the best point so far can hold neither a farther point nor a tie.
  const double margin = 1e-9 * r_thin;
  auto reach2 = [&](const Vec3& center, const Vec3& half) { return window.reach2(center, half); };
  std::vector<std::pair<double, Index>>& cells = scratch.start_cells;
  cells.clear();
  for (Index k : blocks) {
    if (window.outside(grid.block_center(k), grid.block_half(k)) ||
        !grid.block_meets(k, n, offset, offset, &ball))
      continue;
    for (Index c = grid.block_begin(k); c < grid.block_end(k); ++c) {
      const Vec3 &center = grid.cell_center(c), &half = grid.cell_half(c);
      if (grid.meets(c, n, offset, offset) && !window.outside(center, half) &&
          ball.meets_box(center, half))
        cells.emplace_back(reach2(center, half), c);
    }
  }
  std::sort(cells.begin(), cells.end(),
            [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<CutSegment>& segments = scratch.segments;
  double best = -1, below = -1;  // below: (best - margin)^2 once best > margin
  std::uint64_t best_edge = 0;
  Index best_cell = 0;
  Vec2 at(0, 0);
  bool in_x = false, in_y = false;  // as in cut_cell
  auto skip = [&](const Vec3& center, const Vec3& half) {
    return (!(in_x && in_y) && window.outside(center, half, in_x, in_y)) ||
           reach2(center, half) < below;
  };
  for (const auto& [bound, c] : cells) {
    if (bound < below) break;
    segments.clear();
    in_x = in_y = false;
    detail::cut_cell_faces(mesh, grid, c, n, offset, skip, scratch.heights,
                           [&](const std::int32_t* f, const double height[3]) {
                             keep_crossing(mesh, frame, f, height, &window, segments);
                           });
    // (Two faces give one edge's point with different roundings; at equal t and edge the first
    // in the grid's order wins, as in a cut of the cells in order: the smaller cell, and in a
    // cell the earlier face.)
    for (const CutSegment& s : segments)
      for (int k = 0; k < 2; ++k) {
        const double t = s.point[k].norm();
        if (t > ball.radius) continue;
        if (t > best ||
            (t == best && (s.edge[k] < best_edge || (s.edge[k] == best_edge && c < best_cell)))) {
          best = t;
          best_edge = s.edge[k];
          best_cell = c;
          at = s.point[k];
        }
      }
    if (best > margin) below = (best - margin) * (best - margin);
  }
  if (!(best > 0)) return e1;
  const Vec3 d = at.x() * frame.u + at.y() * frame.v;
  return (d - d.dot(u) * u).normalized();
}

// This thread's scratch. Not inlined: GCC re-derives a thread_local's address (a __tls_get_addr
// call in a shared library) at each use, even through a reference bound once.
OSTEON_NOINLINE Scratch& worker_scratch() {
  thread_local Scratch scratch;
  return scratch;
}

// The chains of one plane's segments (linked by the mesh edge they share: point[1] of one on
// the edge of point[0] of the next), each in order, in a canonical order (a chain's first
// segment: the one no other leads to, or in a loop the smallest edge; chains by that edge), so
// that the sums over them do not depend on the grid's layout. Segments shorter than `tiny` are
// left out (a plane through a vertex).
void chains_of(const std::vector<CutSegment>& seg, double tiny, Chains& out) {
  const int n = static_cast<int>(seg.size());
  std::vector<int>& by_start = out.by_start;
  by_start.resize(n);
  std::iota(by_start.begin(), by_start.end(), 0);
  std::sort(by_start.begin(), by_start.end(),
            [&](int x, int y) { return seg[x].edge[0] < seg[y].edge[0]; });
  std::vector<int>& next = out.next;
  std::vector<char>& led = out.led;
  next.assign(n, -1);
  led.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    const auto it =
        std::lower_bound(by_start.begin(), by_start.end(), seg[i].edge[1],
                         [&](int x, std::uint64_t key) { return seg[x].edge[0] < key; });
    if (it != by_start.end() && seg[*it].edge[0] == seg[i].edge[1] && *it != i && !led[*it]) {
      next[i] = *it;
      led[*it] = 1;
    }
  }
  std::vector<char>& used = out.used;
  used.assign(n, 0);
  out.items.clear();
  out.starts.assign(1, 0);
  auto walk = [&](int first) {
    for (int i = first; i >= 0 && !used[i]; i = next[i]) {
      used[i] = 1;
      if ((seg[i].point[1] - seg[i].point[0]).norm() >= tiny) out.items.push_back(i);
    }
    if (out.items.size() - out.starts.back() >= 2)
      out.starts.push_back(out.items.size());
    else
      out.items.resize(out.starts.back());
  };
  for (int i : by_start)
    if (!led[i]) walk(i);
  for (int i : by_start)
    if (!used[i]) walk(i);  // loops
}

// The signed turn at a chain's vertex between segments s0 and s1, radians: >= 0 convex (or
// straight), -1 concave (the loops of an outward-facing surface run counter-clockwise).
double vertex_turn(const CutSegment& s0, const CutSegment& s1) {
  const Vec2 d0 = s0.point[1] - s0.point[0], d1 = s1.point[1] - s1.point[0];
  const double cross = d0.x() * d1.y() - d0.y() * d1.x();
  // (A concave vertex only resets the run's convex sum: its angle is not needed.)
  return cross < 0 ? -1.0 : std::atan2(cross, d0.dot(d1));
}

// The concave runs of chain j, in order: a run ends where the profile has turned convex by more
// than kRunBreak in total since its last concave vertex (the thick side's outer edge, or a
// convex surface beyond the corner: a fine mesh turns it a little at each vertex; the facets'
// noise inside a fillet turns less). `run_of`: each segment's run; `run_flank`: each run's
// largest segment turn from radial towards the thin side (radians; a segment's outward normal
// (d_t, -d_a) / |d|, its turn atan2(-n_a, n_t)).
void chain_runs(const std::vector<CutSegment>& seg, const Chains& chains, std::size_t j,
                std::vector<int>& run_of, std::vector<double>& run_flank,
                std::vector<std::size_t>& run_best) {
  // A segment's turn orders as its pseudo-angle (monotone in atan2(y, x), no trigonometry):
  // each run keeps its largest's segment, whose atan2 is taken once at the end.
  auto pseudo = [](const Vec2& d) {
    const double y = -d.y(), x = -d.x(), m = std::abs(x) + std::abs(y);
    return m > 0 ? std::copysign(1.0 - x / m, y) : -2.0;
  };
  run_flank.assign(1, -3.0);  // (first the pseudo-angles, below every one)
  run_best.assign(1, chains.starts[j]);
  run_of.clear();
  double convex = 0;  // the convex turn since the last concave vertex
  for (std::size_t k = chains.starts[j]; k < chains.starts[j + 1]; ++k) {
    const CutSegment& s = seg[chains.items[k]];
    if (k > chains.starts[j]) {
      const double turn = vertex_turn(seg[chains.items[k - 1]], s);
      if (turn < 0) {
        convex = 0;
      } else if (convex <= kRunBreak && (convex += turn) > kRunBreak) {
        run_flank.push_back(-3.0);
        run_best.push_back(k);
      }
    }
    const double p = pseudo(s.point[1] - s.point[0]);
    if (p > run_flank.back()) {
      run_flank.back() = p;
      run_best.back() = k;
    }
    run_of.push_back(static_cast<int>(run_flank.size()) - 1);
  }
  for (std::size_t r = 0; r < run_flank.size(); ++r) {
    const CutSegment& s = seg[chains.items[run_best[r]]];
    const Vec2 d = s.point[1] - s.point[0];
    run_flank[r] = std::atan2(-d.y(), -d.x());
  }
}

// The fillet points of the concave corner between a thin section (bone point `origin`,
// equivalent radius r_thin) and the thick side along unit axis `u` (thin -> thick), within
// axial [lo, hi] of the thin section's plane and 0.5 .. 2.5 r_thin of the axis, on the
// meridian profiles: a polyline vertex whose normal turns 8..82 degrees from radial towards the
// thin side and at which the profile bends concave (the shoulder's outer, convex edge has the
// same turn). A point's test does not depend on the window beyond its own a, so the points of a
// narrower window are exactly those of this list inside it.
FilletPoints fillet_points(const MeshView& mesh, const FaceGrid& grid, const Vec3& origin,
                           const Vec3& u, double r_thin, double lo, double hi) {
  const std::vector<Index> blocks = window_blocks(grid, origin, u, r_thin, lo, hi);
  Scratch& scratch = worker_scratch();
  const Vec3 e1 = plane_start(mesh, grid, blocks, origin, u, r_thin, u.unitOrthogonal(), scratch);
  const Vec3 e2 = u.cross(e1);
  const double t_lo = 0.5 * r_thin, t_hi = 2.5 * r_thin, margin = 1e-9 * r_thin;
  const double lo_sin = std::sin(8.0 * kPi / 180.0), hi_sin = std::sin(82.0 * kPi / 180.0);
  FilletPoints out;
  std::vector<CutSegment>& seg = scratch.segments;
  Chains& chains = scratch.chains;
  for (int half = 0; half < kHalfPlanes; ++half) {
    const double phi = 2.0 * kPi * (half + kPlanePhase) / kHalfPlanes;
    PlaneFrame frame;  // (a, y): a along u, y along w; the plane holds the axis
    frame.origin = origin;
    frame.u = u;
    frame.v = std::cos(phi) * e1 + std::sin(phi) * e2;
    frame.normal = frame.u.cross(frame.v);
    CutRegion ball;  // the window's rectangle on this half-plane
    ball.point = origin + 0.5 * (lo + hi) * u + 0.5 * (t_lo + t_hi) * frame.v;
    ball.radius = std::hypot(0.5 * (t_hi - t_lo), 0.5 * (hi - lo)) + margin;
    seg.clear();
    const Window window(frame, lo - margin, hi + margin, t_lo - margin, t_hi + margin);
    cut_cells(mesh, grid, blocks, frame, ball, seg, scratch, &window);
    chains_of(seg, margin, chains);
    for (std::size_t j = 0; j < chains.size(); ++j) {
      const std::size_t first = out.points.size();
      scratch.point_at.clear();
      for (std::size_t k = chains.starts[j]; k + 1 < chains.starts[j + 1]; ++k) {
        const CutSegment &s0 = seg[chains.items[k]], &s1 = seg[chains.items[k + 1]];
        const Vec2 p = s0.point[1];
        const double t = p.y();
        if (p.x() < lo || p.x() > hi || t < t_lo || t > t_hi) continue;
        const Vec2 d0 = s0.point[1] - s0.point[0], d1 = s1.point[1] - s1.point[0];
        const double l0 = d0.norm(), l1 = d1.norm();
        // Outward normals (the loops of an outward-facing surface run counter-clockwise); a
        // concave vertex turns clockwise.
        if (!(d0.x() * d1.y() - d0.y() * d1.x() < -1e-9 * l0 * l1)) continue;
        Vec2 n = Vec2(d0.y(), -d0.x()) / l0 + Vec2(d1.y(), -d1.x()) / l1;
        if (!(n.norm() > 0)) continue;
        n.normalize();
        const double na = n.x(), nr = n.y();
        if (!(nr > 0) || !(-na >= lo_sin && -na <= hi_sin)) continue;
        FilletPoint q;
        q.a = p.x();
        q.na = na;
        q.turn = std::atan2(-na, nr);
        q.t = t;
        q.sector = half;
        q.edge_begin = out.edges.size();
        out.edges.push_back(l0 * l0);
        out.edges.push_back(l1 * l1);
        q.edge_end = out.edges.size();
        out.points.push_back(q);
        scratch.point_at.push_back(k - chains.starts[j]);
      }
      // The runs only of a chain with fillet points (most chains in the window have none).
      if (out.points.size() == first) continue;
      chain_runs(seg, chains, j, scratch.run_of, scratch.run_flank, scratch.run_best);
      for (std::size_t m = first; m < out.points.size(); ++m)
        out.points[m].flank = scratch.run_flank[scratch.run_of[scratch.point_at[m - first]]];
    }
  }
  return out;
}

// The sums of the fillet points of half-plane h alone (corner_in's fallback); `lengths`: the
// buffer its edges' squared lengths are copied to.
SectorSums half_plane_sums(const std::vector<const FilletPoint*>& inside,
                           const FilletPoints& fillet, int h, std::vector<double>& lengths) {
  SectorSums q;
  lengths.clear();
  for (const FilletPoint* p : inside) {
    if (p->sector != h) continue;
    add_point(q, *p);
    lengths.insert(lengths.end(), fillet.edges.data() + p->edge_begin,
                   fillet.edges.data() + p->edge_end);
  }
  if (q.n == 0) return q;
  q.ma /= q.n;
  q.mn /= q.n;
  q.mt /= q.n;
  for (const FilletPoint* p : inside) {
    if (p->sector != h) continue;
    const double da = p->a - q.ma, dt = p->t - q.mt, dn = p->na - q.mn;
    q.saa += da * da;
    q.stt += dt * dt;
    q.snn += dn * dn;
    q.san += da * dn;
  }
  q.lengths = lengths.data();
  q.num_lengths = lengths.size();
  return q;
}

// One sector's verdict folded into the corner `c`: the sharpest sector's radius governs, the
// most acute sector's opening is kept. Returns whether the sector's fit said anything.
bool judge_sector(const SectorSums& sums, double r_thin, Corner& c) {
  double rho = 0, axial = 0;
  if (!sector_radius(sums, r_thin, rho, axial)) return false;
  // How far the surface turns at the corner: a sharp edge's normal is the bisector (half the
  // turn), a fillet's points reach the turn. The fit is for a shoulder (a 90-degree turn);
  // creases turning less than kMinTurn (tapers, facets of a low-poly mesh) are not counted:
  // their singularity is weaker (Williams 1952: stress ~ dist^-0.33 at a 45-degree turn
  // against dist^-0.46 at 90), and turns of 45..90 degrees take the shoulder's Kt (safe side).
  const double turn = rho == 0.0 ? 2.0 * sums.turn : sums.turn + 8.0 * kPi / 180.0;
  if (turn < kMinTurn) return true;
  // The most acute sector's opening (the safe side, with the sharpest sector's radius).
  const double opening = kPi - sums.flank;
  if (!c.found || opening < c.opening) c.opening = opening;
  if (!c.found || rho < c.radius) {  // the sharpest sector governs
    c.found = true;
    c.radius = rho;
    c.axial = axial;
  }
  return true;
}

// The corner's radius from the fillet points within axial [lo, hi]: fitted per 45-degree
// sector around the axis (kSectorSpan neighbouring half-planes each), the sharpest sector
// governs.
Corner corner_in(const FilletPoints& fillet, double r_thin, double lo, double hi) {
  std::vector<const FilletPoint*> inside;
  for (const FilletPoint& p : fillet.points)
    if (p.a >= lo && p.a <= hi) inside.push_back(&p);
  // Each sector's sums over its points in their order (the order a sequential sum needs), and
  // its edges' lengths grouped in one buffer: no per-sector copies of the points.
  auto sector_of = [](const FilletPoint* p, int j) {
    return (p->sector - j + kSectors) % kSectors;
  };
  std::array<SectorSums, kSectors> sums{};
  std::array<std::size_t, kSectors + 1> edge_at{};
  for (const FilletPoint* p : inside)
    for (int j = 0; j < kSectorSpan; ++j) {
      const int sector = sector_of(p, j);
      add_point(sums[sector], *p);
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
  std::vector<double> lengths(edge_at[kSectors]);
  std::array<std::size_t, kSectors> edge_next{};
  for (int s = 0; s < kSectors; ++s) {
    edge_next[s] = edge_at[s];
    sums[s].lengths = lengths.data() + edge_at[s];
    sums[s].num_lengths = edge_at[s + 1] - edge_at[s];
  }
  for (const FilletPoint* p : inside)
    for (int j = 0; j < kSectorSpan; ++j) {
      const int sector = sector_of(p, j);
      SectorSums& q = sums[sector];
      const double da = p->a - q.ma, dt = p->t - q.mt, dn = p->na - q.mn;
      q.saa += da * da;
      q.stt += dt * dt;
      q.snn += dn * dn;
      q.san += da * dn;
      std::copy(fillet.edges.data() + p->edge_begin, fillet.edges.data() + p->edge_end,
                lengths.data() + edge_next[sector]);
      edge_next[sector] += p->edge_end - p->edge_begin;
    }
  Corner c;
  std::array<char, kSectors> said{};  // the sector's fit gave a verdict (sector_radius)
  for (int s = 0; s < kSectors; ++s) said[s] = judge_sector(sums[s], r_thin, c);
  // A half-plane whose two sectors both say nothing (their two profiles disagree: a corner
  // whose axial position changes around the axis, a junction's acute side against its sides)
  // is fitted alone when it has 3 points or more (round 6).
  std::vector<double> own_lengths;
  for (int h = 0; h < kHalfPlanes; ++h) {
    if (said[h] || said[(h + kSectors - 1) % kSectors]) continue;
    SectorSums one = half_plane_sums(inside, fillet, h, own_lengths);
    if (one.n >= 3) judge_sector(one, r_thin, c);
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
                                    const std::vector<Step>& steps, int threads) {
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
  // the number of workers.
  const int workers = detail::worker_count(threads, static_cast<long>(firsts.size()));
  detail::parallel_for(static_cast<long>(firsts.size()), workers, [&](long job, int) {
    const std::size_t s = firsts[static_cast<std::size_t>(job)];
    double reach = 0;
    for (std::size_t t = s; t < steps.size(); ++t)
      if (same_side(s, t)) reach = std::max(reach, steps[t].reach);
    const Step& st = steps[s];
    const FilletPoints points =
        fillet_points(mesh, grid, st.point, st.u, st.r_thin, -0.25 * reach, 1.25 * reach);
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
// moved triangle reaches is copied from `memo`, the others are searched (whole gatherings: a
// gathering's window is its widest step's); `memo` then holds this run's.
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
  const std::vector<Corner> measured = measure_corners(mesh, face_grid, todo, threads);
  std::vector<Corner> corners(steps.size());
  std::vector<std::size_t> taken(groups.size(), 0);
  for (std::size_t s = 0, next = 0; s < steps.size(); ++s) {
    CornerGroup& g = groups[group_of[s]];
    if (recalled[group_of[s]]) {
      const CornerFit& f = g.corners[taken[group_of[s]]++];
      corners[s] = Corner{f.found, f.radius, f.axial, f.opening};
    } else {
      corners[s] = measured[next++];
      g.corners.push_back(
          CornerFit{corners[s].found, corners[s].radius, corners[s].axial, corners[s].opening});
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
  // Live updates (what moved is known, after a full run or another live update): the memo. Other
  // runs (one-off, the first of a session, the correction's) search every corner; a full one
  // arms the memo for the next run.
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
    // The stepped bar's Kt, its excess raised at an acute corner (acute_factor).
    const double kt = 1.0 + (shoulder_fillet_kt(2 * st.r_big, 2 * st.r_thin, rho) - 1.0) *
                                acute_factor(c.opening);
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
