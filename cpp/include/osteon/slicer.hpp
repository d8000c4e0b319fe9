// Plane-mesh slicing into closed loops, and the choice of the section around a bone (SPEC §3).
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/mesh.hpp"
#include "osteon/section.hpp"

namespace osteon {

/// Per-section flags (bit mask) saying how a section was obtained; 0 = clean closed cut.
enum SectionFlag : std::uint32_t {
  kFlagGapClosed = 1u << 0,    ///< open polylines were joined across gaps <= the gap tolerance
  kFlagOpen = 1u << 1,         ///< an open polyline touches this section: it may be incomplete
  kFlagOutside = 1u << 2,      ///< the bone point lies in no loop (bone outside): nearest loop used
  kFlagHollow = 1u << 3,       ///< the bone point lies in a hole: the whole wall around it is used
  kFlagEmpty = 1u << 4,        ///< nothing usable was cut: section skipped (no stress)
  kFlagDegenerate = 1u << 5,   ///< zero area or singular second moment: section skipped
  kFlagNonManifold = 1u << 6,  ///< non-manifold edges were cut (more than two faces on an edge)
};

/// An orthonormal plane frame: origin, unit normal and in-plane axes u, v (u x v = normal).
struct PlaneFrame {
  Vec3 origin = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  Vec3 u = Vec3::UnitX();
  Vec3 v = Vec3::UnitY();

  /// Frame with the given origin and (not necessarily unit) normal; u, v chosen deterministically.
  static PlaneFrame make(const Vec3& origin, const Vec3& normal);
  /// 2D coordinates (mm) of a 3D point, relative to the origin.
  Vec2 to_plane(const Vec3& p) const { return Vec2((p - origin).dot(u), (p - origin).dot(v)); }
  /// 3D point of 2D plane coordinates.
  Vec3 to_world(const Vec2& q) const { return origin + q.x() * u + q.y() * v; }
};

/// One triangle's cut: two endpoints, each on a mesh edge identified by its vertex pair.
struct CutSegment {
  std::uint64_t edge[2];  ///< (min vertex << 32) | max vertex of the edge each endpoint lies on
  Vec2 point[2];          ///< endpoints in plane coordinates, mm
};

/// The closed loops (and leftover open polylines) of one plane cut, in plane coordinates.
struct PlaneCut {
  std::vector<std::vector<Vec2>> loops;        ///< closed loops (last point joins the first)
  std::vector<std::vector<Vec2>> open_chains;  ///< polylines that could not be closed
  std::uint32_t flags = 0;                     ///< kFlagGapClosed, kFlagNonManifold
};

/// A section's material region and how it was found.
struct SectionGeometry {
  SectionPolygon polygon;  ///< outer boundary + holes, plane coordinates (mm)
  std::uint32_t flags = 0; ///< SectionFlag bits
  bool found = false;      ///< false when the section had to be skipped
};

/// Cuts every triangle of the mesh that crosses the plane (O(V + F)); appends to `out`.
void cut_mesh(const MeshView& mesh, const PlaneFrame& plane, std::vector<CutSegment>& out);

/// Cuts the mesh by `count` parallel planes base + k*spacing*normal, k = 1..count, in one pass.
/// out[k-1] receives plane k's segments, in coordinates of the frame `plane` (whose origin is base).
/// `scratch` is reused between calls to avoid allocation.
void cut_mesh_parallel(const MeshView& mesh, const PlaneFrame& plane, double spacing, int count,
                       std::vector<std::vector<CutSegment>>& out, std::vector<std::int32_t>& scratch);

/// Links cut segments into loops by shared mesh edges; joins open ends closer than gap_tolerance (mm).
PlaneCut assemble_loops(const std::vector<CutSegment>& segments, double gap_tolerance);

/// The material region around the plane origin (the bone point), following SPEC §3: the deepest
/// outer boundary containing the origin with the loops directly inside it as holes.
SectionGeometry select_section(const PlaneCut& cut);

/// Convenience: cut, assemble and select the section of one plane (origin = bone point).
SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance);

}  // namespace osteon
