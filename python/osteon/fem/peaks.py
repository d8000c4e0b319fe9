"""FEM peaks off the section plane: the largest principal stress of a solved tet mesh's nodes,
and its worst case over the load's direction in the neighbourhood of a corner. Units: mm, MPa.

Nodal stresses are CalculiX's ``(N, 6)`` rows ``xx, yy, zz, xy, yz, zx`` (``solve.read_frd_stress``).

The corner neighbourhood (issue 33, defined here before any run on the models of
docs/validation.md; docs/validation.md "Corners (issue 33)"): osteon's governing stress at a
``notch`` section claims the peak at the corner, which lies on the fillet's surface between the
section's plane and its neighbour planes, not necessarily on the plane itself. So the FEM
counterpart of a section (centre c, unit normal n, interval h, equivalent radius r =
√(area / π)) is the largest value over the nodes of the **slab** ``|(x − c)·n| ≤ h`` (between
the two neighbour planes) that belong to the connected piece of the slab's tetrahedra which
holds the section's own cut (other body parts in the slab are left out, as on the plane), less
the nodes within r of the load point (the point load's local stress, Saint-Venant) and the nodes
within 2 r of the clamp (a crop's clamped cap). The value read at each node is the **largest
principal stress, worst over the direction of the force**: with the three unit load cases σ =
Σ f_k S_k, so max over |f| = F of the largest principal stress is
``F · max_{|v| = 1} ‖(vᵀ S_k v)_k‖`` (the largest principal stress in absolute value, since −f
flips the sign): the counterpart of osteon's worst case (F·d / W with W the minimum over bending
directions), and the quantity the stress concentration charts and the pre-registered studies
(``scripts/study_notch.py``, ``scripts/study_junction.py``) compare Kt × nominal with. σ_nn in the
same slab (the stress along the section's normal, the beam's own stress) is read too.
"""

from __future__ import annotations

import numpy as np


def stress_tensors(s):
    """(N, 6) CalculiX stress rows -> (N, 3, 3) symmetric tensors."""
    s = np.asarray(s, float)
    t = np.zeros((len(s), 3, 3))
    t[:, 0, 0], t[:, 1, 1], t[:, 2, 2] = s[:, 0], s[:, 1], s[:, 2]
    t[:, 0, 1] = t[:, 1, 0] = s[:, 3]
    t[:, 1, 2] = t[:, 2, 1] = s[:, 4]
    t[:, 0, 2] = t[:, 2, 0] = s[:, 5]
    return t


def max_principal(s):
    """The largest principal stress of each (N, 6) stress row, MPa."""
    return np.linalg.eigvalsh(stress_tensors(s))[:, -1]


