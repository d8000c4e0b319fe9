#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <utility>

#include "osteon/section.hpp"
#include "osteon/slicer.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::prism;
using osteon::testing::rectangle;
using osteon::testing::regular_polygon;

TEST(Slicer, PrismCutGivesTheProfile) {
  const auto m = prism(rectangle(8, 4), 50);
  const PlaneFrame plane = PlaneFrame::make(Vec3(23.3, 0, 0), Vec3::UnitX());
  const SectionGeometry g = slice_section(m.view(), plane, 0.0);
  ASSERT_TRUE(g.found);
  EXPECT_EQ(g.flags, 0u);
  EXPECT_EQ(g.containing, 1);
  const SectionProperties p = section_properties(g.polygon);
  EXPECT_NEAR(p.area, 32.0, 1e-9);
  EXPECT_NEAR(p.modulus, 64.0 * 16.0 / (6 * std::sqrt(80.0)), 1e-9);
}

TEST(Slicer, ParallelPlanesMatchSinglePlanes) {
  const auto m = prism(regular_polygon(5, 40), 60);
  const PlaneFrame base = PlaneFrame::make(Vec3::Zero(), Vec3(1, 0, 0));
  std::vector<std::vector<CutSegment>> family;
  FaceGrid grid;
  grid.build(m.view());
  cut_mesh_parallel(m.view(), base, 2.5, 23, family, &grid);
  ASSERT_EQ(family.size(), 23u);
  for (int k = 1; k <= 23; ++k) {
    PlaneFrame plane = base;
    plane.origin = Vec3(2.5 * k, 0, 0);
    std::vector<CutSegment> single;
    cut_mesh(m.view(), plane, single, nullptr);
    EXPECT_EQ(family[k - 1].size(), single.size()) << k;
    const double a1 =
        section_properties(select_section(assemble_loops(family[k - 1], 0)).polygon).area;
    const double a2 = section_properties(select_section(assemble_loops(single, 0)).polygon).area;
    EXPECT_NEAR(a1, a2, 1e-9);
  }
}

namespace {
// The cut as a sorted list of (edge, edge) pairs, to compare cuts as sets of triangles.
std::vector<std::pair<std::uint64_t, std::uint64_t>> cut_keys(const std::vector<CutSegment>& segs) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> keys;
  for (const CutSegment& s : segs)
    keys.emplace_back(std::min(s.edge[0], s.edge[1]), std::max(s.edge[0], s.edge[1]));
  std::sort(keys.begin(), keys.end());
  return keys;
}
}  // namespace

TEST(Slicer, GrownCutsAddExactlyTheTrianglesLeftOut) {
  // A wide prism (many grid cells in each plane) and nested regions off its axis, reaching its
  // wall (radius 40): a local cut, then the ring up to a wider region, then the rest of the
  // plane, is the whole cut exactly.
  const auto m = prism(regular_polygon(40, 240), 60, 61);
  FaceGrid grid;
  grid.build(m.view());
  const CutRegion small{Vec3(0, 36, 0), Vec3::UnitX(), 6.0};
  const CutRegion wide{Vec3(0, 36, 0), Vec3::UnitX(), 18.0};
  PlaneFrame plane = PlaneFrame::make(Vec3(30.3, 0, 0), Vec3::UnitX());
  std::vector<CutSegment> whole, grown;
  cut_mesh(m.view(), plane, whole, &grid);
  cut_mesh(m.view(), plane, grown, &grid, &small);
  const std::size_t local = grown.size();
  cut_mesh(m.view(), plane, grown, &grid, &wide, &small);
  const std::size_t ring = grown.size() - local;
  cut_mesh(m.view(), plane, grown, &grid, nullptr, &wide);
  EXPECT_GT(local, 0u);
  EXPECT_GT(ring, 0u);
  EXPECT_LT(local + ring, whole.size());
  EXPECT_EQ(cut_keys(grown), cut_keys(whole));

  // The same for a family of parallel planes, re-cutting only every third plane.
  const PlaneFrame base = PlaneFrame::make(Vec3::Zero(), Vec3::UnitX());
  std::vector<std::vector<CutSegment>> all, part, step;
  cut_mesh_parallel(m.view(), base, 2.5, 23, all, &grid);
  std::vector<std::uint8_t> wanted(23, 0);
  for (int k = 0; k < 23; k += 3) wanted[k] = 1;
  cut_mesh_parallel(m.view(), base, 2.5, 23, part, &grid, &small);
  cut_mesh_parallel(m.view(), base, 2.5, 23, step, &grid, &wide, wanted.data(), &small);
  for (int k = 0; k < 23; ++k) {
    if (!wanted[k]) {
      EXPECT_TRUE(step[k].empty()) << k;
      continue;
    }
    part[k].insert(part[k].end(), step[k].begin(), step[k].end());
  }
  cut_mesh_parallel(m.view(), base, 2.5, 23, step, &grid, nullptr, wanted.data(), &wide);
  for (int k = 0; k < 23; k += 3) {
    part[k].insert(part[k].end(), step[k].begin(), step[k].end());
    EXPECT_EQ(cut_keys(part[k]), cut_keys(all[k])) << k;
  }
}

