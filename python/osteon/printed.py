"""The printed section's published rules: a :class:`~osteon.profiles.PrintProfile` → the engine's
scalars (``AnalysisOptions.print_*``; the geometry is cpp/src/printed_section.cpp).

The one place these rules live (docs/printing.md, "The printed section"); every front end
reaches them through ``print_profile=`` of :func:`osteon.analyze`, :class:`osteon.Analyzer` and
:func:`osteon.correct`.

Walls (FDM)
    PrusaSlicer's Flow (src/libslic3r/Flow.cpp, ``Flow::spacing``): a line of width ``w`` and
    height ``h`` is a rectangle with semicircular ends, of cross-section ``h · (w − h(1 − π/4))``;
    neighbouring lines are laid at that *spacing* ``s = w − h(1 − π/4)`` so that they overlap by
    ``w − s``. PerimeterGenerator.cpp puts the external perimeter's centreline ``w/2`` inside the
    contour, the next one ``(s_ext + s)/2`` further, the others ``s`` apart, and the infill
    boundary half a spacing inside the last one. The walls' depth in the layer plane is therefore
    ``t_w = w/2 + s/2 + (P − 1)·s`` for P ≥ 1 perimeters (one width for all of them, as
    ``PrintProfile.line_width``): 0.836 mm for 2 × 0.45 mm at 0.2 mm layers (not 2 × 0.45 = 0.9).
    Checked against PrusaSlicer 2.5's G-code (tests/python/test_printed_section.py): the inner
    perimeter's centreline lies 0.41 mm inside the outer one's.

Skins (FDM)
    ``top_bottom_layers × layer_height`` along the build direction (PrusaSlicer's top / bottom
    solid layers: a layer is solid where the layers within that many above or below do not cover
    it).

    A hollow print (0 % infill) keeps only the skins under the flatter surfaces: PrusaSlicer
    (PrintObject::discover_horizontal_shells) drops, at 0 % infill, the solid strips thinner
    than two external perimeter widths ("probably just crossing a sloping wall"). Under a
    surface at angle α to the layer plane each layer's top strip is ``h / tan α`` wide; the N
    skin layers' strips together ``N h / tan α``, of which the walls of the layers below cover
    ``t_w``: a skin survives where ``N h / tan α − t_w ≥ 2w``, i.e. under surfaces with
    ``tan α ≤ N h / (2w + t_w)`` (24.7° for 4 × 0.2 mm, 0.45 mm lines, t_w = 0.84 mm). This is
    our reading of that rule, checked against PrusaSlicer's G-code (lying rods, docs/printing.md).
    With sparse infill PrusaSlicer grows those strips instead, and every slope has its skin.

Skins widened under slopes (FDM, sparse infill)
    PrusaSlicer (PrintObject::discover_horizontal_shells, "make sure the new internal solid is
    wide enough") takes each layer's top (bottom) surface, projects it onto the N − 1 layers
    below (above), and widens every projected strip narrower than ``2 m`` by ``m`` on each side
    within that layer's infill region, ``m = 3 ×`` the solid infill's line width
    (``skin_growth_lines`` × ``line_width``: 1.35 mm for 0.45 mm lines). Under a slope each
    layer's strip is ``h / tan α`` wide, so below about 86° every slope's skin band is widened
    by ``m`` into the infill. The engine applies it on rows one layer apart across the section
    (cpp/src/skin_growth.cpp). Against PrusaSlicer 2.5's G-code (lying rods, 15 % gyroid) the
    walls-and-skins-only W was 9 % (round) and 20 % (ellipse) above osteon's without this rule;
    with it, osteon lies between that W and the W of every strip (tests/python/
    test_printed_section.py). PrusaSlicer runs this step only with
    ``ensure_vertical_shell_thickness`` off (its built-in default, what ``PrintProfile.fdm()``
    describes); Prusa's and Bambu's own profiles turn that on (their slicer then thickens the
    shells by a different rule, not modelled) and Cura's rules differ: those presets set
    ``skin_growth_lines = 0`` (not widened: the safe side; with the option on, osteon's
    unwidened W of the lying ellipse is 0.90 × the slicer's walls-and-skins W, lower).

Infill stiffness (FDM)
    The sparse infill counts with a fraction η of the solid's modulus (a transformed section),
    from Gibson & Ashby, *Cellular Solids*, 2nd ed., Cambridge University Press 1997:

    - patterns whose walls are the same in every layer (grid, honeycomb, triangles) are prisms
      along the build direction: loaded along their walls η = ρ (§4.4, out-of-plane modulus of
      a honeycomb, E₃*/E_s = ρ*/ρ_s);
    - every other pattern along the build direction, and gyroid / cubic in the layer plane:
      bending-dominated, the open-cell law η = ρ² (§5.3, eq. 5.6, C₁ ≈ 1): rectilinear and
      lines cross the layer below only at their crossings, gyroid and cubic are 3D cell walls;
    - grid, honeycomb, rectilinear and lines in the layer plane: the load's direction to the
      fill angle is not known, so the worst one, where the walls bend: η = ρ³ (§4.3, the in-plane
      modulus of a honeycomb scales as (t/l)³; a regular hexagon's E₁*/E_s = 1.5 ρ³, taken as ρ³);
    - triangles in the layer plane: a triangulated, stretch-dominated lattice, η = ρ/3 (its
      isotropic in-plane modulus; Gibson & Ashby §4.3 / Wang & McDowell, J. Eng. Mater. Technol.
      126 (2004) 137).

    A section whose normal makes the angle θ with the build direction takes the Reuss (series)
    bound of the two, ``1/η = cos²θ/η_build + sin²θ/η_layer`` (the lower, conservative one).
    100 % infill is solid (η = 1).

Small areas (FDM)
    PrusaSlicer's ``solid_infill_below_area``: an island of a layer's infill smaller than this is
    filled solid (LayerRegion::prepare_fill_surfaces; only when the infill density is above 0 %,
    as there). A section's island of area A at angle θ is a layer island of area A / cos θ (the
    larger, so the rule applies less often: conservative).

Resin hollow
    An isotropic shell ``shell`` mm thick inside the surface, hollow inside (η = 0); solid where
    the part is thinner than 2 × shell.
"""

