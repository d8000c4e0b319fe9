"""libigl TGF skeletons and DMAT matrices (ascii and binary).

TGF: joint lines ``INDEX x y z [extra…]`` until a line starting with ``#``, then bone lines
``PARENT CHILD [extra…]`` (1-based joint indices) until ``#``. A bone goes from its parent joint
(head) to its child joint (tail); its parent bone is the bone ending at its head joint
(-1 for bones leaving a joint no bone ends at). Bones keep the file order, which is the column
order of the matching DMAT weights.

DMAT: ascii ``COLS ROWS`` then the values column-major, or binary: the line ``0 0``, then the
line ``COLS ROWS``, then ROWS×COLS little-endian float64 column-major.
"""

from __future__ import annotations

import os

import numpy as np

from .atomic import write_atomic
from .model import check_tree


def read_tgf(path):
    """Read a TGF skeleton → ``(joints (J,3), bone_joints (B,2) 0-based, heads, tails, parents)``."""
    path = os.fspath(path)
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a text TGF skeleton file ({e})") from None
    section = 0
    joints, joint_ids, edges = [], [], []
    for ln, line in enumerate(lines, 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            section += 1
            if section >= 2:
                break
            continue
        t = s.split()
        try:
            if section == 0:
                if len(t) < 4:
                    raise ValueError
                joint_ids.append(int(t[0]))
                joints.append([float(t[1]), float(t[2]), float(t[3])])
            else:
                if len(t) < 2:
                    raise ValueError
                edges.append([int(t[0]), int(t[1])])
        except ValueError:
            what = "joint 'INDEX x y z'" if section == 0 else "bone 'PARENT CHILD'"
            raise ValueError(f"{path}:{ln}: expected a TGF {what} line, got {s[:60]!r}") from None
    if not joints:
        raise ValueError(f"{path}: no joints found (not a TGF skeleton?)")
    if not edges:
        raise ValueError(f"{path}: no bones found after the joint list (missing '#' separator?)")
    joints = np.asarray(joints, dtype=np.float64)
    if not np.all(np.isfinite(joints)):
        raise ValueError(f"{path}: joint coordinates contain NaN or inf")
    # TGF indices are 1-based positions in the joint list
    J = len(joints)
    big = next((e for e in edges if not (-2**62 < e[0] < 2**62 and -2**62 < e[1] < 2**62)),
               None)
    if big is not None:
        raise ValueError(f"{path}: bone {big[0]} {big[1]} refers to a joint index outside "
                         f"1..{J} (too big for an integer)")
    E = np.asarray(edges, dtype=np.int64) - 1
    if E.min() < 0 or E.max() >= J:
        raise ValueError(f"{path}: bone refers to joint index outside 1..{J}")
    heads, tails = joints[E[:, 0]], joints[E[:, 1]]
    ends_at = {}
    for b, (_, c) in enumerate(E):
        if c in ends_at:
            raise ValueError(f"{path}: joint {c + 1} is the child of two bones; not a tree")
        ends_at[int(c)] = b
    parents = np.array([ends_at.get(int(p), -1) for p, _ in E], dtype=np.int64)
    check_tree(parents, path, "bone", [f"{a + 1}->{c + 1}" for a, c in E])
    return joints, E, heads, tails, parents


def write_tgf(path, joints, bone_joints):
    """Write joints (J,3) and 0-based bone joint pairs (B,2) as TGF."""
    joints = np.asarray(joints, dtype=np.float64)
    text = "".join(f"{i} {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n" for i, p in enumerate(joints, 1))
    text += "#\n" + "".join(f"{a + 1} {b + 1}\n"
                            for a, b in np.asarray(bone_joints, dtype=np.int64)) + "#\n"
    write_atomic(path, text)


def read_dmat(path) -> np.ndarray:
    """Read a DMAT matrix (ascii or binary) → (ROWS, COLS) float64."""
    path = os.fspath(path)
    with open(path, "rb") as f:
        data = f.read()
    nl = data.find(b"\n")
    try:
        head = data[:nl].split()
        cols, rows = int(head[0]), int(head[1])
    except (ValueError, IndexError):
        raise ValueError(f"{path}: not a DMAT file (first line must be 'COLS ROWS')") from None
    if cols == 0 and rows == 0:  # binary
        nl2 = data.find(b"\n", nl + 1)
        try:
            cols, rows = (int(x) for x in data[nl + 1 : nl2].split())
        except ValueError:
            raise ValueError(f"{path}: binary DMAT without a 'COLS ROWS' second line") from None
        raw = data[nl2 + 1 :]
        n = rows * cols
        if len(raw) < 8 * n:
            raise ValueError(f"{path}: binary DMAT holds {len(raw) // 8} values, header says {n}")
        vals = np.frombuffer(raw, dtype="<f8", count=n)
    else:
        if cols < 0 or rows < 0:
            raise ValueError(f"{path}: negative DMAT size {cols} {rows}")
        try:
            vals = np.array(data[nl + 1 :].split(), dtype=np.float64)
        except ValueError:
            raise ValueError(f"{path}: non-numeric value in ascii DMAT") from None
        if len(vals) != rows * cols:
            raise ValueError(
                f"{path}: DMAT holds {len(vals)} values, header says {cols}x{rows}={rows * cols}"
            )
    return vals.reshape(cols, rows).T.copy()


def write_dmat(path, matrix, binary=False):
    """Write a 2-D array as DMAT (column-major), ascii or binary."""
    m = np.asarray(matrix, dtype=np.float64)
    if m.ndim != 2:
        raise ValueError("DMAT holds a 2-D matrix")
    rows, cols = m.shape
    if binary:
        data = b"0 0\n" + f"{cols} {rows}\n".encode() + np.asarray(m.T, dtype="<f8").tobytes()
    else:
        data = (f"{cols} {rows}\n" + "\n".join(f"{v:.17g}" for v in m.T.ravel()) + "\n").encode()
    write_atomic(path, data)
