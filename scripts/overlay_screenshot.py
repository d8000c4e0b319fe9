"""Screenshot of the live section overlay in a real Blender window (needs a display; Xvfb
works):

    blender -b --factory-startup --python blender_addon/osteon_blender/sample.py -- --out out/sample_rig.blend
    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup out/sample_rig.blend \
        --python scripts/overlay_screenshot.py -- --out docs/img/overlay.png

Opens the sample figurine (a .blend given on the command line also keeps the splash screen
away; without one the figurine is built here), thins its left forearm a little
(pose scale 0.75 across the bone), runs Analyze, switches Live and "Show sections" on,
frames the model in the 3D viewport with the sidebar open, then thins the forearm further
(0.6) and checks that Live followed on its own (depsgraph handler -> timer -> worker ->
colours and outlines), saves a screenshot of the window and quits.  Exit code 1 if the
overlay handler was not installed, Live did not update, or the screenshot was not
written.
"""

from __future__ import annotations

import argparse
import os
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for p in (os.path.join(ROOT, "blender_addon"), os.path.join(ROOT, "scripts"),
          os.path.join(ROOT, "tests", "blender")):
    if p not in sys.path:
        sys.path.insert(0, p)

import osteon_blender
from blender_window import view3d
from osteon_blender import live, overlay
from osteon_blender import sample as make_sample_rig

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
ap = argparse.ArgumentParser()
ap.add_argument("--out", default=os.path.join(ROOT, "docs", "img", "overlay.png"))
args = ap.parse_args(argv)
OUT = os.path.abspath(args.out)
state = {"step": 0, "ok": False}


def setup():
    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    obj, arm = bpy.data.objects.get("Figurine"), bpy.data.objects.get("Figurine_rig")
    if obj is None or arm is None:
        obj, arm = make_sample_rig.build()
    arm.pose.bones["forearm.L"].scale = (0.75, 1.0, 0.75)
    bpy.context.view_layer.update()
    win, area, region, _ui = view3d()
    space = area.spaces.active
    space.shading.type = "SOLID"
    space.shading.color_type = "VERTEX"
    space.show_region_ui = True
    space.overlay.show_floor = True
    for r in area.regions:
        if r.type == "UI" and hasattr(r, "active_panel_category"):
            try:
                r.active_panel_category = "Osteon"
            except (AttributeError, TypeError):
                pass
    arm.hide_set(True)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.osteon.analyze()
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_selected()
    obj.select_set(False)
    space.region_3d.view_distance *= 1.1
    scene = bpy.context.scene
    with bpy.context.temp_override(window=win, area=area, region=region, scene=scene):
        live.start(bpy.context, obj, arm)
    scene.osteon_live.show_sections = True
    state["ok"] = overlay.is_enabled()
    print("osteon screenshot: overlay handler", state["ok"], "outlines",
          getattr(overlay.get_outlines(scene.name), "num_sections", 0))


def tick():
    state["step"] += 1
    if state["step"] == 1:
        setup()
        return 1.0
    if state["step"] == 2:
        # a pose edit in the running UI: the depsgraph handler, the timer and the worker
        # must pick it up on their own (no update_now here)
        state["updates"] = live.readout(bpy.context.scene).updates
        bpy.data.objects["Figurine_rig"].pose.bones["forearm.L"].scale = (0.6, 1.0, 0.6)
        return 2.0
    if state["step"] == 3:
        # wait (up to 30 s: software GL under Xvfb redraws slowly) until Live has analysed
        # the new pose and the outlines of that result are shown
        r = live.readout(bpy.context.scene)
        sess = live.session()
        drawn = sess is not None and sess.outlined is sess.last_result.analysis
        done = r.updates > state["updates"] and drawn
        state["waited"] = state.get("waited", 0.0) + 0.5
        if not done and state["waited"] < 30.0:
            state["step"] = 2
            return 0.5
        print(f"osteon screenshot: live updates {state['updates']} -> {r.updates} "
              f"({r.status}, last {r.last_update_ms:.1f} ms), outlines of the latest "
              f"result: {drawn}, max stress {r.max_stress_mpa:.1f} MPa, weakest "
              f"{r.weakest_bone} x{r.weakest_ratio:.2f}")
        state["ok"] = state["ok"] and done
        return 1.0                      # let the new outlines be drawn
    if state["step"] == 4:
        win, area, _region, _ui = view3d()
        os.makedirs(os.path.dirname(OUT), exist_ok=True)
        with bpy.context.temp_override(window=win, area=area):
            bpy.ops.screen.screenshot(filepath=OUT)
        print("osteon screenshot:", OUT, os.path.isfile(OUT))
        return 0.5
    ok = state["ok"] and os.path.isfile(OUT)
    live.stop()
    bpy.ops.wm.quit_blender()
    if not ok:
        os._exit(1)
    return None


bpy.app.timers.register(tick, first_interval=1.0)
