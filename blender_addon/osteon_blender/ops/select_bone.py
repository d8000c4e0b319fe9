import bpy

from .. import bridge, compat
from ..core import OsteonError
from ._base import OsteonOperator


def select_bone(context, arm, name: str) -> None:
    """Make ``name`` the only selected and the active bone of armature object ``arm``."""
    bones = arm.data.bones
    bone = bones.get(name)
    if bone is None:
        raise OsteonError(f"Armature '{arm.name}' has no bone '{name}'")
    for b in bones:
        compat.set_bone_selected(arm, b.name, False)
    compat.set_bone_selected(arm, name, True)
    bones.active = bone


class OSTEON_OT_select_bone(OsteonOperator, bpy.types.Operator):
    """Select a bone of the analysed armature (and make it active)"""

    bl_idname = "osteon.select_bone"
    bl_label = "Select Bone"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}  # noqa: RUF012

    bone: bpy.props.StringProperty(name="Bone", description="Name of the bone to select")

    def run(self, context):
        s = context.scene.osteon
        arm = context.scene.objects.get(s.result_armature)
        if arm is None:
            _obj, arm = bridge.find_target(context)
        select_bone(context, arm, self.bone)
        return ""
