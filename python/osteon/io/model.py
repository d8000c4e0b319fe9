"""The :class:`RiggedModel` dataclass shared by all readers, and the joint-tree → bone mapping.

Units: whatever the file uses until :meth:`RiggedModel.scaled_to` is called; after that,
millimetres of the printed object.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp


@dataclass
class RiggedModel:
    """A triangle mesh with a skeleton and skinning weights.

    Attributes
    ----------
    vertices : (V, 3) float64 — positions (mm after scaling).
    faces : (F, 3) int32 — triangle vertex indices, 0-based.
    heads, tails : (B, 3) float64 — bone head / tail positions, same units as ``vertices``.
    parents : (B,) int64 — parent bone index, -1 for a root bone.
    bone_names : list of B str.
    weights : scipy.sparse.csr_matrix (V, B) or None — rows sum to 1 (rows of unweighted
        vertices are all zero).
    scale : float — factor applied to the file's coordinates (mm per file unit), 1.0 if unscaled.
    source : str — path of the file the model was read from.
    notes : list of str — what the reader did (sidecar files used, bones dropped).
    warnings : list of str — what the user must hear about (bad weights repaired, bones
        without weight, a skin missing); the CLI prints them, batch lists them, reports keep
        them.
    weight_findings : dict — what the weights in the file held before cleaning
        (:func:`weight_findings`); empty when the file had no weights.
    """

    vertices: np.ndarray
    faces: np.ndarray
    heads: np.ndarray
    tails: np.ndarray
    parents: np.ndarray
    bone_names: list[str]
    weights: sp.csr_matrix | None = None
    scale: float = 1.0
    source: str = ""
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    weight_findings: dict = field(default_factory=dict)

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)
        self.heads = np.ascontiguousarray(self.heads, dtype=np.float64).reshape(-1, 3)
        self.tails = np.ascontiguousarray(self.tails, dtype=np.float64).reshape(-1, 3)
        self.parents = np.ascontiguousarray(self.parents, dtype=np.int64).reshape(-1)
        self.bone_names = [printable(n) for n in self.bone_names]
        validate_model(self)

    @property
    def n_bones(self) -> int:
        return len(self.parents)

    @property
    def skeleton(self):
        """The skeleton as an ``osteon.Skeleton`` (built on first use)."""
        import osteon

        return osteon.Skeleton(self.heads, self.tails, self.parents, names=list(self.bone_names))

    def scaled_to(self, height_mm: float | None = 120.0, axis: str | int | None = None):
        """Return a copy scaled uniformly (about the origin) so that the model's size is
        ``height_mm`` millimetres.

        The size is the largest bounding-box extent of the mesh, or its extent along ``axis``
        (0/1/2 or 'x'/'y'/'z') if given. ``height_mm=None`` returns the model unchanged.
        """
        if height_mm is None:
            return self
        if not np.isfinite(height_mm) or height_mm <= 0:
            raise ValueError(f"height_mm must be a positive number of millimetres, got {height_mm}")
        ext = self.vertices.max(axis=0) - self.vertices.min(axis=0)
        if axis is None or axis == "longest":
            size = float(ext.max())
        else:
            ax = {"x": 0, "y": 1, "z": 2}.get(axis, axis)
            if ax not in (0, 1, 2):
                raise ValueError(f"axis must be one of x, y, z or longest, got {axis!r}")
            size = float(ext[ax])
        if size <= 0:
            raise ValueError("mesh has zero size along the requested axis; cannot scale it")
        s = float(height_mm) / size
        return replace(
            self,
            vertices=self.vertices * s,
            heads=self.heads * s,
            tails=self.tails * s,
            scale=self.scale * s,
            notes=list(self.notes),
            warnings=list(self.warnings),
        )


def printable(text) -> str:
    """``text`` as a str that encodes to UTF-8: undecodable bytes of a file name
    (surrogate escapes) or a joint name become U+FFFD (names go to the engine, JSON and HTML)."""
    if isinstance(text, bytes):
        return text.decode("utf-8", "replace")
    text = str(text)
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        pass
    try:  # bytes of a file name that are not UTF-8 (os.fsdecode's surrogate escapes)
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
    except UnicodeEncodeError:  # other lone surrogates (a JSON "\ud800")
        return text.encode("utf-8", "replace").decode("utf-8")


def weight_findings(rows, values, n_vertices: int) -> dict:
    """What skinning weights given as triplets (vertex ``rows``, ``values``) hold before they
    are cleaned: ``nonfinite`` and ``negative`` entries (set to 0), ``rows_far_from_1`` (vertex
    rows with weight whose sum is off 1 by more than 1 %, rescaled to 1) with their
    ``row_sum_min`` / ``row_sum_max``, ``unweighted_vertices`` (no positive weight)."""
    rows = np.asarray(rows, dtype=np.int64).reshape(-1)
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    finite = np.isfinite(values)
    good = np.where(finite & (values > 0), values, 0.0)
    sums = np.bincount(rows, good, minlength=n_vertices)[:n_vertices]
    has = sums > 0
    far = has & (np.abs(sums - 1.0) > 1e-2)
    out = {"nonfinite": int(np.count_nonzero(~finite)),
           "negative": int(np.count_nonzero(finite & (values < 0))),
           "rows_far_from_1": int(np.count_nonzero(far)),
           "unweighted_vertices": int(np.count_nonzero(~has)),
           "vertices": int(n_vertices)}
    if out["rows_far_from_1"]:
        out["row_sum_min"] = float(sums[far].min())
        out["row_sum_max"] = float(sums[far].max())
    return out


def weight_warnings(found: dict, source: str) -> list[str]:
    """The warnings :func:`weight_findings` calls for (empty when the weights were clean)."""
    out = []
    bad = []
    if found.get("nonfinite"):
        bad.append(f"{found['nonfinite']} NaN/inf")
    if found.get("negative"):
        bad.append(f"{found['negative']} negative")
    if bad:
        out.append(f"{source}: weights: {' and '.join(bad)} entries set to 0")
    if found.get("rows_far_from_1"):
        out.append(f"{source}: weights: {found['rows_far_from_1']} of {found['vertices']} vertex "
                   f"rows summed to {found['row_sum_min']:.3g} .. {found['row_sum_max']:.3g}, "
                   "not 1; rescaled to sum to 1")
    n_un = found.get("unweighted_vertices", 0)
    if n_un and n_un < found.get("vertices", 0):
        out.append(f"{source}: weights: {n_un} of {found['vertices']} vertices carry no weight "
                   "(they follow no bone)")
    return out


def unweighted_bones(weights, names) -> list[str]:
    """Names of the bones whose weight column is all zero (nothing of the mesh follows them)."""
    col = np.asarray(abs(weights).sum(axis=0)).ravel()
    return [names[b] for b in np.flatnonzero(col == 0)]


def bare_bones_warning(bare: list[str], source: str) -> list[str]:
    """The warning that names bones without any weight (``[]`` when there are none)."""
    if not bare:
        return []
    text = (f"{source}: {len(bare)} bone(s) without any weight (nothing of the mesh follows "
            f"them): {', '.join(bare[:10])}")
    return [text]


def clean_weights(rows, values, n_vertices: int, source: str):
    """Findings and warnings for triplet weights; raises ValueError when no usable weight is
    left (every entry NaN, negative or 0), where nothing sensible can be done."""
    found = weight_findings(rows, values, n_vertices)
    if n_vertices and found["unweighted_vertices"] == n_vertices and len(np.ravel(values)):
        raise ValueError(f"{source}: weights hold no usable value ({found['nonfinite']} NaN/inf, "
                         f"{found['negative']} negative, the rest 0)")
    return found, weight_warnings(found, source)


def dense_weights(w: np.ndarray, source: str, names):
    """A dense (V, B) weight matrix from a file → ``(csr weights, findings, warnings)``:
    NaN/inf/negative entries set to 0, non-empty rows rescaled to sum to 1 (as
    :func:`normalize_rows`), what was found in words (:func:`weight_findings`), bones without
    weight named. One pass over the dense array (no sparse round trips: the read of a 13 k-face
    model's weights in ~1 ms)."""
    w = np.asarray(w, dtype=np.float64)
    V = w.shape[0]
    finite = np.isfinite(w)
    nonfinite = int(w.size - np.count_nonzero(finite))
    negative = int(np.count_nonzero(w < 0))
    # the usual file: nothing to clean, and the array is the reader's own (no copy)
    clean = np.where(finite & (w > 0), w, 0.0) if nonfinite or negative else w
    sums = clean.sum(axis=1)
    has = sums > 0
    far = has & (np.abs(sums - 1.0) > 1e-2)
    found = {"nonfinite": nonfinite, "negative": negative,
             "rows_far_from_1": int(np.count_nonzero(far)),
             "unweighted_vertices": int(V - np.count_nonzero(has)), "vertices": int(V)}
    if found["rows_far_from_1"]:
        found["row_sum_min"] = float(sums[far].min())
        found["row_sum_max"] = float(sums[far].max())
    if V and not has.any() and w.size:
        raise ValueError(f"{source}: weights hold no usable value ({found['nonfinite']} NaN/inf, "
                         f"{found['negative']} negative, the rest 0)")
    warns = weight_warnings(found, source)
    rows, cols = np.nonzero(clean)  # row-major: CSR order, no sort needed
    data = clean[rows, cols] / sums[rows]
    indptr = np.zeros(V + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=V), out=indptr[1:])
    out = sp.csr_matrix((data, cols, indptr), shape=w.shape)
    colsum = np.bincount(cols, data, minlength=w.shape[1])
    warns += bare_bones_warning([names[b] for b in np.flatnonzero(colsum == 0)], source)
    return out, found, warns


