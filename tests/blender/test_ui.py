"""The sidebar (issue 20): its panels draw and only name real properties and operators, the
summary leads with the verdict, every text fits the default sidebar width, a result row
shows where its bone is weakest, "Next weak bone" walks the weak bones, Apply's message.

Drawn against a recording layout (``tests/blender/ui_fit.py``): background Blender has no window.
``scripts/ui_screenshots.py`` draws the same panels in a real window (Xvfb) and saves
screenshots."""

import re

import bpy
import numpy as np
import pytest
import ui_fit
from conftest import activate, run_op
from osteon_blender import overlay, state
from osteon_blender.ops import select_bone as sb
from osteon_blender.ui import doubt_ui, widgets

PANELS = ("OSTEON_PT_main", "OSTEON_PT_results", "OSTEON_PT_colours", "OSTEON_PT_material",
          "OSTEON_PT_load", "OSTEON_PT_print", "OSTEON_PT_correction", "OSTEON_PT_live")


def _items(node, out):
    for k in node.children:
        if isinstance(k, ui_fit.Item):
            out.append(k)
        else:
            _items(k, out)
    return out


class Recorder(ui_fit.FitLayout):
    """FitLayout that also checks every prop / operator it is given exists."""

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, name
        self.node.children.append(ui_fit.Item("prop", f"prop:{name}", where=self.where))
        return super().prop(data, name, **kwargs)

    def prop_search(self, data, name, search_data, search_name, **kwargs):
        assert name in data.bl_rna.properties, name
        assert search_name in search_data.bl_rna.properties, search_name
        self.node.children.append(ui_fit.Item("prop", f"prop:{name}", where=self.where))
        return super().prop_search(data, name, search_data, search_name, **kwargs)

    def operator(self, idname, **kwargs):
        mod, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, mod), name), idname
        self.node.children.append(ui_fit.Item("operator", f"op:{idname}", where=self.where))
        return super().operator(idname, **kwargs)


def _draw(name, context=None):
    """Texts (and 'prop:' / 'op:' markers) a panel draws, in order."""
    context = context or bpy.context
    cls = getattr(bpy.types, name)
    root = ui_fit.Box("column")
    cls.draw(type("P", (), {"layout": Recorder(root, name)})(), context)
    return [i.text for i in _items(root, [])]


def test_panels_are_subpanels_of_one_tab(addon):
    for name in PANELS:
        cls = getattr(bpy.types, name)
        assert cls.bl_category == "Osteon" and cls.bl_region_type == "UI", name
        assert not hasattr(cls, "poll"), f"{name} polls: panels would jump between redraws"
        if name != "OSTEON_PT_main":
            assert cls.bl_parent_id == "OSTEON_PT_main", name
    assert not hasattr(bpy.types.OSTEON_PT_live, "draw_header"), "one Live control only"


def test_panels_draw_before_and_after_results(sample):
    main = _draw("OSTEON_PT_main")
    ops = [t for t in main if t.startswith("op:")]
    assert ops[:3] == ["op:osteon.analyze", "op:osteon.correct", "op:osteon.reset"]
    assert "Not analysed yet" in main
    assert {"op:osteon.find_orientation", "op:osteon.apply_orientation"} <= set(
        _draw("OSTEON_PT_print"))
    assert "Allowable 30.0 MPa" in _draw("OSTEON_PT_material")   # 60 MPa / 2
    corr = _draw("OSTEON_PT_correction")
    assert {"prop:scaling", "prop:max_scale", "prop:max_rounds"} <= set(corr)
    live = _draw("OSTEON_PT_live")
    assert [t for t in live if t == "prop:enabled"] == ["prop:enabled"]
    assert _draw("OSTEON_PT_results") == ["No result yet"]
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    res = _draw("OSTEON_PT_results")
    # names first, then one narrow number column; the scale column once Correct scaled bones
    assert res[:3] == ["Bone", "σ/[σ]", "op:osteon.select_bone"]
    assert "op:osteon.next_weak_bone" in res
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    assert "op:osteon.apply" in _draw("OSTEON_PT_main")
    assert _draw("OSTEON_PT_results")[:3] == ["Bone", "σ/[σ]", "Scale"]
    activate(None)
    for name in PANELS:
        _draw(name)


