"""Headless osteon: analyse (and optionally correct) a rigged model, write a JSON report
and a PNG of the stress map.

    blender -b model.blend --python blender_addon/osteon_blender/batch.py -- \
        --report r.json --png p.png [--correct] [--save out.blend] [options]

Options (units: mm, N, MPa): --object NAME, --material {PLA,PETG,ABS,RESIN,NYLON,CUSTOM},
--strength MPA, --safety FACTOR, --force N, --size-mode {HEIGHT,LARGEST,UNITS},
--print-size MM, --interval MM, --held-bone NAME, --max-scale S, --max-rounds N,
--scaling THIN|UNIFORM, --auto-skeleton (rig an unrigged mesh first: Make skeleton),
--resolution PIXELS.  Exit code 0 on success, 1 on any error (message on stderr).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import traceback

import bpy
import numpy as np
from mathutils import Vector

if __package__ in (None, ""):  # run as a script: make the package importable
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    import osteon_blender
    from osteon_blender import bridge, core, service
    from osteon_blender.core import OsteonError
else:
    from . import bridge, core, service
    from .core import OsteonError

    osteon_blender = sys.modules[__package__]


def parse_args(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog="batch.py", description=__doc__.splitlines()[0])
    ap.add_argument("--report", help="JSON report path")
    ap.add_argument("--png", help="PNG stress-map render path")
    ap.add_argument("--correct", action="store_true", help="thicken weak bones (pose scales)")
    ap.add_argument("--save", help="save the .blend (with stress layer and correction) here")
    ap.add_argument("--object", help="mesh object to analyse (default: active rigged mesh)")
    ap.add_argument("--material", choices=[item[0] for item in core.MATERIAL_ITEMS])
    ap.add_argument("--strength", type=float, help="material strength, MPa")
    ap.add_argument("--safety", type=float, help="safety factor (allowable = strength / safety)")
    ap.add_argument("--force", type=float, help="load, N")
    ap.add_argument("--size-mode", choices=[m[0] for m in core.SIZE_MODES])
    ap.add_argument("--print-size", type=float, help="printed height / largest size, mm")
    ap.add_argument("--interval", type=float, help="section interval, mm")
    ap.add_argument("--held-bone", help="bone where the print is held")
    ap.add_argument("--max-scale", type=float)
    ap.add_argument("--max-rounds", type=int)
    ap.add_argument("--scaling", choices=[m[0] for m in core.SCALING_MODES],
                    help="THIN (flat parts across their thickness only) or UNIFORM (both axes)")
    ap.add_argument("--no-junction-cores", dest="junction_cores", action="store_false",
                    help="whole cuts: do not trim a side branch's stub from the sections that "
                    "cut it (faster; docs/junctions.md)")
    ap.add_argument("--auto-skeleton", action="store_true",
                    help="rig an unrigged mesh first (Make skeleton: osteon.auto_skeleton, "
                    "needs pygel3d); the largest unrigged mesh unless --object")
    ap.add_argument("--resolution", type=int, default=1000, help="PNG width, pixels")
    return ap.parse_args(argv)


def ensure_registered() -> None:
    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()


def pick_unrigged(scene, name: str | None):
    """The mesh to rig for --auto-skeleton: ``name``, else the largest mesh without an
    Armature modifier."""
    if name:
        return pick_object(scene, name)
    meshes = [o for o in scene.objects if o.type == "MESH" and bridge.armature_of(o) is None]
    if not meshes:
        raise OsteonError("--auto-skeleton: no mesh without an Armature modifier in the scene")
    return max(meshes, key=lambda o: len(o.data.vertices))


def pick_object(scene, name: str | None):
    if name:
        obj = scene.objects.get(name)
        if obj is None:
            raise OsteonError(f"no object named '{name}' in the scene")
        return obj
    active = bpy.context.view_layer.objects.active
    if active is not None and (active.type == "ARMATURE" or
                               (active.type == "MESH" and bridge.armature_of(active))):
        return active
    rigged = [o for o in scene.objects if o.type == "MESH" and bridge.armature_of(o) is not None]
    if not rigged:
        raise OsteonError("no mesh with an Armature modifier in the scene")
    return max(rigged, key=lambda o: len(o.data.vertices))


def apply_settings(s, a: argparse.Namespace) -> None:
    if a.material:
        s.material = a.material
    for attr, val in (("strength_mpa", a.strength), ("safety_factor", a.safety),
                      ("force_n", a.force), ("print_size_mm", a.print_size),
                      ("interval_mm", a.interval), ("max_scale", a.max_scale),
                      ("max_rounds", a.max_rounds)):
        if val is not None:
            setattr(s, attr, val)
    if a.size_mode:
        s.size_mode = a.size_mode
    if a.scaling:
        s.scaling = a.scaling
    if a.held_bone is not None:
        s.held_bone = a.held_bone
    if not a.junction_cores:
        s.junction_cores = False


# --------------------------------------------------------------------------- render


def _colour_mesh(name: str, verts, faces, colours):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    me.update()
    bridge.write_point_colors(me, np.asarray(colours, dtype=np.float32))
    return me


def _text(name: str, body: str, size: float):
    cu = bpy.data.curves.new(name, "FONT")
    cu.body = body
    cu.size = size
    return cu


def render_png(context, obj, path: str, allowable: float, worst_ratio: float,
               width: int = 1000) -> None:
    """Workbench render of the stress colours, orthographic 3/4 front view framing the
    model, with a colour legend (a gradient bar of stress / allowable, 0 to 1.2: red from the
    limit on, and labels parented to the camera)."""
    scene = context.scene
    r = scene.render
    shading = scene.display.shading
    saved = {
        "engine": r.engine, "x": r.resolution_x, "y": r.resolution_y, "pct": r.resolution_percentage,
        "path": r.filepath, "fmt": r.image_settings.file_format, "camera": scene.camera,
        "light": shading.light, "color_type": shading.color_type,
        "view": scene.view_settings.view_transform, "world": scene.world,
        "cavity": shading.show_cavity,
    }
    made: list = []
    try:
        verts = bridge.evaluated_positions(obj, context.evaluated_depsgraph_get())
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        center = Vector(((lo + hi) / 2).tolist())
        size = float(np.linalg.norm(hi - lo)) or 1.0
        az, el = math.radians(30.0), math.radians(12.0)
        direction = Vector((math.sin(az) * math.cos(el), math.cos(az) * math.cos(el),
                            -math.sin(el)))  # looking from the front (-Y), a bit right and above
        rot = direction.to_track_quat("-Z", "Y")
        right, up = rot @ Vector((1, 0, 0)), rot @ Vector((0, 1, 0))
        rel = verts - np.array(center)
        u, v = rel @ np.array(right), rel @ np.array(up)
        u0, u1, v0, v1 = float(u.min()), float(u.max()), float(v.min()), float(v.max())
        h = v1 - v0 or size
        pad = 0.06 * h
        legend_w = 0.42 * h
        frame_u0, frame_u1 = u0 - pad, u1 + pad + legend_w
        frame_v0, frame_v1 = v0 - pad, v1 + pad
        fw, fh = frame_u1 - frame_u0, frame_v1 - frame_v0
        cu, cv = (frame_u0 + frame_u1) / 2, (frame_v0 + frame_v1) / 2

        cam_data = bpy.data.cameras.new("osteon_render_cam")
        cam_data.type = "ORTHO"
        cam_data.ortho_scale = max(fw, fh)
        cam_data.clip_start = size * 0.001
        cam_data.clip_end = size * 10.0
        cam = bpy.data.objects.new("osteon_render_cam", cam_data)
        made += [cam, cam_data]
        scene.collection.objects.link(cam)
        cam.rotation_mode = "QUATERNION"
        cam.rotation_quaternion = rot
        cam.location = center - direction * (3.0 * size) + right * cu + up * cv
        scene.camera = cam

        # legend in camera space: x right, y up, z towards the viewer
        bx0 = u1 + pad + 0.04 * h - cu
        bw = 0.07 * h
        by0, by1 = v0 + 0.30 * h - cv, v1 - 0.10 * h - cv
        z = -1.5 * size
        n, top = 36, 1.2                 # the bar spans stress / allowable 0 .. 1.2; 1 on row 30
        ts = np.linspace(0.0, 1.0, n + 1)
        bar_v = [(bx0 + dx, by0 + t * (by1 - by0), z) for t in ts for dx in (0.0, bw)]
        bar_f = [(2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2) for i in range(n)]
        bar_c = np.repeat(core.stress_colors(ts * top * allowable, allowable), 2, axis=0)
        sw0, sw1 = by0 - 0.14 * h, by0 - 0.07 * h
        bar_v += [(bx0, sw0, z), (bx0 + bw, sw0, z), (bx0 + bw, sw1, z), (bx0, sw1, z)]
        bar_f += [(2 * n + 2, 2 * n + 3, 2 * n + 4, 2 * n + 5)]
        bar_c = np.vstack([bar_c, np.tile(core.GREY, (4, 1))])
        me = _colour_mesh("osteon_legend", bar_v, bar_f, bar_c)
        legend = bpy.data.objects.new("osteon_legend", me)
        made += [legend, me]
        ts_ = 0.035 * h
        at = [by0 + (r / top) * (by1 - by0) - 0.3 * ts_ for r in (1.0, 0.5, 0.0)]
        labels = [
            ("1: the limit (red: over)", at[0]),
            ("0.5", at[1]),
            ("0", at[2]),
            ("safe for sure", (sw0 + sw1) / 2 - 0.3 * ts_),
        ]
        objs = [legend]
        for i, (body, y) in enumerate(labels):
            c = _text(f"osteon_label{i}", body, ts_)
            t = bpy.data.objects.new(f"osteon_label{i}", c)
            t.location = (bx0 + bw + 0.3 * ts_, y, z)
            made += [t, c]
            objs.append(t)
        title = _text("osteon_title", f"stress / allowable, worst {worst_ratio:.2f}", ts_ * 1.1)
        tobj = bpy.data.objects.new("osteon_title", title)
        tobj.location = (bx0, by1 + 0.06 * h, z)
        made += [tobj, title]
        objs.append(tobj)
        for o in objs:
            scene.collection.objects.link(o)
            o.parent = cam

        world = bpy.data.worlds.new("osteon_render_world")
        world.color = (0.16, 0.17, 0.19)
        made.append(world)
        scene.world = world
        r.engine = "BLENDER_WORKBENCH"
        shading.light = "STUDIO"
        shading.color_type = "VERTEX"
        shading.show_cavity = False
        scene.view_settings.view_transform = "Standard"
        r.resolution_percentage = 100
        if fw >= fh:
            r.resolution_x, r.resolution_y = width, max(16, round(width * fh / fw))
        else:
            r.resolution_x, r.resolution_y = max(16, round(width * fw / fh)), width
        r.image_settings.file_format = "PNG"
        r.filepath = os.path.abspath(path)
        os.makedirs(os.path.dirname(r.filepath) or ".", exist_ok=True)
        bpy.ops.render.render(write_still=True)
        if not os.path.isfile(r.filepath):
            raise OsteonError(f"render did not write {r.filepath}")
    finally:
        r.engine = saved["engine"]
        r.resolution_x, r.resolution_y = saved["x"], saved["y"]
        r.resolution_percentage = saved["pct"]
        r.filepath = saved["path"]
        r.image_settings.file_format = saved["fmt"]
        scene.camera = saved["camera"]
        scene.world = saved["world"]
        shading.light = saved["light"]
        shading.color_type = saved["color_type"]
        shading.show_cavity = saved["cavity"]
        scene.view_settings.view_transform = saved["view"]
        data = [idb for idb in made if not isinstance(idb, bpy.types.Object)]
        for idb in made:
            if isinstance(idb, bpy.types.Object):
                bpy.data.objects.remove(idb, do_unlink=True)
        owners = ((bpy.types.Mesh, bpy.data.meshes), (bpy.types.Curve, bpy.data.curves),
                  (bpy.types.Camera, bpy.data.cameras), (bpy.types.World, bpy.data.worlds))
        for idb in data:
            for typ, coll in owners:
                if isinstance(idb, typ):
                    coll.remove(idb)
                    break


# --------------------------------------------------------------------------- main


def run(argv: list[str]) -> int:
    a = parse_args(argv)
    ensure_registered()
    context = bpy.context
    scene = context.scene
    t0 = time.perf_counter()
    obj = pick_unrigged(scene, a.object) if a.auto_skeleton else pick_object(scene, a.object)
    if obj.mode != "OBJECT" and bpy.ops.object.mode_set.poll():
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in scene.objects:
        o.select_set(o == obj)
    context.view_layer.objects.active = obj
    apply_settings(scene.osteon, a)
    if a.auto_skeleton and obj.type == "MESH" and bridge.armature_of(obj) is None:
        r = service.run_make_skeleton(context)
        print(f"osteon: {obj.name}: skeleton made by osteon.auto_skeleton: {r['armature']}, "
              f"{r['bones']} bones in {r['seconds']:.1f} s")
        for text in r["warnings"]:
            print(f"osteon: warning: {text}")
    report = service.run_correct(context) if a.correct else service.run_analyze(context)
    report["run"].update(seconds=time.perf_counter() - t0,
                         blender_version=bpy.app.version_string, blend_file=bpy.data.filepath)
    if a.report:
        os.makedirs(os.path.dirname(os.path.abspath(a.report)), exist_ok=True)
        with open(a.report, "w", encoding="utf-8") as fh:
            fh.write(core.report.to_json(report, indent=2))
    print(service.summary(report))
    for w in report.get("warnings", []):
        print(f"osteon: warning: {w}", file=sys.stderr)
    if a.png:
        target = bpy.data.objects[report["object"]]
        render_png(context, target, a.png, report["allowable_stress_mpa"],
                   (report.get("worst") or {}).get("ratio") or 0.0, a.resolution)
    if a.save:
        os.makedirs(os.path.dirname(os.path.abspath(a.save)), exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save), check_existing=False)
    return 0


def main() -> int:
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        return run(argv)
    except OsteonError as e:
        print(f"osteon: error: {e}", file=sys.stderr)
        return 1
    except SystemExit as e:  # argparse
        return int(e.code or 0)
    except Exception:  # noqa: BLE001 -- any failure must give a non-zero exit code
        traceback.print_exc()
        return 1


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if code:
        sys.exit(code)
