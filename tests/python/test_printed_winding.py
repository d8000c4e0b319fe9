"""The printed section's own polygon passes (cpp/src/wall_inset.cpp, cpp/src/winding_region.cpp)
against Clipper2's passes (OSTEON_PRINTED_CLIPPER=1, the code before them), section by section on
real models at h = 8 mm for the FDM 15 %, hollow FDM and resin shell profiles (issue 31's cost).

Tolerance 1e-4 of the section's solid W / solid area: Clipper2's union pass rounds its corners'
crossings about a fifth of a unit (0.02 um) inward on average, which on mesh outlines with
hundreds of corners is ~2e-5 of the area (cpp/tests/test_wall_inset.cpp measures that bias
against a finer grid); a wrong region would be off by whole walls or islands."""

from __future__ import annotations

import numpy as np
import osteon
import pytest
from rigged_models import load

PROFILES = {
    "fdm": osteon.PrintProfile.fdm(),
    "fdm 0 %": osteon.PrintProfile.fdm(infill=0.0),
    "resin": osteon.PrintProfile.resin_hollow(2.0),
}
AREAS = ("section_wall_area", "section_skin_area", "section_infill_area")


@pytest.mark.parametrize("model", ["arm", "rignet2982"])
def test_same_printed_sections_as_clipper(model, monkeypatch):
    v, f, sk, w = load(model)
    for name, profile in PROFILES.items():
        monkeypatch.delenv("OSTEON_PRINTED_CLIPPER", raising=False)
        ours = osteon.analyze(v, f, sk, w, interval=8.0, threads=1, print_profile=profile)
        monkeypatch.setenv("OSTEON_PRINTED_CLIPPER", "1")
        ref = osteon.analyze(v, f, sk, w, interval=8.0, threads=1, print_profile=profile)
        solid_area = sum(np.asarray(getattr(ref, a)) for a in AREAS)
        printed = np.isfinite(ref.section_modulus) & (solid_area > 0)
        assert printed.sum() > 10, name
        assert np.any(np.asarray(ref.section_infill_area)[printed] > 0), name
        ws = np.asarray(ref.section_solid_modulus)[printed]
        dw = np.abs(np.asarray(ours.section_modulus) - np.asarray(ref.section_modulus))[printed]
        assert np.all(dw <= 1e-4 * ws), (name, float(np.max(dw / ws)))
        for a in AREAS:
            da = np.abs(np.asarray(getattr(ours, a)) - np.asarray(getattr(ref, a)))[printed]
            assert np.all(da <= 1e-4 * solid_area[printed]), (name, a)


def _printed_fields(a):
    return [np.asarray(getattr(a, n)) for n in ("section_modulus", "section_cut_modulus",
                                                "section_solid_modulus") + AREAS]


def test_printed_sections_same_on_any_worker_count_and_live():
    """The printed sections are computed inside the cuts, on whichever worker cuts their family
    (docs/performance.md, "The printed section's cost"): every printed field and the sparse loops
    are the same bits with one or two workers, and a live Analyzer's re-run after a local edit
    gives a fresh analysis's bits (its reused sections keep the printed results of the run
    before)."""
    v, f, sk, w = load("arm")
    profile = osteon.PrintProfile.fdm()
    one = osteon.analyze(v, f, sk, w, interval=4.0, threads=1, print_profile=profile,
                         keep_outlines=True)
    two = osteon.analyze(v, f, sk, w, interval=4.0, threads=2, print_profile=profile,
                         keep_outlines=True)
    assert np.any(np.asarray(one.section_infill_area) > 0)
    assert np.any(np.asarray(one.section_modulus) < np.asarray(one.section_solid_modulus))
    for x, y in zip(_printed_fields(one), _printed_fields(two)):
        assert np.array_equal(x, y, equal_nan=True)
    for a, b in zip(one.infill_loops, two.infill_loops):
        assert len(a) == len(b) and all(np.array_equal(p, q) for p, q in zip(a, b))
    live = osteon.Analyzer(f, len(v), sk, w, interval=4.0, threads=2, print_profile=profile)
    live.run(v)
    moved = np.array(v, dtype=float)
    tip = np.argmax(moved[:, 0])  # one vertex at the model's edge moved outward
    moved[tip] += 0.5 * (moved[tip] - moved.mean(axis=0)) / np.linalg.norm(moved[tip])
    again = live.run(moved)
    fresh = osteon.analyze(moved, f, sk, w, interval=4.0, threads=1, print_profile=profile)
    for x, y in zip(_printed_fields(again), _printed_fields(fresh)):
        assert np.array_equal(x, y, equal_nan=True)