from __future__ import annotations

import math

from .profiles import PrintProfile, get_profile

#: Engine kinds (cpp/include/osteon/printed_section.hpp, PrintOptions::Kind).
ENGINE_KIND = {"solid": 0, "fdm": 1, "resin_hollow": 2}

#: Patterns whose walls repeat in every layer: prisms along the build direction.
PRISMATIC_PATTERNS = ("grid", "honeycomb", "triangles")


def line_spacing(line_width: float, layer_height: float) -> float:
    """PrusaSlicer's spacing of neighbouring lines (mm): ``w − h(1 − π/4)`` (Flow::spacing)."""
    return line_width - layer_height * (1.0 - math.pi / 4.0)


def wall_depth(profile: PrintProfile) -> float:
    """Depth of the FDM walls in the layer plane, mm: ``w/2 + s/2 + (P − 1)·s`` (0 for none)."""
    p = profile.perimeters
    if p <= 0:
        return 0.0
    s = line_spacing(profile.line_width, profile.layer_height)
    return profile.line_width / 2.0 + s / 2.0 + (p - 1) * s


def skin_depth(profile: PrintProfile) -> float:
    """Depth of the solid top / bottom skins along the build direction, mm."""
    return profile.top_bottom_layers * profile.layer_height


def skin_max_slope(profile: PrintProfile) -> float:
    """Steepest surface (radians from the layer plane) with a skin under it: all (π/2) with
    sparse infill; ``atan(N h / (2w + t_w))`` for a hollow (0 %) print."""
    if profile.infill > 0 or profile.top_bottom_layers == 0:
        return math.pi / 2
    return math.atan(skin_depth(profile) / (2.0 * profile.line_width + wall_depth(profile)))


def skin_growth(profile: PrintProfile) -> float:
    """How far a narrow skin strip is widened into sparse infill, mm: ``skin_growth_lines``
    line widths (PrusaSlicer: 3 × the solid infill's width, strips under 2 × that wide), only
    with sparse infill (a hollow print's narrow skins follow :func:`skin_max_slope`)."""
    if not 0.0 < profile.infill < 1.0:
        return 0.0
    return profile.skin_growth_lines * profile.line_width


def infill_stiffness(pattern: str, density: float) -> tuple[float, float]:
    """(η along the build direction, η in the layer plane) of sparse infill of ``pattern`` at
    ``density`` (fraction 0…1): the stiffness fraction of the solid (module docstring)."""
    rho = min(max(float(density), 0.0), 1.0)
    if rho >= 1.0:
        return 1.0, 1.0
    along = rho if pattern in PRISMATIC_PATTERNS else rho**2
    if pattern == "triangles":
        across = rho / 3.0
    elif pattern in ("gyroid", "cubic"):
        across = rho**2
    else:
        across = rho**3
    return along, across


def engine_print_options(options, profile: PrintProfile | str | None) -> None:
    """Writes the engine's ``print_*`` options for ``profile`` (a solid one writes kind 0 only:
    no print code runs, results bit for bit those without a profile)."""
    profile = get_profile(profile)
    if profile.is_solid:
        options.print_kind = 0
        return
    options.print_kind = ENGINE_KIND[profile.kind]
    if profile.kind == "fdm":
        options.print_wall_depth = wall_depth(profile)
        options.print_skin_depth = skin_depth(profile)
        options.print_skin_max_slope = skin_max_slope(profile)
        along, across = infill_stiffness(profile.pattern, profile.infill)
        options.print_infill_build, options.print_infill_layer = along, across
        # PrusaSlicer fills small islands solid only when there is sparse infill at all.
        options.print_solid_infill_below_area = (profile.solid_infill_below_area
                                                 if profile.infill > 0 else 0.0)
        options.print_layer_height = profile.layer_height
        options.print_skin_growth = skin_growth(profile)
    else:
        options.print_wall_depth = profile.shell
        options.print_skin_depth = 0.0
        options.print_skin_max_slope = math.pi / 2
        options.print_infill_build = options.print_infill_layer = 0.0
        options.print_solid_infill_below_area = 0.0
