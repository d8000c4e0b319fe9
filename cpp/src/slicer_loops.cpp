// Loop assembly: cut segments linked into closed loops by shared mesh edges, open ends joined
// across small gaps (see osteon/slicer.hpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "osteon/slicer.hpp"

namespace osteon {
namespace {

// Open-addressing table pairing the two segment endpoints ("occurrences") on each mesh edge.
struct EdgeTable {
  struct Slot {
    std::uint64_t key;
    std::int32_t first;
    std::uint32_t stamp;  // the slot is in use in this round only when stamp == round
  };
  std::vector<Slot> slots;
  std::uint64_t mask = 0;
  int bits = 0;
  std::uint32_t round = 0;

  // `keys` = distinct edges expected (at most); the table stays at most half full. Slots are
  // not cleared: a new round number empties them all at once (the table is reused per thread).
  void reset(std::size_t keys) {
    bits = 4;
    while ((std::size_t(1) << bits) < 2 * keys + 16) ++bits;
    const std::size_t size = std::size_t(1) << bits;
    mask = size - 1;
    if (slots.size() < size) slots.resize(size, Slot{0, -1, round});
    if (++round == 0) {  // wrapped: make every stamp stale again
      for (Slot& slot : slots) slot.stamp = 0;
      round = 1;
    }
  }
  // This round's table seen through local copies: partner[] stores cannot alias them, so
  // nothing is reloaded after each store (they could alias the members above).
  struct Round {
    Slot* slots;
    std::uint64_t mask;
    int shift;
    std::uint32_t round;
    std::int32_t* partner;
    // Pairs `occurrence` with the endpoint already on the edge (partner[] both ways; an endpoint
    // alone so far gets -1); returns false if the edge already had two endpoints (non-manifold).
    bool insert(std::uint64_t key, std::int32_t occurrence) const {
      std::uint64_t h = (key * 0x9E3779B97F4A7C15ull) >> shift;
      while (true) {
        Slot& slot = slots[h];
        if (slot.stamp != round) {
          slot = Slot{key, occurrence, round};
          partner[occurrence] = -1;
          return true;
        }
        if (slot.key == key) {
          if (slot.first < 0) {
            partner[occurrence] = -1;
            return false;
          }
          partner[slot.first] = occurrence;
          partner[occurrence] = slot.first;
          slot.first = -1;  // paired: a third endpoint is non-manifold
          return true;
        }
        h = (h + 1) & mask;
      }
    }
  };
  Round view(std::int32_t* partner) { return Round{slots.data(), mask, 64 - bits, round, partner}; }
};

// Unordered pair of the two edge keys of a segment: identical for a doubled triangle.
std::pair<std::uint64_t, std::uint64_t> segment_key(const CutSegment& s) {
  return s.edge[0] < s.edge[1] ? std::make_pair(s.edge[0], s.edge[1])
                               : std::make_pair(s.edge[1], s.edge[0]);
}

// A total order of segments that does not depend on the order they come in (the grid cells'
// order, which depends on the grid's layout): by their edges' unordered pair (so that duplicates
// are adjacent), then by orientation, then by the endpoints' bits (a doubled triangle's copies
// may round their points differently: the one kept must not be whichever came first).
bool segment_less(const CutSegment& x, const CutSegment& y) {
  const auto kx = segment_key(x), ky = segment_key(y);
  if (kx != ky) return kx < ky;
  if (x.edge[0] != y.edge[0]) return x.edge[0] < y.edge[0];
  std::uint64_t bx[4], by[4];
  std::memcpy(bx, x.point[0].data(), 2 * sizeof(double));
  std::memcpy(bx + 2, x.point[1].data(), 2 * sizeof(double));
  std::memcpy(by, y.point[0].data(), 2 * sizeof(double));
  std::memcpy(by + 2, y.point[1].data(), 2 * sizeof(double));
  return std::lexicographical_compare(bx, bx + 4, by, by + 4);
}

// A total order of points (x, then y; NaN last), for the canonical order below.
bool point_less(const Vec2& a, const Vec2& b) {
  auto key = [](double t) { return std::make_pair(std::isnan(t), std::isnan(t) ? 0.0 : t); };
  const auto ax = key(a.x()), bx = key(b.x());
  return ax < bx || (ax == bx && key(a.y()) < key(b.y()));
}

bool points_less(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.size() != b.size()) return a.size() < b.size();
  return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), point_less);
}

