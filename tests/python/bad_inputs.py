"""The catalogue of bad and odd input files (issue 36), generated at test time: a small good
model in each format (a round bar, 60 mm, two bones), and one builder per bad case that writes a
mutated copy. Each case names the message it must give. Units: mm.

``CASES``: name -> (builder, kind, expected), where ``builder(folder)`` writes the files and
returns the model path; ``kind`` is "error" (load_model raises ValueError matching
``expected``), "warning" (the model loads and one of its warnings matches ``expected``) or
"ok" (loads cleanly).
"""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np
from batch_library import bar, rigged_bar

LENGTH = 60.0


# --- a skinned glTF (joints root -> mid -> tip along +x) ------------------------------------

def gltf_document(folder: Path | None = None) -> dict:
    """A valid skinned glTF of the bar as a dict (one base64 buffer)."""
    V, F = bar(LENGTH, 5.0)
    V = V.astype(np.float32)
    idx = np.asarray(F, dtype=np.uint32).ravel()
    joints = np.zeros((len(V), 4), dtype=np.uint16)
    joints[V[:, 0] >= LENGTH / 2, 0] = 1
    weights = np.zeros((len(V), 4), dtype=np.float32)
    weights[:, 0] = 1.0
    xs = [0.0, LENGTH / 2, LENGTH]
    ibm = np.zeros((3, 16), dtype=np.float32)
    for k, x in enumerate(xs):
        m = np.eye(4, dtype=np.float32)
        m[3, 0] = -x  # column-major: translation in elements 12..14
        ibm[k] = m.ravel()
    blobs = [V.tobytes(), idx.tobytes(), joints.tobytes(), weights.tobytes(), ibm.tobytes()]
    views, off = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(b)})
        off += len(b)
    data = b"".join(blobs)
    lo, hi = V.min(0).tolist(), V.max(0).tolist()
    return {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode()}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(V), "type": "VEC3",
             "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5123, "count": len(V), "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": len(V), "type": "VEC4"},
            {"bufferView": 4, "componentType": 5126, "count": 3, "type": "MAT4"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 2,
                                                   "WEIGHTS_0": 3}, "indices": 1}]}],
        "nodes": [
            {"name": "bar", "mesh": 0, "skin": 0},
            {"name": "root", "children": [2]},
            {"name": "mid", "translation": [LENGTH / 2, 0, 0], "children": [3]},
            {"name": "tip", "translation": [LENGTH / 2, 0, 0]},
        ],
        "skins": [{"joints": [1, 2, 3], "inverseBindMatrices": 4}],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0,
    }


def _set_buffer(doc, data: bytes):
    doc["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                + base64.b64encode(data).decode())


def _buffer(doc) -> bytearray:
    return bytearray(base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1]))


def write_gltf(folder: Path, name: str, mutate=None) -> Path:
    doc = gltf_document()
    if mutate is not None:
        mutate(doc, folder)
    path = folder / f"{name}.gltf"
    path.write_text(json.dumps(doc))
    return path


def _gltf(mutate):
    def build(folder: Path, name: str) -> Path:
        return write_gltf(folder, name, mutate)
    return build


def _cycle_through_non_joint(doc, folder):
    # root's parent chain runs into two non-joint nodes that are each other's parent: the old
    # reader walked up from the joint for ever (one core at 100 %)
    doc["nodes"].append({"name": "helper_a", "children": [1, 5]})
    doc["nodes"].append({"name": "helper_b", "children": [4]})


def _weights_nan(doc, folder):
    buf = _buffer(doc)
    view = doc["bufferViews"][3]
    w = np.frombuffer(bytes(buf[view["byteOffset"]:view["byteOffset"] + view["byteLength"]]),
                      dtype=np.float32).reshape(-1, 4).copy()
    w[:10, 0] = np.nan
    w[10:20, 0] = 7.3
    buf[view["byteOffset"]:view["byteOffset"] + view["byteLength"]] = w.tobytes()
    _set_buffer(doc, bytes(buf))


def _singular_ibm(doc, folder):
    buf = _buffer(doc)
    view = doc["bufferViews"][4]
    buf[view["byteOffset"]:view["byteOffset"] + 64] = bytes(64)
    _set_buffer(doc, bytes(buf))


def _uri_folder(doc, folder):
    (folder / "buffers.bin").mkdir(exist_ok=True)
    doc["buffers"][0]["uri"] = "buffers.bin"


def _no_weights(doc, folder):
    attrs = doc["meshes"][0]["primitives"][0]["attributes"]
    del attrs["JOINTS_0"], attrs["WEIGHTS_0"]


def _joint_index_out(doc, folder):
    buf = _buffer(doc)
    view = doc["bufferViews"][2]
    j = np.frombuffer(bytes(buf[view["byteOffset"]:view["byteOffset"] + view["byteLength"]]),
                      dtype=np.uint16).reshape(-1, 4).copy()
    j[0, 0] = 7
    buf[view["byteOffset"]:view["byteOffset"] + view["byteLength"]] = j.tobytes()
    _set_buffer(doc, bytes(buf))


def _set(path, value):
    def mutate(doc, folder):
        d = doc
        for k in path[:-1]:
            d = d[k]
        d[path[-1]] = value
    return mutate


# --- TGF / DMAT / RigNet ---------------------------------------------------------------------

def _tgf(text_of_bones: str):
    def build(folder: Path, name: str) -> Path:
        p = rigged_bar(folder, name)
        (folder / f"{name}.tgf").write_text(
            f"1 0 0 0\n2 {LENGTH / 2} 0 0\n3 {LENGTH} 0 0\n#\n{text_of_bones}#\n")
        return p
    return build


