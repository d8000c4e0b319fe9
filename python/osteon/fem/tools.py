"""The external FEM programs: gmsh (meshing) and CalculiX ``ccx`` (solving)."""

from __future__ import annotations

import os
import shutil


def find_tools() -> dict:
    """Paths of the external programs: ``{'gmsh': path or None, 'ccx': path or None}``."""
    return {
        "gmsh": os.environ.get("OSTEON_GMSH") or shutil.which("gmsh"),
        "ccx": os.environ.get("OSTEON_CCX") or shutil.which("ccx"),
    }


def _require_tools():
    t = find_tools()
    missing = [k for k, v in t.items() if v is None]
    if missing:
        raise RuntimeError(
            "FEM cross-check needs the programs "
            + " and ".join(missing)
            + " (Debian/Ubuntu: apt-get install gmsh calculix-ccx)"
        )
    return t
