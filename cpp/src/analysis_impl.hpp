// Internal state of an Analyzer, shared with the correction loop (not a public header).
#pragma once

#include <cstdint>
#include <vector>

#include "osteon/analysis.hpp"
#include "osteon/loads.hpp"
#include "osteon/slicer.hpp"

namespace osteon {

/// Axis-aligned box in 3D, mm.
struct Box3 {
  Vec3 lo = Vec3::Constant(1e300);
  Vec3 hi = Vec3::Constant(-1e300);
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool empty() const { return lo.x() > hi.x(); }
};

/// Where a section is and how its downstream side is found.
struct SectionSpec {
  int bone = 0;
  std::int8_t kind = kInterior;
  int boundary = 0;       // index into slab params of the bone
  bool plus_side = true;  // downstream lies beyond the param (towards the tail)
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  int job = 0;  // slicing job that computes it
};

/// Geometry of a computed section, kept between runs for partial re-analysis.
struct SectionState {
  bool found = false;
  bool whole_plane = true;  // false: the cut was proven inside `region` alone
  CutRegion region;         // where the cut was made (a cylinder or a ball), mm
  std::uint32_t flags = 0;
  double area = 0.0;
  double modulus = 0.0;
  Vec3 center = Vec3::Zero();
  Vec3 thin_axis = Vec3::Zero();  // unit, in the plane: the direction across the thinnest width
  double aspect = 1.0;            // width / thickness
  double thickness = 0.0;         // minimum width of the region, mm
};

struct Analyzer::Impl {
  AnalysisOptions options;
  std::vector<std::int32_t> faces;
  Index num_vertices = 0;
  int num_bones = 0;
  bool has_weights = false;  // weights given: `dominant` holds each vertex's bone (-1: none)
  std::vector<int> dominant;

  // State of the last run.
  std::vector<SectionSpec> specs;
  std::vector<SectionState> states;
  std::vector<std::vector<double>> slab_params;
  std::vector<int> job_bone;     // >= 0: interior family of that bone; -1: a single plane
  std::vector<int> job_section;  // first section of the job
  LoadTree tree;

  // Inputs of the last run, so that the next run re-cuts only what changed (live mode).
  std::vector<double> last_vertices;
  std::vector<Vec3> last_heads, last_tails;
  std::vector<int> last_parents;
  double last_gap = -1.0;

  /// Full or partial run: with `dirty` set, only sections whose plane crosses the box are re-cut
  /// (the skeleton must be the one of the previous run).
  AnalysisResult run(const double* vertices, const Skeleton& skeleton, const Box3* dirty);
};

}  // namespace osteon
