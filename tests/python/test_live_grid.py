"""Live mode's face grid (issue 34): a reused Analyzer keeps its grid's layout and re-files only
the faces that moved (FaceGrid::refile), rebuilding it when the mesh leaves the kept box. Its
sections and stresses are a one-off analysis's, up to the order of the sums (1e-12 relative)."""

from __future__ import annotations

import numpy as np
import osteon
from shapes import revolve

JOINT = np.array([40.0, 0.0, 0.0])
FIELDS = ("section_area", "section_modulus", "stress", "moment_arm", "vertex_stress")


def body_and_arm():
    """A thick body (radius 25 mm, x 0..38) and a thin arm (radius 3 mm, x 40..80) on the x
    axis; the body holds most rings, so that the arm's faces are under a quarter of the mesh."""
    body = np.linspace(0.0, 38.0, 160)
    arm = np.linspace(40.0, 80.0, 30)
    return revolve(np.concatenate([body, arm]), [25.0] * len(body) + [3.0] * len(arm))


def posed(v, degrees: float, stretch: float = 1.0, thin: float = 1.0):
    """The arm (x > 39) turned about z at the joint, stretched along itself and thinned."""
    a = np.radians(degrees)
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    out = v.copy()
    arm = v[:, 0] > 39.0
    local = v[arm] - JOINT
    local[:, 0] *= stretch
    local[:, 1:] *= thin
    out[arm] = local @ rot.T + JOINT
    tail = JOINT + rot @ np.array([40.0 * stretch, 0.0, 0.0])
    sk = osteon.Skeleton(np.array([[0.0, 0, 0], JOINT]), np.array([JOINT, tail]), [-1, 0])
    return out, sk


def assert_close(live, one_off):
    for name in FIELDS:
        x, y = (np.asarray(getattr(r, name), float) for r in (live, one_off))
        assert x.shape == y.shape, name
        scale = np.nanmax(np.abs(y)) if y.size else 0.0
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12 * scale, err_msg=name)


def test_a_reused_analyzer_follows_the_moved_arm_like_one_off_analyses():
    v, f = body_and_arm()
    arm_faces = np.any(v[f][:, :, 0] > 39.0, axis=1).mean()
    assert 0.05 < arm_faces < 0.25  # re-filed, not rebuilt
    # Straight; turned +-30 deg (inside the first box: the arm's faces cross the grid, up to
    # 20 mm: re-filed); turned 60 deg (its tip leaves the box: rebuilt); thinned (inside the new
    # box: re-filed); stretched (more sections: a full run, rebuilt), thinned, the same again
    # (nothing moved).
    poses = [(0.0, 1.0, 1.0), (30.0, 1.0, 1.0), (-30.0, 1.0, 1.0), (60.0, 1.0, 1.0),
             (60.0, 1.0, 0.8), (-30.0, 1.4, 1.0), (-30.0, 1.4, 0.9), (-30.0, 1.4, 0.9)]
    _, sk0 = posed(v, 0.0)
    kw = {"force": 1.0, "interval": 2.0, "root": 0}
    an = osteon.Analyzer(f, len(v), sk0, **kw)
    areas = []
    for degrees, stretch, thin in poses:
        vp, sk = posed(v, degrees, stretch, thin)
        live = an.run(vp, sk)
        one_off = osteon.analyze(vp, f, sk, **kw)
        assert_close(live, one_off)
        areas.append(np.asarray(live.section_area, float) / thin**2)
    # The arm's sections followed it: the same circle (pi 3^2 mm^2, the polygon's) wherever the
    # arm points, so a section cut through stale cells (faces filed where the arm was) would
    # lose area.
    arm_area = np.pi * 9.0 * np.sinc(2 / 96)  # 96-gon of radius 3 (before thinning)
    for a in areas:
        arm_sections = a[np.abs(a - arm_area) < 0.05 * arm_area]
        assert len(arm_sections) >= 10


def test_a_one_off_run_keeps_nothing_so_the_next_run_is_a_fresh_analyzers():
    """``analyze`` runs its Analyzer once with keep_for_next_run=False (no copy of the inputs
    for a partial re-run): the same numbers as a kept run, and a later run of that Analyzer is a
    full one, bit for bit a fresh Analyzer's (not a re-filed grid's, which may sum in another
    order)."""
    v, f = body_and_arm()
    kw = {"force": 1.0, "interval": 2.0, "root": 0}
    v0, sk0 = posed(v, 0.0)
    v1, sk1 = posed(v, 30.0)
    once = osteon.Analyzer(f, len(v), sk0, **kw)
    kept = osteon.Analyzer(f, len(v), sk0, **kw)
    first = once._run_rows(v0, sk0, None, keep_for_next_run=False)
    reference = kept.run(v0, sk0)
    later = once.run(v1, sk1)
    fresh = osteon.Analyzer(f, len(v), sk0, **kw).run(v1, sk1)
    for name in FIELDS:
        for x, y in ((first, reference), (later, fresh)):
            a, b = (np.asarray(getattr(r, name), float) for r in (x, y))
            assert a.shape == b.shape and a.tobytes() == b.tobytes(), name