TEST(Slicer, ARegionKeepsTheTrianglesWhoseSegmentMeetsItWhateverTheGrid) {
  // Balls and cylinders across a wide prism's wall, cut through grids of three layouts (cell
  // sizes, a box widened as a live rebuild widens it) and without a grid: the same triangles,
  // those whose segment comes within the radius (checked directly), so a loop is clipped where
  // it leaves the region, not where a cell ends.
  const auto m = prism(regular_polygon(40, 240), 60, 61);
  FaceGrid fine, coarse, wide_box;
  fine.build(m.view(), 4);
  coarse.build(m.view(), 40);
  wide_box.build(m.view(), 12, 0, 0.05);
  auto meets = [](const CutRegion& r, const Vec2& a, const Vec2& b, const PlaneFrame& plane) {
    // Densely sampled distance from the segment to the axis (or point), mm.
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 1000; ++k) {
      Vec3 p = plane.to_world(a + (b - a) * (k / 1000.0)) - r.point;
      p -= p.dot(r.axis) * r.axis;
      best = std::min(best, p.norm());
    }
    return best;
  };
  int clipped = 0;
  for (int k = 0; k < 12; ++k) {
    const double x = 5.0 + 4.3 * k;
    const PlaneFrame plane = PlaneFrame::make(Vec3(x, 0, 0), Vec3(1, 0.1 * (k % 3), 0));
    const Vec3 axis = k % 2 == 0 ? Vec3(Vec3::Zero()) : Vec3(Vec3::UnitX());
    const CutRegion region{Vec3(x, 30 + k, 3.0 * (k % 4)), axis, 12.0 + 0.7 * k};
    std::vector<CutSegment> whole, none, a, b, c;
    cut_mesh(m.view(), plane, whole, nullptr);
    cut_mesh(m.view(), plane, none, nullptr, &region);
    cut_mesh(m.view(), plane, a, &fine, &region, nullptr, true);
    cut_mesh(m.view(), plane, b, &coarse, &region, nullptr, true);
    cut_mesh(m.view(), plane, c, &wide_box, &region, nullptr, true);
    EXPECT_EQ(cut_keys(a), cut_keys(none)) << k;
    EXPECT_EQ(cut_keys(b), cut_keys(none)) << k;
    EXPECT_EQ(cut_keys(c), cut_keys(none)) << k;
    EXPECT_GT(none.size(), 0u) << k;
    for (const CutSegment& s : whole) {
      const double d = meets(region, s.point[0], s.point[1], plane);
      if (std::abs(d - region.radius) < 1e-6) continue;  // the sampling's own error
      const bool kept = std::find_if(none.begin(), none.end(), [&](const CutSegment& t) {
                          return cut_keys({t}) == cut_keys({s});
                        }) != none.end();
      EXPECT_EQ(kept, d < region.radius) << k;
    }
    clipped += assemble_loops(a, 0.0).open_chains.size() > 0;
  }
  EXPECT_GT(clipped, 6);  // the regions clip the wall's loop
}

namespace {
// The turn of turned_prism(): oblique to the grid axes.
Eigen::Matrix3d prism_turn() {
  return (Eigen::AngleAxisd(0.4, Vec3::UnitZ()) *
          Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()))
      .toRotationMatrix();
}
// A wide prism turned by prism_turn() and moved off the origin (heights need rounding).
osteon::testing::OwnedMesh turned_prism() {
  auto m = prism(regular_polygon(40, 240), 60, 61);
  const Eigen::Matrix3d turn = prism_turn();
  for (std::size_t i = 0; i < m.v.size(); i += 3) {
    const Vec3 p = turn * Vec3(m.v[i], m.v[i + 1], m.v[i + 2]) + Vec3(100.25, -3.5, 7.0);
    for (int k = 0; k < 3; ++k) m.v[i + k] = p[k];
  }
  return m;
}
}  // namespace

