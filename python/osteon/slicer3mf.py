"""The slicer project: a 3MF with the model and one modifier volume per reinforced region.

:func:`write_3mf` writes what PrusaSlicer, Bambu Studio or OrcaSlicer open as a project: the
model (mm, turned so that the build direction is +Z, standing on the bed: min z = 0, centred on
the bed) and, inside the same object, one *modifier* volume per region carrying its own
settings (walls and infill). The slicer applies a modifier's settings to the part of the model
inside it, so the weak span prints with more walls or denser infill and the rest as before.

Formats (read from the slicers' own readers and writers):

- PrusaSlicer (2.4+, Debian's 2.5; ``src/libslic3r/Format/3mf.cpp``): one ``<object>`` in
  ``3D/3dmodel.model`` whose single mesh holds every volume's triangles one after another, and
  ``Metadata/Slic3r_PE_model.config`` with one ``<volume firstid lastid>`` per volume (its
  triangle range), ``<metadata type="volume" key="modifier" value="1">`` and
  ``volume_type="ParameterModifier"`` for a modifier, then the volume's own config keys
  (``perimeters``, ``fill_density``, ...). The object's settings (``<metadata type="object">``)
  carry the profile osteon analysed, so the rest of the part prints with it whatever the user's
  print preset says. The ``slic3rpe:Version3mf`` metadata marks the file as PrusaSlicer's, so
  the reader keeps the geometry where it is written.
- Bambu Studio and OrcaSlicer (``src/libslic3r/Format/bbs_3mf.cpp``): one mesh object per
  volume and an assembly object whose ``<components>`` list them (the 3MF core spec);
  ``Metadata/model_settings.config`` has one ``<object id>`` (the assembly) with one
  ``<part id="mesh object id" subtype="normal_part|modifier_part">`` per volume and the part's
  settings as ``<metadata key value>`` (``wall_loops``, ``sparse_infill_density``, ...).

No print / printer preset is written (``Metadata/Slic3r_PE.config``, ``project_settings.config``):
the user's printer, filament and print presets stay as they are; only what osteon's analysis
assumed (walls, skins, infill, layer height, line width, small-area rule) is set, on the object
and its modifiers.

Why no ``lib3mf``: the 3MF core part here is four small XML files in a zip (``zipfile`` and
``xml.etree`` of the standard library write them), while what matters to the slicers — the
volumes' triangle ranges, modifier flags and per-volume settings — lives in the slicers' own
config files, which lib3mf does not know. lib3mf would add a native library to the wheel and to
the Blender add-on's bundle for the smallest part of the job.
"""

from __future__ import annotations

import io
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Sequence
from typing import Any

import numpy as np

SLICERS = ("prusaslicer", "bambu", "orca")

#: Bed centre (mm) per slicer, where the model is placed: PrusaSlicer's Original Prusa i3 MK3S
#: bed (250 x 210 mm), Bambu Lab X1/P1 bed (256 x 256 mm) for Bambu Studio and OrcaSlicer.
BED_CENTER = {"prusaslicer": (125.0, 105.0), "bambu": (128.0, 128.0), "orca": (128.0, 128.0)}

_CORE_NS = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"

#: osteon pattern name -> the slicers' own infill pattern key (PrusaSlicer ``fill_pattern``;
#: Bambu/Orca ``sparse_infill_pattern``, whose rectilinear is "zig-zag").
_PATTERN = {
    "prusaslicer": {"gyroid": "gyroid", "grid": "grid", "rectilinear": "rectilinear",
                    "cubic": "cubic", "honeycomb": "honeycomb", "triangles": "triangles",
                    "lines": "line"},
    "bambu": {"gyroid": "gyroid", "grid": "grid", "rectilinear": "zig-zag", "cubic": "cubic",
              "honeycomb": "honeycomb", "triangles": "triangles", "lines": "line"},
}
_PATTERN["orca"] = _PATTERN["bambu"]


