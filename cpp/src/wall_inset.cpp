// The walls' inset (wall_inset.hpp): Clipper2's ClipperOffset (clipper.offset.cpp: DoGroupOffset,
// BuildNormals, OffsetPoint, DoRound) for closed paths, round joins and a negative delta, point
// for point; its union pass by winding_region.
#include "wall_inset.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "round_to_unit.hpp"
#include "winding_region.hpp"

namespace osteon::detail {
namespace {

using Clipper2Lib::Path64;
using Clipper2Lib::Paths64;
using Clipper2Lib::Point64;
using Clipper2Lib::PointD;

// Clipper2's arc steps for |delta| (ClipperOffset::DoGroupOffset), the sine negated for an inset.
struct ArcSteps {
  double sin, cos, per_rad;
  ArcSteps(double delta, double arc_tolerance) {
    const double tol = arc_tolerance > 1e-12 ? std::min(delta, arc_tolerance) : delta * 0.002;
    const double per_360 = std::min(M_PI / std::acos(1 - tol / delta), delta * M_PI);
    sin = -std::sin(2 * M_PI / per_360);
    cos = std::cos(2 * M_PI / per_360);
    per_rad = per_360 / (2 * M_PI);
  }
};

// Clipper2's Point64(double, double): std::round of each coordinate.
inline Point64 rounded(double x, double y) { return Point64(round_to_unit(x), round_to_unit(y)); }

// One closed path's raw offset by -delta (no repeated points).
void offset_path(const Path64& path, double delta, const ArcSteps& arc, Path64& out) {
  const std::size_t n = path.size();
  std::vector<PointD> norms(n);  // Clipper2's GetUnitNormal: (dy, -dx) / length
  for (std::size_t k = 0; k < n; ++k) {
    const Point64& a = path[k];
    const Point64& b = path[k + 1 == n ? 0 : k + 1];
    const double dx = static_cast<double>(b.x - a.x), dy = static_cast<double>(b.y - a.y);
    const double inv = 1.0 / std::sqrt(dx * dx + dy * dy);
    norms[k] = PointD(dy * inv, -dx * inv);
  }
  const double gd = -delta;
  for (std::size_t j = 0, k = n - 1; j < n; k = j, ++j) {
    const Point64& p = path[j];
    const PointD &nk = norms[k], &nj = norms[j];
    const double sin_a = std::clamp(nj.y * nk.x - nk.y * nj.x, -1.0, 1.0);
    const double cos_a = nj.x * nk.x + nj.y * nk.y;
    if (cos_a > -0.999 && sin_a * gd < 0) {  // convex corner: Clipper2's three points
      out.push_back(rounded(p.x + nk.x * gd, p.y + nk.y * gd));
      out.push_back(p);
      out.push_back(rounded(p.x + nj.x * gd, p.y + nj.y * gd));
      continue;
    }
    PointD v(nk.x * gd, nk.y * gd);  // DoRound
    out.push_back(rounded(p.x + v.x, p.y + v.y));
    const int steps = static_cast<int>(std::ceil(arc.per_rad * std::abs(std::atan2(sin_a, cos_a))));
    for (int i = 1; i < steps; ++i) {
      v = PointD(v.x * arc.cos - arc.sin * v.y, v.x * arc.sin + v.y * arc.cos);
      out.push_back(rounded(p.x + v.x, p.y + v.y));
    }
    out.push_back(rounded(p.x + nj.x * gd, p.y + nj.y * gd));
  }
}

bool positive(const Windings& w) { return w[0] > 0; }

}  // namespace

Paths64 wall_inset(const Paths64& paths, double delta, double arc_tolerance) {
  Paths64 in = paths;
  for (Path64& p : in) Clipper2Lib::StripDuplicates(p, true);
  // Clipper2's orientation rule: the path with the lowest point (largest y, then smallest x)
  // sets it; anything but a positive one there, tiny offsets or short paths: Clipper2 itself.
  std::optional<std::size_t> lowest;
  Point64 bot(INT64_MAX, INT64_MIN);
  for (std::size_t i = 0; i < in.size(); ++i)
    for (const Point64& pt : in[i])
      if (pt.y > bot.y || (pt.y == bot.y && pt.x < bot.x)) bot = pt, lowest = i;
  const bool plain =
      delta >= 0.5 && lowest && Clipper2Lib::Area(in[*lowest]) > 0 &&
      std::all_of(in.begin(), in.end(), [](const Path64& p) { return p.size() > 2; });
  Paths64 out;
  if (plain) {
    const ArcSteps arc(delta, arc_tolerance);
    Paths64 raw(in.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
      raw[i].reserve(2 * in[i].size());
      offset_path(in[i], delta, arc, raw[i]);
    }
    if (winding_region({&raw}, positive, out)) return out;
  }
  return Clipper2Lib::InflatePaths(paths, -delta, Clipper2Lib::JoinType::Round,
                                   Clipper2Lib::EndType::Polygon, 2.0, arc_tolerance);
}

}  // namespace osteon::detail
