"""Show where a bone of the result is: osteon.select_bone (a row of the result list) and
osteon.next_weak_bone (walks through the weak and not-analysed bones).

Showing a bone (issue 20):

* the bone becomes the armature's only selected and active bone (Pose Mode shows it at once
  when the user is in it; the mode is never changed);
* the viewport overlay draws the bone (its analysed segment) and the outline of its weakest
  section in yellow, over the mesh, whatever the mode and even with the armature hidden
  inside the mesh (``overlay.set_highlight``) -- nothing in the scene is shown, hidden or
  moved for it;
* every 3D viewport of the window turns to that section (view centre on it, distance from
  the bone's length): ``region_3d.view_location`` / ``view_distance``, which behave the same
  in Blender 3.4, 4.x and 5.x, instead of ``view3d.view_selected`` with a context override
  (that would need the bone's vertices selected, i.e. an edit of the user's selection).
"""

from __future__ import annotations

import bpy
import numpy as np

from .. import bridge, compat, overlay, state, viewclip
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


def weakest_section(scene, name: str) -> dict | None:
    """Where bone ``name`` of the scene's last result is weakest, in world space (Blender
    units): ``{"analysis": the result's, "bone": (2, 3) head/tail, "section": index or None, "centre": (3,),
    "loops": list of (n, 3) outline loops, "radius": float}``; None without a result or when
    the result has no such bone."""
    st = state.get(scene)
    last = (st.shown or st.last) if st is not None else None
    if not last:
        return None
    analysis, inp = last["analysis"], last["inputs"]
    names = list(inp.skeleton.names)
    if name not in names:
        return None
    b = names.index(name)
    head = np.asarray(inp.skeleton.heads[b], dtype=np.float64)
    tail = np.asarray(inp.skeleton.tails[b], dtype=np.float64)
    k = float(inp.mm_per_unit)
    sb = np.asarray(analysis.section_bone, dtype=np.int64)
    ratio = np.asarray(analysis.stress_ratio, dtype=np.float64)
    mine = np.flatnonzero((sb == b) & np.isfinite(ratio))
    out = {"analysis": analysis, "bone": np.stack([head, tail]), "section": None, "centre": (head + tail) / 2.0,
           "loops": [], "radius": max(float(np.linalg.norm(tail - head)) / 2.0, 1e-6)}
    if len(mine) == 0:
        return out
    s = int(mine[np.argmax(ratio[mine])])
    out["section"] = s
    out["centre"] = np.asarray(analysis.section_center[s], dtype=np.float64) / k
    out["normal"] = np.asarray(analysis.section_normal[s], dtype=np.float64)
    ss = getattr(analysis, "outline_section_start", None)
    if ss is not None and len(ss) > s + 1:
        pts = np.asarray(analysis.outline_points, dtype=np.float64) / k
        ls = np.asarray(analysis.outline_loop_start, dtype=np.int64)
        for loop in range(int(ss[s]), int(ss[s + 1])):
            out["loops"].append(pts[ls[loop]:ls[loop + 1]])
    if out["loops"]:
        allp = np.concatenate(out["loops"])
        out["radius"] = max(float(np.max(np.linalg.norm(allp - out["centre"], axis=1))),
                            1e-9)
    verts = np.asarray(inp.vertices_mm, dtype=np.float64) / k
    out["size"] = float(np.ptp(verts, axis=0).max()) if len(verts) else out["radius"]
    out["view"] = view_direction(out["centre"], out["normal"], out["radius"], verts)
    return out


#: how far the view stands from the section, in section radii (the section spans about a
#: fifth of the view: the limb around it stays in sight)
FRAME_RADII = 12.0


