"""One report schema: the CLI's JSON and the Blender batch's JSON on the same model and settings
have the same keys (recursively) and agree to 1e-9 on every number.

The batch runs on the sample figurine. The CLI runs in-process on the same model: the mesh,
skeleton and weights the batch reads (through the bridge), as the CLI's loader would hand them
over (``RiggedModel``, weight rows normalised, scaled to the printed height along z), with the
settings parsed from the CLI's own options (``osteon.cli.analyze.analyze_model``).
"""

import json

import bpy
import numpy as np
import pytest
import scipy.sparse as sp
from osteon_blender import batch, bridge

FORCE, MATERIAL, INTERVAL, SIZE = "20", "PETG", "1.5", "90"


def _cli_report(obj, arm):
    from osteon.cli import build_parser
    from osteon.cli.analyze import analyze_model
    from osteon.cli.common import settings_from_args
    from osteon.io import RiggedModel
    from osteon.io.model import normalize_rows
    from osteon.report import to_json

    verts = bridge.evaluated_positions(obj, bpy.context.evaluated_depsgraph_get())
    faces = bridge.triangles(obj.data)
    sk = bridge.skeleton_arrays(arm)
    data, indices, indptr = bridge.vertex_weights_csr(obj, sk.names)
    w = normalize_rows(sp.csr_matrix((data, indices, indptr), shape=(len(verts), len(sk.names))))
    model = RiggedModel(verts, faces, sk.heads, sk.tails, sk.parents, list(sk.names), w,
                        source="figurine.obj").scaled_to(float(SIZE), "z")
    args = build_parser().parse_args(
        ["analyze", "figurine.obj", "--height-mm", SIZE, "--axis", "z", "--force", FORCE,
         "--material", MATERIAL, "--interval", INTERVAL])
    _a, report, _secs = analyze_model(model, settings_from_args(args), args.model)
    return json.loads(to_json(report))  # what the CLI writes with --json


def _same(a, b, path="report"):
    """Same keys and list lengths everywhere; numbers equal to 1e-9 (relative to max(1, |x|))."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), (
            f"{path}: keys differ: {sorted(set(a) ^ set(b))}")
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{path}[{i}]")
    elif isinstance(a, bool) or a is None:
        assert a is b, f"{path}: {a!r} != {b!r}"
    elif isinstance(a, (int, float)):
        assert isinstance(b, (int, float)) and not isinstance(b, bool), f"{path}: {a!r} vs {b!r}"
        assert abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b)), f"{path}: {a!r} != {b!r}"
    else:
        assert isinstance(b, str), f"{path}: {a!r} vs {b!r}"


def test_cli_and_batch_reports_share_one_schema_and_numbers(sample, tmp_path):
    obj, arm = sample
    cli = _cli_report(obj, arm)
    path = tmp_path / "batch.json"
    assert batch.run(["--report", str(path), "--object", obj.name, "--material", MATERIAL,
                      "--force", FORCE, "--size-mode", "HEIGHT", "--print-size", SIZE,
                      "--interval", INTERVAL]) == 0
    blend = json.loads(path.read_text())
    assert cli["schema_version"] == blend["schema_version"] == 2
    assert (cli["run"]["front_end"], blend["run"]["front_end"]) == ("cli", "blender")
    # not a trivial case: many sections, weak bones, culled sections
    assert cli["sections"] > 50 and cli["weak_bones"] and cli["culled_sections"] > 0
    assert cli["allowable_stress_mpa"] == pytest.approx(50.0 / 2.0)  # PETG / default factor
    # not isotropic: both take PETG's layer ratio (one settings -> engine mapping)
    assert cli["layer_strength_ratio"] == blend["layer_strength_ratio"] == pytest.approx(0.6)
    assert cli["bone_names"] == blend["bone_names"]
    # the strings that name the source differ by nature; everything else is the same
    assert (cli["model"], cli["object"]) == ("figurine.obj", None)
    assert blend["object"] == obj.name and blend["armature"] == arm.name
    for rep in (cli, blend):
        for key in ("run", "model", "object", "armature"):
            rep.pop(key)
    assert cli["settings"] == blend["settings"]
    _same(cli, blend)
    assert np.isfinite(cli["max_stress_mpa"])
