"""Linear elasticity with CalculiX ``ccx``: write the deck, run it, read the nodal stresses from
the ``.frd`` file. Units: mm, N, MPa."""

from __future__ import annotations

import os
import subprocess

import numpy as np

from .tools import _require_tools


def solve(
    nodes, tets, fixed, load_cases, workdir, young=3500.0, poisson=0.35, threads=2, timeout=1800
):
    """Linear static solve with CalculiX, one step per load case.

    ``fixed``: node indices held in x, y, z. ``load_cases``: list of ``(node_ids, forces (k,3))``
    in N. Returns nodal stresses ``(K, N, 6)`` in MPa, components xx, yy, zz, xy, yz, zx.
    """
    tools = _require_tools()
    fixed = np.unique(np.asarray(fixed, dtype=np.int64))
    if len(fixed) < 3:
        raise ValueError("FEM: fewer than 3 held nodes; enlarge the hold radius")
    inp = os.path.join(workdir, "job.inp")
    with open(inp, "w") as f:
        f.write("*HEADING\nosteon FEM cross-check (mm, N, MPa)\n*NODE, NSET=NALL\n")
        ids = np.arange(1, len(nodes) + 1)
        np.savetxt(f, np.column_stack([ids, nodes]), fmt="%d, %.9g, %.9g, %.9g")
        f.write("*ELEMENT, TYPE=C3D10, ELSET=EALL\n")
        np.savetxt(
            f, np.column_stack([np.arange(1, len(tets) + 1), tets + 1]), fmt="%d", delimiter=", "
        )
        f.write("*NSET, NSET=HELD\n")
        f.writelines(
            ", ".join(str(x + 1) for x in fixed[k : k + 16]) + "\n"
            for k in range(0, len(fixed), 16)
        )
        f.write(f"*BOUNDARY\nHELD, 1, 3, 0.\n*MATERIAL, NAME=MAT\n*ELASTIC\n{young}, {poisson}\n")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n")
        for node_ids, forces in load_cases:
            f.write("*STEP\n*STATIC\n*CLOAD, OP=NEW\n")
            for nid, fv in zip(np.atleast_1d(node_ids), np.atleast_2d(forces), strict=True):
                for d in range(3):
                    if fv[d] != 0.0:
                        f.write(f"{nid + 1}, {d + 1}, {fv[d]:.12g}\n")
            f.write("*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n")
    env = dict(
        os.environ,
        OMP_NUM_THREADS=str(threads),
        CCX_NPROC_EQUATION_SOLVER=str(threads),
        CCX_NPROC_STIFFNESS=str(threads),
        CCX_NPROC_RESULTS=str(threads),
    )
    try:
        p = subprocess.run(
            ["ccx", "-i", "job"] if tools["ccx"] is None else [tools["ccx"], "-i", "job"],
            cwd=workdir,
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"CalculiX did not finish within {timeout:g} s (stopped)") from None
    frd = os.path.join(workdir, "job.frd")
    if p.returncode != 0 or not os.path.exists(frd) or "*ERROR" in p.stdout:
        tail = [ln for ln in (p.stdout + p.stderr).splitlines() if ln.strip()][-6:]
        raise RuntimeError("CalculiX failed: " + " | ".join(tail))
    S = read_frd_stress(frd, len(nodes))
    if len(S) != len(load_cases):
        raise RuntimeError(f"CalculiX wrote {len(S)} stress results for {len(load_cases)} steps")
    return S


def read_frd_stress(path, n_nodes):
    """All STRESS blocks of a CalculiX ``.frd`` file → ``(K, N, 6)`` (xx, yy, zz, xy, yz, zx)."""
    out = []
    with open(path) as f:
        lines = f.readlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith(" -4  STRESS"):
            S = np.zeros((n_nodes, 6))
            i += 1
            while lines[i].startswith(" -5"):
                i += 1
            while not lines[i].startswith(" -3"):
                ln = lines[i]
                if ln.startswith(" -1"):
                    nid = int(ln[3:13])
                    vals = [float(ln[13 + 12 * k : 25 + 12 * k]) for k in range(6)]
                    if 1 <= nid <= n_nodes:
                        S[nid - 1] = vals
                i += 1
            out.append(S)
        i += 1
    return np.asarray(out)