TEST(Slicer, TightBoundsCutTheSameSegmentsInTheSameOrder) {
  // A wide prism, turned so that its faces and the planes are oblique to the grid, cut by planes
  // of random directions, by planes through rings of its vertices (heights exactly 0: such a
  // vertex counts as above, and a box that rounds it out would lose a segment) and inside
  // balls, with and without tight bounds: the same segments, bit for bit, in the same order, on
  // the cut that computes a cell's boxes and on the later ones that read them.
  const auto m = turned_prism();
  const Eigen::Matrix3d turn = prism_turn();
  FaceGrid loose, tight;
  loose.build(m.view());
  tight.build(m.view());
  tight.enable_tight_bounds();
  ASSERT_TRUE(tight.tight_bounds());
  ASSERT_FALSE(loose.tight_bounds());
  std::vector<PlaneFrame> planes;
  std::vector<CutRegion> balls;
  std::uint64_t state = 12345;
  auto uniform = [&]() {  // deterministic, in [-1, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 4503599627370496.0 - 1.0;
  };
  const Vec3 axis = turn * Vec3::UnitX();
  for (int k = 0; k < 40; ++k) {
    const Vec3 origin =
        turn * Vec3(30 + 30 * uniform(), 20 * uniform(), 20 * uniform()) + Vec3(100.25, -3.5, 7.0);
    const Vec3 normal = k % 2 == 0 ? Vec3(uniform(), uniform(), uniform()) : axis;
    planes.push_back(PlaneFrame::make(origin, normal.norm() > 0.1 ? normal : Vec3::UnitX()));
    balls.push_back({origin, Vec3::Zero(), 5 + 40 * (uniform() + 1)});
  }
  for (int s = 0; s < 61; s += 6) {  // through ring s of the prism's vertices
    const Vec3 origin(m.v[3 * 240 * s], m.v[3 * 240 * s + 1], m.v[3 * 240 * s + 2]);
    planes.push_back(PlaneFrame::make(origin, axis));
    balls.push_back({origin, Vec3::Zero(), 30.0});
  }
  auto same = [](const std::vector<CutSegment>& a, const std::vector<CutSegment>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      for (int e = 0; e < 2; ++e)
        if (a[i].edge[e] != b[i].edge[e] || a[i].point[e].x() != b[i].point[e].x() ||
            a[i].point[e].y() != b[i].point[e].y())
          return false;
    return true;
  };
  std::size_t segments = 0;
  for (int pass = 0; pass < 2; ++pass)  // the first pass computes the boxes, the second reads
    for (std::size_t k = 0; k < planes.size(); ++k) {
      const CutRegion* regions[2] = {nullptr, &balls[k]};
      for (const CutRegion* region : regions) {
        std::vector<CutSegment> a, b;
        cut_mesh(m.view(), planes[k], a, &loose, region);
        cut_mesh(m.view(), planes[k], b, &tight, region);
        EXPECT_TRUE(same(a, b)) << "plane " << k << " pass " << pass;
        segments += a.size();
      }
      // A grown cut (the ring beyond a smaller ball) too.
      const CutRegion inner{balls[k].point, Vec3::Zero(), 0.5 * balls[k].radius};
      std::vector<CutSegment> a, b;
      cut_mesh(m.view(), planes[k], a, &loose, &balls[k], &inner);
      cut_mesh(m.view(), planes[k], b, &tight, &balls[k], &inner);
      EXPECT_TRUE(same(a, b)) << "grown, plane " << k;
    }
  EXPECT_GT(segments, 10000u);
  // Cuts on several threads at once, on a grid whose boxes no cut has computed yet (a cell is
  // bounded by whichever cut gets there first; the others cut it face by face meanwhile).
  FaceGrid shared;
  shared.build(m.view());
  shared.enable_tight_bounds();
  std::vector<std::vector<CutSegment>> expected(planes.size()), got(planes.size());
  for (std::size_t k = 0; k < planes.size(); ++k)
    cut_mesh(m.view(), planes[k], expected[k], &loose, &balls[k]);
  std::vector<std::thread> workers;
  for (int w = 0; w < 4; ++w)
    workers.emplace_back([&, w]() {
      for (std::size_t k = w; k < planes.size(); k += 4)
        cut_mesh(m.view(), planes[k], got[k], &shared, &balls[k]);
    });
  for (auto& t : workers) t.join();
  for (std::size_t k = 0; k < planes.size(); ++k)
    EXPECT_TRUE(same(expected[k], got[k])) << "threads, plane " << k;
  // A new build turns them off.
  tight.build(m.view());
  EXPECT_FALSE(tight.tight_bounds());
}

