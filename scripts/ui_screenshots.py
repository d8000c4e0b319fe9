"""Screenshots of the Osteon sidebar as a user meets it, in a real Blender window, and a check
that every text it draws fits at the default sidebar width (issue 20).

    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup --enable-event-simulate \
        --python scripts/ui_screenshots.py -- --out out/screenshots

(``scripts/ui_screenshots.sh`` runs exactly that.)  Factory settings, the sidebar opened at its
default width on the "Osteon" tab; then

1. the sample figurine (scripts/make_sample_rig.py): Analyze, screenshot (``sample``);
2. a click on the first weak bone (osteon.select_bone, as the list's row does), screenshot
   (``sample_bone``: the bone and its weakest section outlined in yellow, framed);
   "Next weak bone" must move to the next weak row;
3. Correct, screenshot (``sample_corrected``: the scale column); Reset must put back the
   viewport's Solid colour the user had (Analyze switched it to the attribute);
4. the RigNet dog FBX from tests/data (an imported rig: joint names, cm units): Analyze,
   screenshot (``dog``), a click on its first weak bone, screenshot (``dog_bone``).

Each step saves the window (``<step>_window.png``) and the sidebar cut out of it
(``<step>_panel.png``) to the output folder, and checks, from the UI itself:

* every label, property and button text the panels draw fits its button at the sidebar's
  real width and UI scale (``scripts/ui_fit.py``: ``blf.dimensions`` against the width
  Blender's layout gives it);
* the result summary's first words are the verdict ("N bones over the limit", "all within
  the limit", "not analysed: ...").

Writes ``report.json`` there and exits 1 if a check failed or a screenshot is missing.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import traceback

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for p in (os.path.join(ROOT, "blender_addon"), os.path.join(ROOT, "scripts")):
    if p not in sys.path:
        sys.path.insert(0, p)

import make_sample_rig
import osteon_blender
import ui_fit
from blender_window import view3d

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
ap = argparse.ArgumentParser()
ap.add_argument("--out", default=os.path.join(ROOT, "out", "screenshots"))
ap.add_argument("--dog", default=os.path.join(ROOT, "tests", "data", "RigNet", "2982_ori.fbx"))
args = ap.parse_args(argv)
OUT = os.path.abspath(args.out)
VERDICT_STARTS = ("all within the limit", "not analysed", "1 bone over the limit")
REPORT: dict = {"steps": [], "failures": []}
TAB_OSTEON_FROM_TOP_PX = 161  # the middle of the 4th tab, px at scale 1 (3.4, factory settings)


def fail(msg: str) -> None:
    print("osteon ui screenshots: FAIL", msg)
    REPORT["failures"].append(msg)


def open_sidebar():
    _win, area, _region, _ui = view3d()
    space = area.spaces.active
    space.show_region_ui = True
    space.shading.type = "SOLID"


def click_osteon_tab(phase: int):
    """Blender 4.x+: Region.active_panel_category; 3.4 has no such property, so a simulated
    click on the tab (Blender started with --enable-event-simulate; the tabs "Item", "Tool",
    "View", "Osteon" stand at the region's right edge, top down).  Move, press and release
    go in separate timer ticks (``phase`` 0, 1, 2): Blender drops a click sent at once."""
    win, _area, _region, ui = view3d()
    if "active_panel_category" in bpy.types.Region.bl_rna.properties:
        ui.active_panel_category = "Osteon"
        return
    if not bpy.app.use_event_simulate:
        fail("start Blender with --enable-event-simulate (3.4 cannot pick the sidebar tab)")
        return
    scale = ui_fit.ui_scale()
    x = ui.x + ui.width - int(10 * scale)
    y = ui.y + ui.height - int(TAB_OSTEON_FROM_TOP_PX * scale)
    kind, value = (("MOUSEMOVE", "NOTHING"), ("LEFTMOUSE", "PRESS"),
                   ("LEFTMOUSE", "RELEASE"))[phase]
    win.event_simulate(type=kind, value=value, x=x, y=y)


def activate(obj):
    for o in bpy.context.scene.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def analyze_and_frame(obj):
    win, area, region, _ui = view3d()
    activate(obj)
    with bpy.context.temp_override(window=win, area=area, region=region):
        res = bpy.ops.osteon.analyze()
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_selected()
    if res != {"FINISHED"}:
        fail(f"Analyze on {obj.name} returned {res}")


def summary_text() -> str:
    from osteon_blender.ui import panel

    return panel.summary(bpy.context.scene.osteon)[0] if hasattr(panel, "summary") else ""


def check(step: str):
    _win, _area, _region, ui = view3d()
    misfits, items = ui_fit.check_panels(osteon_blender._classes, bpy.context, ui.width)
    for m in misfits:
        fail(f"{step}: {m}")
    summ = summary_text()
    if bpy.context.scene.osteon.has_result:
        low = summ.lower()
        ok = low.startswith(VERDICT_STARTS) or (low.split(" ", 1)[0].isdigit()
                                                 and " bones over the limit" in low)
        if not ok:
            fail(f"{step}: the summary does not lead with the verdict: '{summ}'")
    REPORT["steps"].append({
        "step": step, "sidebar_width_px": ui.width, "ui_scale": ui_fit.ui_scale(),
        "summary": summ, "texts": len(items), "misfits": [str(m) for m in misfits]})
    print(f"osteon ui screenshots: {step}: sidebar {ui.width} px, {len(items)} texts, "
          f"{len(misfits)} do not fit; summary '{summ}'")


def screenshot(step: str):
    win, area, _region, ui = view3d()
    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, f"{step}_window.png")
    with bpy.context.temp_override(window=win, area=area):
        bpy.ops.screen.screenshot(filepath=path)
    if not os.path.isfile(path):
        fail(f"{step}: no screenshot {path}")
        return
    crop(path, os.path.join(OUT, f"{step}_panel.png"), ui.x, ui.y, ui.width, ui.height)


def crop(src: str, dst: str, x: int, y: int, w: int, h: int) -> None:
    """Cut the rectangle (window pixels, origin bottom left) out of a screenshot."""
    import numpy as np

    img = bpy.data.images.load(src)
    W, H = img.size
    px = np.empty(W * H * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    px = px.reshape(H, W, 4)[y:y + h, x:x + w]
    out = bpy.data.images.new("osteon_crop", px.shape[1], px.shape[0], alpha=False)
    out.pixels.foreach_set(np.ascontiguousarray(px).ravel())
    out.filepath_raw = dst
    out.file_format = "PNG"
    out.save()
    bpy.data.images.remove(out)
    bpy.data.images.remove(img)


def load_dog():
    import addon_utils

    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    addon_utils.enable("io_scene_fbx", default_set=True)
    win, area, region, _ui = view3d()
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.import_scene.fbx(filepath=args.dog)
    mesh = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    return mesh


def run(op, *args, **kw):
    win, area, region, _ui = view3d()
    with bpy.context.temp_override(window=win, area=area, region=region):
        return op(*args, **kw)


def select_first_weak():
    s = bpy.context.scene.osteon
    weak = [b for b in s.weak_bones if b.weak]
    if not weak:
        fail("no weak bone to click")
        return
    res = run(bpy.ops.osteon.select_bone, "INVOKE_DEFAULT", bone=weak[0].name)
    if res != {"FINISHED"}:
        fail(f"select_bone({weak[0].name}) returned {res}")


STEPS = []


def step(fn):
    STEPS.append(fn)
    return fn


@step
def s_setup():
    if not hasattr(bpy.types.Scene, "osteon"):
        osteon_blender.register()
    open_sidebar()
    REPORT["color_type_before"] = view3d()[1].spaces.active.shading.color_type


for _click in range(2):  # the first click after start-up may only give the window focus
    for _phase in range(3):
        STEPS.append(lambda p=_phase: click_osteon_tab(p))
        STEPS[-1].__name__ = f"s_tab{_phase}"


@step
def s_empty():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)


@step
def s_empty_shot():
    check("empty")
    screenshot("empty")


@step
def s_sample():
    obj, _arm = make_sample_rig.build()
    analyze_and_frame(obj)


@step
def s_sample_shot():
    check("sample")
    screenshot("sample")


@step
def s_click():
    select_first_weak()


@step
def s_click_shot():
    check("sample_bone")
    screenshot("sample_bone")
    s = bpy.context.scene.osteon
    weak = [i for i, b in enumerate(s.weak_bones) if b.weak]
    before = s.weak_bones_index
    run(bpy.ops.osteon.next_weak_bone)
    later = [i for i in weak if i > before] or weak
    if s.weak_bones_index != later[0]:
        fail(f"Next weak bone went from row {before} to {s.weak_bones_index}, not {later[0]}")


@step
def s_correct():
    if run(bpy.ops.osteon.correct) != {"FINISHED"}:
        fail("Correct did not finish")


@step
def s_correct_shot():
    check("sample_corrected")
    screenshot("sample_corrected")
    space = view3d()[1].spaces.active
    if space.shading.color_type != "VERTEX":
        fail(f"Analyze left the viewport colour at {space.shading.color_type}, not Attribute")
    run(bpy.ops.osteon.reset)
    if space.shading.color_type != REPORT["color_type_before"]:
        fail(f"Reset left the viewport colour at {space.shading.color_type}, not the user's "
             f"{REPORT['color_type_before']}")


@step
def s_dog():
    analyze_and_frame(load_dog())


@step
def s_dog_shot():
    check("dog")
    screenshot("dog")
    select_first_weak()


@step
def s_dog_bone_shot():
    check("dog_bone")
    screenshot("dog_bone")


state = {"i": 0}


def tick():
    i = state["i"]
    state["i"] += 1
    if i < len(STEPS):
        try:
            STEPS[i]()
        except Exception as e:  # noqa: BLE001 -- report, go on, fail at the end
            traceback.print_exc()
            fail(f"{STEPS[i].__name__}: {type(e).__name__}: {e}")
        return 0.4 if STEPS[i].__name__.startswith("s_tab") else 1.5
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, "report.json"), "w") as fh:
        json.dump(REPORT, fh, indent=1)
    ok = not REPORT["failures"]
    print("osteon ui screenshots:", "OK" if ok else f"{len(REPORT['failures'])} failures",
          "->", OUT)
    sys.stdout.flush()
    os._exit(0 if ok else 1)


bpy.app.timers.register(tick, first_interval=2.0)
