#include "osteon/skeleton.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace osteon {

std::string Skeleton::name(int b) const {
  if (b >= 0 && b < static_cast<int>(names.size()) && !names[b].empty()) return names[b];
  return "bone_" + std::to_string(b);
}

void validate_skeleton(const Skeleton& s) {
  const int nb = s.num_bones();
  if (nb == 0) throw std::invalid_argument("skeleton has no bones");
  if (static_cast<int>(s.tails.size()) != nb || static_cast<int>(s.parents.size()) != nb)
    throw std::invalid_argument("skeleton heads, tails and parents must have the same length");
  if (!s.names.empty() && static_cast<int>(s.names.size()) != nb)
    throw std::invalid_argument("skeleton names must have one entry per bone");
  for (int b = 0; b < nb; ++b) {
    if (!s.heads[b].allFinite() || !s.tails[b].allFinite())
      throw std::invalid_argument("bone '" + s.name(b) + "' has a NaN or infinite position");
    if (!std::isfinite(s.length(b)))  // |tail - head| overflows: squared distances would be inf
      throw std::invalid_argument("bone '" + s.name(b) +
                                  "' is too long (coordinates out of range)");
    const double scale =
        std::max({s.heads[b].cwiseAbs().maxCoeff(), s.tails[b].cwiseAbs().maxCoeff(), 1e-300});
    if (s.length(b) <= 1e-12 * scale || s.length(b) == 0.0)
      throw std::invalid_argument("bone '" + s.name(b) + "' has zero length (head == tail)");
    const int p = s.parents[b];
    if (p < -1 || p >= nb)
      throw std::invalid_argument("bone '" + s.name(b) + "' has parent index " + std::to_string(p) +
                                  " out of range [-1, " + std::to_string(nb - 1) + "]");
    if (p == b) throw std::invalid_argument("bone '" + s.name(b) + "' is its own parent");
  }
  // Cycle check: walk up from every bone; a walk longer than B steps loops.
  std::vector<std::int8_t> state(nb, 0);  // 0 unknown, 1 reaches a root
  for (int b = 0; b < nb; ++b) {
    std::vector<int> path;
    int cur = b;
    while (cur != -1 && state[cur] == 0) {
      path.push_back(cur);
      if (static_cast<int>(path.size()) > nb)
        throw std::invalid_argument("parent cycle in skeleton through bone '" + s.name(b) + "'");
      cur = s.parents[cur];
    }
    for (int x : path) state[x] = 1;
  }
}

std::vector<int> root_bones(const Skeleton& s) {
  std::vector<int> roots;
  for (int b = 0; b < s.num_bones(); ++b)
    if (s.parents[b] < 0) roots.push_back(b);
  return roots;
}

double project_onto_bone(const Skeleton& s, int b, const Vec3& p) {
  const Vec3 d = s.tails[b] - s.heads[b];
  const double len = d.norm();
  const double t = (p - s.heads[b]).dot(d) / len;
  return std::clamp(t, 0.0, len);
}

double squared_distance_to_bone(const Skeleton& s, int b, const Vec3& p) {
  const double t = project_onto_bone(s, b, p);
  return (p - (s.heads[b] + t * s.direction(b))).squaredNorm();
}

}  // namespace osteon