TEST(Slicer, GridEntriesAreTheDistinctVerticesOfEachCell) {
  // Checked against the mesh directly; the same on one worker and on several (29 276 faces: two
  // parts).
  const auto m = turned_prism();
  const MeshView mesh = m.view();
  FaceGrid one, many;
  one.build(mesh, 12, 1);
  many.build(mesh, 12, 4);
  for (const FaceGrid* grid : {&one, &many}) {
    Index listed = 0;
    for (Index c = 0; c < grid->num_cells(); ++c) {
      const Index vb = grid->vertex_begin(c), ve = grid->vertex_end(c);
      ASSERT_EQ(vb, listed) << c;
      listed = ve;
      std::vector<std::int32_t> corners(grid->faces() + 3 * grid->begin(c),
                                        grid->faces() + 3 * grid->end(c));
      std::vector<std::int32_t> listed_vertices(grid->entry_vertex() + vb,
                                                grid->entry_vertex() + ve);
      for (Index k = 3 * grid->begin(c); k < 3 * grid->end(c); ++k) {
        const Index e = grid->face_entries()[k];
        ASSERT_TRUE(e >= vb && e < ve) << "cell " << c << " corner " << k;
        ASSERT_EQ(grid->entry_vertex()[e], grid->faces()[k]);
      }
      for (Index e = vb; e < ve; ++e) {
        const double* p = mesh.vertices + 3 * static_cast<Index>(grid->entry_vertex()[e]);
        ASSERT_EQ(grid->entry_x()[e], p[0]);  // exact copies
        ASSERT_EQ(grid->entry_y()[e], p[1]);
        ASSERT_EQ(grid->entry_z()[e], p[2]);
      }
      std::sort(corners.begin(), corners.end());
      corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
      std::sort(listed_vertices.begin(), listed_vertices.end());
      ASSERT_EQ(listed_vertices, corners) << "cell " << c;  // each vertex once, none missing
    }
    EXPECT_EQ(listed, grid->num_entries());
  }
  ASSERT_EQ(one.num_entries(), many.num_entries());
  EXPECT_TRUE(
      std::equal(one.entry_vertex(), one.entry_vertex() + one.num_entries(), many.entry_vertex()));
  EXPECT_TRUE(
      std::equal(one.face_entries(), one.face_entries() + 3 * mesh.num_faces, many.face_entries()));
}

TEST(Slicer, GridCellBoxesHoldTheirTriangles) {
  // The cell of each triangle (tabulated cell ids, x/y of the centroid and overhang as SSE2
  // pairs) must be the one whose box holds it: every corner inside its cell's box along each
  // axis, every face exactly once. A random soup (sizes from 0.01 to 20 mm, off the origin) and
  // the turned prism, on one worker and on four.
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> pos(-40.0, 60.0), unit(-1.0, 1.0), size(-2.0, 1.3);
  osteon::testing::OwnedMesh soup;
  for (int t = 0; t < 40000; ++t) {
    const Vec3 base(pos(rng) + 1000.5, pos(rng), 0.25 * pos(rng));
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = base + std::pow(10.0, size(rng)) * Vec3(unit(rng), unit(rng), unit(rng));
      soup.v.insert(soup.v.end(), {p.x(), p.y(), p.z()});
      soup.f.push_back(3 * t + k);
    }
  }
  for (const auto& m : {soup, turned_prism()}) {
    const MeshView mesh = m.view();
    for (int threads : {1, 4}) {
      FaceGrid grid;
      grid.build(mesh, 12, threads);
      std::vector<std::array<std::int32_t, 3>> listed, faces;
      for (Index c = 0; c < grid.num_cells(); ++c)
        for (Index k = 3 * grid.begin(c); k < 3 * grid.end(c); k += 3) {
          const std::int32_t* t = grid.faces() + k;
          listed.push_back({t[0], t[1], t[2]});
          for (int j = 0; j < 3; ++j)
            for (int a = 0; a < 3; ++a) {
              const double x = mesh.vertices[3 * static_cast<Index>(t[j]) + a];
              ASSERT_TRUE(grid.meets(c, Vec3::Unit(a), x, x)) << "cell " << c << " axis " << a;
            }
        }
      for (Index f = 0; f < mesh.num_faces; ++f)
        faces.push_back({mesh.faces[3 * f], mesh.faces[3 * f + 1], mesh.faces[3 * f + 2]});
      std::sort(listed.begin(), listed.end());
      std::sort(faces.begin(), faces.end());
      EXPECT_EQ(listed, faces);
    }
  }
}

