// Clipper2's SimplifyPath for closed paths, made cheaper (internal to the engine).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "clipper2/clipper.h"

namespace osteon::detail {

/// Clipper2Lib::SimplifyPath(path, epsilon, true) -- the same vertices removed in the same order,
/// so the same result, point for point (cpp/tests/test_regions.cpp compares the two). Clipper2
/// finds a vertex's remaining neighbours by scanning past the removed ones, which is most of its
/// cost on a finely faceted outline (most vertices go); here the remaining vertices form a
/// linked ring. Units are the path's (Clipper2 integers or mm).
template <typename T>
Clipper2Lib::Path<T> simplify_closed(const Clipper2Lib::Path<T>& path, double epsilon) {
  const std::size_t len = path.size();
  if (len < 4) return path;
  const std::size_t high = len - 1;
  const double eps2 = epsilon * epsilon;
  // Written in full before they are read: no zeroing (new T[] leaves them uninitialised).
  const std::unique_ptr<std::uint32_t[]> next_of(new std::uint32_t[len]),
      prior_of(new std::uint32_t[len]);
  const std::unique_ptr<double[]> dist2(new double[len]);
  std::vector<char> gone(len, 0);
  for (std::size_t i = 0; i < len; ++i) {
    next_of[i] = static_cast<std::uint32_t>(i == high ? 0 : i + 1);
    prior_of[i] = static_cast<std::uint32_t>(i == 0 ? high : i - 1);
  }
  dist2[0] = Clipper2Lib::PerpendicDistFromLineSqrd(path[0], path[high], path[1]);
  dist2[high] = Clipper2Lib::PerpendicDistFromLineSqrd(path[high], path[0], path[high - 1]);
  for (std::size_t i = 1; i < high; ++i)
    dist2[i] = Clipper2Lib::PerpendicDistFromLineSqrd(path[i], path[i - 1], path[i + 1]);
  std::size_t curr = 0;
  for (;;) {
    if (dist2[curr] > eps2) {
      const std::size_t start = curr;
      do {
        curr = next_of[curr];
      } while (curr != start && dist2[curr] > eps2);
      if (curr == start) break;
    }
    std::size_t prior = prior_of[curr], next = next_of[curr], prior2;
    if (next == prior) break;
    // remove the smaller of the two adjacent distances
    if (dist2[next] < dist2[curr]) {
      prior2 = prior;
      prior = curr;
      curr = next;
      next = next_of[next];
    } else {
      prior2 = prior_of[prior];
    }
    gone[curr] = 1;
    next_of[prior_of[curr]] = next_of[curr];
    prior_of[next_of[curr]] = prior_of[curr];
    curr = next;
    next = next_of[next];
    dist2[curr] = Clipper2Lib::PerpendicDistFromLineSqrd(path[curr], path[prior], path[next]);
    dist2[prior] = Clipper2Lib::PerpendicDistFromLineSqrd(path[prior], path[prior2], path[curr]);
  }
  Clipper2Lib::Path<T> out;
  out.reserve(len);
  for (std::size_t i = 0; i < len; ++i)
    if (!gone[i]) out.push_back(path[i]);
  return out;
}

/// simplify_closed on every path.
template <typename T>
Clipper2Lib::Paths<T> simplify_closed(const Clipper2Lib::Paths<T>& paths, double epsilon) {
  Clipper2Lib::Paths<T> out;
  out.reserve(paths.size());
  for (const auto& path : paths) out.push_back(simplify_closed(path, epsilon));
  return out;
}

}  // namespace osteon::detail
