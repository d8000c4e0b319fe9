"""No false all-clear (issue 13): skipped and doubtful sections are counted and named in the
report, the CLI's summary line, and a bone with too many skipped sections is "not analysed"."""

from __future__ import annotations

import json

import numpy as np
import osteon
import pytest
from osteon import doubt, report
from osteon.cli import main
from shapes import prism, rectangle


def open_box(length=60.0, side=10.0):
    """A closed box along +x with its +y and -y walls deleted (two faces of a cube gone)."""
    v, f = prism(rectangle(side, side), length)
    v, f = np.asarray(v, float), np.asarray(f)
    y = v[f][:, :, 1]
    keep = ~(np.all(y > side / 2 - 1e-9, axis=1) | np.all(y < -side / 2 + 1e-9, axis=1))
    return v, f[keep]


def write_open_box(tmp_path):
    v, f = open_box()
    obj = tmp_path / "openbox.obj"
    with open(obj, "w") as fh:
        fh.writelines(f"v {a} {b} {c}\n" for a, b, c in v)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    rig = tmp_path / "openbox_rig.txt"
    lines = ["joints root 0 0 0\n", "joints tip 60 0 0\n", "root root\n", "hier root tip\n"]
    lines += [f"skin {i} root 1.0\n" for i in range(len(v))]
    rig.write_text("".join(lines))
    return obj, rig


def analyse_open_box():
    v, f = open_box()
    sk = osteon.Skeleton([[0, 0, 0]], [[60, 0, 0]], [-1], names=["bone"])
    w = np.ones((len(v), 1))
    return osteon.analyze(v, f, sk, w, force=20.0, allowable_stress=30.0, interval=1.0)


def test_open_box_sections_are_skipped():
    a = analyse_open_box()
    d = doubt.section_doubt(a)
    assert len(a.stress) > 10
    # every section of the open box is flagged open (and skipped: nothing closed was cut)
    assert d["by_flag"].get("open", 0) > 0
    assert np.count_nonzero(d["skipped"]) > doubt.NOT_ANALYSED_SHARE * len(a.stress)


def test_open_box_report_is_not_an_all_clear():
    a = analyse_open_box()
    r = report.build_report(analysis=a, bone_names=["bone"], allowable_mpa=30.0,
                            settings={"force_n": 20.0}, front_end="test", model="openbox")
    n = len(a.stress)
    assert r["skipped_sections"] == int(np.count_nonzero(doubt.section_doubt(a)["skipped"]))
    assert r["skipped_sections"] > 0
    assert r["verdict"] == "not analysed"
    assert [b["bone"] for b in r["not_analysed_bones"]] == ["bone"]
    row = r["bones"][0]
    assert row["status"] == "not analysed"
    assert row["reason"].startswith(f"{r['skipped_sections']} of {n} sections could not be cut")
    assert "open" in row["reason"]
    assert r["doubt"] and "could not be cut" in r["doubt"]
    # it names the bone and says what to do (issue 35: a count alone helps nobody)
    assert f"(bone {r['skipped_sections']})" in r["doubt"]
    assert "close the mesh's holes there" in r["doubt"]
    json.loads(report.to_json(r))  # still valid JSON (no NaN)


def test_clean_closed_box_has_no_doubt():
    v, f = prism(rectangle(10.0, 10.0), 60.0)
    sk = osteon.Skeleton([[0, 0, 0]], [[60, 0, 0]], [-1], names=["bone"])
    a = osteon.analyze(np.asarray(v, float), np.asarray(f), sk, np.ones((len(v), 1)),
                       force=20.0, allowable_stress=1e6, interval=1.0)
    r = report.build_report(analysis=a, bone_names=["bone"], allowable_mpa=1e6,
                            settings={"force_n": 20.0}, front_end="test", model="box")
    # the free head's section on the end cap (param 0) is cut just inside it: nothing skipped
    assert r["skipped_sections"] == 0 and r["not_analysed_bones"] == []
    head = np.flatnonzero(np.asarray(a.section_param) == 0.0)
    assert len(head) == 1 and a.section_area[head[0]] == pytest.approx(100.0, rel=1e-9)
    assert a.max_stress == a.stress[head[0]]  # the cantilever's largest moment is there
    assert r["verdict"] == "ok" and r["bones"][0]["status"] == "ok"
    assert r["max_stress_doubt"] == [] and r["doubtful_sections"] == 0