TEST(Slicer, RefileIsABuildWithTheKeptLayout) {
  // Live mode re-files the moved faces in the kept layout (FaceGrid::refile): the grid must be
  // the one build() gives for the new positions with that layout. A soup on a 1/16 mm lattice
  // whose moved triangles shift by lattice steps inside the box: their edges (so the sampled
  // area) and the box are bitwise the same, so a fresh build has the same layout. The shift
  // crosses cells (~1-2 mm); moved faces at the low end of the numbering (every later cell
  // re-sorted), at the high end (the cells before kept), or none; one and four workers.
  std::mt19937 rng(34);
  std::uniform_int_distribution<int> pos(16, 1008), step(-12, 12);
  osteon::testing::OwnedMesh soup;
  auto add = [&](const Vec3& base) {
    const Index first = static_cast<Index>(soup.v.size() / 3);
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = base + Vec3(step(rng), step(rng), step(rng)) / 16.0;
      soup.v.insert(soup.v.end(), {p.x(), p.y(), p.z()});
      soup.f.push_back(static_cast<std::int32_t>(first + k));
    }
  };
  add(Vec3::Zero());
  add(Vec3::Constant(66.0));  // the box: -0.75 .. 66.75 mm
  for (int t = 0; t < 40000; ++t) add(Vec3(pos(rng), pos(rng), pos(rng)) / 16.0);
  const MeshView before = soup.view();
  const Index nf = before.num_faces;
  for (int end = 0; end < 3; ++end)
    for (int threads : {1, 4}) {
      osteon::testing::OwnedMesh moved_mesh = soup;
      std::vector<std::int32_t> moved;
      for (Index f = 2; f < nf && end < 2; ++f) {
        const double x = soup.v[3 * static_cast<Index>(soup.f[3 * f])];
        if ((end == 0 ? x > 10.0 : x < 54.0) || f % 2 != 0) continue;
        moved.push_back(static_cast<std::int32_t>(f));
        for (int k = 0; k < 3; ++k) {
          double* p = &moved_mesh.v[3 * static_cast<Index>(soup.f[3 * f + k])];
          p[0] += end == 0 ? 2.5 : -2.5;
          p[1] += 1.25;
          p[2] -= 0.75;
        }
      }
      ASSERT_LT(4 * static_cast<Index>(moved.size()), nf);
      const MeshView after = moved_mesh.view();
      FaceGrid live, fresh;
      live.build(before, 12, threads);
      ASSERT_TRUE(live.refile(after, moved.data(), static_cast<Index>(moved.size()), threads));
      fresh.build(after, 12, threads);
      const std::string where =
          "end " + std::to_string(end) + ", threads " + std::to_string(threads);
      ASSERT_EQ(live.num_cells(), fresh.num_cells()) << where;
      for (Index c = 0; c <= live.num_cells(); ++c) {
        ASSERT_EQ(c < live.num_cells() ? live.begin(c) : live.end(c - 1),
                  c < fresh.num_cells() ? fresh.begin(c) : fresh.end(c - 1))
            << where << ", cell " << c;
        if (c == live.num_cells()) break;
        ASSERT_EQ(live.vertex_begin(c), fresh.vertex_begin(c)) << where << ", cell " << c;
        ASSERT_EQ(live.cell_center(c), fresh.cell_center(c)) << where << ", cell " << c;
        ASSERT_EQ(live.cell_half(c), fresh.cell_half(c)) << where << ", cell " << c;
      }
      EXPECT_TRUE(std::equal(live.faces(), live.faces() + 3 * nf, fresh.faces())) << where;
      EXPECT_TRUE(
          std::equal(live.face_entries(), live.face_entries() + 3 * nf, fresh.face_entries()))
          << where;
      ASSERT_EQ(live.num_entries(), fresh.num_entries()) << where;
      const Index ne = live.num_entries();
      EXPECT_TRUE(std::equal(live.entry_vertex(), live.entry_vertex() + ne, fresh.entry_vertex()));
      EXPECT_TRUE(std::equal(live.entry_x(), live.entry_x() + ne, fresh.entry_x())) << where;
      EXPECT_TRUE(std::equal(live.entry_y(), live.entry_y() + ne, fresh.entry_y())) << where;
      EXPECT_TRUE(std::equal(live.entry_z(), live.entry_z() + ne, fresh.entry_z())) << where;
      ASSERT_EQ(live.num_blocks(), fresh.num_blocks()) << where;
      for (Index k = 0; k < live.num_blocks(); ++k) {
        ASSERT_EQ(live.block_begin(k), fresh.block_begin(k)) << where;
        ASSERT_EQ(live.block_end(k), fresh.block_end(k)) << where;
      }
    }
}