def _slicer(name: str) -> str:
    key = str(name).strip().lower().replace(" ", "").replace("_", "")
    key = {"prusa": "prusaslicer", "bambustudio": "bambu", "orcaslicer": "orca"}.get(key, key)
    if key not in SLICERS:
        raise ValueError(f"unknown slicer {name!r}; choose one of {', '.join(SLICERS)}")
    return key


def _percent(fraction: float) -> str:
    return f"{100.0 * float(fraction):.4g}%"


def object_settings(profile: Any, slicer: str) -> dict[str, str]:
    """The slicer's keys for the whole object: what osteon's analysis assumed (``profile``: an
    FDM :class:`osteon.profiles.PrintProfile`). Units as the slicers take them: mm, %, counts."""
    s = _slicer(slicer)
    if getattr(profile, "kind", None) != "fdm":
        raise ValueError("a slicer project needs an FDM print profile (walls and infill), "
                         f"got {getattr(profile, 'kind', profile)!r}")
    pattern = _PATTERN[s][profile.pattern]
    if s == "prusaslicer":
        return {"layer_height": f"{profile.layer_height:g}",
                "extrusion_width": f"{profile.line_width:g}",
                "perimeters": str(profile.perimeters),
                "top_solid_layers": str(profile.top_bottom_layers),
                "bottom_solid_layers": str(profile.top_bottom_layers),
                "fill_density": _percent(profile.infill), "fill_pattern": pattern,
                "solid_infill_below_area": f"{profile.solid_infill_below_area:g}"}
    return {"layer_height": f"{profile.layer_height:g}", "line_width": f"{profile.line_width:g}",
            "wall_loops": str(profile.perimeters),
            "top_shell_layers": str(profile.top_bottom_layers),
            "bottom_shell_layers": str(profile.top_bottom_layers),
            "sparse_infill_density": _percent(profile.infill),
            "sparse_infill_pattern": pattern,
            "minimum_sparse_infill_area": f"{profile.solid_infill_below_area:g}"}


def modifier_settings(perimeters: int, infill: float, slicer: str) -> dict[str, str]:
    """A modifier volume's keys: its wall count and infill density (fraction 0…1)."""
    s = _slicer(slicer)
    if s == "prusaslicer":
        return {"perimeters": str(int(perimeters)), "fill_density": _percent(infill)}
    return {"wall_loops": str(int(perimeters)), "sparse_infill_density": _percent(infill)}


def build_rotation(build_direction: Any) -> np.ndarray:
    """(3,3) the smallest rotation taking the unit ``build_direction`` to +Z (Rodrigues)."""
    d = np.asarray(build_direction, dtype=float).reshape(-1)
    n = np.linalg.norm(d) if d.shape == (3,) else 0.0
    if not (np.isfinite(n) and n > 0.0):
        raise ValueError(f"build_direction must be a non-zero 3-vector, got {build_direction!r}")
    d = d / n
    z = np.array([0.0, 0.0, 1.0])
    c = float(d @ z)
    if c < -1.0 + 1e-12:  # upside down: half a turn about x
        return np.diag([1.0, -1.0, -1.0])
    k = np.cross(d, z)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + kx + kx @ kx / (1.0 + c)


def bed_placement(vertices: np.ndarray, build_direction: Any,
                  bed_center: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """(R (3,3), t (3,)): ``p' = R p + t`` turns the model so the build direction is +Z, puts its
    lowest point at z = 0 and the centre of its footprint's bounding box on ``bed_center``."""
    r = build_rotation(build_direction)
    p = np.asarray(vertices, dtype=float) @ r.T
    lo, hi = p.min(0), p.max(0)
    t = np.array([bed_center[0] - 0.5 * (lo[0] + hi[0]), bed_center[1] - 0.5 * (lo[1] + hi[1]),
                  -lo[2]])
    return r, t


def _mesh(vertices: Any, faces: Any, what: str) -> tuple[np.ndarray, np.ndarray]:
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) == 0 or not np.all(np.isfinite(v)):
        raise ValueError(f"{what}: vertices must be a non-empty (V,3) array of finite mm")
    if f.ndim != 2 or f.shape[1] != 3 or len(f) == 0 or not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"{what}: faces must be a non-empty (F,3) integer array")
    if f.min() < 0 or f.max() >= len(v):
        raise ValueError(f"{what}: a face refers to a vertex index outside 0..{len(v) - 1}")
    return v, f.astype(np.int64)


