"""The FEM cross-check of osteon's section stresses (:func:`cross_check`) and its report.
Units: mm, N, MPa."""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field

import numpy as np

from .crop import crop_mesh
from .mesh import tet_mesh
from .peaks import corner_peak
from .sections import section_cut
from .solve import solve


@dataclass
class FemSection:
    """One tested section; stresses in MPa for the force ``force`` N."""

    index: int
    bone: int
    center: np.ndarray
    normal: np.ndarray
    load_point: np.ndarray
    moment_arm_mm: float
    axial_arm_mm: float
    osteon_stress_mpa: float
    fem_stress_mpa: float
    cut_points: int
    extra: dict = field(default_factory=dict)

    @property
    def rel_error(self) -> float:
        """(osteon − FEM) / FEM."""
        return (self.osteon_stress_mpa - self.fem_stress_mpa) / self.fem_stress_mpa

    def as_dict(self):
        return {
            "section": int(self.index),
            "bone": int(self.bone),
            "center_mm": [float(x) for x in self.center],
            "normal": [float(x) for x in self.normal],
            "load_point_mm": [float(x) for x in self.load_point],
            "moment_arm_mm": float(self.moment_arm_mm),
            "axial_arm_mm": float(self.axial_arm_mm),
            "osteon_stress_mpa": float(self.osteon_stress_mpa),
            "fem_stress_mpa": float(self.fem_stress_mpa),
            "rel_error": float(self.rel_error),
            # osteon's stress with the arm measured along the section normal only: the lower
            # end of what beam theory predicts for an oblique load point (see docs/validation.md)
            "osteon_axial_arm_stress_mpa": float(
                self.osteon_stress_mpa * self.axial_arm_mm / self.moment_arm_mm
            )
            if self.moment_arm_mm > 0
            else None,
            "cut_points": int(self.cut_points),
            **{k: v for k, v in self.extra.items() if not k.startswith("field_")},
        }


@dataclass
class FemReport:
    force_n: float
    mode: str = "crop"
    sections: list = field(default_factory=list)
    nodes: int = 0
    elements: int = 0
    mesh_size_mm: float = 0.0
    hold_point_mm: np.ndarray | None = None
    hold_radius_mm: float = 0.0
    mesh_seconds: float = 0.0
    solve_seconds: float = 0.0
    failed: list = field(default_factory=list)

    @property
    def errors(self):
        return np.array([abs(s.rel_error) for s in self.sections])

    @property
    def median_error(self):
        return float(np.median(self.errors)) if self.sections else float("nan")

    @property
    def worst_error(self):
        return float(np.max(self.errors)) if self.sections else float("nan")

    def fail(self, k, section, reason):
        """Lists the k-th tested section (a section dict) as failed, with the reason."""
        self.failed.append({"index": int(section.get("index", k)),
                            "bone": int(section.get("bone", -1)), "reason": reason})

    def as_dict(self):
        return {
            "force_n": self.force_n,
            "mode": self.mode,
            "nodes": self.nodes,
            "elements": self.elements,
            "mesh_size_mm": self.mesh_size_mm,
            "hold_point_mm": None
            if self.hold_point_mm is None
            else [float(x) for x in self.hold_point_mm],
            "hold_radius_mm": self.hold_radius_mm,
            "mesh_seconds": self.mesh_seconds,
            "solve_seconds": self.solve_seconds,
            # null when no section could be checked (JSON has no NaN)
            "median_abs_rel_error": self.median_error if self.sections else None,
            "worst_abs_rel_error": self.worst_error if self.sections else None,
            "sections": [s.as_dict() for s in self.sections],
            "failed_sections": self.failed,
        }


def load_nodes(nodes, surface_nodes, point, radius):
    """Surface nodes within ``radius`` of ``point`` (at least the nearest one)."""
    d = np.linalg.norm(nodes[surface_nodes] - point, axis=1)
    sel = surface_nodes[d <= radius]
    if len(sel) == 0:
        sel = surface_nodes[[np.argmin(d)]]
    return sel


