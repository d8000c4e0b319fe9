// Text parsers for the model readers (osteon.io): OBJ meshes and whitespace-separated numbers.
// The Python readers do every check that needs context (file names, counts); these functions
// only turn bytes into numbers fast (no allocation per line) and report where they stopped.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace osteon::readers {

/// An OBJ file's `v` and `f` lines, in file order.
struct ObjData {
  std::vector<double> vertices;       ///< x y z per `v` line (3 per vertex)
  std::vector<std::int64_t> corners;  ///< 0-based vertex index of every face corner
  std::vector<std::int32_t> counts;   ///< corners per `f` line
  std::string error;                  ///< empty, or "line N: what is wrong"
  bool unsupported = false;           ///< a layout left to another reader (line continuation)
};

/// Parse OBJ text: `v x y z [...]` and `f i[/t[/n]] ...` lines (negative indices resolved
/// against the vertices read so far); other lines are skipped. Stops at the first error.
ObjData parse_obj(std::string_view text);

/// Append every whitespace-separated number of `text` to `out`. Returns the byte offset of
/// the first token that is not a number, or std::string_view::npos when all were numbers.
std::size_t parse_numbers(std::string_view text, std::vector<double>& out);

}  // namespace osteon::readers