def _dmat(fill):
    def build(folder: Path, name: str) -> Path:
        from osteon.io import write_dmat

        p = rigged_bar(folder, name)
        V, _ = bar(LENGTH, 5.0)
        W = np.zeros((len(V), 2))
        W[V[:, 0] < LENGTH / 2, 0] = 1.0
        W[V[:, 0] >= LENGTH / 2, 1] = 1.0
        fill(W, V)
        write_dmat(folder / f"{name}.dmat", W)
        return p
    return build


def _bad_weights(W, V):
    W[:5, 0] = np.nan
    W[5:8, 0] = -1.0
    W[8:20] *= 7.3


def _bone_without_weight(W, V):
    W[:, 0] = 1.0
    W[:, 1] = 0.0


def rignet_text(skin=True, cycle=False) -> str:
    lines = ["joints root 0 0 0", f"joints mid {LENGTH / 2} 0 0", f"joints tip {LENGTH} 0 0",
             "root root", "hier root mid", "hier mid tip"]
    if cycle:
        lines.append("hier tip root")
    if skin:
        V, _ = bar(LENGTH, 5.0)
        lines += [f"skin {i} {'root' if x < LENGTH / 2 else 'mid'} 1.0"
                  for i, x in enumerate(V[:, 0])]
    return "\n".join(lines) + "\n"


def _rignet(**kw):
    def build(folder: Path, name: str) -> Path:
        from osteon.io import write_mesh

        V, F = bar(LENGTH, 5.0)
        p = folder / f"{name}.obj"
        write_mesh(p, V, F)
        (folder / f"{name}_rig.txt").write_text(rignet_text(**kw))
        return p
    return build


def _good_bar(folder: Path, name: str) -> Path:
    return rigged_bar(folder, name)


def _stl_header_only(folder: Path, name: str) -> Path:
    p = folder / f"{name}.stl"
    p.write_bytes(b"\0" * 80 + struct.pack("<I", 10**6))  # promises a million triangles
    return p


#: name -> (builder(folder, name) -> model path, kind, expected message regex)
CASES = {
    "gltf_joint_chain_cycle": (_gltf(_cycle_through_non_joint), "error",
                               r"glTF node parents form a cycle"),
    "gltf_accessor_out_of_range": (_gltf(_set(["meshes", 0, "primitives", 0, "attributes",
                                               "POSITION"], 99)), "error",
                                   r"accessors index 99 .*outside the file's 5 accessors"),
    "gltf_buffer_view_out_of_range": (_gltf(_set(["accessors", 0, "bufferView"], 42)),
                                      "error", r"bufferViews index 42"),
    "gltf_mesh_out_of_range": (_gltf(_set(["nodes", 0, "mesh"], 7)), "error",
                               r"meshes index 7"),
    "gltf_skin_joint_out_of_range": (_gltf(_set(["skins", 0, "joints"], [1, 2, 99])), "error",
                                     r"nodes index 99 \(joint 2 of skin 0\)"),
    "gltf_unknown_component_type": (_gltf(_set(["accessors", 1, "componentType"], 5130)),
                                    "error", r"unknown componentType 5130"),
    "gltf_buffer_uri_is_a_folder": (_gltf(_uri_folder), "error",
                                    r"'buffers.bin' is not a file"),
    "gltf_joint_index_out_of_range": (_gltf(_joint_index_out), "error",
                                      r"JOINTS_0 index outside the skin's 3 joints"),
    "gltf_singular_bind_matrix": (_gltf(_singular_ibm), "error",
                                  r"inverse bind matrix of joint 0 cannot be inverted"),
    "gltf_accessor_past_buffer": (_gltf(_set(["accessors", 0, "count"], 10**6)), "error",
                                  r"accessor 0: .* runs past"),
    "gltf_non_utf8_joint_name": (_gltf(_set(["nodes", 2, "name"], "mid\udcff")), "ok", None),
    "gltf_skin_without_weights": (_gltf(_no_weights), "warning",
                                  r"the skin has no weights .* no weights for its 2 bones"),
    "gltf_nan_and_7_3_weights": (_gltf(_weights_nan), "warning",
                                 r"10 NaN/inf .*entries set to 0"),
    "tgf_index_too_big": (_tgf("1 2\n2 99999999999999999999999\n"), "error",
                          r"too big for an integer"),
    "tgf_bone_cycle": (_tgf("1 2\n2 3\n3 1\n"), "error", r"bone parents form a cycle"),
    "dmat_nan_negative_7_3": (_dmat(_bad_weights), "warning",
                              r"5 NaN/inf and 3 negative entries set to 0"),
    "dmat_rows_far_from_1": (_dmat(_bad_weights), "warning",
                             r"12 of \d+ vertex rows summed to 7\.3 \.\. 7\.3, not 1; rescaled"),
    "dmat_bone_without_weight": (_dmat(_bone_without_weight), "warning",
                                 r"1 bone\(s\) without any weight .*: bone_1"),
    "rignet_without_skin_lines": (_rignet(skin=False), "warning",
                                  r"no 'skin' lines: no weights for its 2 bones"),
    "rignet_hier_cycle": (_rignet(cycle=True), "error", r"joint parents form a cycle"),
    "stl_promises_more_than_it_holds": (_stl_header_only, "error", r"no triangles found|cannot read mesh"),
    "good_bar": (_good_bar, "ok", None),
}


def build(folder: Path, name: str) -> Path:
    """Write case ``name`` into ``folder`` (its own files, named after the case)."""
    return CASES[name][0](folder, name)
