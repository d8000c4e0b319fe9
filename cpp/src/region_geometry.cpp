#include "region_geometry.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace osteon {

using Clipper2Lib::Point64;
using Clipper2Lib::PointInPolygonResult;
using Clipper2Lib::PolyPath64;

Box2 box_of(const std::vector<Vec2>& pts) {
  Box2 b;
#if defined(__SSE2__)
  // Both coordinates at once: minpd(q, lo) is q < lo ? q : lo per lane, i.e. std::min(lo, q)
  // (NaN and equal zeros included), maxpd(q, hi) likewise std::max(hi, q): the same box as add().
  __m128d lo = _mm_loadu_pd(b.lo.data()), hi = _mm_loadu_pd(b.hi.data());
  for (const Vec2& p : pts) {
    const __m128d q = _mm_loadu_pd(p.data());
    lo = _mm_min_pd(q, lo);
    hi = _mm_max_pd(q, hi);
  }
  _mm_storeu_pd(b.lo.data(), lo);
  _mm_storeu_pd(b.hi.data(), hi);
#else
  for (const Vec2& p : pts) b.add(p);
#endif
  return b;
}

void collect_outers(const PolyPath64& node, std::vector<const PolyPath64*>& out) {
  for (const auto& outer : node) {
    out.push_back(outer.get());
    for (const auto& hole : *outer) collect_outers(*hole, out);
  }
}

SectionPolygon polygon_of(const PolyPath64& outer, const Scaler& s) {
  SectionPolygon poly;
  poly.outer = s.from(outer.Polygon());
  for (const auto& hole : outer) poly.holes.push_back(s.from(hole->Polygon()));
  return poly;
}

const PolyPath64* locate(const PolyPath64& node, const Point64& q, bool& hollow) {
  for (const auto& outer : node) {
    if (Clipper2Lib::PointInPolygon(q, outer->Polygon()) == PointInPolygonResult::IsOutside)
      continue;
    for (const auto& hole : *outer) {
      if (Clipper2Lib::PointInPolygon(q, hole->Polygon()) != PointInPolygonResult::IsInside)
        continue;
      if (const PolyPath64* island = locate(*hole, q, hollow)) return island;
      hollow = true;
      return outer.get();
    }
    hollow = false;
    return outer.get();
  }
  return nullptr;
}

}  // namespace osteon
