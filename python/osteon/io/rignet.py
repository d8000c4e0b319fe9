"""RigNet ``*_rig.txt`` rigs (ModelsResource-RigNetv1).

Lines: ``joints NAME x y z``, ``root NAME``, ``hier PARENT CHILD``,
``skin VERTEX_ID J1 W1 J2 W2 …`` (0-based vertex ids in the ``v`` order of the matching OBJ).

Joints become bones as described in :func:`osteon.io.model.bones_from_joint_tree`: one bone per
``hier`` edge, head at the parent joint; duplicated joints (``NAME_dup_K``, at nearly the position
of their parent, RigNet's way of giving a branching joint one bone per child) are merged into
their parent, so each ``X_dup_K`` starts the bone towards its own child and is named after it;
a joint's skin weight goes to the bone leaving it (nearest of several if it branches), a leaf
joint's weight to the bone ending at it.
"""

from __future__ import annotations

import os
import re

import numpy as np

from .model import (
    bones_from_joint_tree,
    check_tree,
    clean_weights,
    finish_joint_rig,
    joint_weights_to_bones,
)

_DUP = re.compile(r"_dup_\d+$")


def _skin_triplets(skin_lines, path):
    """``skin VERTEX J1 W1 J2 W2 …`` lines → (rows, joint names, values) arrays, converted
    together (one NumPy call per column instead of one float() per entry)."""
    if not skin_lines:
        return np.zeros(0, np.int64), np.zeros(0, dtype=str), np.zeros(0)
    toks = [line.split() for _, line in skin_lines]
    counts = np.fromiter((len(t) for t in toks), dtype=np.int64, count=len(toks))
    bad = np.flatnonzero((counts < 4) | (counts % 2 == 1))
    verts = None
    if not len(bad):
        try:
            verts = np.array([t[1] for t in toks], dtype=np.int64)
        except (ValueError, OverflowError):
            bad = [k for k, t in enumerate(toks) if not _is_index(t[1])]
    if len(bad):
        ln, line = skin_lines[int(bad[0])]
        raise ValueError(f"{path}:{ln}: not a RigNet skin line 'skin VERTEX JOINT WEIGHT …': "
                         f"{line.strip()[:60]!r}")
    pairs = [x for t in toks for x in t[2:]]
    try:
        vals = np.array(pairs[1::2], dtype=np.float64)
    except ValueError:
        k = next(i for i, t in enumerate(toks) if not all(_is_number(x) for x in t[3::2]))
        ln, line = skin_lines[k]
        raise ValueError(f"{path}:{ln}: a skin weight is not a number: "
                         f"{line.strip()[:60]!r}") from None
    rows = np.repeat(verts, (counts - 2) // 2)
    if len(rows) and rows.min() < 0:
        raise ValueError(f"{path}: a skin line has a negative vertex index {int(rows.min())}")
    return rows, np.array(pairs[0::2]), vals


def _is_index(text) -> bool:
    try:
        return 0 <= int(text) < 2**62
    except ValueError:
        return False


def _is_number(text) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def read_rignet_rig(path):
    """Parse a RigNet rig file → dict with joint names, positions, parent per joint, root name and
    skin triplets (rows, joint indices, values)."""
    path = os.fspath(path)
    names, pos, hier, root = [], [], [], None
    index: dict[str, int] = {}
    try:
        with open(path) as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: cannot read rig file ({e})") from None
    skin_lines = []
    for ln, line in enumerate(text.splitlines(), 1):
        if line.startswith("skin "):  # most lines: parsed together below
            skin_lines.append((ln, line))
            continue
        t = line.split()
        if not t:
            continue
        try:
            key = t[0]
            if key == "joints":
                if t[1] not in index:  # RigNet files list the joints twice
                    index[t[1]] = len(names)
                    names.append(t[1])
                    pos.append([float(t[2]), float(t[3]), float(t[4])])
            elif key == "root":
                root = t[1]
            elif key == "hier":
                hier.append((t[1], t[2]))
            elif key == "skin":
                skin_lines.append((ln, line))
            else:
                raise ValueError
        except (ValueError, IndexError):
            raise ValueError(
                f"{path}:{ln}: not a RigNet rig line (joints/root/hier/skin): {line.strip()[:60]!r}"
            ) from None
    rows, jn, vals = _skin_triplets(skin_lines, path)
    if not names:
        raise ValueError(f"{path}: no 'joints' lines (not a RigNet _rig.txt file?)")
    parent = np.full(len(names), -1, dtype=np.int64)
    for p, c in hier:
        if p not in index or c not in index:
            raise ValueError(f"{path}: 'hier {p} {c}' names an undeclared joint")
        if parent[index[c]] >= 0:
            raise ValueError(f"{path}: joint {c!r} has two parents")
        parent[index[c]] = index[p]
    check_tree(parent, path, "joint", names)
    if root is not None and root not in index:
        raise ValueError(f"{path}: root joint {root!r} is not declared")
    used, inverse = np.unique(jn, return_inverse=True)
    unknown = [str(j) for j in used if j not in index]
    if unknown:
        raise ValueError(f"{path}: skin lines name undeclared joints {unknown[:5]}")
    joint_of = np.array([index[str(j)] for j in used], dtype=np.int64)
    return {
        "names": names,
        "positions": np.asarray(pos, dtype=np.float64),
        "parent": parent,
        "root": root,
        "skin_rows": rows,
        "skin_joints": joint_of[inverse.ravel()] if len(jn) else np.zeros(0, np.int64),
        "skin_values": vals,
    }


def rignet_skeleton(rig, vertices, info: dict | None = None, source: str = "RigNet rig"):
    """Bones and (V, B) bone weights from a parsed rig and the mesh vertices.

    ``info`` (a dict, optional) receives ``warnings`` (repaired weights, bones without weight,
    no skin at all), ``findings`` (:func:`osteon.io.model.weight_findings`) and ``notes``. A rig
    without ``skin`` lines keeps all its bones and returns ``None`` weights (each vertex then
    follows its nearest bone), with a warning: dropping unweighted bones would leave one."""
    info = {} if info is None else info
    info.setdefault("warnings", [])
    info.setdefault("notes", [])
    names = rig["names"]
    dup = np.array([bool(_DUP.search(n)) for n in names])
    heads, tails, parents, bnames, targets = bones_from_joint_tree(
        rig["positions"], rig["parent"], names, degenerate=dup
    )
    if len(heads) == 0:
        raise ValueError(f"{source}: RigNet rig has no bones (a single joint or only duplicated "
                         "joints)")
    V = len(vertices)
    r = rig["skin_rows"]
    if len(r) == 0:
        info["warnings"].append(
            f"{source}: no 'skin' lines: no weights for its {len(heads)} bones; each vertex "
            "follows its nearest bone")
        return heads, tails, parents, bnames, None
    if r.min() < 0 or r.max() >= V:
        raise ValueError(
            f"{source}: skin line refers to vertex {int(r.max() if r.max() >= V else r.min())} "
            f"but the mesh has {V} vertices"
        )
    found, warns = clean_weights(r, rig["skin_values"], V, source)
    info["findings"] = found
    info["warnings"].extend(warns)
    w = joint_weights_to_bones(
        vertices, r, rig["skin_joints"], rig["skin_values"], targets, heads, tails, names
    )
    return finish_joint_rig(heads, tails, parents, bnames, w, info, source)
