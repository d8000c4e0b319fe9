"""The one place where Blender data becomes NumPy arrays and back, one module per thing it
bridges:

- ``objects``: which mesh and armature to analyse; turning objects (Print direction)
- ``mesh``: positions (posed, rest, live), triangles, the vertex selection
- ``skeleton``: posed deform bones as arrays, joint-rig segments, a new armature (Make skeleton)
- ``weights``: vertex-group weights <-> sparse (V, B) matrices, and their cache
- ``viewport``: the stress colour layer, Solid shading by it, redraws
- ``pose``: the correction as pose-bone scales (apply, restore, read back, bake)

Bulk ``foreach_get``/``foreach_set`` everywhere.  Everything returned is in world space and
Blender units unless a name says mm.  The names below are re-exported so that callers write
``bridge.triangles``; a new function goes into the module of what it bridges (or a new one).
"""

from .mesh import (  # noqa: F401
    corner_vertices,
    evaluated_positions,
    evaluated_positions_into,
    local_positions,
    read_co,
    select_vertices,
    set_local_positions,
    topology_key,
    triangles,
    world_rest_positions,
)
from .objects import (  # noqa: F401
    armature_of,
    arrow_empty,
    find_target,
    meshes_of_armature,
    remove_object,
    rotate_objects,
    set_world_matrices,
    world_matrices,
)
from .pose import (  # noqa: F401
    SAVED_POSE_KEY,
    apply_bone_scales,
    bake_scales_into_mesh,
    correction_ratios,
    has_saved_pose,
    pose_scales,
    restore_pose,
)
from .skeleton import (  # noqa: F401
    MIN_BONE_LENGTH_REL,
    SkeletonArrays,
    bind_armature,
    build_armature,
    correction_pose_scales,
    skeleton_arrays,
    use_joint_segments,
)
from .viewport import (  # noqa: F401
    LAYER,
    SHADING_BEFORE,
    read_point_colors,
    remove_point_colors,
    restore_viewport_colors,
    show_colors_in_viewports,
    tag_redraw_view3d,
    write_point_colors,
)
from .weights import (  # noqa: F401
    CSRWeights,
    WeightCache,
    sparse_weights,
    vertex_weights_csr,
    write_bone_weights,
)
