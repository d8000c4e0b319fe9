"""FEM cross-check of osteon's section stresses with gmsh (tet mesh) and CalculiX (``ccx``).

Pipeline (:func:`cross_check`):

1. tet-mesh the closed surface with the ``gmsh`` binary (surface re-meshed at ``mesh_size`` mm,
   quadratic 10-node tetrahedra, mid-side nodes on straight edges);
2. hold the root region: every node within ``hold_radius`` mm of the held point is fixed;
3. for every distinct load point of the tested sections, three unit load cases (x, y, z), the
   force spread evenly over the surface nodes within one element size of the point;
4. solve linear elasticity with ``ccx`` (E and ν do not change the stress of this statically
   determinate load case much; defaults are PLA-like, 3500 MPa and 0.35), read the nodal
   stresses (extrapolated, averaged) from the ``.frd`` file;
5. for each section plane, cut the tetrahedra of the body part around the section centre by the
   plane, interpolate the stress tensor to the cut points and take σ_nn = nᵀσn. With the three
   unit cases, σ_nn at a point is a linear function g·f of the force vector f, so the worst
   normal stress over all force directions of magnitude F is ``F · max_p |g_p|``. That is the FEM
   counterpart of osteon's worst case (``F·d / W`` with W the minimum over bending directions).

Units: mm, N, M

Modules (one job each): ``tools`` (finding gmsh and ccx), ``mesh`` (tet meshing), ``crop``
(cutting the body part around a section), ``solve`` (CalculiX), ``sections`` (σ_nn on a section
plane), ``crosscheck`` (the pipeline and its report), ``pick`` (which sections to test), ``peaks`` (FEM's
peak by a corner, off the plane: the largest principal stress in the slab between the
neighbour planes, worst force direction; docs/validation.md "Corners (issue 33)").
"""

from .crop import crop_mesh
from .crosscheck import (
    FemReport,
    FemSection,
    cross_check,
    find_load_point,
    load_nodes,
    surface_node_ids,
)
from .mesh import read_msh2, tet_mesh
from .peaks import corner_peak, max_principal, worst_principal
from .pick import chosen_sections, hold_point, parse_section_ids, pick_sections, section_dict
from .sections import section_cut
from .solve import read_frd_stress, solve
from .tools import find_tools, missing_tools_message

__all__ = [
    "FemReport",
    "FemSection",
    "chosen_sections",
    "corner_peak",
    "crop_mesh",
    "cross_check",
    "find_load_point",
    "find_tools",
    "hold_point",
    "load_nodes",
    "max_principal",
    "missing_tools_message",
    "parse_section_ids",
    "pick_sections",
    "read_frd_stress",
    "read_msh2",
    "section_cut",
    "section_dict",
    "solve",
    "surface_node_ids",
    "tet_mesh",
    "worst_principal",
]