def surface_node_ids(tets):
    """Nodes on the boundary faces of a C3D10 mesh (corner and mid-side nodes)."""
    # faces by corner triples; boundary faces appear once
    fc = np.array([[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]])
    fm = np.array([[4, 5, 6], [4, 8, 7], [5, 9, 8], [6, 9, 7]])
    F = tets[:, fc].reshape(-1, 3)
    M = tets[:, fm].reshape(-1, 3)
    key = np.sort(F, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    b = cnt[inv.ravel()] == 1
    return np.unique(np.concatenate([F[b].ravel(), M[b].ravel()]))


def find_load_point(vertices, center, normal, moment_arm):
    """The mesh vertex at distance ``moment_arm`` from ``center`` (osteon's load point: the
    downstream point farthest from the section centroid), preferring the downstream side."""
    d = np.linalg.norm(vertices - center, axis=1)
    side = (vertices - center) @ normal
    close = np.abs(d - moment_arm) <= 1e-6 * max(moment_arm, 1e-9) + 1e-9
    cand = np.nonzero(close & (side > 0))[0]
    if len(cand) == 0:
        cand = np.nonzero(close)[0]
    if len(cand) == 0:
        cand = [int(np.argmin(np.abs(d - moment_arm)))]
    return vertices[cand[0]]


#: what a section dict passes through to its report row (pick.py's keys)
_PASSED = ("tier", "slenderness", "end_distance", "nodes", "elements", "surface", "clamp_distance",
           "junction", "osteon_cut_stress", "nominal_stress", "stress_concentration",
           "notch_radius", "flags", "interval", "area")


def _corner_reading(s, nodes, tets, S3, force, c, n, lp):
    """FEM's corner reading (peaks.py's definition) in the slab of ±``s["interval"]`` mm."""
    area = float(s.get("area") or 0.0)
    r = float(np.sqrt(area / np.pi)) if area > 0 else 0.0
    got = corner_peak(nodes, tets, S3, c, n, float(s["interval"]), force, load_point=lp,
                      exclude_load=r, clamp=s.get("clamp_plane"), exclude_clamp=2.0 * r)
    return {
        "fem_corner_peak_mpa": got["peak_mpa"],
        "fem_corner_peak_at_mm": got["peak_at_mm"],
        "fem_corner_offset_mm": got["peak_offset_mm"],
        "fem_corner_angle_deg": got["peak_angle_deg"],
        "fem_corner_sigma_nn_mpa": got["sigma_nn_mpa"],
        "corner_slab_nodes": got["slab_nodes"],
    }


def _finish_section(rep, k, s, nodes, tets, S3, force, keep_field=False):
    c = np.asarray(s["center"], float)
    n = np.asarray(s["normal"], float)
    n = n / np.linalg.norm(n)
    P, G = section_cut(nodes, tets, c, n, S3)
    fem = float(np.max(np.linalg.norm(G, axis=0))) * force if G.shape[1] else float("nan")
    lp = np.asarray(s["load_point"], float)
    extra = {k2: s[k2] for k2 in _PASSED if k2 in s}
    if s.get("interval"):
        extra.update(_corner_reading(s, nodes, tets, S3, force, c, n, lp))
    rep.sections.append(
        FemSection(
            index=int(s.get("index", k)),
            bone=int(s.get("bone", -1)),
            center=c,
            normal=n,
            load_point=lp,
            moment_arm_mm=float(s.get("moment_arm", np.linalg.norm(lp - c))),
            axial_arm_mm=float(abs((lp - c) @ n)),
            osteon_stress_mpa=float(s["osteon_stress"]),
            fem_stress_mpa=fem,
            cut_points=int(G.shape[1]),
            extra=extra,
        )
    )
    if keep_field:
        rep.sections[-1].extra.update(field_points_mm=P, field_mpa_per_n=G)


def _unit_cases(nodes, tets, point, radius):
    surf = surface_node_ids(tets)
    ids = load_nodes(nodes, surf, point, radius)
    cases = []
    for d in range(3):
        fv = np.zeros((len(ids), 3))
        fv[:, d] = 1.0 / len(ids)
        cases.append((ids, fv))
    return cases


@dataclass
class _Run:
    """What every FEM solve of one cross-check shares: the model (mm), its sections, the load (N),
    the material (MPa) and where and how to run."""

    V: np.ndarray
    F: np.ndarray
    sections: list
    force: float
    workdir: str
    threads: int
    young: float
    poisson: float
    progress: object
    fine_factor: float
    keep_field: bool = False
    mesh_timeout_s: float = 600.0  # gmsh stopped after this per meshing attempt


def cross_check(
    vertices,
    faces,
    sections,
    force=20.0,
    hold_point=None,
    hold_radius=None,
    mesh_size=None,
    workdir=None,
    threads=2,
    young=3500.0,
    poisson=0.35,
    hold_plane=None,
    progress=None,
    keep_files=False,
    fine_factor=3.0,
    mode="crop",
    clamp_distance=4.0,
    keep_field=False,
    mesh_timeout_s=None,
):
    """Run the FEM cross-check; returns a :class:`FemReport`.

    ``sections``: list of dicts with ``center``, ``normal``, ``load_point`` (mm),
    ``osteon_stress`` (MPa at ``force``) and optionally ``index``, ``bone``, ``moment_arm`` and
    ``area`` (mm², r = √(area/π)).

    ``mode="crop"`` (default): one small model per section — the mesh is cut by a plane
    ``clamp_distance`` × r upstream of the section, the cut is capped, the piece holding the
    section (everything downstream of it plus that stub) is kept, its surface is subdivided to
    edges ≤ r/``fine_factor`` (same geometry) and the capped face is clamped. The downstream part
    is a free body loaded only at the load point, so the section carries the same moment as in
    the whole model held at its root (statics), and the clamp is 2 diameters away
    (Saint-Venant); the small model keeps every run to seconds and avoids re-meshing the whole
    surface, which gmsh cannot do for every real model.

    ``mode="full"``: the whole model is re-meshed (element size ``mesh_size``, default 1/40 of
    the diagonal, refined to r/``fine_factor`` within 3 r of each section) and held at all nodes
    within ``hold_radius`` mm of ``hold_point`` (default radius: 1.25 × the depth of the point
    below the surface), or, with ``hold_plane=(point, normal)``, at all nodes on the negative
    side of that plane.

    ``keep_field=True``: each section's ``extra["field_points_mm"]`` (P, 3) holds the points where
    the plane cuts the tetrahedra and ``extra["field_mpa_per_n"]`` (3, P) σ_nn there per newton
    of force along x, y and z (MPa/N): the stress field on the plane, not only its peak.

    ``mesh_timeout_s``: gmsh is stopped after this many seconds per meshing attempt (default:
    120 s in crop mode, where a section's small model meshes in seconds and the next clamp
    distance or the original triangles are tried instead; 600 s in full mode). A section whose
    every attempt fails, or whose CalculiX run fails, is listed in ``failed`` with the reason;
    the others are still checked.
    """
    V = np.asarray(vertices, float)
    F = np.asarray(faces)
    if len(sections) == 0:
        raise ValueError("FEM cross-check: no sections to test")
    ext = float(np.linalg.norm(V.max(0) - V.min(0)))
    own_dir = workdir is None
    wd = tempfile.mkdtemp(prefix="osteon_fem_") if own_dir else workdir
    os.makedirs(wd, exist_ok=True)
    rep = FemReport(force_n=float(force), mode=mode)
    run = _Run(V, F, sections, force, wd, threads, young, poisson, progress, fine_factor,
               keep_field, mesh_timeout_s or (120.0 if mode == "crop" else 600.0))
    try:
        if mode == "crop":
            _cross_check_crop(rep, run, clamp_distance)
        elif mode == "full":
            _cross_check_full(rep, run, hold_point, hold_radius, hold_plane, mesh_size, ext)
        else:
            raise ValueError(f"FEM mode must be 'crop' or 'full', got {mode!r}")
        return rep
    finally:
        if own_dir and not keep_files:
            shutil.rmtree(wd, ignore_errors=True)


def _cross_check_crop(rep, run: _Run, clamp_distance):
    V, F, sections, wd, threads, progress = (run.V, run.F, run.sections, run.workdir, run.threads,
                                             run.progress)
    fine_factor = run.fine_factor
    for k, sec in enumerate(sections):
        c = np.asarray(sec["center"], float)
        n = np.asarray(sec["normal"], float)
        n = n / np.linalg.norm(n)
        lp = np.asarray(sec["load_point"], float)
        if (lp - c) @ n < 0:  # keep the side holding the load point
            n = -n
        area = float(sec.get("area") or 0.0)
        r = np.sqrt(area / np.pi) if area > 0 else 0.02 * float(np.ptp(V, axis=0).max())
        sub = os.path.join(wd, f"s{k}")
        os.makedirs(sub, exist_ok=True)
        t0 = time.perf_counter()
        h = r / fine_factor
        nodes = None
        errors = []
        # gmsh fails on some cut surfaces: try a few clamp distances, re-meshed surface first,
        # then the original triangles
        for cd in (clamp_distance, 1.25 * clamp_distance, 0.8 * clamp_distance):
            origin = c - cd * r * n
            if not np.any((V - origin) @ n < 0):
                errors.append(f"the model ends within {cd:g} r upstream of the section: no room "
                              "for the clamp")
                continue
            try:
                Vc, Fc = crop_mesh(V, F, origin, n, c)
            except ValueError as e:
                errors.append(str(e))
                continue
            coarse = max(min(4.0 * h, 0.1 * float(np.ptp(Vc, axis=0).max())), h)
            if progress:
                progress(f"section {k + 1}/{len(sections)}: meshing")
            for remesh in (True, False):
                try:
                    nodes, tets = tet_mesh(
                        Vc,
                        Fc,
                        coarse,
                        sub,
                        threads=threads,
                        refine=[(c, 3.0 * r, h)] if remesh else (),
                        remesh=remesh,
                        timeout=run.mesh_timeout_s,
                    )
                    sec = dict(
                        sec,
                        surface="re-meshed" if remesh else "original triangles",
                        clamp_distance=cd,
                    )
                    break
                except RuntimeError as e:
                    errors.append(str(e)[:120])
            if nodes is not None:
                break
        if nodes is None:
            rep.fail(k, sec, "; ".join(errors[-2:]))
            rep.mesh_seconds += time.perf_counter() - t0
            continue
        rep.mesh_seconds += time.perf_counter() - t0
        rep.nodes += len(nodes)
        rep.elements += len(tets)
        fixed = np.nonzero((nodes - origin) @ n <= 1e-6 * r + 1e-9)[0]
        if len(fixed) < 3:
            rep.fail(k, sec, f"the clamp cap at {cd:g} r holds {len(fixed)} nodes")
            continue
        cases = _unit_cases(nodes, tets, lp, 0.75 * h)
        if progress:
            progress(f"section {k + 1}/{len(sections)}: solving {len(nodes)} nodes")
        t1 = time.perf_counter()
        try:
            S = solve(nodes, tets, fixed, cases, sub, young=run.young, poisson=run.poisson,
                      threads=threads)
        except RuntimeError as e:
            rep.fail(k, sec, str(e)[:200])
            continue
        finally:
            rep.solve_seconds += time.perf_counter() - t1
        sec = dict(sec, nodes=len(nodes), elements=len(tets), clamp_plane=(origin, n))
        _finish_section(rep, k, sec, nodes, tets, S, run.force, run.keep_field)
        rep.mesh_size_mm = max(rep.mesh_size_mm, float(h))


def _cross_check_full(rep, run: _Run, hold_point, hold_radius, hold_plane, mesh_size, ext):
    V, F, sections, wd, threads, progress = (run.V, run.F, run.sections, run.workdir, run.threads,
                                             run.progress)
    fine_factor = run.fine_factor
    if mesh_size is None:
        mesh_size = ext / 40.0
    refine = []
    for sec in sections:
        if sec.get("area"):
            r_eq = float(np.sqrt(float(sec["area"]) / np.pi))
            h = float(np.clip(r_eq / fine_factor, mesh_size / 12.0, mesh_size))
            refine.append((np.asarray(sec["center"], float), 3.0 * r_eq, h))
    t0 = time.perf_counter()
    for attempt in range(4):  # coarse re-meshing of a detailed surface can fail: refine
        try:
            nodes, tets = tet_mesh(V, F, mesh_size, wd, threads=threads, refine=refine,
                                   timeout=run.mesh_timeout_s)
            break
        except RuntimeError:
            if attempt == 3:
                raise
            mesh_size *= 0.7
            refine = [(c, r, min(h, mesh_size)) for c, r, h in refine]
    rep.mesh_size_mm = float(mesh_size)
    rep.mesh_seconds = time.perf_counter() - t0
    rep.nodes, rep.elements = len(nodes), len(tets)
    if hold_plane is not None:
        hp, hn = (np.asarray(x, float) for x in hold_plane)
        fixed = np.nonzero((nodes - hp) @ hn <= 1e-6 * ext)[0]
    else:
        hold_point = np.asarray(hold_point, float)
        if hold_radius is None:
            # depth of the held point below the surface (nearest surface vertex)
            depth = float(np.min(np.linalg.norm(V - hold_point, axis=1)))
            hold_radius = max(1.25 * depth, 2.0 * mesh_size)
        fixed = np.nonzero(np.linalg.norm(nodes - hold_point, axis=1) <= hold_radius)[0]
        rep.hold_point_mm = hold_point
        rep.hold_radius_mm = float(hold_radius)
    # one set of 3 unit load cases per distinct load point
    lps = np.array([np.asarray(s["load_point"], float) for s in sections]).reshape(-1, 3)
    uniq, which = np.unique(np.round(lps, 9), axis=0, return_inverse=True)
    which = which.ravel()
    cases = []
    for p in uniq:
        cases += _unit_cases(nodes, tets, p, 0.75 * mesh_size)
    if progress:
        progress(f"solving {len(cases)} load cases on {len(nodes)} nodes")
    t1 = time.perf_counter()
    S = solve(nodes, tets, fixed, cases, wd, young=run.young, poisson=run.poisson,
              threads=threads)
    rep.solve_seconds = time.perf_counter() - t1
    for k, s in enumerate(sections):
        j = which[k]
        _finish_section(rep, k, s, nodes, tets, S[3 * j : 3 * j + 3], run.force, run.keep_field)