def view_direction(centre, normal, radius: float, vertices) -> np.ndarray:
    """A unit direction (3,) from the section towards the eye that shows the section: among
    directions 30 degrees off the section's plane, on either side and all around (the ring
    then reads as an ellipse half as wide as long), the one whose line of sight passes by
    the fewest of the model's ``vertices`` (world, (V, 3)) beyond the section's own
    surroundings -- no other part (a forearm before a tail root) hides it; ties go to the most
    upward (the way one looks at a model on a table)."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / (np.linalg.norm(n) or 1.0)
    helper = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    cands = []
    for t in np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False):
        side = np.cos(t) * u + np.sin(t) * v
        cands += [np.cos(np.pi / 6) * side + sign * np.sin(np.pi / 6) * n for sign in (1, -1)]
    cands = np.array(cands)
    p = np.asarray(vertices, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
    if len(p) > 20000:                   # a sample is enough to tell the sides apart
        p = p[:: len(p) // 20000 + 1]
    p = p[(p * p).sum(1) > (2.0 * radius) ** 2]          # the section's own surroundings
    along = p @ cands.T                                  # (V, C) distance along each sight line
    across2 = np.maximum((p * p).sum(1)[:, None] - along * along, 0.0)
    blocked = (along > 0.0) & (across2 < (1.2 * radius) ** 2)
    cost = blocked.sum(axis=0) - 1e-3 * cands[:, 2]      # fewest in the way; then from above
    return cands[int(np.argmin(cost))]


def frame(context, centre, radius: float, direction=None, model_size: float | None = None,
          areas=None) -> int:
    """Turn every 3D viewport of the window (or of ``areas``) to ``centre`` (world, Blender
    units) at a distance that shows ``radius`` around it, looking along ``-direction`` (from
    the section towards the eye; None keeps the view's direction).  Where the viewport's clip
    range would cut the section (a model of 1 cm: the default near clip, 0.01, is farther
    than the section) it is moved, and the user's range comes back when the view leaves the
    section (``viewclip``).  Returns how many viewports moved (0 headless)."""
    from mathutils import Vector

    if areas is None:
        screen = getattr(getattr(context, "window", None), "screen", None)
        areas = getattr(screen, "areas", None) or []
    distance = FRAME_RADII * float(radius)
    size = float(model_size) if model_size else distance
    moved = 0
    for area in areas:
        if area.type != "VIEW_3D":
            continue
        space = area.spaces.active
        r3d = space.region_3d
        if r3d.view_perspective == "CAMERA":
            r3d.view_perspective = "PERSP"
        r3d.view_location = tuple(float(x) for x in centre)
        if direction is not None:
            r3d.view_rotation = Vector(tuple(float(x) for x in direction)).to_track_quat("Z", "Y")
        r3d.view_distance = distance
        viewclip.fit(space, centre, distance, size)
        area.tag_redraw()
        moved += 1
    return moved

def show_bone(context, arm, name: str) -> dict | None:
    """Select bone ``name``, outline it and its weakest section, frame it (module doc)."""
    select_bone(context, arm, name)
    where = weakest_section(context.scene, name)
    if where is None:
        overlay.set_highlight(context.scene, None)
        return None
    overlay.set_highlight(context.scene, where)
    frame(context, where["centre"], where["radius"], where.get("view"), where.get("size"))
    return where


def result_rows(scene) -> list:
    """The result list's rows to walk through: weak or not analysed, in list order."""
    s = scene.osteon
    return [i for i, r in enumerate(s.weak_bones) if r.weak or r.status == "not analysed"]


def row_tooltip(row, allowable_mpa: float) -> str:
    """The full text of one result row (the list's tooltip): name, stress / allowable at the
    bone's governing section with both numbers (MPa) and which allowable that is (across or
    along the layers), the verdict, the scale after Correct."""
    if row.status == "not analysed":
        return f"{row.name}: not analysed. {row.reason}"
    allow = row.allowable_mpa or allowable_mpa
    stress = row.stress_mpa if row.allowable_mpa else row.max_stress_mpa
    text = (f"{row.name}: stress / allowable {row.ratio:.2f} at its weakest section: "
            f"{stress:.1f} MPa of {allow:.1f} MPa allowed")
    text += f" {row.limit}" if row.limit else ""
    text += ", over the limit" if row.weak else ", within the limit"
    if row.stress_concentration > 1.0:
        text += (f"; its worst section is next to a corner: the peak there, Kt "
                 f"{row.stress_concentration:.2f} (a larger fillet lowers it)")
    if row.max_stress_mpa > stress * (1.0 + 1e-6):
        text += (f" (its highest stress, {row.max_stress_mpa:.1f} MPa, lies where more is "
                 "allowed)")
    if abs(row.scale - 1.0) > 1e-6:
        text += f"; Correct scaled its cross-section x{row.scale:.2f}"
    return text + ". Click: select the bone, outline its weakest section, frame it"


def _armature(context):
    s = context.scene.osteon
    arm = context.scene.objects.get(s.result_armature)
    if arm is None or arm.type != "ARMATURE":
        _obj, arm = bridge.find_target(context)
    return arm


class OSTEON_OT_select_bone(OsteonOperator, bpy.types.Operator):
    """Show a bone of the result: select it, outline its weakest section, frame it"""

    bl_idname = "osteon.select_bone"
    bl_label = "Select Bone"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}  # noqa: RUF012

    bone: bpy.props.StringProperty(name="Bone", description="Name of the bone to select")

    @classmethod
    def description(cls, context, properties):
        s = context.scene.osteon
        row = s.weak_bones.get(properties.bone)
        if row is None:
            return cls.__doc__
        return row_tooltip(row, s.allowable_mpa)

    def run(self, context):
        s = context.scene.osteon
        arm = _armature(context)
        i = s.weak_bones.find(self.bone)
        if i >= 0 and i != s.weak_bones_index and self.bone in arm.data.bones:
            s.weak_bones_index = i           # the list's highlight; its update shows the bone
        else:
            show_bone(context, arm, self.bone)
        return ""


