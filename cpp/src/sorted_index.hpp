// std::upper_bound on evenly spaced sorted values (section params along a bone), found faster.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace osteon::detail {

/// std::upper_bound(p.begin(), p.end(), t) - p.begin() for sorted p (mm): a guess from p's ends
/// (section params are about evenly spaced), then a walk to the first p[j] > t (the same index:
/// it is unique in a sorted vector). NaN t falls back to std::upper_bound.
inline std::size_t upper_index(const std::vector<double>& p, double t) {
  const std::size_t n = p.size();
  if (n == 0 || t < p[0]) return 0;
  if (!(t >= p[0])) return std::upper_bound(p.begin(), p.end(), t) - p.begin();  // NaN
  if (t >= p[n - 1]) return n;
  // p[0] <= t < p[n - 1]: the answer lies in [1, n - 1].
  const double guess = (t - p[0]) / (p[n - 1] - p[0]) * static_cast<double>(n - 1);
  std::size_t j = std::clamp<std::size_t>(static_cast<std::size_t>(guess), 1, n - 1);
  while (p[j - 1] > t) --j;
  while (p[j] <= t) ++j;
  return j;
}

}  // namespace osteon::detail
