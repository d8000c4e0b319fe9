// The one list of an analysis's outputs (docs/architecture.md, "Adding a result field or an
// option"). Each row makes a member of AnalysisResult (analysis.hpp), a key of the Python
// binding's result dict and an attribute of osteon.Analysis, documented from this row (its
// docstring and osteon._core.result_fields()). Adding an output = adding one row here.
//
// X(type, name, init, shape, unit, doc)
//   type   C++ type of the member: std::vector<T> (a NumPy array, std::uint8_t -> bool, Vec3 ->
//          (N,3) rows), double / int (a Python scalar), std::vector<std::vector<std::int32_t>>
//          (a list of arrays)
//   init   its initialiser, e.g. {} or {-1}
//   shape  "(S,)" one per section, "(S,3)", "(V,)" one per vertex, "()" scalar; the packed
//          outlines "(P,3)", "(L+1,)", "(S+1,)"; "[(n,)]" a list of arrays
//   unit   "mm", "mm^2", "N mm", "MPa", ... ; "" when it has none
//   doc    one sentence for the docstring
//
// Packed outlines (only with AnalysisOptions::keep_outlines; otherwise empty, None in Python):
// section s owns loops outline_section_start[s] .. outline_section_start[s+1] (S+1 entries):
// first its outer boundary, then its holes; none when the section was skipped. Loop l is the
// points outline_points[outline_loop_start[l] .. outline_loop_start[l+1]) (L+1 entries), in
// order, the last joining the first; 3D on the section plane. The cut_outline_* arrays pack the
// whole cut of each junction section (kFlagJunction) the same way (none for other sections).
#pragma once

