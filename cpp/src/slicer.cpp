#include "osteon/slicer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace osteon {
namespace {

inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const std::uint32_t lo = static_cast<std::uint32_t>(std::min(a, b));
  const std::uint32_t hi = static_cast<std::uint32_t>(std::max(a, b));
  return (static_cast<std::uint64_t>(lo) << 32) | hi;
}

// Cut of triangle (a, b, c) given per-vertex "above" flags and signed heights (height 0 = plane).
// Exactly two edges change side; each gives an endpoint at linear interpolation of the heights.
inline void emit_segment(const MeshView& mesh, const PlaneFrame& plane, const std::int32_t* f,
                         const bool above[3], const double height[3], CutSegment& seg) {
  int n = 0;
  for (int e = 0; e < 3 && n < 2; ++e) {
    const int i = e, j = (e + 1) % 3;
    if (above[i] == above[j]) continue;
    const double denom = height[j] - height[i];
    double lambda = denom != 0.0 ? -height[i] / denom : 0.5;
    lambda = std::clamp(lambda, 0.0, 1.0);
    const double* pi = mesh.vertices + 3 * static_cast<Index>(f[i]);
    const double* pj = mesh.vertices + 3 * static_cast<Index>(f[j]);
    const Vec3 p(pi[0] + lambda * (pj[0] - pi[0]), pi[1] + lambda * (pj[1] - pi[1]),
                 pi[2] + lambda * (pj[2] - pi[2]));
    seg.edge[n] = edge_key(f[i], f[j]);
    seg.point[n] = plane.to_plane(p);
    ++n;
  }
}

// Open-addressing table: mesh edge key -> up to two segment endpoints ("occurrences").
struct EdgeTable {
  std::vector<std::uint64_t> keys;
  std::vector<std::int32_t> first, second;
  std::uint64_t mask = 0;
  int bits = 0;
  static constexpr std::uint64_t kEmpty = ~0ull;

  void reset(std::size_t entries) {
    bits = 4;
    while ((std::size_t(1) << bits) < 2 * entries + 16) ++bits;
    const std::size_t size = std::size_t(1) << bits;
    mask = size - 1;
    keys.assign(size, kEmpty);
    first.assign(size, -1);
    second.assign(size, -1);
  }
  // Returns false if the edge already had two endpoints (non-manifold).
  bool insert(std::uint64_t key, std::int32_t occurrence) {
    std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> (64 - bits);
    while (true) {
      if (keys[h] == kEmpty) {
        keys[h] = key;
        first[h] = occurrence;
        return true;
      }
      if (keys[h] == key) {
        if (second[h] < 0) {
          second[h] = occurrence;
          return true;
        }
        return false;
      }
      h = (h + 1) & mask;
    }
  }
};

double squared_distance_to_polyline(const std::vector<Vec2>& pts, bool closed, const Vec2& q) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = pts.size();
  if (n == 1) return (pts[0] - q).squaredNorm();
  const std::size_t edges = closed ? n : n - 1;
  for (std::size_t i = 0; i < edges; ++i) {
    const Vec2& a = pts[i];
    const Vec2& b = pts[(i + 1) % n];
    const Vec2 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - q).squaredNorm());
  }
  return best;
}

struct Box2 {
  Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  void add(const Vec2& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool contains(const Vec2& p) const {
    return p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() && p.y() <= hi.y();
  }
  bool contains(const Box2& b) const {
    return b.lo.x() >= lo.x() && b.lo.y() >= lo.y() && b.hi.x() <= hi.x() && b.hi.y() <= hi.y();
  }
  bool overlaps(const Box2& b) const {
    return !(b.lo.x() > hi.x() || b.hi.x() < lo.x() || b.lo.y() > hi.y() || b.hi.y() < lo.y());
  }
};

Box2 box_of(const std::vector<Vec2>& pts) {
  Box2 b;
  for (const Vec2& p : pts) b.add(p);
  return b;
}

}  // namespace

PlaneFrame PlaneFrame::make(const Vec3& origin, const Vec3& normal) {
  PlaneFrame f;
  f.origin = origin;
  f.normal = normal.normalized();
  // Pick the world axis least aligned with the normal to build u deterministically.
  Vec3 helper = Vec3::UnitX();
  const Vec3 a = f.normal.cwiseAbs();
  if (a.x() <= a.y() && a.x() <= a.z()) helper = Vec3::UnitX();
  else if (a.y() <= a.z()) helper = Vec3::UnitY();
  else helper = Vec3::UnitZ();
  f.u = (helper - helper.dot(f.normal) * f.normal).normalized();
  f.v = f.normal.cross(f.u);
  return f;
}