def _sphere(n):
    """n roughly even unit vectors on the half sphere z >= 0 (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    z = k / n
    phi = k * np.pi * (3.0 - np.sqrt(5.0))
    rho = np.sqrt(1.0 - z * z)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


def worst_principal(S3, directions=1500, refine=True):
    """The largest principal stress in absolute value, worst over the force's direction, per
    node and per newton: ``max_{|f| = 1} max |eig(Σ f_k S_k)|`` for the three unit load cases
    ``S3`` (3, N, 6). Equals max over unit v of ‖(vᵀ S_k v)_k‖, evaluated on ``directions`` v
    of a half-sphere lattice, then (``refine``) polished at the nodes within 2 % of the best by
    a local search on v. Returns (N,) MPa/N."""
    S3 = np.asarray(S3, float)
    V = _sphere(int(directions))
    W = np.stack([V[:, 0] ** 2, V[:, 1] ** 2, V[:, 2] ** 2, 2 * V[:, 0] * V[:, 1],
                  2 * V[:, 1] * V[:, 2], 2 * V[:, 2] * V[:, 0]], axis=1)  # (D, 6)
    q = np.einsum("dj,knj->kdn", W, S3)  # (3, D, N): vᵀ S_k v
    val = np.sqrt((q * q).sum(0))  # (D, N)
    best = val.max(0)
    if refine and best.size:
        from scipy.optimize import minimize

        top = np.nonzero(best >= 0.98 * best.max())[0]
        arg = val.argmax(0)
        for i in top:
            T = stress_tensors(S3[:, i, :])

            def neg(x, T=T):
                v = x / np.linalg.norm(x)
                return -float(np.linalg.norm(np.einsum("i,kij,j->k", v, T, v)))

            res = minimize(neg, V[arg[i]], method="Nelder-Mead",
                           options={"xatol": 1e-7, "fatol": 1e-10 * best[i]})
            best[i] = max(best[i], -res.fun)
    return best


def slab_nodes(nodes, tets, center, normal, half_width, load_point=None, exclude_load=0.0,
               clamp=None, exclude_clamp=0.0):
    """The corner neighbourhood's node ids: nodes with |(x − center)·normal| ≤ half_width in the
    connected piece of the slab's tetrahedra (tets with a corner node in the slab, linked by
    shared nodes) that holds the tet of the slab nearest to ``center``; minus the nodes within
    ``exclude_load`` of ``load_point`` and, with ``clamp=(point, normal)``, the nodes within
    ``exclude_clamp`` of the clamp's plane."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nodes = np.asarray(nodes, float)
    c = np.asarray(center, float)
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    s = (nodes - c) @ n
    inside = np.abs(s) <= half_width
    T = tets[inside[tets[:, :4]].any(1)]
    if len(T) == 0:
        return np.zeros(0, int)
    rows = np.repeat(np.arange(len(T)), 4)
    inc = coo_matrix((np.ones(rows.size), (rows, T[:, :4].ravel())),
                     shape=(len(T), len(nodes))).tocsr()
    _, lab = connected_components(inc @ inc.T, directed=False)
    cen = nodes[T[:, :4]].mean(1)
    near = int(np.argmin(np.linalg.norm(cen - c, axis=1)))
    ids = np.unique(T[lab == lab[near]].ravel())
    keep = inside[ids]
    if load_point is not None and exclude_load > 0:
        keep &= np.linalg.norm(nodes[ids] - np.asarray(load_point, float), axis=1) > exclude_load
    if clamp is not None and exclude_clamp > 0:
        cp, cn = (np.asarray(x, float) for x in clamp)
        cn = cn / np.linalg.norm(cn)
        keep &= np.abs((nodes[ids] - cp) @ cn) > exclude_clamp
    return ids[keep]


def corner_peak(nodes, tets, S3, center, normal, half_width, force, load_point=None,
                exclude_load=0.0, clamp=None, exclude_clamp=0.0):
    """FEM's corner reading of a section (module docstring): a dict with ``peak_mpa`` (largest
    principal stress, worst force direction, over the slab's nodes, × ``force``), ``peak_at_mm``
    (where), ``peak_offset_mm`` (its signed distance from the plane along ``normal``), ``peak_angle_deg``
    (the angle between its principal direction and ``normal``, 0 = along the bone),
    ``sigma_nn_mpa`` (the largest |σ_nn| there, worst direction) and ``slab_nodes``. NaN values
    when the slab holds no node."""
    ids = slab_nodes(nodes, tets, center, normal, half_width, load_point, exclude_load, clamp,
                     exclude_clamp)
    nan = float("nan")
    if len(ids) == 0:
        return {"peak_mpa": nan, "peak_at_mm": [nan] * 3, "peak_offset_mm": nan,
                "peak_angle_deg": nan,
                "sigma_nn_mpa": nan, "slab_nodes": 0}
    from .sections import _sigma_nn

    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    S3 = np.asarray(S3, float)[:, ids, :]
    p = worst_principal(S3)
    k = int(np.argmax(p))
    g = _sigma_nn(S3, n)  # (3, M)
    x = nodes[ids[k]]
    # the peak's principal direction: v maximising ‖(vᵀS_k v)_k‖ at that node
    V = _sphere(4000)
    W = np.stack([V[:, 0] ** 2, V[:, 1] ** 2, V[:, 2] ** 2, 2 * V[:, 0] * V[:, 1],
                  2 * V[:, 1] * V[:, 2], 2 * V[:, 2] * V[:, 0]], axis=1)
    v = V[int(np.argmax(np.linalg.norm(W @ S3[:, k, :].T, axis=1)))]
    return {
        "peak_angle_deg": float(np.degrees(np.arccos(min(1.0, abs(float(v @ n)))))),
        "peak_mpa": float(p[k] * force),
        "peak_at_mm": [float(v) for v in x],
        "peak_offset_mm": float((x - np.asarray(center, float)) @ n),
        "sigma_nn_mpa": float(np.linalg.norm(g, axis=0).max() * force),
        "slab_nodes": len(ids),
    }