// Is the loop a (from its rotation ra) less than loop b (from rb), n points each?
bool rotation_less(const Vec2* a, std::size_t ra, const Vec2* b, std::size_t rb, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 &p = a[(ra + k) % n], &q = b[(rb + k) % n];
    if (point_less(p, q)) return true;
    if (point_less(q, p)) return false;
  }
  return false;
}

// Where a closed loop of n points starts when it starts at its least point (x, then y), so that
// it does not depend on which segment the walk started from; of several rotations starting
// there (a loop through one point twice, rare), the least. One pass of plain comparisons (a NaN
// is never least).
std::size_t least_rotation(const Vec2* loop, std::size_t n) {
  std::size_t best = 0;
  bool tie = false;
  double bx = loop[0].x(), by = loop[0].y();
  for (std::size_t k = 1; k < n; ++k) {
    const double x = loop[k].x(), y = loop[k].y();
    if (x < bx || (x == bx && y < by)) {
      best = k;
      bx = x;
      by = y;
      tie = false;
    } else if (x == bx && y == by) {
      tie = true;
    }
  }
  if (tie) {
    const std::size_t first = best;
    for (std::size_t k = 0; k < n; ++k)
      if (k != first && loop[k].x() == bx && loop[k].y() == by &&
          rotation_less(loop, k, loop, best, n))
        best = k;
  }
  return best;
}

// Scratch reused per thread (a run assembles thousands of cuts).
struct LoopScratch {
  EdgeTable table;
  std::vector<std::int32_t> partner;
  std::vector<std::uint8_t> used;
  std::vector<Vec2> forward, backward;  // the chain being walked (a loop is copied out exactly)
};

// This thread's scratch, reached through a call the compiler cannot see into: in a shared library
// GCC re-derives a thread_local's address (a __tls_get_addr call) at each use in a loop, which
// cost ~4 % of a whole analysis here.
[[gnu::noinline]] LoopScratch& loop_scratch() {
  thread_local LoopScratch scratch;
  return scratch;
}

// Pairs the two endpoints of `input`'s segments that lie on the same mesh edge (partner[] in the
// scratch, both ways; -1 for an endpoint alone on its edge); orientation-agnostic so that
// inconsistently wound meshes still give loops. An edge with more than two endpoints is first
// explained by exact duplicate segments (doubled triangles), which are dropped; whatever is still
// non-manifold after that is flagged in `flags`. When any edge had more than two endpoints, the
// segments are paired again in a canonical order (`segment_less`, into `deduplicated`, which the
// answer then points to): which endpoints of a crowded edge pair, and the walk after it, then
// depend on the mesh and the plane alone, not on the order the grid's cells gave the segments.
// Returns the segments the partners index.
const std::vector<CutSegment>* pair_segment_ends(const std::vector<CutSegment>& input,
                                                 LoopScratch& scratch,
                                                 std::vector<CutSegment>& deduplicated,
                                                 std::uint32_t& flags) {
  const std::vector<CutSegment>* source = &input;
  EdgeTable& table = scratch.table;
  std::vector<std::int32_t>& partner = scratch.partner;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::vector<CutSegment>& segs = *source;
    const std::size_t count = segs.size();
    table.reset(2 * count);     // 2*count endpoints: at most that many distinct edges
    partner.resize(2 * count);  // every endpoint's entry is written by its insert
    const EdgeTable::Round edges = table.view(partner.data());
    const CutSegment* seg = segs.data();
    bool crowded = false;
    for (std::size_t s = 0; s < count; ++s) {
      const std::int32_t o = static_cast<std::int32_t>(2 * s);
      crowded |= !edges.insert(seg[s].edge[0], o);
      crowded |= !edges.insert(seg[s].edge[1], o + 1);
    }
    if (crowded && attempt == 0) {
      deduplicated = input;
      std::sort(deduplicated.begin(), deduplicated.end(), segment_less);
      const auto last = std::unique(deduplicated.begin(), deduplicated.end(),
                                    [](const CutSegment& x, const CutSegment& y) {
                                      return segment_key(x) == segment_key(y);
                                    });
      deduplicated.erase(last, deduplicated.end());
      source = &deduplicated;
      continue;
    }
    if (crowded) flags |= kFlagNonManifold;
    break;
  }
  return source;
}

