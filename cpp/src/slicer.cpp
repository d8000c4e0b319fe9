// Choice of the section around a bone among a plane cut's loops (select_region, region_choice.hpp),
// and the one-plane convenience (see osteon/slicer.hpp). The slicer's other parts: slicer_grid.cpp
// (face grid), slicer_cut.cpp (plane cut), slicer_loops.cpp (loop assembly).
#include "osteon/slicer.hpp"

#include <vector>

#include "region_choice.hpp"

namespace osteon {

SectionGeometry select_section(const PlaneCut& cut) { return select_region(cut, nullptr); }

SectionGeometry slice_section(const MeshView& mesh, const PlaneFrame& plane, double gap_tolerance) {
  std::vector<CutSegment> segments;
  cut_mesh(mesh, plane, segments, nullptr);
  return select_section(assemble_loops(segments, gap_tolerance));
}

}  // namespace osteon