void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out) {
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  for (Index fi = 0; fi < mesh.num_faces; ++fi) {
    const std::int32_t* f = mesh.faces + 3 * fi;
    double height[3];
    bool above[3];
    for (int k = 0; k < 3; ++k) {
      const double* p = mesh.vertices + 3 * static_cast<Index>(f[k]);
      height[k] = p[0] * nx + p[1] * ny + p[2] * nz - offset;
      above[k] = height[k] >= 0.0;
    }
    if (above[0] == above[1] && above[1] == above[2]) continue;
    CutSegment seg;
    emit_segment(mesh, plane, f, above, height, seg);
    out.push_back(seg);
  }
}

void cut_mesh_parallel(const MeshView& mesh, const PlaneFrame& plane, double spacing, int count,
                       std::vector<std::vector<CutSegment>>& out, std::vector<std::int32_t>& scratch) {
  out.resize(count);
  for (auto& o : out) o.clear();
  if (count <= 0) return;
  // Bucket index of every vertex: number of planes at or below it (0..count). A triangle crosses
  // plane k exactly when its vertices' buckets straddle k, so one pass finds every cut.
  scratch.resize(mesh.num_vertices);
  const double nx = plane.normal.x(), ny = plane.normal.y(), nz = plane.normal.z();
  const double offset = plane.normal.dot(plane.origin);
  const double inv = 1.0 / spacing;
  const double top = static_cast<double>(count);
  std::int32_t* bucket = scratch.data();
  for (Index i = 0; i < mesh.num_vertices; ++i) {
    const double* p = mesh.vertices + 3 * i;
    double q = std::floor((p[0] * nx + p[1] * ny + p[2] * nz - offset) * inv);
    q = q < 0.0 ? 0.0 : (q > top ? top : q);
    bucket[i] = static_cast<std::int32_t>(q);
  }
  for (Index fi = 0; fi < mesh.num_faces; ++fi) {
    const std::int32_t* f = mesh.faces + 3 * fi;
    const std::int32_t b0 = bucket[f[0]], b1 = bucket[f[1]], b2 = bucket[f[2]];
    const std::int32_t lo = std::min({b0, b1, b2}), hi = std::max({b0, b1, b2});
    if (lo == hi) continue;
    double t[3];
    for (int k = 0; k < 3; ++k) {
      const double* p = mesh.vertices + 3 * static_cast<Index>(f[k]);
      t[k] = p[0] * nx + p[1] * ny + p[2] * nz - offset;
    }
    const std::int32_t b[3] = {b0, b1, b2};
    for (std::int32_t k = lo + 1; k <= hi; ++k) {
      const double c = k * spacing;
      bool above[3];
      double height[3];
      for (int j = 0; j < 3; ++j) {
        above[j] = b[j] >= k;
        height[j] = t[j] - c;
      }
      CutSegment seg;
      emit_segment(mesh, plane, f, above, height, seg);
      out[k - 1].push_back(seg);
    }
  }
}

PlaneCut assemble_loops(const std::vector<CutSegment>& segments, double gap_tolerance) {
  PlaneCut cut;
  const std::size_t m = segments.size();
  if (m == 0) return cut;
  // Pair the two endpoints that lie on the same mesh edge; orientation-agnostic so that
  // inconsistently wound meshes still give loops.
  EdgeTable table;
  table.reset(2 * m);
  std::vector<std::int32_t> partner(2 * m, -1);
  for (std::size_t s = 0; s < m; ++s)
    for (int e = 0; e < 2; ++e)
      if (!table.insert(segments[s].edge[e], static_cast<std::int32_t>(2 * s + e)))
        cut.flags |= kFlagNonManifold;
  for (std::size_t h = 0; h < table.keys.size(); ++h) {
    if (table.second[h] >= 0) {
      partner[table.first[h]] = table.second[h];
      partner[table.second[h]] = table.first[h];
    }
  }
  std::vector<std::uint8_t> used(m, 0);
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
      cut.loops.push_back(forward);
    }
  }
  // Close small gaps: repeatedly join the closest pair of open ends within the tolerance
  // (a chain's own two ends closes it into a loop).
  auto& chains = cut.open_chains;
  if (!chains.empty() && gap_tolerance > 0 && chains.size() <= 256) {
    const double tol2 = gap_tolerance * gap_tolerance;
    while (!chains.empty()) {
      double best = tol2;
      int bi = -1, bj = -1;
      bool flip = false;  // join back of i to back of j (reverse j)
      for (std::size_t i = 0; i < chains.size(); ++i) {
        for (std::size_t j = 0; j < chains.size(); ++j) {
          const double d_front = (chains[i].back() - chains[j].front()).squaredNorm();
          if (d_front <= best) {
            best = d_front;
            bi = static_cast<int>(i);
            bj = static_cast<int>(j);
            flip = false;
          }
          if (i != j) {
            const double d_back = (chains[i].back() - chains[j].back()).squaredNorm();
            if (d_back < best) {
              best = d_back;
              bi = static_cast<int>(i);
              bj = static_cast<int>(j);
              flip = true;
            }
          }
        }
      }
      if (bi < 0) break;
      cut.flags |= kFlagGapClosed;
      if (bi == bj) {
        if (chains[bi].size() >= 3) cut.loops.push_back(std::move(chains[bi]));
        chains.erase(chains.begin() + bi);
        continue;
      }
      std::vector<Vec2> tail = std::move(chains[bj]);
      if (flip) std::reverse(tail.begin(), tail.end());
      chains[bi].insert(chains[bi].end(), tail.begin(), tail.end());
      chains.erase(chains.begin() + bj);
    }
  }
  // Drop degenerate loops (fewer than three points cannot bound area).
  cut.loops.erase(std::remove_if(cut.loops.begin(), cut.loops.end(),
                                 [](const std::vector<Vec2>& l) { return l.size() < 3; }),
                  cut.loops.end());
  return cut;
}