// The chain of `count` segments whose first is `start`, entered at endpoint `in`, walked the
// other way (partners both ways: pair_segment_ends): each segment entered at the endpoint the
// given walk leaves it by. out[0 .. count) are those points, last segment's first; for an open
// chain (`closed` false) out[count] is the start's entry point, the reversed chain's end. A
// closed loop's points come out in a rotation of its own (least_rotation decides the start).
void reversed_chain(const CutSegment* segments, const std::int32_t* pair, std::size_t start, int in,
                    std::size_t count, bool closed, Vec2* out) {
  if (!closed) out[count] = segments[start].point[in];
  std::size_t cur = start;
  for (std::size_t k = 0; k < count; ++k) {
    out[count - 1 - k] = segments[cur].point[1 - in];
    const std::int32_t next = pair[2 * cur + (1 - in)];
    if (next < 0) break;  // the open chain's last segment
    cur = static_cast<std::size_t>(next / 2);
    in = next % 2;
  }
}

// Copies the closed loop walked from s0 (forward[0 .. n), `reversed` of its segments walked
// against their own direction) into cut.loops from its least point, in the direction most of its
// segments run (each keeps its face's orientation; on a tie, the direction whose points come
// first in point_less's order). On an inconsistently wound surface the walk's direction is the
// first segment's, i.e. the grid cells' order; a consistent one (reversed = 0) is copied as is.
void emit_loop(const CutSegment* segments, LoopScratch& scratch, std::size_t s0, std::size_t n,
               std::size_t reversed, PlaneCut& cut) {
  const Vec2* points = scratch.forward.data();
  std::size_t best = n >= 3 ? least_rotation(points, n) : 0;
  if (2 * reversed >= n && n >= 3) {
    Vec2* other = scratch.backward.data();
    reversed_chain(segments, scratch.partner.data(), s0, 0, n, true, other);
    const std::size_t other_best = least_rotation(other, n);
    if (2 * reversed > n || rotation_less(other, other_best, points, best, n)) {
      points = other;
      best = other_best;
    }
  }
  std::vector<Vec2>& loop = cut.loops.emplace_back();
  loop.reserve(n);
  loop.insert(loop.end(), points + best, points + n);
  loop.insert(loop.end(), points, points + best);
}

// Walks the paired segments (pair_segment_ends) into chains: closed ones into cut.loops, open
// ones (from their true start) into cut.open_chains, each in the direction most of its segments
// run (emit_loop).
void walk_segment_chains(const CutSegment* segments, std::size_t m, LoopScratch& scratch,
                         PlaneCut& cut) {
  const std::int32_t* pair = scratch.partner.data();
  std::vector<std::uint8_t>& used_flags = scratch.used;
  used_flags.assign(m, 0);
  std::uint8_t* used = used_flags.data();
  // A chain holds each segment once, plus its last point: m + 1 points at most either way.
  if (scratch.forward.size() < m + 1) {
    scratch.forward.resize(m + 1);
    scratch.backward.resize(m + 1);
  }
  Vec2* forward = scratch.forward.data();
  Vec2* backward = scratch.backward.data();
  for (std::size_t s0 = 0; s0 < m; ++s0) {
    if (used[s0]) continue;
    std::size_t nf = 0, nb = 0;
    std::size_t reversed = 0;  // segments walked against their own direction (entered at 1)
    bool closed = false;
    // Walk forward: enter s at endpoint `in`, leave through the other endpoint.
    std::size_t cur = s0;
    int in = 0;
    while (true) {
      used[cur] = 1;
      reversed += static_cast<std::size_t>(in);
      forward[nf++] = segments[cur].point[in];
      const std::int32_t next = pair[2 * cur + (1 - in)];
      if (next < 0) {
        forward[nf++] = segments[cur].point[1 - in];
        break;
      }
      const std::size_t ns = static_cast<std::size_t>(next / 2);
      if (ns == s0) {
        closed = true;
        break;
      }
      if (used[ns]) {
        forward[nf++] = segments[cur].point[1 - in];
        break;
      }
      cur = ns;
      in = next % 2;
    }
    if (closed) {
      emit_loop(segments, scratch, s0, nf, reversed, cut);
      continue;
    }
    // Walk backward from s0's entry endpoint to find the chain's true start.
    std::size_t start = s0;
    int start_in = 0;
    std::int32_t prev = pair[2 * s0 + 0];
    while (prev >= 0) {
      const std::size_t ps = static_cast<std::size_t>(prev / 2);
      if (used[ps]) break;
      used[ps] = 1;
      const int out_end = prev % 2;  // we reach ps through this endpoint: it is ps's exit
      reversed += static_cast<std::size_t>(out_end == 0);
      backward[nb++] = segments[ps].point[1 - out_end];
      start = ps;
      start_in = 1 - out_end;
      prev = pair[2 * ps + (1 - out_end)];
    }
    std::vector<Vec2> chain;
    chain.reserve(nb + nf);
    chain.insert(chain.end(), std::reverse_iterator<Vec2*>(backward + nb),
                 std::reverse_iterator<Vec2*>(backward));
    chain.insert(chain.end(), forward, forward + nf);
    const std::size_t count = chain.size() - 1;  // segments
    if (2 * reversed >= count) {
      // Mostly walked against the segments' direction (or a tie): the chain the other way, each
      // segment entered at its other endpoint (backward is free again).
      reversed_chain(segments, pair, start, start_in, count, false, backward);
      if (2 * reversed > count ||
          std::lexicographical_compare(backward, backward + count + 1, chain.begin(), chain.end(),
                                       point_less))
        chain.assign(backward, backward + count + 1);
    }
    cut.open_chains.push_back(std::move(chain));
  }
}