def test_not_analysed_share_threshold():
    """A bone with exactly 25 % of its sections skipped is analysed; one more is not."""

    class A:  # a stand-in analysis: 8 sections of one bone
        section_bone = np.zeros(8, int)
        section_flags = np.zeros(8, np.uint32)
        stress = np.ones(8)

    a = A()
    a.stress = np.array([1, 1, 1, 1, 1, 1, np.nan, np.nan])
    assert not doubt.bone_doubt(a, 1)[0]["not_analysed"]
    a.stress = np.array([1, 1, 1, 1, 1, np.nan, np.nan, np.nan])
    d = doubt.bone_doubt(a, 1)[0]
    assert d["not_analysed"] and d["skipped_sections"] == 3


def test_max_on_outside_section_is_marked():
    class A:
        section_bone = np.zeros(3, int)
        section_flags = np.array([0, osteon.SECTION_FLAGS["outside"], 0], np.uint32)
        stress = np.array([5.0, 500.0, 7.0])

    assert doubt.worst_section_doubt(A()) == ["outside"]
    A.section_flags = np.array([0, 0, osteon.SECTION_FLAGS["outside"]], np.uint32)
    assert doubt.worst_section_doubt(A()) == []


def test_cli_summary_and_json_show_skipped(tmp_path, capsys):
    obj, rig = write_open_box(tmp_path)
    js = tmp_path / "r.json"
    rc = main(["analyze", str(obj), "--skeleton", str(rig), "--height-mm", "60", "--force",
               "20", "--json", str(js)])
    assert rc == 0
    out = capsys.readouterr().out
    assert "NOT A CLEAN RESULT" in out and "could not be cut" in out
    r = json.loads(js.read_text())
    assert r["skipped_sections"] > 0 and r["verdict"] == "not analysed"
    assert r["not_analysed_bones"]


@pytest.mark.parametrize("name", sorted(osteon.SECTION_FLAGS))
def test_every_engine_flag_has_a_category_or_reason(name):
    assert name in doubt.REASONS


def test_bone_that_deforms_no_vertex_is_not_listed_not_analysed():
    """A helper bone with no vertex (a glTF ``_rootJoint`` from the floor to the hips) outside
    the mesh: its sections are skipped and counted, but there is nothing of the model to analyse
    along it, so it is not "not analysed"; the bar's own bone is analysed, and the verdict too."""
    v, f = prism(rectangle(10.0, 10.0), 60.0)
    v = np.asarray(v, float)
    sk = osteon.Skeleton([[0, 0, 0], [0, 0, -40]], [[60, 0, 0], [0, 0, -10]], [-1, -1],
                         names=["bone", "helper"])
    w = np.zeros((len(v), 2))
    w[:, 0] = 1.0
    a = osteon.analyze(v, np.asarray(f), sk, w, force=20.0, allowable_stress=1e6, interval=1.0)
    rows = doubt.bone_doubt(a, 2)
    assert rows[1]["skipped_sections"] > 0 and not rows[1]["not_analysed"]
    assert "deforms no vertex" in rows[1]["reason"]
    assert rows[0]["skipped_sections"] == 0 and not rows[0]["not_analysed"]
    r = report.build_report(analysis=a, bone_names=["bone", "helper"], allowable_mpa=1e6,
                            settings={"force_n": 20.0}, front_end="test", model="box")
    assert r["not_analysed_bones"] == [] and r["skipped_sections"] == rows[1]["skipped_sections"]