def validate_model(m: RiggedModel) -> None:
    """Raise ValueError naming the problem if the arrays do not fit together."""
    V, B = len(m.vertices), len(m.parents)
    if V == 0 or len(m.faces) == 0:
        raise ValueError(f"{m.source or 'model'}: empty mesh ({V} vertices, {len(m.faces)} faces)")
    if not np.all(np.isfinite(m.vertices)):
        raise ValueError(f"{m.source or 'model'}: vertex coordinates contain NaN or inf")
    if m.faces.min() < 0 or m.faces.max() >= V:
        raise ValueError(f"{m.source or 'model'}: face index out of range 0..{V - 1}")
    if len(m.heads) != B or len(m.tails) != B or len(m.bone_names) != B:
        raise ValueError(
            f"{m.source or 'model'}: skeleton arrays disagree: {len(m.heads)} heads, "
            f"{len(m.tails)} tails, {B} parents, {len(m.bone_names)} names"
        )
    check_tree(m.parents, m.source or "model", "bone", m.bone_names)
    if m.weights is not None:
        w = m.weights
        if w.shape != (V, B):
            raise ValueError(
                f"{m.source or 'model'}: weights have shape {w.shape[0]}x{w.shape[1]} but the "
                f"mesh has {V} vertices and the skeleton {B} bones"
            )


