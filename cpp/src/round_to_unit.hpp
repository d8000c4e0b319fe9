// Rounding to Clipper2's integer units, inline (internal to the engine).
#pragma once

#include <cstdint>

namespace osteon::detail {

/// std::llround / std::round for |x| < 2^52, inline (the library calls were 1-2 % of the printed
/// section's stage): the same integer, half-way cases away from zero; x - trunc(x) is exact in
/// double.
inline std::int64_t round_to_unit(double x) {
  const auto whole = static_cast<std::int64_t>(x);
  const double frac = x - static_cast<double>(whole);
  return whole + (frac >= 0.5 ? 1 : 0) - (frac <= -0.5 ? 1 : 0);
}

}  // namespace osteon::detail