SectionGeometry select_section(const PlaneCut& cut) {
  SectionGeometry geom;
  geom.flags = cut.flags & (kFlagGapClosed | kFlagNonManifold);
  const Vec2 origin = Vec2::Zero();
  const std::size_t n = cut.loops.size();
  std::vector<Box2> boxes(n);
  std::vector<double> area(n);
  std::vector<int> containing;
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i] = box_of(cut.loops[i]);
    area[i] = std::abs(signed_area(cut.loops[i]));
    if (boxes[i].contains(origin) && point_in_loop(cut.loops[i], origin))
      containing.push_back(static_cast<int>(i));
  }
  // An unclosed polyline around the bone point means the cut here is incomplete: skip it.
  for (const auto& chain : cut.open_chains) {
    if (chain.size() >= 2 && box_of(chain).contains(origin)) {
      geom.flags |= kFlagOpen;
      if (containing.empty()) {
        geom.flags |= kFlagEmpty;
        return geom;
      }
    }
  }
  int outer = -1;
  if (!containing.empty()) {
    // Loops containing the point are nested: sort outermost first; depth = position.
    std::sort(containing.begin(), containing.end(),
              [&](int a, int b) { return area[a] > area[b]; });
    const std::size_t count = containing.size();
    if (count % 2 == 1) {
      outer = containing[count - 1];
    } else {
      outer = containing[count - 2];
      geom.flags |= kFlagHollow;
    }
  } else {
    // Bone outside the mesh here: use the nearest loop (or nearest open geometry: skip).
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) {
      const double d = squared_distance_to_polyline(cut.loops[i], true, origin);
      if (d < best) {
        best = d;
        outer = static_cast<int>(i);
      }
    }
    double best_open = std::numeric_limits<double>::infinity();
    for (const auto& chain : cut.open_chains)
      best_open = std::min(best_open, squared_distance_to_polyline(chain, false, origin));
    if (outer < 0 || best_open < best) {
      geom.flags |= kFlagEmpty | ((outer < 0 && cut.open_chains.empty()) ? 0u : kFlagOpen);
      return geom;
    }
    geom.flags |= kFlagOutside;
  }
  // Holes: loops inside the outer boundary that are not inside another such loop.
  std::vector<int> inside;
  for (std::size_t i = 0; i < n; ++i) {
    if (static_cast<int>(i) == outer || area[i] >= area[outer]) continue;
    if (!boxes[outer].contains(boxes[i])) continue;
    if (point_in_loop(cut.loops[outer], cut.loops[i][0])) inside.push_back(static_cast<int>(i));
  }
  for (int i : inside) {
    bool direct = true;
    for (int j : inside) {
      if (i == j || area[j] <= area[i] || !boxes[j].contains(boxes[i])) continue;
      if (point_in_loop(cut.loops[j], cut.loops[i][0])) {
        direct = false;
        break;
      }
    }
    if (direct) geom.polygon.holes.push_back(cut.loops[i]);
  }
  geom.polygon.outer = cut.loops[outer];
  for (const auto& chain : cut.open_chains)
    if (chain.size() >= 2 && boxes[outer].overlaps(box_of(chain))) geom.flags |= kFlagOpen;
  geom.found = true;
  return geom;
}

SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance) {
  std::vector<CutSegment> segments;
  cut_mesh(mesh, plane, segments);
  return select_section(assemble_loops(segments, gap_tolerance));
}

}  // namespace osteon