def check_tree(parents, source: str, what: str = "bone", names=None) -> np.ndarray:
    """Check a parent array (-1 = root) before anything walks it: every index in -1..N-1 and
    no cycle. Raises ValueError naming ``source`` and the nodes (``names`` or indices); returns
    the parents as int64. O(N): each node is visited once."""
    p = np.asarray(parents).reshape(-1)
    if p.dtype.kind not in "iu":
        raise ValueError(f"{source}: {what} parents must be integers, got {p.dtype}")
    p = p.astype(np.int64)
    n = len(p)

    def label(k):
        return repr(names[k]) if names is not None and k < len(names) else str(k)

    bad = np.flatnonzero((p < -1) | (p >= n))
    if len(bad):
        k = int(bad[0])
        raise ValueError(f"{source}: {what} {label(k)} has parent {int(p[k])}, outside "
                         f"-1..{n - 1} ({len(bad)} such {what}s)")
    state = np.zeros(n, dtype=np.int8)  # 0 not seen, 1 on the current chain, 2 checked
    for start in range(n):
        chain, k = [], start
        while k >= 0 and state[k] == 0:
            state[k] = 1
            chain.append(k)
            k = int(p[k])
        if k >= 0 and state[k] == 1:
            loop = chain[chain.index(k):]
            shown = " -> ".join(label(q) for q in loop[:8]) + (" -> …" if len(loop) > 8 else "")
            raise ValueError(f"{source}: the {what} parents form a cycle ({len(loop)} {what}s: "
                             f"{shown} -> {label(k)})")
        state[chain] = 2
    return p


