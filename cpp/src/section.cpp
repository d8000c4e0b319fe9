#include "osteon/section.hpp"

#include <Eigen/LU>
#include <cmath>

namespace osteon {
namespace {

// Green's-theorem integrals of one closed loop: area, first and second moments (about the origin).
struct LoopIntegrals {
  double a = 0, sx = 0, sy = 0, ixx = 0, iyy = 0, ixy = 0;
};

LoopIntegrals integrate(const std::vector<Vec2>& loop, const Vec2& ref) {
  LoopIntegrals r;
  const std::size_t n = loop.size();
  if (n == 0) return r;
  // Each point's offset and squares are computed once and carried to the next edge (the same
  // values as computing them on both of its edges).
  Vec2 p = loop[0] - ref;
  double pxx = p.x() * p.x(), pyy = p.y() * p.y(), pxy2 = 2 * p.x() * p.y();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 q = loop[i + 1 == n ? 0 : i + 1] - ref;
    const double qxx = q.x() * q.x(), qyy = q.y() * q.y(), qxy2 = 2 * q.x() * q.y();
    const double cr = p.x() * q.y() - q.x() * p.y();
    r.a += cr;
    r.sx += (p.x() + q.x()) * cr;
    r.sy += (p.y() + q.y()) * cr;
    r.ixx += (pxx + p.x() * q.x() + qxx) * cr;
    r.iyy += (pyy + p.y() * q.y() + qyy) * cr;
    r.ixy += (p.x() * q.y() + pxy2 + qxy2 + q.x() * p.y()) * cr;
    p = q;
    pxx = qxx;
    pyy = qyy;
    pxy2 = qxy2;
  }
  r.a /= 2;
  r.sx /= 6;
  r.sy /= 6;
  r.ixx /= 12;
  r.iyy /= 12;
  r.ixy /= 24;
  return r;
}

void accumulate(LoopIntegrals& total, const LoopIntegrals& l, double sign) {
  total.a += sign * l.a;
  total.sx += sign * l.sx;
  total.sy += sign * l.sy;
  total.ixx += sign * l.ixx;
  total.iyy += sign * l.iyy;
  total.ixy += sign * l.ixy;
}

}  // namespace

double signed_area(const std::vector<Vec2>& loop) {
  double a = 0.0;
  const std::size_t n = loop.size();
  if (n == 0) return a;
  // Edges (i, i + 1), then the closing edge (n - 1, 0), in the order of a modulo per edge.
  auto edge = [&](const Vec2& p, const Vec2& q) { a += p.x() * q.y() - q.x() * p.y(); };
  for (std::size_t i = 0; i + 1 < n; ++i) edge(loop[i], loop[i + 1]);
  edge(loop[n - 1], loop[0]);
  return a / 2;
}

bool point_in_loop(const std::vector<Vec2>& loop, const Vec2& q) {
  bool inside = false;
  const std::size_t n = loop.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec2& a = loop[i];
    const Vec2& b = loop[j];
    if ((a.y() > q.y()) != (b.y() > q.y())) {
      const double x = a.x() + (q.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (q.x() < x) inside = !inside;
    }
  }
  return inside;
}

SectionProperties section_properties(const SectionPolygon& polygon) {
  SectionProperties props;
  if (polygon.outer.size() < 3) return props;
  // Integrate about a point of the section itself so that far-away coordinates lose no digits.
  const Vec2 ref = polygon.outer[0];
  LoopIntegrals total;
  const LoopIntegrals outer = integrate(polygon.outer, ref);
  accumulate(total, outer, outer.a >= 0 ? 1.0 : -1.0);
  for (const auto& hole : polygon.holes) {
    if (hole.size() < 3) continue;
    const LoopIntegrals h = integrate(hole, ref);
    accumulate(total, h, h.a >= 0 ? -1.0 : 1.0);
  }
  if (!(total.a > 0)) return props;
  const Vec2 c(total.sx / total.a, total.sy / total.a);
  Mat2 J;
  J(0, 0) = total.ixx - total.a * c.x() * c.x();
  J(1, 1) = total.iyy - total.a * c.y() * c.y();
  J(0, 1) = J(1, 0) = total.ixy - total.a * c.x() * c.y();
  props.area = total.a;
  props.centroid = c + ref;
  props.second_moment = J;
  const double det = J.determinant();
  const double scale = J(0, 0) * J(1, 1);
  if (!(det > 1e-14 * scale) || !(J(0, 0) > 0) || !(J(1, 1) > 0)) return props;
  const Mat2 Jinv = J.inverse();
  // Peak stress of a unit moment in the worst direction: max over boundary points of |J^-1 p|;
  // the maximum of this convex function over the polygon is at a vertex.
  double peak = 0.0;
  auto scan = [&](const std::vector<Vec2>& loop) {
    for (const Vec2& p : loop) peak = std::max(peak, (Jinv * (p - ref - c)).squaredNorm());
  };
  scan(polygon.outer);
  for (const auto& hole : polygon.holes) scan(hole);
  if (!(peak > 0)) return props;
  props.modulus = 1.0 / std::sqrt(peak);
  props.valid = std::isfinite(props.modulus);
  return props;
}

}  // namespace osteon
