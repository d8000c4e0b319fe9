"""File readers: meshes, skeletons and skinning weights → :class:`RiggedModel` in mm.

Formats
-------
* meshes: OBJ, OFF, PLY, STL (trimesh, vertex order kept so weights still match);
* skeletons: libigl TGF (+ DMAT weights, ascii or binary), RigNet ``_rig.txt`` (weights inside);
* skinned glTF 2.0 ``.gltf`` / ``.glb`` (mesh, skeleton and weights in one file).

:func:`load_model` picks the reader by extension, finds sidecar files next to the mesh
(``NAME.tgf`` + ``NAME.dmat`` / ``NAME-weights.dmat``, ``NAME_rig.txt``) and scales the model to
a printed size in millimetres.
"""

from .libigl import read_dmat, read_tgf, write_dmat, write_tgf
from .loader import MESH_EXTENSIONS, load_model, read_mesh, write_mesh
from .model import RiggedModel

__all__ = [
    "MESH_EXTENSIONS",
    "RiggedModel",
    "load_model",
    "read_dmat",
    "read_mesh",
    "read_tgf",
    "write_dmat",
    "write_mesh",
    "write_tgf",
]