TEST(Slicer, ParallelCutsThroughTheGridMatchTheFullHeightTable) {
  // Families of random planes (some through vertices: height exactly 0), in regions, with masks:
  // the grid's per-cell heights give the segments of the full per-vertex table (no grid), bit for
  // bit (compared as sets, the two visit the faces in different orders).
  const auto m = turned_prism();
  FaceGrid grid;
  grid.build(m.view());
  std::uint64_t state = 777;
  auto uniform = [&]() {  // deterministic, in [-1, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 4503599627370496.0 - 1.0;
  };
  using Key = std::tuple<std::uint64_t, std::uint64_t, double, double, double, double>;
  auto keys = [](const std::vector<CutSegment>& segs) {
    std::vector<Key> out;
    for (const CutSegment& s : segs)
      out.emplace_back(s.edge[0], s.edge[1], s.point[0].x(), s.point[0].y(), s.point[1].x(),
                       s.point[1].y());
    std::sort(out.begin(), out.end());
    return out;
  };
  std::size_t segments = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const Index v = static_cast<Index>((uniform() + 1) * 0.5 * (m.v.size() / 3 - 1));
    Vec3 origin(m.v[3 * v], m.v[3 * v + 1], m.v[3 * v + 2]);
    if (trial % 3 != 0) origin += 30 * Vec3(uniform(), uniform(), uniform());
    const Vec3 normal(uniform(), uniform(), uniform() + 1.5);
    const PlaneFrame base = PlaneFrame::make(origin, normal);
    const double spacing = trial % 3 == 0 ? 1.0 : 0.5 + 3 * (uniform() + 1);
    const int count = 5 + static_cast<int>(20 * (uniform() + 1));
    // Start one spacing below the origin so that plane 1 passes through the vertex when
    // trial % 3 == 0 (spacing 1.0 is exact).
    PlaneFrame shifted = base;
    shifted.origin = base.origin - spacing * base.normal;
    std::vector<std::uint8_t> wanted(count);
    for (auto& w : wanted) w = uniform() > -0.4;
    const CutRegion region{origin, base.normal, 10 + 20 * (uniform() + 1)};
    const CutRegion* regions[2] = {nullptr, &region};
    for (const CutRegion* r : regions) {
      std::vector<std::vector<CutSegment>> full, cells;
      cut_mesh_parallel(m.view(), shifted, spacing, count, full, nullptr, nullptr, wanted.data());
      cut_mesh_parallel(m.view(), shifted, spacing, count, cells, &grid, r, wanted.data());
      for (int k = 0; k < count; ++k) {
        if (r == nullptr) {
          EXPECT_EQ(keys(cells[k]), keys(full[k])) << "trial " << trial << " plane " << k;
        } else {  // the region's cut is a subset of the plane's
          const auto all = keys(full[k]), part = keys(cells[k]);
          EXPECT_TRUE(std::includes(all.begin(), all.end(), part.begin(), part.end()))
              << "trial " << trial << " plane " << k;
        }
        if (!wanted[k]) {
          EXPECT_TRUE(cells[k].empty());
        } else if (r == nullptr && trial % 3 != 0) {
          // The same triangles as a single-plane cut (its own per-face heights; rounded
          // differently, so compared by edges, on planes through no vertex).
          PlaneFrame single = shifted;
          single.origin = shifted.origin + (k + 1) * spacing * shifted.normal;
          std::vector<CutSegment> one;
          cut_mesh(m.view(), single, one, nullptr);
          EXPECT_EQ(cut_keys(cells[k]), cut_keys(one)) << "trial " << trial << " plane " << k;
        }
        segments += cells[k].size();
      }
    }
  }
  EXPECT_GT(segments, 5000u);
}