class OSTEON_OT_next_weak_bone(OsteonOperator, bpy.types.Operator):
    """Show the next bone over the limit (or not analysed) of the result: select it,
    outline its weakest section, frame it"""

    bl_idname = "osteon.next_weak_bone"
    bl_label = "Next weak bone"
    bl_options = {"REGISTER", "UNDO"}  # noqa: RUF012

    @classmethod
    def poll(cls, context):
        """Greyed out while the result has no bone to walk to (none weak, none unanalysed)."""
        scene = getattr(context, "scene", None)
        s = getattr(scene, "osteon", None)
        if s is None or not s.has_result or not result_rows(scene):
            cls.poll_message_set_compat("No bone over the limit: nothing to walk through")
            return False
        return True

    @classmethod
    def poll_message_set_compat(cls, text: str) -> None:
        setter = getattr(cls, "poll_message_set", None)  # Blender 3.0+
        if setter is not None:
            setter(text)

    def run(self, context):
        s = context.scene.osteon
        if not s.has_result:
            raise OsteonError("No result: press Analyze first")
        rows = result_rows(context.scene)
        if not rows:
            raise OsteonError("No weak bone: all within the limit")
        later = [i for i in rows if i > s.weak_bones_index]
        i = later[0] if later else rows[0]
        arm = _armature(context)
        if i == s.weak_bones_index:
            show_bone(context, arm, s.weak_bones[i].name)
        else:
            s.weak_bones_index = i
        row = s.weak_bones[i]
        n = rows.index(i) + 1
        if row.status == "not analysed":
            return f"osteon: {row.name} ({n} of {len(rows)}): not analysed"
        return (f"osteon: {row.name} ({n} of {len(rows)}): {row.max_stress_mpa:.1f} MPa, "
                f"{row.ratio:.2f} x allowable")


classes = (OSTEON_OT_select_bone, OSTEON_OT_next_weak_bone)