def normalize_rows(w) -> sp.csr_matrix:
    """CSR copy of ``w`` with negative/NaN entries dropped and each non-empty row summing to 1."""
    w = sp.csr_matrix(w, dtype=np.float64)
    w.data[~np.isfinite(w.data)] = 0.0
    w.data[w.data < 0] = 0.0
    w.eliminate_zeros()
    s = np.asarray(w.sum(axis=1)).ravel()
    inv = np.zeros_like(s)
    inv[s > 0] = 1.0 / s[s > 0]
    w = sp.diags(inv) @ w
    return sp.csr_matrix(w)


def bones_from_joint_tree(
    positions: np.ndarray,
    joint_parent: np.ndarray,
    joint_names: list[str],
    degenerate: np.ndarray | None = None,
    rel_eps: float = 1e-6,
):
    """Turn a joint tree into bones and a joint → bone weight map.

    Mapping (used for RigNet ``_rig.txt`` and glTF skins, where weights belong to joints):

    * one bone per tree edge parent joint → child joint, head at the parent, tail at the child;
    * an edge whose child coincides with its parent (distance below ``rel_eps`` × joint
      bounding-box diagonal, or flagged in ``degenerate``, e.g. RigNet ``root_dup_*`` joints) is
      not a bone: the child is merged into the parent, and the child's own outgoing bones start
      at the child's position;
    * the bone's parent is the bone that ends at its head joint (through merged joints),
      -1 if none;
    * a joint's skin weight drives the region *after* the joint (the way FBX/glTF/Blender skins
      work: a joint's transform moves the limb segment from that joint to its child), so the
      weight of joint j goes to the bone(s) leaving j; if several bones leave j, each vertex's
      weight goes to the nearest of those bones; a leaf joint (no bone leaves it) gives its
      weight to the bone ending at it.

    Returns ``heads, tails, parents, names, joint_targets`` where ``joint_targets[j]`` is the list
    of bone indices that joint j's weight may go to.
    """
    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    J = len(P)
    jp = check_tree(joint_parent, "joint tree", "joint", joint_names)
    if len(jp) != J:
        raise ValueError(f"joint tree: {J} joint positions but {len(jp)} parents")
    diag = float(np.linalg.norm(P.max(0) - P.min(0))) if J else 0.0
    eps = rel_eps * max(diag, 1e-300)
    if degenerate is None:
        degenerate = np.zeros(J, dtype=bool)
    # An edge p -> j is degenerate when j is flagged or coincides with p.
    degen_edge = np.zeros(J, dtype=bool)
    for j in range(J):
        p = jp[j]
        if p >= 0 and (degenerate[j] or np.linalg.norm(P[j] - P[p]) <= eps):
            degen_edge[j] = True
    children = [[] for _ in range(J)]
    for j in range(J):
        if jp[j] >= 0:
            children[jp[j]].append(j)
    # bones: non-degenerate edges
    edge_child = [j for j in range(J) if jp[j] >= 0 and not degen_edge[j]]
    bone_of_child = {j: b for b, j in enumerate(edge_child)}

    def outgoing(j):
        """Non-degenerate edges leaving j or joints merged into j."""
        out, stack = [], [j]
        while stack:
            k = stack.pop()
            for c in children[k]:
                if degen_edge[c]:
                    stack.append(c)
                else:
                    out.append(bone_of_child[c])
        return out

    def incoming(j):
        """The bone ending at j (following merged joints up)."""
        k = j
        while k >= 0 and degen_edge[k]:
            k = jp[k]
        if k >= 0 and jp[k] >= 0:
            return bone_of_child[k]
        return -1

    heads = np.array([P[jp[c]] for c in edge_child]).reshape(-1, 3)
    tails = np.array([P[c] for c in edge_child]).reshape(-1, 3)
    parents = np.array([incoming(jp[c]) for c in edge_child], dtype=np.int64)
    names = []
    for c in edge_child:
        start = jp[c]
        if len(outgoing(start)) == 1:
            names.append(joint_names[start])
        else:
            names.append(f"{joint_names[start]}->{joint_names[c]}")
    if len(set(names)) != len(names):  # fall back to edge names, always unique in a tree
        names = [f"{joint_names[jp[c]]}->{joint_names[c]}" for c in edge_child]
    targets = []
    for j in range(J):
        # a dup/merged joint drives only its own outgoing bones
        out = outgoing(j)
        if out:
            targets.append(out)
        else:
            b = incoming(j)
            targets.append([b] if b >= 0 else [])
    return heads, tails, parents, names, targets