// clang-format off
#define OSTEON_RESULT_FIELDS(X)                                                                  \
  X(std::vector<int>, section_bone, {}, "(S,)", "", "bone each section belongs to")              \
  X(std::vector<std::int8_t>, section_kind, {}, "(S,)", "",                                       \
    "where the section sits: 0 interior (k*interval along the bone), 1 joint, 2 free end")      \
  X(std::vector<double>, section_param, {}, "(S,)", "mm", "distance along the bone from its head") \
  X(std::vector<Vec3>, section_point, {}, "(S,3)", "mm", "where the bone pierces the plane")     \
  X(std::vector<Vec3>, section_center, {}, "(S,3)", "mm", "centroid of the section region")      \
  X(std::vector<Vec3>, section_normal, {}, "(S,3)", "", "unit plane normal")                     \
  X(std::vector<Vec3>, load_point, {}, "(S,3)", "mm", "farthest downstream mesh point")          \
  X(std::vector<double>, section_area, {}, "(S,)", "mm^2", "area (0 when skipped)")              \
  X(std::vector<double>, section_modulus, {}, "(S,)", "mm^3",                                     \
    "minimum section modulus W over all bending directions (NaN when skipped)")                 \
  X(std::vector<Vec3>, section_thin_axis, {}, "(S,3)", "",                                        \
    "unit in-plane direction across the section's thinnest width")                             \
  X(std::vector<double>, section_aspect, {}, "(S,)", "",                                          \
    "width / thickness, sqrt of the second moments' eigenvalue ratio (1 for a circle or square)") \
  X(std::vector<double>, section_thickness, {}, "(S,)", "mm",                                     \
    "the region's minimum width: narrowest distance between two parallel lines enclosing it "   \
    "(a solid round section's diameter, a plate's thickness; thickness.hpp); NaN when skipped; "  \
    "in Python computed on first read, except where the too_thin check needed it")             \
  X(std::vector<double>, section_cut_area, {}, "(S,)", "mm^2",                                    \
    "area of the whole cut around the bone point; differs from section_area only at a "         \
    "junction section, whose numbers are the core's (docs/junctions.md); 0 when skipped")       \
  X(std::vector<double>, section_cut_modulus, {}, "(S,)", "mm^3",                                 \
    "modulus W of the whole cut (as section_cut_area); NaN when skipped")                       \
  X(std::vector<double>, section_solid_modulus, {}, "(S,)", "mm^3",                               \
    "W of the section's region solid; section_modulus is the printed one (print_profile, "      \
    "docs/printing.md), equal when the part is solid; NaN when skipped")                        \
  X(std::vector<double>, section_wall_area, {}, "(S,)", "mm^2",                                   \
    "printed walls: FDM perimeters or the resin shell (0 when solid or skipped)")               \
  X(std::vector<double>, section_skin_area, {}, "(S,)", "mm^2",                                   \
    "solid infill: top/bottom skins and small islands filled solid (0 when solid or skipped)")   \
  X(std::vector<double>, section_infill_area, {}, "(S,)", "mm^2",                                \
    "sparse infill (FDM) or hollow (resin) region (0 when solid or skipped)")                    \
  X(std::vector<double>, moment_arm, {}, "(S,)", "mm", "distance centroid -> load point d")      \
  X(std::vector<double>, moment, {}, "(S,)", "N mm", "bending moment M = F d")                   \
  X(std::vector<double>, stress, {}, "(S,)", "MPa",                                               \
    "governing stress: the beam stress M / W, at a notch section the peak at the corner next to " \
    "it, (1 + q (Kt - 1)) x the beam stress there (docs/notch.md); NaN when skipped or unreliable") \
  X(std::vector<double>, nominal_stress, {}, "(S,)", "MPa",                                       \
    "beam stress M / W (NaN when skipped or unreliable)")                                       \
  X(std::vector<double>, stress_concentration, {}, "(S,)", "",                                    \
    "Kt of the concave corner next to the section (flag notch), 1 where none")                  \
  X(std::vector<double>, notch_radius, {}, "(S,)", "mm",                                          \
    "corner radius Kt was computed with, never below the print's (NaN where none)")             \
  X(std::vector<double>, notch_step, {}, "(S,)", "",                                              \
    "step ratio D/d (big / small equivalent diameter) of that corner (NaN where none)")         \
  X(std::vector<std::uint8_t>, culled, {}, "(S,)", "",                                            \
    "W > safe modulus: safe for sure (drawn grey)")                                             \
  X(std::vector<std::uint8_t>, weak, {}, "(S,)", "", "stress > section_allowable")               \
  X(std::vector<double>, section_allowable, {}, "(S,)", "MPa",                                    \
    "allowable [sigma](theta) for the angle between the normal and the build direction")        \
  X(std::vector<double>, stress_ratio, {}, "(S,)", "",                                            \
    "stress / section_allowable (NaN when skipped or unreliable)")                              \
  X(std::vector<std::uint8_t>, across_layers, {}, "(S,)", "",                                     \
    "the layer (Z) strength governs the allowable")                                             \
  X(std::vector<std::uint32_t>, section_flags, {}, "(S,)", "", "bit mask, see SECTION_FLAGS")    \
  X(double, max_moment, {0.0}, "()", "N mm", "largest section moment M_gmax")                    \
  X(double, safe_modulus, {0.0}, "()", "mm^3", "W_k = M_gmax / [sigma]")                         \
  X(double, max_stress, {0.0}, "()", "MPa", "largest section stress")                            \
  X(double, max_stress_ratio, {0.0}, "()", "", "largest stress_ratio")                           \
  X(int, weakest_section, {-1}, "()", "", "index of the largest stress_ratio, -1 if none")      \
  X(int, held_bone, {-1}, "()", "", "bone the object was held by")                               \
  X(std::vector<double>, vertex_stress, {}, "(V,)", "MPa",                                        \
    "stress interpolated along the vertex's bone")                                              \
  X(std::vector<std::uint8_t>, vertex_culled, {}, "(V,)", "", "vertex lies among culled sections") \
  X(std::vector<int>, vertex_bone, {}, "(V,)", "", "bone whose sections colour the vertex")      \
  X(std::vector<Vec3>, outline_points, {}, "(P,3)", "mm",                                         \
    "with keep_outlines: the loop points of each section's region (see section_loops)")         \
  X(std::vector<std::int64_t>, outline_loop_start, {}, "(L+1,)", "",                              \
    "with keep_outlines: first point of each loop")                                             \
  X(std::vector<std::int64_t>, outline_section_start, {}, "(S+1,)", "",                           \
    "with keep_outlines: first loop of each section")                                           \
  X(std::vector<Vec3>, cut_outline_points, {}, "(P,3)", "mm",                                     \
    "with keep_outlines: loop points of each junction section's whole cut "                     \
    "(see section_cut_loops)")                                                                  \
  X(std::vector<std::int64_t>, cut_outline_loop_start, {}, "(L+1,)", "",                          \
    "with keep_outlines: first point of each whole-cut loop")                                   \
  X(std::vector<std::int64_t>, cut_outline_section_start, {}, "(S+1,)", "",                       \
    "with keep_outlines: first whole-cut loop of each section")                                 \
  X(std::vector<Vec3>, infill_outline_points, {}, "(P,3)", "mm",                                 \
    "with keep_outlines: loop points of each section's sparse infill or hollow region "          \
    "(print_profile; none when solid; see infill_loops)")                                        \
  X(std::vector<std::int64_t>, infill_outline_loop_start, {}, "(L+1,)", "",                      \
    "with keep_outlines: first point of each infill loop")                                       \
  X(std::vector<std::int64_t>, infill_outline_section_start, {}, "(S+1,)", "",                   \
    "with keep_outlines: first infill loop of each section")                                     \
  X(std::vector<std::vector<std::int32_t>>, loose_pieces, {}, "[(n,)]", "",                       \
    "vertex indices of each shell that neither touches nor overlaps the held piece (it would "  \
    "fall off the print); no load point, vertex_stress 0; sections along its bones still cut")
// clang-format on
