"""Export for slicer (3MF), issue 32: reinforce the active rigged mesh (``osteon.reinforce``:
more walls, then denser infill where the print is weak), show each region's modifier volume as
a wireframe object, and write the slicer project (``osteon.slicer3mf``) with the model and the
modifiers in the chosen slicer's format. The model's shape is not changed."""

from __future__ import annotations

import bpy
import numpy as np
from bpy.props import EnumProperty, IntProperty, StringProperty

from .. import core, service, state
from ..core import OsteonError
from ._base import OsteonOperator

COLLECTION = "osteon modifiers"
SLICER_ITEMS = [("prusaslicer", "PrusaSlicer", "PrusaSlicer 2.4+ project (modifier volumes)"),
                ("bambu", "Bambu Studio", "Bambu Studio project (modifier parts)"),
                ("orca", "OrcaSlicer", "OrcaSlicer project (modifier parts)")]


def _profile(params: dict):
    """The print profile of the scene's settings (the engine's ``print_profile``), else the
    PrusaSlicer preset; an FDM one is needed (walls and infill to change)."""
    from osteon.profiles import get_profile, print_profiles

    profile = params.pop("print_profile", None)
    if profile is None:
        profile = get_profile("prusaslicer" if "prusaslicer" in print_profiles() else None)
    if profile.kind != "fdm":
        raise OsteonError("Export for slicer needs an FDM print profile (walls and infill): "
                          "choose one under Print settings")
    return profile


def reinforce_active(context, max_perimeters: int = 10):
    """``osteon.reinforce`` of the active rigged mesh (scene settings, mm); the result and the
    gathered inputs."""
    osteon = core.import_engine()
    inp = service.gather(context)
    params = dict(inp.params)
    profile = _profile(params)
    skeleton = service.engine_skeleton(osteon, inp)
    try:
        r = osteon.reinforce(inp.vertices_mm, inp.faces, skeleton, inp.weights,
                             print_profile=profile, max_perimeters=max_perimeters, **params)
    except ValueError as e:
        raise OsteonError(f"osteon could not reinforce '{inp.obj.name}': {e}") from e
    return r, inp


def show_modifiers(context, r, mm_per_unit: float) -> list:
    """One wireframe mesh object per region in the collection "osteon modifiers" (replacing
    the last ones), in scene units; named by bone and settings."""
    from osteon.slicer3mf import settings_label

    coll = bpy.data.collections.get(COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(COLLECTION)
        context.scene.collection.children.link(coll)
    for old in list(coll.objects):
        mesh = old.data
        bpy.data.objects.remove(old, do_unlink=True)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    made = []
    for reg in r.regions:
        name = f"osteon {reg['bone']}: {settings_label(reg)}"
        mesh = bpy.data.meshes.new(name)
        v = np.asarray(reg["vertices"], dtype=float) / mm_per_unit
        mesh.from_pydata(v.tolist(), [], np.asarray(reg["faces"]).tolist())
        mesh.update()
        obj = bpy.data.objects.new(name, mesh)
        obj.display_type = "WIRE"
        obj.show_in_front = True
        obj["osteon_perimeters"] = int(reg["perimeters"])
        obj["osteon_infill_percent"] = float(100.0 * reg["infill"])
        coll.objects.link(obj)
        made.append(obj)
    return made


class OSTEON_OT_export_slicer(OsteonOperator, bpy.types.Operator):
    """Reinforce instead of reshape: give each weak region more walls (then denser infill, up
    to solid), show the regions as wireframe modifier volumes, and write a 3MF project with the
    model and the modifiers for PrusaSlicer, Bambu Studio or OrcaSlicer (shape unchanged)"""

    bl_idname = "osteon.export_slicer"
    bl_label = "Export for slicer (3MF)"
    bl_options = {"REGISTER"}  # noqa: RUF012 (Blender wants a set)

    filepath: StringProperty(subtype="FILE_PATH")  # type: ignore[valid-type]
    filter_glob: StringProperty(default="*.3mf", options={"HIDDEN"})  # type: ignore[valid-type]
    slicer: EnumProperty(name="Slicer", items=SLICER_ITEMS,  # type: ignore[valid-type]
                         default="prusaslicer")
    max_perimeters: IntProperty(name="Most walls", default=10, min=1,  # type: ignore[valid-type]
                                max=100, description="walls a region gets before its infill "
                                "is raised")

    def invoke(self, context, event):
        # reinforce and show the modifier volumes first, then ask where to write
        try:
            r, inp = reinforce_active(context, self.max_perimeters)
        except OsteonError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        show_modifiers(context, r, inp.mm_per_unit)
        state.of(context.scene).slicer_export = {"object": inp.obj.name, "result": r}
        if not self.filepath:
            self.filepath = bpy.path.ensure_ext(inp.obj.name, ".3mf")
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def run(self, context) -> str:
        if not self.filepath:
            raise OsteonError("Export for slicer: no file name given")
        path = bpy.path.ensure_ext(bpy.path.abspath(self.filepath), ".3mf")
        st = state.of(context.scene)
        kept = getattr(st, "slicer_export", None)
        obj, _ = core_target(context)
        if kept is not None and kept["object"] == obj.name:
            r = kept["result"]
        else:
            r, inp = reinforce_active(context, self.max_perimeters)
            show_modifiers(context, r, inp.mm_per_unit)
        try:
            r.write_3mf(path, slicer=self.slicer, name=obj.name)
        except (OSError, ValueError) as e:
            raise OsteonError(f"could not write '{path}': {e}") from e
        st.slicer_export = None
        fixed = sum(1 for g in r.regions if g["fixed"])
        msg = (f"osteon: {len(r.regions)} region(s) reinforced ({fixed} hold), "
               f"+{r.extra_volume_mm3:.0f} mm³; {self.slicer} project written to {path}")
        if r.unfixable:
            self.report({"WARNING"}, f"osteon: {len(r.unfixable)} section(s) even solid cannot "
                        "carry: Correct thickens them")
        return msg


def core_target(context):
    from .. import bridge

    return bridge.find_target(context)


classes = (OSTEON_OT_export_slicer,)
