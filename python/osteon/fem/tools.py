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


def missing_tools_message(what: str = "FEM cross-check") -> str | None:
    """``"<what> needs the programs ... (apt-get install ...)"``, or None when both are found."""
    missing = [k for k, v in find_tools().items() if v is None]
    if not missing:
        return None
    return (f"{what} needs the programs " + " and ".join(missing)
            + " (Debian/Ubuntu: apt-get install gmsh calculix-ccx)")


def _require_tools():
    msg = missing_tools_message()
    if msg is not None:
        raise RuntimeError(msg)
    return find_tools()