def test_summary_leads_with_the_verdict(sample):
    s = bpy.context.scene.osteon
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rep = state.get(bpy.context.scene).last["report"]
    weak = [r for r in rep["weak_bones"] if r["weak"]]
    assert len(weak) >= 2
    lines = [t for t, _ in doubt_ui.summary_lines(s)]
    assert lines[0] == f"{len(weak)} bones over the limit"
    # one verdict: the summary's ratio is ITS stress over ITS allowable (across the layers
    # here), both shown; the same numbers as the worst row and the JSON's "worst"
    worst = max(rep["weak_bones"], key=lambda r: r["ratio"])
    w = rep["worst"]
    assert w["bone"] == worst["bone"] and w["ratio"] == worst["ratio"]
    assert w["ratio"] == pytest.approx(w["stress_mpa"] / w["allowable_mpa"], rel=1e-9)
    assert lines[1] == (f"Worst σ/[σ] {w['ratio']:.2f}: {w['bone']}, {w['stress_mpa']:.1f} / "
                        f"{w['allowable_mpa']:.1f} MPa {w['limit']}")
    nums = [float(x) for x in re.findall(r"\d+\.\d+", lines[1])]
    assert nums[0] == pytest.approx(nums[1] / nums[2], abs=0.006)   # adds up as printed
    assert lines[2] == f"{rep['weak_sections']} of {rep['sections']} sections over"
    assert not any(rep["object"] in t for t in lines), "the verdict, not the object's name"
    # 20 N -> 2 N: the stresses fall tenfold (sigma = F l / W), the worst ratio below 1
    s.force_n = 2.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    rep2 = state.get(bpy.context.scene).last["report"]
    assert rep2["max_stress_mpa"] == pytest.approx(rep["max_stress_mpa"] / 10.0, rel=1e-6)
    assert doubt_ui.summary_lines(s)[0] == ("All within the limit", "CHECKMARK")


def test_every_text_fits_the_default_sidebar(sample):
    """At 229 px and UI scale 1, with a result and a correction (the longest lists)."""
    import osteon_blender

    def misfits():
        bad, items = ui_fit.check_panels(osteon_blender._classes, bpy.context, 229, 1.0)
        assert len(items) > 20
        return [str(m) for m in bad]

    assert misfits() == []
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    assert misfits() == []
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    assert misfits() == []


def test_fit_check_catches_the_old_wide_labels(addon):
    """The check can fail: the old panel's labels do not fit (issue 20's "Section interval
    (m", "Ana..." at 229 px), short ones do."""
    room = 229 - ui_fit.PANEL_MARGIN
    assert ui_fit.text_width("Section interval (mm)  2.000", 1.0) > room * 0.75
    assert ui_fit.text_width("Interval (mm)  2.00", 1.0) < room * 0.75
    root = ui_fit.Box("row")
    lay = ui_fit.FitLayout(root, "test")
    for text in ("Find best orientation", "Apply orientation"):
        lay.label(text=text, icon="BONE_DATA")
    bad = []
    ui_fit._measure(root, room, 1.0, bad, [])
    assert len(bad) == 2


def test_result_row_columns_and_tooltip(sample):
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    s = bpy.context.scene.osteon
    row = s.weak_bones[0]
    root = ui_fit.Box("row")
    ul = bpy.types.OSTEON_UL_weak_bones
    ul.draw_item(None, bpy.context, Recorder(root, "row"), s, row, 0, s, "weak_bones_index", 0)
    texts = [i.text for i in _items(root, [])]
    # "K " marks a ratio that includes a corner's Kt (the sample's worst, the tail's root)
    corner = "K " if row.stress_concentration > 1.0 else ""
    assert texts == ["op:osteon.select_bone", corner + row.name, f"{row.ratio:.2f}"]  # no scale
    assert row.ratio > 1.0
    # PLA's layers are weaker across (0.55): a row's ratio is its governing section's stress
    # over ITS allowable, and the tooltip shows both numbers and which allowable it is
    for r in s.weak_bones:
        assert r.ratio == pytest.approx(r.stress_mpa / r.allowable_mpa, rel=1e-5)
    across = [r for r in s.weak_bones if r.limit == "across layers"]
    assert across, "the sample's antenna is governed by its across-layers allowable"
    row = across[0]
    assert row.allowable_mpa < s.allowable_mpa
    tip = sb.OSTEON_OT_select_bone.description(bpy.context, type("P", (), {"bone": row.name}))
    assert tip.startswith(f"{row.name}: stress / allowable {row.ratio:.2f} at its weakest "
                          f"section: {row.stress_mpa:.1f} MPa of {row.allowable_mpa:.1f} MPa "
                          f"allowed across layers, over the limit")