// A pair of open-chain ends within the gap tolerance (end 2i: chain i's front, 2i+1 its back).
struct EndPair {
  double d2;  // squared distance, mm^2
  std::uint32_t a, b;
};

// The chains' end pairs closer than the tolerance (mm), closest first (ties by end index). Ends
// are bucketed on a grid of the tolerance's size, so this stays linear even for triangle soups
// where every triangle is its own chain.
std::vector<EndPair> close_end_pairs(const std::vector<std::vector<Vec2>>& chains,
                                     double gap_tolerance) {
  const std::size_t c = chains.size();
  auto end_point = [&](std::size_t end) -> const Vec2& {
    return end % 2 == 0 ? chains[end / 2].front() : chains[end / 2].back();
  };
  const double cell = gap_tolerance;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> buckets;
  auto cell_of = [&](const Vec2& p, int dx, int dy) {
    const std::int64_t x = static_cast<std::int64_t>(std::floor(p.x() / cell)) + dx;
    const std::int64_t y = static_cast<std::int64_t>(std::floor(p.y() / cell)) + dy;
    return (static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull) ^ static_cast<std::uint64_t>(y);
  };
  for (std::size_t end = 0; end < 2 * c; ++end)
    buckets[cell_of(end_point(end), 0, 0)].push_back(static_cast<std::uint32_t>(end));
  std::vector<EndPair> pairs;
  const double tol2 = gap_tolerance * gap_tolerance;
  for (std::size_t end = 0; end < 2 * c; ++end) {
    const Vec2& p = end_point(end);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) {
        auto it = buckets.find(cell_of(p, dx, dy));
        if (it == buckets.end()) continue;
        for (std::uint32_t other : it->second) {
          if (other <= end) continue;
          const double d2 = (end_point(other) - p).squaredNorm();
          if (d2 <= tol2) pairs.push_back({d2, static_cast<std::uint32_t>(end), other});
        }
      }
  }
  std::sort(pairs.begin(), pairs.end(), [](const EndPair& x, const EndPair& y) {
    return x.d2 < y.d2 || (x.d2 == y.d2 && (x.a < y.a || (x.a == y.a && x.b < y.b)));
  });
  return pairs;
}

// Joins ends greedily, closest pairs first (a chain's own two ends close it into a loop): the
// answer's [end] is the end it is joined to, or -1. Chains then form paths and cycles of chains;
// a cycle is a closed loop. Sets kFlagGapClosed in `flags` when any pair is joined.
std::vector<std::int64_t> link_chain_ends(const std::vector<EndPair>& pairs, std::size_t c,
                                          std::uint32_t& flags) {
  std::vector<std::int64_t> link(2 * c, -1);
  std::vector<std::size_t> group(c);
  for (std::size_t i = 0; i < c; ++i) group[i] = i;
  auto root = [&](std::size_t i) {
    while (group[i] != i) i = group[i] = group[group[i]];
    return i;
  };
  std::vector<std::uint8_t> closed_group(c, 0);
  for (const EndPair& pr : pairs) {
    if (link[pr.a] >= 0 || link[pr.b] >= 0) continue;
    const std::size_t ra = root(pr.a / 2), rb = root(pr.b / 2);
    if (ra == rb) {
      if (closed_group[ra]) continue;
      closed_group[ra] = 1;  // joining the two free ends of one path closes it
    } else {
      group[ra] = rb;
      closed_group[rb] = closed_group[ra] || closed_group[rb];
    }
    link[pr.a] = pr.b;
    link[pr.b] = pr.a;
    flags |= kFlagGapClosed;
  }
  return link;
}