namespace {
// A loop traversed the other way (a hole: an inward-facing surface's cut).
std::vector<Vec2> reversed(std::vector<Vec2> loop) {
  std::reverse(loop.begin(), loop.end());
  return loop;
}
}  // namespace

TEST(Slicer, PointInAHoleTakesTheWall) {
  // Two concentric square loops, the inner one clockwise (a real hole): the origin lies in it.
  PlaneCut cut;
  cut.loops = {rectangle(10, 10), reversed(rectangle(6, 6))};
  const SectionGeometry g = select_section(cut);
  ASSERT_TRUE(g.found);
  EXPECT_TRUE(g.flags & kFlagHollow);
  EXPECT_EQ(g.polygon.holes.size(), 1u);
  EXPECT_NEAR(section_properties(g.polygon).area, 100 - 36, 1e-12);
}

TEST(Slicer, IslandsInsideHolesAreNotPartOfTheSection) {
  PlaneCut cut;
  std::vector<Vec2> island = rectangle(2, 2);
  for (auto& p : island) p += Vec2(0, 0);
  cut.loops = {rectangle(20, 20), reversed(rectangle(14, 14)), island};  // origin in the island
  const SectionGeometry g = select_section(cut);
  EXPECT_EQ(g.containing, 3);
  EXPECT_NEAR(section_properties(g.polygon).area, 4.0, 1e-12);  // the island itself
}

TEST(Slicer, OtherLoopsInThePlaneAreIgnored) {
  PlaneCut cut;
  std::vector<Vec2> far = rectangle(3, 3);
  for (auto& p : far) p += Vec2(50, 0);
  cut.loops = {far, rectangle(4, 4)};
  const SectionGeometry g = select_section(cut);
  EXPECT_NEAR(section_properties(g.polygon).area, 16.0, 1e-12);
  EXPECT_TRUE(g.polygon.holes.empty());
}

TEST(Slicer, OutsideBoneUsesNearestLoopAndFlags) {
  PlaneCut cut;
  std::vector<Vec2> a = rectangle(2, 2), b = rectangle(2, 2);
  for (auto& p : a) p += Vec2(5, 0);
  for (auto& p : b) p += Vec2(-9, 0);
  cut.loops = {b, a};
  const SectionGeometry g = select_section(cut);
  ASSERT_TRUE(g.found);
  EXPECT_TRUE(g.flags & kFlagOutside);
  EXPECT_NEAR(section_properties(g.polygon).centroid.x(), 5.0, 1e-12);
}

TEST(Slicer, SmallGapsAreClosedLargeOnesSkip) {
  // A square loop cut open by removing one side's segment: an open chain with a 4 mm gap.
  std::vector<CutSegment> segs;
  const std::vector<Vec2> sq = rectangle(4, 4);
  for (int i = 0; i < 3; ++i) {
    CutSegment s;
    s.edge[0] = 100 + i;
    s.edge[1] = 101 + i;
    s.point[0] = sq[i];
    s.point[1] = sq[i + 1];
    segs.push_back(s);
  }
  const PlaneCut closed = assemble_loops(segs, 5.0);
  EXPECT_EQ(closed.loops.size(), 1u);
  EXPECT_TRUE(closed.flags & kFlagGapClosed);
  const PlaneCut open = assemble_loops(segs, 1.0);
  EXPECT_EQ(open.loops.size(), 0u);
  EXPECT_EQ(open.open_chains.size(), 1u);
  const SectionGeometry g = select_section(open);
  EXPECT_FALSE(g.found);
  EXPECT_TRUE(g.flags & kFlagEmpty);
}

TEST(Slicer, LineCrossingsOfAClosedPrism) {
  const auto m = prism(regular_polygon(5, 32), 40);
  FaceGrid grid;
  grid.build(m.view());
  // The x axis enters at x=0 and leaves at x=40: two crossings.
  const auto hits = line_crossings(m.view(), grid, Vec3(-10, 0.1, 0.2), Vec3::UnitX());
  ASSERT_EQ(hits.size(), 2u);
  EXPECT_NEAR(hits[0], 10.0, 1e-9);
  EXPECT_NEAR(hits[1], 50.0, 1e-9);
}