def test_row_click_shows_the_weakest_section(sample):
    obj, arm = sample
    activate(obj)
    s = bpy.context.scene.osteon
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    last = state.get(bpy.context.scene).last
    a, inp = last["analysis"], last["inputs"]
    name = s.weak_bones[0].name
    assert bpy.ops.osteon.select_bone(bone=name) == {"FINISHED"}
    assert s.weak_bones_index == 0 and arm.data.bones.active.name == name
    hl = state.get(bpy.context.scene).highlight
    b = list(inp.skeleton.names).index(name)
    mine = [i for i in range(len(a.stress)) if a.section_bone[i] == b
            and np.isfinite(a.stress_ratio[i])]
    worst = max(mine, key=lambda i: a.stress_ratio[i])
    assert hl["section"] == worst
    # the bone's weakest section is its row's ratio
    assert a.stress_ratio[worst] == pytest.approx(s.weak_bones[0].ratio, rel=1e-5)
    ss, ls = a.outline_section_start, a.outline_loop_start
    npts = sum(ls[j + 1] - ls[j] for j in range(ss[worst], ss[worst + 1]))
    assert len(hl["lines"]) == 2 + 2 * npts            # the bone segment + the outline
    centre = np.asarray(a.section_center[worst]) / inp.mm_per_unit
    assert np.allclose(hl["centre"], centre)
    seg = hl["lines"][2:]
    assert np.allclose(seg.mean(axis=0), centre, atol=hl["radius"])


def test_next_weak_bone_walks_the_weak_rows(sample, capfd):
    s = bpy.context.scene.osteon
    s.force_n = 60.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    weak = [i for i, r in enumerate(s.weak_bones) if r.weak]
    assert len(weak) >= 2
    seen = []
    for _ in range(len(weak) + 1):
        res, out = run_op(bpy.ops.osteon.next_weak_bone, capfd)
        assert res == {"FINISHED"}
        seen.append(s.weak_bones_index)
        name = s.weak_bones[s.weak_bones_index].name
        assert re.search(rf"osteon: {re.escape(name)} \(\d+ of {len(weak)}\)", out)
    assert seen == [*weak, weak[0]]
    s.force_n = 0.5
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    assert not any(r.weak or r.status == "not analysed" for r in s.weak_bones)
    # nothing to walk to: the button is greyed out (poll), no Error after a click
    assert not bpy.ops.osteon.next_weak_bone.poll()
    with pytest.raises(RuntimeError, match="poll"):
        bpy.ops.osteon.next_weak_bone()


def test_overlay_default_draws_weak_and_doubtful_only(sample):
    s = bpy.context.scene.osteon
    # 20 N (the demo's load): weak sections and corners that are not weak both exist (at 60 N
    # every corner section is weak since round 6's acute-corner Kt, docs/notch.md)
    s.force_n = 20.0
    assert bpy.ops.osteon.analyze() == {"FINISHED"}
    live = bpy.context.scene.osteon_live
    assert not live.show_all_sections
    a = state.get(bpy.context.scene).last["analysis"]
    out = overlay.compute_outlines(a, 1.0)
    weak = np.asarray(a.weak, bool)
    assert len(out.weak_ids) == np.count_nonzero(weak[out.section_ids]) > 0
    doubt = overlay.doubtful_sections(a, len(a.stress)) & ~weak
    ss, ls = a.outline_section_start, a.outline_loop_start
    npts = sum(ls[ss[i + 1]] - ls[ss[i]] for i in np.flatnonzero(doubt))
    assert len(out.doubt_lines) == 2 * npts
    assert overlay.WIDTH < overlay.WEAK_WIDTH and out.colors[:, 3].max() <= overlay.ALPHA
    # corner sections (issue 33): every outlined section with Kt > 1 that is not weak, and
    # only those
    kt = np.asarray(a.stress_concentration)
    corners = (kt > 1.0) & ~weak & (np.diff(ss) > 0)
    assert np.any(corners), "the sample has corners (its thighs, paws)"
    npts = sum(ls[ss[i + 1]] - ls[ss[i]] for i in np.flatnonzero(corners))
    assert len(out.notch_lines) == 2 * npts


def test_apply_says_osteon_once(sample, capfd):
    assert bpy.ops.osteon.correct() == {"FINISHED"}
    res, out = run_op(bpy.ops.osteon.apply, capfd)
    assert res == {"FINISHED"}
    line = next(ln for ln in out.splitlines() if "correction applied" in ln)
    assert line.count("osteon:") == 1, line