def joint_weights_to_bones(
    vertices: np.ndarray,
    rows: np.ndarray,
    joints: np.ndarray,
    values: np.ndarray,
    targets: list[list[int]],
    heads: np.ndarray,
    tails: np.ndarray,
    joint_names: list[str] | None = None,
) -> sp.csr_matrix:
    """Map per-joint weights (COO triplets) to per-bone weights with ``targets`` from
    :func:`bones_from_joint_tree`; a joint with several target bones gives each vertex's weight
    to the nearest of them (distance from the vertex to the bone segment)."""
    V, B = len(vertices), len(heads)
    rows = np.asarray(rows, dtype=np.int64)
    joints = np.asarray(joints, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    out_bone = np.full(len(rows), -1, dtype=np.int64)
    for j in np.unique(joints):
        sel = np.nonzero(joints == j)[0]
        tg = targets[j]
        if not tg:
            name = joint_names[j] if joint_names else str(j)
            raise ValueError(f"joint {name!r} has skin weights but no bone starts or ends at it")
        if len(tg) == 1:
            out_bone[sel] = tg[0]
            continue
        x = vertices[rows[sel]]
        d = np.empty((len(sel), len(tg)))
        for k, b in enumerate(tg):
            a, e = heads[b], tails[b]
            ab = e - a
            t = np.clip(((x - a) @ ab) / max(ab @ ab, 1e-300), 0.0, 1.0)
            d[:, k] = np.linalg.norm(x - (a + t[:, None] * ab), axis=1)
        out_bone[sel] = np.asarray(tg)[np.argmin(d, axis=1)]
    w = sp.coo_matrix((values, (rows, out_bone)), shape=(V, B)).tocsr()
    w.sum_duplicates()
    return normalize_rows(w)


def finish_joint_rig(heads, tails, parents, names, weights, info: dict, source: str):
    """The last step of a joint-rig reader (glTF, RigNet): root bones without weight left out
    (a note in ``info``), the bones still without weight named in a warning. Returns
    ``heads, tails, parents, names, weights``."""
    heads, tails, parents, names, weights, dropped = drop_unweighted_roots(
        heads, tails, parents, names, weights)
    if dropped:
        info["notes"].append(f"root bones without weight left out: {', '.join(dropped)}")
    info["warnings"].extend(bare_bones_warning(unweighted_bones(weights, names), source))
    return heads, tails, parents, names, weights


def drop_unweighted_roots(heads, tails, parents, names, weights):
    """Remove root bones that carry no skin weight at all (e.g. a glTF ``Root`` bone running
    from the floor to the hips), repeatedly; their children become roots. Returns the reduced
    ``heads, tails, parents, names, weights, dropped_names``."""
    parents = np.asarray(parents).copy()
    B = len(parents)
    colsum = np.asarray(abs(weights).sum(axis=0)).ravel()
    keep = np.ones(B, dtype=bool)
    changed = True
    while changed:
        changed = False
        for b in range(B):
            if keep[b] and colsum[b] == 0 and (parents[b] < 0 or not keep[parents[b]]):
                if keep.sum() <= 1:
                    break
                keep[b] = False
                changed = True
    idx = np.nonzero(keep)[0]
    new_of_old = np.full(B, -1, dtype=np.int64)
    new_of_old[idx] = np.arange(len(idx))
    newp = np.array(
        [new_of_old[parents[b]] if parents[b] >= 0 else -1 for b in idx], dtype=np.int64
    )
    dropped = [names[b] for b in range(B) if not keep[b]]
    return (
        heads[idx],
        tails[idx],
        newp,
        [names[b] for b in idx],
        sp.csr_matrix(weights)[:, idx],
        dropped,
    )
