// What the section-region files share (region_choice.cpp, junction_core.cpp, thickness.cpp):
// plane coordinates <-> Clipper2's integers (Scaler), boxes of plane points, and Clipper2's
// polygon trees read back as regions.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "clipper2/clipper.h"
#include "osteon/section.hpp"

namespace osteon {

/// Plane coordinates <-> Clipper2's integers: a power-of-two scale (exact in binary) that maps the
/// largest coordinate to about 2^40, far inside Clipper2's range (2^61) and resolving ~1e-12 of
/// the extent.
struct Scaler {
  double scale = 1.0, inv = 1.0;
  explicit Scaler(const std::vector<std::vector<Vec2>>& loops) {
    double extent = 0.0;
    for (const auto& loop : loops)
      for (const Vec2& p : loop) extent = std::max({extent, std::abs(p.x()), std::abs(p.y())});
    if (extent > 0 && std::isfinite(extent)) {
      int e = 0;
      std::frexp(extent, &e);  // extent < 2^e
      scale = std::ldexp(1.0, 40 - e);
      inv = std::ldexp(1.0, e - 40);
    }
  }
  // std::llround (halves away from zero), without the library call for |x| < 2^52: x minus its
  // truncation is exact there.
  static std::int64_t round(double x) {
    if (!(std::abs(x) < 4503599627370496.0)) return static_cast<std::int64_t>(std::llround(x));
    const auto i = static_cast<std::int64_t>(x);
    const double f = x - static_cast<double>(i);
    return f >= 0.5 ? i + 1 : (f <= -0.5 ? i - 1 : i);
  }
  Clipper2Lib::Point64 to(const Vec2& p) const {
    return Clipper2Lib::Point64(round(p.x() * scale), round(p.y() * scale));
  }
  Vec2 from(const Clipper2Lib::Point64& q) const {
    return Vec2(static_cast<double>(q.x) * inv, static_cast<double>(q.y) * inv);
  }
  std::vector<Vec2> from(const Clipper2Lib::Path64& path) const {
    std::vector<Vec2> out;
    out.reserve(path.size());
    for (const Clipper2Lib::Point64& q : path) out.push_back(from(q));
    return out;
  }
};

/// An axis-aligned box in the plane (mm); empty (inverted) until a point is added.
struct Box2 {
  Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Vec2 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  void add(const Vec2& p) {
    lo.x() = std::min(lo.x(), p.x());
    lo.y() = std::min(lo.y(), p.y());
    hi.x() = std::max(hi.x(), p.x());
    hi.y() = std::max(hi.y(), p.y());
  }
  bool contains(const Vec2& p) const {
    return p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() && p.y() <= hi.y();
  }
  bool overlaps(const Box2& b) const {
    return !(b.lo.x() > hi.x() || b.hi.x() < lo.x() || b.lo.y() > hi.y() || b.hi.y() < lo.y());
  }
};

/// The box of a set of plane points (the same as Box2::add over them; SSE2 where available).
Box2 box_of(const std::vector<Vec2>& pts);

/// Every outer (material) node of the tree, islands inside holes included.
void collect_outers(const Clipper2Lib::PolyPath64& node,
                    std::vector<const Clipper2Lib::PolyPath64*>& out);

/// The region of an outer node (its boundary and its holes) in plane coordinates.
SectionPolygon polygon_of(const Clipper2Lib::PolyPath64& outer, const Scaler& s);

/// The outer node whose region holds q, searching islands inside holes; `hollow` is set when q
/// lies in a hole with no island around it (the region around the hole is returned).
const Clipper2Lib::PolyPath64* locate(const Clipper2Lib::PolyPath64& node,
                                      const Clipper2Lib::Point64& q, bool& hollow);

}  // namespace osteon
