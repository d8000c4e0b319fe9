"""scene.osteon: the add-on's settings and last results (units in every name)."""

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .. import core, printdir
from .print_settings import OsteonPrintSettings

_MATERIAL_ITEMS = core.MATERIAL_ITEMS
_DEFAULT = core.materials.get(core.materials.DEFAULT_MATERIAL)


def _on_material(self, _context):
    m = core.MATERIAL_BY_KEY.get(self.material)
    if m is not None:
        self.strength_mpa = m.strength_mpa
        self.layer_strength_ratio = m.layer_strength_ratio


def _on_bone_row(self, context):
    """Clicking a row of the weak-bone list shows that bone (ops/select_bone.show_bone)."""
    i = self.weak_bones_index
    if not (0 <= i < len(self.weak_bones)):
        return
    arm = context.scene.objects.get(self.result_armature)
    if arm is None or arm.type != "ARMATURE":
        return
    from ..ops.select_bone import show_bone

    if self.weak_bones[i].name in arm.data.bones:
        show_bone(context, arm, self.weak_bones[i].name)


class OsteonBoneResult(bpy.types.PropertyGroup):
    # name (StringProperty) comes with PropertyGroup: the bone name
    max_stress_mpa: FloatProperty(name="Max stress (MPa)", description="Highest section stress "
                                  "along the bone, MPa")
    ratio: FloatProperty(name="Stress ratio", description="Stress / allowable at the bone's "
                         "governing section (> 1 = weak)")
    stress_mpa: FloatProperty(name="Stress (MPa)", description="Stress at the bone's governing "
                              "section (the highest stress / allowable), MPa")
    allowable_mpa: FloatProperty(name="Allowable (MPa)", description="Allowable stress at the "
                                 "governing section (across or along the layers), MPa")
    weak: BoolProperty(name="Weak", description="Stress above the allowable stress now")
    limit: StringProperty(name="Limit", description="Which strength governs the worst section: "
                          "'across layers' or 'along layers'")
    status: StringProperty(name="Status", description="weak, ok or not analysed (too many of "
                           "the bone's sections could not be cut)")
    reason: StringProperty(name="Reason", description="Why sections were skipped or doubtful")
    scale: FloatProperty(name="Scale", default=1.0, description="Cross-section scale applied by "
                         "Correct (1 = unchanged)")
    stress_concentration: FloatProperty(name="Kt", default=1.0, description="Stress "
                                        "concentration at a corner next to the worst section "
                                        "(1 = none; docs/notch.md)")


class OsteonSettings(bpy.types.PropertyGroup):
    material: EnumProperty(name="Material", items=_MATERIAL_ITEMS, default=_DEFAULT.key,
                           update=_on_material, description="Print material preset: sets the "
                           "strength (MPa)")
    strength_mpa: FloatProperty(name="Strength (MPa)", default=_DEFAULT.strength_mpa, min=0.001,
                                soft_max=200.0, precision=1,
                                description="Tensile strength of the printed material, MPa")
    safety_factor: FloatProperty(name="Safety factor", default=core.DEFAULT_SAFETY_FACTOR,
                                 min=0.01, soft_max=10.0, precision=2, description="Allowable stress = "
                                 "strength / safety factor")
    force_n: FloatProperty(name="Force (N)", default=20.0, min=0.0, soft_max=500.0, precision=1,
                           description="Force on the worst point of each branch, newtons")
    size_mode: EnumProperty(name="Print size", items=core.SIZE_MODES, default="HEIGHT",
                            description="How Blender units become mm of the printed object")
    print_size_mm: FloatProperty(name="Size (mm)", default=120.0, min=0.001, precision=1,
                                 soft_max=1000.0, description="Printed height (or largest "
                                 "dimension) of the model, mm")
    interval_mm: FloatProperty(name="Interval (mm)", default=2.0, min=0.01, precision=2,
                               soft_max=20.0, description="Distance between sections along a "
                               "bone, mm of the printed object")
    junction_cores: BoolProperty(
        name="Junction cores", default=True,
        description="Where a section cuts the stub of a side branch, count only the core that "
        "continues through it (the stub carries almost no load; docs/junctions.md). Off: whole "
        "cuts, faster, but a stub then counts as carrying load")
    held_bone: StringProperty(name="Held bone", default="", description="Bone where the object "
                              "is held (empty = the root bone)")
    max_scale: FloatProperty(name="Max scale", default=3.0, min=1.0, soft_max=10.0, precision=2,
                             description="Largest cross-section scale Correct may give a bone")
    max_rounds: IntProperty(name="Max rounds", default=100, min=1, soft_max=1000,
                            description="Largest number of correction rounds")
    scaling: EnumProperty(name="Scaling", items=core.SCALING_MODES, default="THIN",
                          description="How Correct thickens a weak part")
    reinforce_first: BoolProperty(
        name="Reinforce first", default=False,
        description="Keep the shape: Correct gives weak regions more walls / denser infill "
        "first (shown as "
        "modifier volumes; Export for slicer writes them) and thickens only what even solid "
        "cannot carry (needs an FDM print profile; docs/correction.md)")
    # print direction (FDM layers, docs/printing.md); the engine mapping is osteon.settings'
    layer_strength_ratio: FloatProperty(
        name="Layer strength", default=_DEFAULT.layer_strength_ratio, min=0.01, max=1.0,
        description="Strength across the layers / in-plane strength (1 = isotropic); set by "
        "the material preset")
    print_direction: EnumProperty(name="Print direction", items=printdir.MODES, default="Z",
                                  description="Direction the layers stack along")
    print_axis: EnumProperty(name="Axis", items=printdir.AXIS_ITEMS, default="+Z",
                             description="Scene axis the layers stack along")
    # walls, skins, infill (the "Print settings" sub-panel, ui/print_settings.py)
    print_settings: PointerProperty(type=OsteonPrintSettings)
    # results of the last run
    weak_bones: CollectionProperty(type=OsteonBoneResult)
    weak_bones_index: IntProperty(default=-1, update=_on_bone_row)
    has_result: BoolProperty(default=False)
    result_object: StringProperty()
    result_armature: StringProperty()
    max_stress_mpa: FloatProperty(name="Max stress (MPa)")
    allowable_mpa: FloatProperty(name="Allowable stress (MPa)")
    # the governing section of the whole model (report["worst"]): what the verdict speaks of
    worst_bone: StringProperty(name="Worst bone")
    worst_stress_mpa: FloatProperty(name="Worst section's stress (MPa)")
    worst_allowable_mpa: FloatProperty(name="Worst section's allowable (MPa)")
    worst_ratio: FloatProperty(name="Worst stress / allowable")
    worst_limit: StringProperty(name="Worst section's limit", description="'across layers' or "
                                "'along layers'")
    result_source: StringProperty(name="Result from", description="'analyze', 'correct' or "
                                  "'live': which run the panel shows")
    sections: IntProperty(name="Sections")
    weak_sections: IntProperty(name="Weak sections")
    converged: BoolProperty(name="Converged")
    skipped_sections: IntProperty(name="Skipped sections", description="Sections that could "
                                  "not be cut (open mesh, nothing cut): no stress there")
    doubt: StringProperty(name="Doubt", description="What the result does not cover")
    verdict: StringProperty(name="Verdict", description="ok, weak or not analysed")


classes = (OsteonBoneResult, OsteonSettings)