def _mesh_xml(parent: ET.Element, v: np.ndarray, f: np.ndarray) -> None:
    mesh = ET.SubElement(parent, "mesh")
    verts = ET.SubElement(mesh, "vertices")
    for x, y, z in v:
        # %.9g: float32 round trip, as the slicers store coordinates
        ET.SubElement(verts, "vertex", x=f"{x:.9g}", y=f"{y:.9g}", z=f"{z:.9g}")
    tris = ET.SubElement(mesh, "triangles")
    for a, b, c in f:
        ET.SubElement(tris, "triangle", v1=str(a), v2=str(b), v3=str(c))


def _xml(root: ET.Element) -> bytes:
    buf = io.BytesIO()
    ET.ElementTree(root).write(buf, encoding="UTF-8", xml_declaration=True)
    return buf.getvalue()


_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" '
    'ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" '
    'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    '<Default Extension="config" ContentType="text/xml"/></Types>')
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel-1" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>')


def _model_root(slicer: str, title: str) -> ET.Element:
    root = ET.Element("model", unit="millimeter", xmlns=_CORE_NS)
    root.set("xml:lang", "en-US")
    if slicer == "prusaslicer":
        root.set("xmlns:slic3rpe", "http://schemas.slic3r.org/3mf/2017/06")
        meta = {"slic3rpe:Version3mf": "1"}
    else:
        root.set("xmlns:BambuStudio", "http://schemas.bambulab.com/package/2021")
        meta = {"BambuStudio:3mfVersion": "1"}
    meta.update({"Title": title, "Application": "osteon"})
    for k, val in meta.items():
        ET.SubElement(root, "metadata", name=k).text = val
    return root


def _prusa_files(title, volumes, obj_settings) -> dict[str, bytes]:
    root = _model_root("prusaslicer", title)
    res = ET.SubElement(root, "resources")
    obj = ET.SubElement(res, "object", id="1", type="model")
    vs = np.concatenate([v for _, v, _, _ in volumes])
    offsets = np.cumsum([0] + [len(v) for _, v, _, _ in volumes])
    fs = np.concatenate([f + o for (_, _, f, _), o in zip(volumes, offsets)])
    _mesh_xml(obj, vs, fs)
    ET.SubElement(ET.SubElement(root, "build"), "item", objectid="1")

    cfg = ET.Element("config")
    cobj = ET.SubElement(cfg, "object", id="1", instances_count="1")
    ET.SubElement(cobj, "metadata", type="object", key="name", value=title)
    for k, val in obj_settings.items():
        ET.SubElement(cobj, "metadata", type="object", key=k, value=val)
    first = 0
    for name, _, f, settings in volumes:
        vol = ET.SubElement(cobj, "volume", firstid=str(first), lastid=str(first + len(f) - 1))
        first += len(f)
        ET.SubElement(vol, "metadata", type="volume", key="name", value=name)
        if settings is not None:
            ET.SubElement(vol, "metadata", type="volume", key="modifier", value="1")
        ET.SubElement(vol, "metadata", type="volume", key="volume_type",
                      value="ParameterModifier" if settings is not None else "ModelPart")
        for k, val in (settings or {}).items():
            ET.SubElement(vol, "metadata", type="volume", key=k, value=val)
    return {"3D/3dmodel.model": _xml(root), "Metadata/Slic3r_PE_model.config": _xml(cfg)}


_IDENTITY_3MF = "1 0 0 0 1 0 0 0 1 0 0 0"
_IDENTITY_4X4 = "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"


