// Live mode's reuse of the corner search (issue 34, notch_reuse.hpp).
#include "notch_reuse.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace osteon {

namespace {

// Sorts packed keys ascending: least significant digit first, 11 bits a pass, stable; about
// 2 n + 2048 steps a pass (the corner search sorts 10^4..10^5 faces per corner, where
// std::sort's n log n comparisons of triples cost ~10 % of a one-off analysis).
void radix_sort(std::vector<std::uint64_t>& keys, int bits) {
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  std::vector<std::uint64_t> other(keys.size());
  std::vector<std::size_t> count(kBuckets);
  for (int shift = 0; shift < bits; shift += kDigit) {
    std::fill(count.begin(), count.end(), 0);
    for (std::uint64_t k : keys) ++count[(k >> shift) & (kBuckets - 1)];
    if (count[(keys.front() >> shift) & (kBuckets - 1)] == keys.size()) continue;  // one digit
    std::size_t sum = 0;
    for (std::size_t& c : count) {
      const std::size_t n = c;
      c = sum;
      sum += n;
    }
    for (std::uint64_t k : keys) other[count[(k >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(other);
  }
}

}  // namespace

void canonical_face_order(std::vector<std::int32_t>& faces, std::vector<std::int32_t>& vertices,
                          std::vector<int>& slot) {
  const std::size_t n = faces.size() / 3;
  if (n == 0) return;
  std::int32_t largest = 0;
  for (std::int32_t v : faces) largest = std::max(largest, v);
  int bits = 1;
  while (bits < 31 && (std::int64_t{1} << bits) <= largest) ++bits;
  if (3 * bits <= 64) {  // the triple packed into one key: the same order as comparing triples
    std::vector<std::uint64_t> keys(n);
    for (std::size_t f = 0; f < n; ++f)
      keys[f] = (std::uint64_t(faces[3 * f]) << (2 * bits)) |
                (std::uint64_t(faces[3 * f + 1]) << bits) | std::uint64_t(faces[3 * f + 2]);
    radix_sort(keys, 3 * bits);
    const std::uint64_t mask = (std::uint64_t{1} << bits) - 1;
    for (std::size_t f = 0; f < n; ++f) {
      faces[3 * f] = static_cast<std::int32_t>(keys[f] >> (2 * bits));
      faces[3 * f + 1] = static_cast<std::int32_t>((keys[f] >> bits) & mask);
      faces[3 * f + 2] = static_cast<std::int32_t>(keys[f] & mask);
    }
  } else {
    using Face = std::array<std::int32_t, 3>;
    std::vector<Face> sorted(n);
    for (std::size_t f = 0; f < n; ++f)
      sorted[f] = {faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]};
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t f = 0; f < n; ++f)
      for (int j = 0; j < 3; ++j) faces[3 * f + j] = sorted[f][j];
  }
  for (std::int32_t v : vertices) slot[v] = -1;
  vertices.clear();
  for (std::int32_t v : faces) {
    if (slot[v] >= 0) continue;
    slot[v] = static_cast<int>(vertices.size());
    vertices.push_back(v);
  }
}

void CornerGroup::bound(Vec3& center, double& radius) const {
  double largest = 0.0;
  for (double r : reach) largest = std::max(largest, r);
  center = point + 0.5 * largest * u;
  radius = std::hypot(2.5 * r_thin, 0.75 * largest);
  // The search tests axial positions and distances in rounded arithmetic (~1e-16 of the
  // coordinates); a margin far above that keeps every vertex it could take inside the ball.
  radius += 1e-6 * (radius + center.cwiseAbs().maxCoeff());
}

bool CornerMemo::recall(CornerGroup& g, const MeshChange& change) const {
  if (!valid || !change.known) return false;
  for (const CornerGroup& old : groups) {
    if (!old.same_inputs(g) || old.corners.size() != g.reach.size()) continue;
    if (!(change.lo.x() > change.hi.x())) {  // something moved: does it reach the region?
      Vec3 center;
      double radius = 0.0;
      g.bound(center, radius);
      const Vec3 nearest = center.cwiseMax(change.lo).cwiseMin(change.hi);
      if ((nearest - center).squaredNorm() <= radius * radius) return false;
    }
    g.corners = old.corners;
    return true;
  }
  return false;
}

}  // namespace osteon
