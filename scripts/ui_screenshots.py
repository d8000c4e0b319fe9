"""Screenshots of the Osteon sidebar as a user meets it, in a real Blender window, and a check
that every text it draws fits at the default sidebar width (issue 20).

    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup --enable-event-simulate \
        --python scripts/ui_screenshots.py -- --out out/screenshots

(``scripts/ui_screenshots.sh`` runs exactly that.)  Factory settings, the sidebar opened at its
default width on the "Osteon" tab; then

1. the sample figurine (blender_addon/osteon_blender/sample.py): Analyze, screenshot (``sample``);
2. a click on the first weak bone (osteon.select_bone, as the list's row does), screenshot
   (``sample_bone``: the bone and its weakest section outlined in yellow, framed);
   "Next weak bone" must move to the next weak row;
3. Correct, screenshot (``sample_corrected``: the scale column); Reset must put back the
   viewport's Solid colour the user had (Analyze switched it to the attribute);
4. the RigNet dog FBX from tests/data (an imported rig: joint names, cm units, 1 cm tall in
   scene units): Analyze, screenshot (``dog``), a click on its first weak bone in a
   perspective view, screenshot (``dog_bone``).

After each click the pixels where the section projects must not be the background and must
hold its yellow outline (``check_section_shown``); with the sample's result and with Live on,
the summary's worst line, the worst row and the Live box must show the same numbers
(``check_numbers_agree``).

Each step saves the window (``<step>_window.png``) and the sidebar cut out of it
(``<step>_panel.png``) to the output folder, and checks, from the UI itself:

* every label, property and button text the panels draw fits its button at the sidebar's
  real width and UI scale (``tests/blender/ui_fit.py``: ``blf.dimensions`` against the width
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
for p in (os.path.join(ROOT, "blender_addon"), os.path.join(ROOT, "scripts"),
          os.path.join(ROOT, "tests", "blender")):
    if p not in sys.path:
        sys.path.insert(0, p)

import osteon_blender
import ui_fit
from blender_window import view3d
from osteon_blender import sample as make_sample_rig

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


def _pixels(path: str):
    """(H, W, 4) float pixels of a PNG (bottom row first, as Blender stores images)."""
    import numpy as np

    img = bpy.data.images.load(path)
    W, H = img.size
    px = np.empty(W * H * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(H, W, 4)


def check_section_shown(step: str) -> None:
    """A row click must show the section (issue 35): in the screenshot just taken, the disc
    where the highlighted section projects (its centre and outline radius) is mostly not the
    viewport's background, and the yellow outline is drawn there -- read from the pixels, not
    from the view distance (a 1 cm model once left a blank view, the section behind the near
    clip)."""
    import numpy as np
    from bpy_extras.view3d_utils import location_3d_to_region_2d
    from mathutils import Vector
    from osteon_blender import overlay, state

    _win, area, region, _ui = view3d()
    st = state.get(bpy.context.scene)
    hl = st.highlight if st is not None else None
    if not hl:
        fail(f"{step}: no section highlighted after the click")
        return
    r3d = area.spaces.active.region_3d
    centre = Vector(tuple(float(x) for x in hl["centre"]))
    right = r3d.view_rotation @ Vector((1.0, 0.0, 0.0))
    c2 = location_3d_to_region_2d(region, r3d, centre)
    e2 = location_3d_to_region_2d(region, r3d, centre + right * float(hl["radius"]))
    if c2 is None or e2 is None:
        fail(f"{step}: the section's centre is behind the view")
        return
    rad = max(6.0, (e2 - c2).length)
    px = _pixels(os.path.join(OUT, f"{step}_window.png"))
    h, w = px.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    cx, cy = region.x + c2.x, region.y + c2.y
    disc = (xs - cx) ** 2 + (ys - cy) ** 2 <= rad ** 2
    disc &= (xs >= region.x) & (xs < region.x + region.width)
    disc &= (ys >= region.y) & (ys < region.y + region.height)
    theme = bpy.context.preferences.themes[0].view_3d.space.gradients
    bg = np.array(tuple(theme.high_gradient)[:3], dtype=np.float32)
    rgb = px[..., :3][disc]
    if len(rgb) == 0:
        fail(f"{step}: the section projects outside the viewport ({cx:.0f}, {cy:.0f})")
        return
    not_bg = float(np.mean(np.abs(rgb - bg).max(axis=1) > 0.04))
    yellow = np.array(overlay.HIGHLIGHT_RGBA[:3], dtype=np.float32)
    n_yellow = int(np.count_nonzero(np.abs(rgb - yellow).max(axis=1) < 0.15))
    REPORT.setdefault("sections_shown", []).append({
        "step": step, "centre_px": [round(cx), round(cy)], "radius_px": round(rad, 1),
        "not_background": round(not_bg, 3), "yellow_px": n_yellow,
        "view_distance": r3d.view_distance, "clip_start": area.spaces.active.clip_start,
        "clip_end": area.spaces.active.clip_end})
    print(f"osteon ui screenshots: {step}: section disc {rad:.0f} px at ({cx:.0f}, {cy:.0f}): "
          f"{100 * not_bg:.0f}% not background, {n_yellow} yellow px, view distance "
          f"{r3d.view_distance:.4g}, clip {area.spaces.active.clip_start:.3g}..."
          f"{area.spaces.active.clip_end:.3g}")
    if not_bg < 0.5:
        fail(f"{step}: the section's place in the view is background ({100 * not_bg:.0f}% "
             "not background): the click does not show it")
    if n_yellow < 3:
        fail(f"{step}: the yellow outline of the section is not in the view")


_NUM = r"\d+\.\d+"


def check_numbers_agree(step: str) -> None:
    """The summary, the worst row and the Live box show the same verdict (issue 35): read the
    texts the panels draw (ui_fit's recorder) and compare their numbers."""
    import re

    _w, _a, _r, ui = view3d()
    _misfits, items = ui_fit.check_panels(osteon_blender._classes, bpy.context, ui.width)
    texts = {}
    for item, _need, _have in items:
        texts.setdefault(item.where.split(" ")[0], []).append(item.text)
    summ = " ".join(t for t in texts.get("OSTEON_PT_main", []) if t)
    live = " ".join(t for t in texts.get("OSTEON_PT_live", []) if t)
    m = re.search(rf"Worst σ/\[σ\] ({_NUM}): (.+?), ({_NUM}) / ({_NUM}) MPa", summ)
    if not m:
        fail(f"{step}: no worst line in the summary: {summ!r}")
        return
    ratio, bone, stress, allow = float(m.group(1)), m.group(2), float(m.group(3)), float(
        m.group(4))
    s = bpy.context.scene.osteon
    rows = [r for r in s.weak_bones if r.status != "not analysed"]
    row = max(rows, key=lambda r: r.ratio) if rows else None
    got = {"summary": [ratio, bone, stress, allow]}
    if abs(ratio - stress / allow) > 0.006:
        fail(f"{step}: the summary's numbers do not add up: {stress} / {allow} != {ratio}")
    if row is None or row.name != bone or f"{row.ratio:.2f}" != f"{ratio:.2f}":
        fail(f"{step}: the worst row ({row and row.name} {row and row.ratio:.2f}) is not the "
             f"summary's ({bone} {ratio:.2f})")
    if "sections over" in live:           # Live has a result: it must say the same
        lm = re.search(rf"Worst σ/\[σ\] ({_NUM}): (.+?), ({_NUM}) / ({_NUM}) MPa", live)
        if not lm:
            fail(f"{step}: no worst line in the Live box: {live!r}")
        else:
            got["live"] = [float(lm.group(1)), lm.group(2), float(lm.group(3)),
                           float(lm.group(4))]
            if got["live"] != got["summary"]:
                fail(f"{step}: Live says {got['live']}, the summary {got['summary']}")
    REPORT.setdefault("agreement", []).append({"step": step, **got})
    print(f"osteon ui screenshots: {step}: summary {got['summary']}, live {got.get('live')}, "
          f"worst row {row and row.name} {row and round(row.ratio, 2)}")


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
    check_numbers_agree("sample")


@step
def s_sample_live():
    win, area, region, _ui = view3d()
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.context.scene.osteon_live.enabled = True


@step
def s_sample_live_shot():
    from osteon_blender import live

    if not live.is_live(bpy.context.scene):
        fail("Live did not start on the sample")
    check("sample_live")
    screenshot("sample_live")
    check_numbers_agree("sample_live")
    if not doubt_summary()[0].endswith("(Live)"):
        fail(f"sample_live: the summary does not show Live's result: {doubt_summary()[0]!r}")
    bpy.context.scene.osteon_live.enabled = False


def doubt_summary() -> list[str]:
    from osteon_blender.ui import panel

    return panel.summary(bpy.context.scene.osteon)


@step
def s_click():
    select_first_weak()


@step
def s_click_shot():
    check("sample_bone")
    screenshot("sample_bone")
    check_section_shown("sample_bone")
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
    # the user's view is perspective (Front made it orthographic): there a 1 cm model's
    # section once fell inside the near clip (0.01) and the view went blank
    view3d()[1].spaces.active.region_3d.view_perspective = "PERSP"
    select_first_weak()


@step
def s_dog_bone_shot():
    check("dog_bone")
    screenshot("dog_bone")
    check_section_shown("dog_bone")


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
