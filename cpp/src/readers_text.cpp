// OBJ and plain-number parsing for the Python readers (osteon.io.fastmesh, libigl DMAT):
// std::from_chars over the file's bytes, one pass, no allocation per line.
#include <charconv>
#include <string>

#include "osteon/readers.hpp"

namespace osteon::readers {
namespace {

inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
inline bool is_space(char c) { return is_blank(c) || c == '\n'; }

// One number at p (a leading '+' allowed, as strtod takes it); advances p past it.
template <class T>
bool read_number(const char*& p, const char* end, T& value, bool& too_big) {
  const char* s = p;
  if (s < end && *s == '+') ++s;
  auto [q, ec] = std::from_chars(s, end, value);
  too_big = ec == std::errc::result_out_of_range;
  if (ec != std::errc() || q == s) return false;
  p = q;
  return true;
}

struct LineCursor {
  const char* p;
  const char* end;
  void skip_blanks() {
    while (p < end && is_blank(*p)) ++p;
  }
  bool at_line_end() const { return p >= end || *p == '\n'; }
  void skip_token() {
    while (p < end && !is_space(*p)) ++p;
  }
};

std::string at_line(long line, const std::string& what) {
  return "line " + std::to_string(line) + ": " + what;
}

// The corners of one `f` line; false (with ObjData::error set) on a bad corner.
bool read_face(LineCursor& c, long line, ObjData& out) {
  const auto nv = static_cast<std::int64_t>(out.vertices.size() / 3);
  std::int32_t n = 0;
  for (c.skip_blanks(); !c.at_line_end(); c.skip_blanks()) {
    std::int64_t idx = 0;
    bool too_big = false;
    if (!read_number(c.p, c.end, idx, too_big)) {
      out.error = at_line(line, too_big ? "a face index is too big for an integer"
                                        : "an 'f' corner does not start with a vertex index");
      return false;
    }
    if (idx == 0) {
      out.error = at_line(line, "face index 0 (OBJ indices start at 1)");
      return false;
    }
    out.corners.push_back(idx > 0 ? idx - 1 : nv + idx);
    if (idx < 0 && nv + idx < 0) {
      out.error = at_line(line, "a negative face index reaches before the first vertex");
      return false;
    }
    c.skip_token();  // "/t/n"
    ++n;
  }
  if (n < 3) {
    out.error = at_line(line, "an 'f' line has fewer than 3 corners");
    return false;
  }
  out.counts.push_back(n);
  return true;
}

bool read_vertex(LineCursor& c, long line, ObjData& out) {
  for (int k = 0; k < 3; ++k) {
    c.skip_blanks();
    double x = 0.0;
    bool too_big = false;
    if (!read_number(c.p, c.end, x, too_big)) {
      out.error = at_line(line, too_big ? "a vertex coordinate is out of range"
                                        : "a 'v' line has fewer than 3 numbers");
      return false;
    }
    out.vertices.push_back(x);
  }
  return true;
}

}  // namespace

ObjData parse_obj(std::string_view text) {
  ObjData out;
  LineCursor c{text.data(), text.data() + text.size()};
  long line = 0;
  while (c.p < c.end) {
    ++line;
    const char* eol = c.p;
    while (eol < c.end && *eol != '\n') ++eol;
    const char* last = eol;
    while (last > c.p && is_blank(last[-1])) --last;
    if (last > c.p && last[-1] == '\\') {
      out.unsupported = true;  // a line continued on the next: rare, left to trimesh
      return out;
    }
    c.skip_blanks();
    const bool two = c.p + 1 < c.end && is_blank(c.p[1]);
    bool ok = true;
    if (two && c.p[0] == 'v') {
      ++c.p;
      ok = read_vertex(c, line, out);
    } else if (two && c.p[0] == 'f') {
      ++c.p;
      LineCursor lc{c.p, eol};
      ok = read_face(lc, line, out);
    }
    if (!ok) return out;
    c.p = eol < c.end ? eol + 1 : c.end;
  }
  return out;
}

std::size_t parse_numbers(std::string_view text, std::vector<double>& out) {
  const char* p = text.data();
  const char* end = p + text.size();
  while (true) {
    while (p < end && is_space(*p)) ++p;
    if (p >= end) return std::string_view::npos;
    double x = 0.0;
    bool too_big = false;
    const char* start = p;
    if (!read_number(p, end, x, too_big) || (p < end && !is_space(*p)))
      return static_cast<std::size_t>(start - text.data());
    out.push_back(x);
  }
}

}  // namespace osteon::readers