def test_long_texts_wrap_to_the_sidebar(addon):
    """The doubt text (issue 13) is wrapped at spaces to lines that fit, nothing lost."""
    text = ("9 of 145 sections could not be cut: the bone lies outside the mesh there; the cut "
            "is unreliable there")
    room = 229 - widgets.MARGINS - widgets.BOX_INSET
    lines = widgets.wrap(text, room, 1.0, icon=True)
    assert len(lines) >= 3 and " ".join(lines) == text
    for ln in lines:
        assert ui_fit.text_width(ln, 1.0) <= room - 32.0
    assert widgets.wrap("short", room, 1.0) == ["short"]


def test_row_names_fit_and_keep_what_tells_them_apart(sample):
    """At 229 px the name column has room for a rig's usual names; a longer one keeps its
    start and its distinguishing end ("auto_skeleton_bone_12" and "..._13" stay apart)."""
    from osteon_blender.ui import panel

    s = bpy.context.scene.osteon
    _share, name_px, ncols = panel.row_columns(bpy.context, s)
    assert ncols == 1 and name_px >= 95      # the number column is narrow and fixed
    for name in ("auto_07", "antenna.L", "upper_arm.L"):
        assert widgets.fit_text(name, name_px, 1.0) == name
    a = widgets.fit_text("auto_skeleton_bone_12", 70, 1.0)
    b = widgets.fit_text("auto_skeleton_bone_13", 70, 1.0)
    assert a != b and a.endswith("_12") and widgets.ELLIPSIS in a and a.startswith("au")
    assert ui_fit.text_width(a, 1.0) + 10 <= 70


def test_colour_legend_is_the_scale_the_mesh_gets(addon):
    """The legend (sub-panel "Colour scale") names the colours stress_colors paints: orange
    just below the limit (0.99 is not red), red from the limit on, grey for the culled
    (surely safe) sections, magenta for bones not analysed; its icons exist in this Blender."""
    from osteon_blender import core

    icons = bpy.types.UILayout.bl_rna.functions["label"].parameters["icon"].enum_items.keys()
    legend = {text.split(":")[0]: (rgba, icon) for rgba, icon, text in core.LEGEND}
    assert all(icon in icons for _rgba, icon in legend.values())
    c = core.stress_colors(np.array([0.0, 15.0, 29.99, 30.0, 5.0, 5.0]), 30.0,
                           np.array([0, 0, 0, 0, 1, 0], bool), np.array([0, 0, 0, 0, 0, 1], bool))
    for i, key in enumerate(["0", "0.5", "just below 1", "1 and over", "grey", "magenta"]):
        assert np.allclose(c[i], legend[key][0], atol=0.01), key
    text = " ".join(_draw("OSTEON_PT_colours"))
    assert "within the limit" in text and "surely safe" in text and "not analysed" in text


def test_view_direction_avoids_what_hides_the_section(addon):
    """The row click's view (issue 35): 30 degrees off the section's plane (the ring reads as
    an ellipse), on the side no other part of the model stands in the way, else from above."""
    d = sb.view_direction(np.zeros(3), (0.0, 0.0, 1.0), 1.0, np.zeros((0, 3)))
    assert np.linalg.norm(d) == pytest.approx(1.0)
    assert d[2] == pytest.approx(0.5)            # sin 30 degrees, from above
    assert d[1] > 0.8                            # ... on the +y side, all else equal
    g = np.linspace(-10.0, 10.0, 21)
    wall = np.array([(x, y, z) for y in (3.0, 4.0, 6.0, 9.0) for x in g for z in g])
    d = sb.view_direction(np.zeros(3), (0.0, 0.0, 1.0), 1.0, wall)
    assert d[1] < 0.3 and d[2] == pytest.approx(0.5)  # a wall on +y: another side, from above
    along = wall @ d
    assert not np.any((along > 0) & (np.linalg.norm(wall - np.outer(along, d), axis=1) < 1.2))
    # the section's own surroundings (within 2 radii) never count as in the way
    ring = np.array([(np.cos(t), np.sin(t), 0.0) for t in np.linspace(0, 6.2, 50)]) * 1.5
    d2 = sb.view_direction(np.zeros(3), (0.0, 0.0, 1.0), 1.0, np.vstack([wall, ring]))
    assert np.allclose(d, d2)
