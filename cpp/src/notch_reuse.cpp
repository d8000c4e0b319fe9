// Live mode's reuse of the corner search (issue 34, notch_reuse.hpp).
#include "notch_reuse.hpp"

#include <algorithm>
#include <array>

namespace osteon {

void canonical_face_order(std::vector<std::int32_t>& faces, std::vector<std::int32_t>& vertices,
                          std::vector<int>& slot) {
  using Face = std::array<std::int32_t, 3>;
  const std::size_t n = faces.size() / 3;
  std::vector<Face> sorted(n);
  for (std::size_t f = 0; f < n; ++f)
    sorted[f] = {faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]};
  std::sort(sorted.begin(), sorted.end());
  for (std::int32_t v : vertices) slot[v] = -1;
  vertices.clear();
  for (std::size_t f = 0; f < n; ++f)
    for (int j = 0; j < 3; ++j) {
      const std::int32_t v = sorted[f][j];
      faces[3 * f + j] = v;
      if (slot[v] >= 0) continue;
      slot[v] = static_cast<int>(vertices.size());
      vertices.push_back(v);
    }
}

}  // namespace osteon