def _bambu_files(title, volumes, obj_settings) -> dict[str, bytes]:
    root = _model_root("bambu", title)
    res = ET.SubElement(root, "resources")
    for k, (name, v, f, _) in enumerate(volumes, start=1):
        _mesh_xml(ET.SubElement(res, "object", id=str(k), name=name, type="model"), v, f)
    assembly = len(volumes) + 1
    comps = ET.SubElement(ET.SubElement(res, "object", id=str(assembly), name=title,
                                        type="model"), "components")
    for k in range(1, assembly):
        ET.SubElement(comps, "component", objectid=str(k), transform=_IDENTITY_3MF)
    ET.SubElement(ET.SubElement(root, "build"), "item", objectid=str(assembly),
                  transform=_IDENTITY_3MF, printable="1")

    cfg = ET.Element("config")
    cobj = ET.SubElement(cfg, "object", id=str(assembly))
    ET.SubElement(cobj, "metadata", key="name", value=title)
    for k, val in obj_settings.items():
        ET.SubElement(cobj, "metadata", key=k, value=val)
    for k, (name, _, _, settings) in enumerate(volumes, start=1):
        part = ET.SubElement(cobj, "part", id=str(k),
                             subtype="modifier_part" if settings is not None else "normal_part")
        ET.SubElement(part, "metadata", key="name", value=name)
        ET.SubElement(part, "metadata", key="matrix", value=_IDENTITY_4X4)
        for key, val in (settings or {}).items():
            ET.SubElement(part, "metadata", key=key, value=val)
    return {"3D/3dmodel.model": _xml(root), "Metadata/model_settings.config": _xml(cfg)}


def write_3mf(path: str | os.PathLike, vertices: Any, faces: Any, regions: Sequence[dict],
              profile: Any, build_direction: Any = (0.0, 0.0, 1.0), slicer: str = "prusaslicer",
              *, name: str = "osteon", bed_center: Sequence[float] | None = None) -> dict:
    """Write the slicer project ``path`` (.3mf): the model and one modifier volume per region.

    ``vertices`` (V,3) mm and ``faces`` (F,3) of the model, in the model's frame (the frame of
    the analysis); ``regions``: dicts with ``vertices``/``faces`` (a closed modifier mesh, same
    frame), ``perimeters`` (count) and ``infill`` (fraction 0…1), optionally ``bone`` (its name
    names the volume); ``profile``: the FDM :class:`~osteon.profiles.PrintProfile` of the rest of
    the part; ``build_direction`` (3,) in the model's frame, turned to +Z; ``slicer``:
    "prusaslicer", "bambu" or "orca"; ``bed_center`` (x, y) mm (default: :data:`BED_CENTER`).

    Returns ``{"rotation": (3,3), "translation": (3,)}``: the placement ``p' = R p + t`` applied
    to every mesh. The file is written next to ``path`` and moved in place when complete."""
    s = _slicer(slicer)
    obj_settings = object_settings(profile, s)
    v, f = _mesh(vertices, faces, "model")
    r, t = bed_placement(v, build_direction, BED_CENTER[s] if bed_center is None else bed_center)
    volumes = [(name, v @ r.T + t, f, None)]
    for i, reg in enumerate(regions):
        try:
            rv, rf = _mesh(reg["vertices"], reg["faces"], f"region {i}")
            settings = modifier_settings(reg["perimeters"], reg["infill"], s)
        except KeyError as e:
            raise ValueError(f"region {i} has no {e.args[0]!r}") from None
        label = f"osteon {reg.get('bone', i)}: {settings_label(reg)}"
        volumes.append((label, rv @ r.T + t, rf, settings))
    build = _prusa_files if s == "prusaslicer" else _bambu_files
    files = {"[Content_Types].xml": _CONTENT_TYPES.encode(), "_rels/.rels": _RELS.encode(),
             **build(name, volumes, obj_settings)}
    target = os.fspath(path)
    fd, tmp = tempfile.mkstemp(suffix=".3mf.part", dir=os.path.dirname(os.path.abspath(target)))
    try:
        with os.fdopen(fd, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as z:
            for member, data in files.items():
                z.writestr(member, data)
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return {"rotation": r, "translation": t}


def settings_label(region: dict) -> str:
    """"5 walls, 15 % infill": a region's settings in words (volume names, reports)."""
    return f"{int(region['perimeters'])} walls, {100.0 * float(region['infill']):.0f} % infill"