// Joins the open chains whose ends are closer than the tolerance (mm): the linked groups that
// form cycles become loops of `cut`, the others its open chains.
void close_small_gaps(PlaneCut& cut, double gap_tolerance) {
  auto& chains = cut.open_chains;
  const std::size_t c = chains.size();
  const std::vector<std::int64_t> link =
      link_chain_ends(close_end_pairs(chains, gap_tolerance), c, cut.flags);
  // Walk each joined group from a free end (paths) or any end (cycles).
  std::vector<std::uint8_t> done(c, 0);
  std::vector<std::vector<Vec2>> remaining;
  auto walk = [&](std::size_t start_end, bool cycle) {
    std::vector<Vec2> pts;
    std::size_t end = start_end;
    std::size_t reversed = 0;  // points of the chains walked against their own direction
    while (true) {
      const std::size_t chain = end / 2;
      if (done[chain]) break;
      done[chain] = 1;
      // Enter the chain at `end`, traverse to its other end.
      if (end % 2 == 0) {
        pts.insert(pts.end(), chains[chain].begin(), chains[chain].end());
      } else {
        pts.insert(pts.end(), chains[chain].rbegin(), chains[chain].rend());
        reversed += chains[chain].size();
      }
      const std::size_t exit_end = end ^ 1u;
      if (link[exit_end] < 0) break;
      end = static_cast<std::size_t>(link[exit_end]);
    }
    if (cycle) {
      // A loop keeps the direction of most of its points' chains (the segments' direction says
      // material from hole), not of whichever chain the walk started from.
      if (2 * reversed > pts.size()) std::reverse(pts.begin(), pts.end());
      if (pts.size() >= 3) cut.loops.push_back(std::move(pts));
    } else {
      remaining.push_back(std::move(pts));
    }
  };
  for (std::size_t i = 0; i < c; ++i) {
    if (done[i]) continue;
    // Find a free end of this group by walking backwards from chain i's front.
    std::size_t end = 2 * i;
    bool cycle = false;
    for (std::size_t steps = 0; steps <= 2 * c; ++steps) {
      if (link[end] < 0) break;
      end = static_cast<std::size_t>(link[end]) ^ 1u;  // the other end of the linked chain
      if (end == 2 * i) {
        cycle = true;
        break;
      }
    }
    walk(end, cycle);
  }
  chains.swap(remaining);
}

// The loops and chains in an order of their own: each loop from its least point (the first
// `started` loops were copied out of the walk that way), the loops and the chains sorted. The
// segments' order (the grid cells' order, which depends on the grid's layout) then changes nothing
// downstream, not even the last bits of a sum over a loop.
void canonical_order(PlaneCut& cut, std::size_t started) {
  for (std::size_t i = started; i < cut.loops.size(); ++i) {
    std::vector<Vec2>& loop = cut.loops[i];
    const std::size_t best = least_rotation(loop.data(), loop.size());
    if (best != 0)
      std::rotate(loop.begin(), loop.begin() + static_cast<std::ptrdiff_t>(best), loop.end());
  }
  std::sort(cut.loops.begin(), cut.loops.end(), points_less);
  std::sort(cut.open_chains.begin(), cut.open_chains.end(), points_less);
}

}  // namespace

PlaneCut assemble_loops(const std::vector<CutSegment>& input, double gap_tolerance) {
  PlaneCut cut;
  if (input.empty()) return cut;
  LoopScratch& scratch = loop_scratch();
  std::vector<CutSegment> deduplicated;
  const std::vector<CutSegment>* source =
      pair_segment_ends(input, scratch, deduplicated, cut.flags);
  walk_segment_chains(source->data(), source->size(), scratch, cut);
  // The walk's loops of three points or more start at their least point already.
  const std::size_t started = static_cast<std::size_t>(
      std::count_if(cut.loops.begin(), cut.loops.end(),
                    [](const std::vector<Vec2>& l) { return l.size() >= 3; }));
  if (!cut.open_chains.empty() && gap_tolerance > 0) {
    // Chains sorted first: the gaps' ties are broken by the chains' order.
    std::sort(cut.open_chains.begin(), cut.open_chains.end(), points_less);
    close_small_gaps(cut, gap_tolerance);
  }
  // Drop degenerate loops (fewer than three points cannot bound area).
  cut.loops.erase(std::remove_if(cut.loops.begin(), cut.loops.end(),
                                 [](const std::vector<Vec2>& l) { return l.size() < 3; }),
                  cut.loops.end());
  canonical_order(cut, started);
  return cut;
}

}  // namespace osteon
