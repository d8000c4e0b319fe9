// Small closed meshes for the engine's unit tests.
#pragma once

#include <cmath>
#include <vector>

#include "osteon/mesh.hpp"

namespace osteon::testing {

/// A closed triangle mesh owning its arrays.
struct OwnedMesh {
  std::vector<double> v;
  std::vector<std::int32_t> f;
  MeshView view() const {
    return MeshView{v.data(), static_cast<Index>(v.size() / 3), f.data(),
                    static_cast<Index>(f.size() / 3)};
  }
};

/// Closed prism along +x (x in [0, length]) over a convex CCW polygon in the y-z plane.
inline OwnedMesh prism(const std::vector<Vec2>& poly, double length, int stations = 11) {
  OwnedMesh m;
  const int n = static_cast<int>(poly.size());
  for (int s = 0; s < stations; ++s)
    for (const Vec2& p : poly) {
      m.v.push_back(length * s / (stations - 1));
      m.v.push_back(p.x());
      m.v.push_back(p.y());
    }
  for (int s = 0; s + 1 < stations; ++s)
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      const int a = s * n + i, b = s * n + j, c = (s + 1) * n + j, d = (s + 1) * n + i;
      m.f.insert(m.f.end(), {a, c, b, a, d, c});
    }
  const int last = (stations - 1) * n;
  for (int i = 1; i + 1 < n; ++i) {
    m.f.insert(m.f.end(), {0, i, i + 1});
    m.f.insert(m.f.end(), {last, last + i + 1, last + i});
  }
  return m;
}

inline std::vector<Vec2> regular_polygon(double radius, int n) {
  std::vector<Vec2> p;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    p.emplace_back(radius * std::cos(t), radius * std::sin(t));
  }
  return p;
}

inline std::vector<Vec2> rectangle(double b, double h) {
  return {{-b / 2, -h / 2}, {b / 2, -h / 2}, {b / 2, h / 2}, {-b / 2, h / 2}};
}

}  // namespace osteon::testing
