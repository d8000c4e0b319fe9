"""Reader fuzz (issue 36): every reader fed mutated copies of a valid file. Every outcome must be
a model or a ValueError — never another exception, never a hang (each read has a few seconds).

Small in CI (``OSTEON_READER_FUZZ`` cases per reader, default 12, ~10 s in all); longer on demand:
``OSTEON_READER_FUZZ=500 pytest tests/python/test_reader_fuzz.py -s`` prints the outcome
counts per reader. The fast mesh parsers are also checked against trimesh on valid files."""

from __future__ import annotations

import io
import json
import os
import random
import signal
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from bad_inputs import gltf_document, rignet_text
from batch_library import bar
from osteon.io import load_model, write_dmat, write_mesh, write_tgf

N = int(os.environ.get("OSTEON_READER_FUZZ", "12"))
SECONDS_PER_READ = 10

TOKENS = [b"-1", b"0", b"99999999999999999999999", b"nan", b"inf", b"1e400", b"-0", b"",
          b"\xff\xfe", b"#", b"\n", b"f", b"v", b"3", b"1/2/3", b"2147483648", b" ", b"x"]


def _seed_files(folder: Path) -> dict[str, tuple[Path, Path]]:
    """reader -> (model to load, file to mutate)."""
    V, F = bar(60.0, 5.0, n=12, stations=6)
    joints = np.array([[0.0, 0, 0], [30, 0, 0], [60, 0, 0]])
    W = np.zeros((len(V), 2))
    W[V[:, 0] < 30, 0] = 1.0
    W[V[:, 0] >= 30, 1] = 1.0
    seeds = {}
    for ext in (".obj", ".off", ".ply", ".stl"):
        stem = folder / f"m{ext[1:]}"
        write_mesh(stem.with_suffix(ext), V, F)
        write_tgf(stem.with_suffix(".tgf"), joints, [[0, 1], [1, 2]])
        if ext != ".stl":  # STL keeps corners apart: no per-vertex weights to match
            write_dmat(stem.with_suffix(".dmat"), W)
        seeds[ext[1:]] = (stem.with_suffix(ext), stem.with_suffix(ext))
    seeds["tgf"] = (folder / "mobj.obj", folder / "mobj.tgf")
    seeds["dmat ascii"] = (folder / "mobj.obj", folder / "mobj.dmat")
    write_dmat(folder / "mply.dmat", W, binary=True)
    seeds["dmat binary"] = (folder / "mply.ply", folder / "mply.dmat")
    import trimesh

    asc = folder / "masc.stl"
    asc.write_text(trimesh.exchange.stl.export_stl_ascii(trimesh.Trimesh(V, F, process=False)))
    write_tgf(folder / "masc.tgf", joints, [[0, 1], [1, 2]])
    seeds["stl ascii"] = (asc, asc)
    plya = folder / "mplya.ply"
    plya.write_bytes(trimesh.exchange.ply.export_ply(trimesh.Trimesh(V, F, process=False),
                                                     encoding="ascii"))
    write_tgf(folder / "mplya.tgf", joints, [[0, 1], [1, 2]])
    seeds["ply ascii"] = (plya, plya)
    write_mesh(folder / "rig.obj", V, F)
    # the bar of bad_inputs has more vertices: keep the skin lines of this one's
    lines = [ln for ln in rignet_text().splitlines()
             if not ln.startswith("skin") or int(ln.split()[1]) < len(V)]
    (folder / "rig_rig.txt").write_text("\n".join(lines) + "\n")
    seeds["rignet"] = (folder / "rig.obj", folder / "rig_rig.txt")
    g = folder / "skin.gltf"
    g.write_text(json.dumps(gltf_document()))
    seeds["gltf"] = (g, g)
    return seeds


def _mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        kind = rng.randrange(6)
        pos = rng.randrange(max(len(b), 1))
        if kind == 0 and b:  # flip a byte
            b[pos] = rng.randrange(256)
        elif kind == 1:  # truncate
            del b[pos:]
        elif kind == 2:  # insert a token
            b[pos:pos] = rng.choice(TOKENS)
        elif kind == 3:  # replace a number-looking run with a token
            end = pos
            while end < len(b) and chr(b[end]) in "0123456789.-e":
                end += 1
            b[pos:end] = rng.choice(TOKENS)
        elif kind == 4:  # duplicate a line
            lines = bytes(b).split(b"\n")
            k = rng.randrange(len(lines))
            lines.insert(k, lines[k])
            b = bytearray(b"\n".join(lines))
        else:  # delete a line
            lines = bytes(b).split(b"\n")
            del lines[rng.randrange(len(lines))]
            b = bytearray(b"\n".join(lines))
    return bytes(b)


def _mutate_json(doc, rng: random.Random):
    """Change one value of a glTF document: an index, a count, a type, a list, a key."""

    def walk(x, path, paths):
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, path + [k], paths)
        elif isinstance(x, list):
            for k, v in enumerate(x):
                walk(v, path + [k], paths)
        if path and path[-1] != "uri":
            paths.append(path)

    for _ in range(rng.randint(1, 3)):
        paths: list = []
        walk(doc, [], paths)
        path = rng.choice(paths)
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        choice = rng.randrange(6)
        if choice == 0:
            value = rng.choice([-1, 0, 1, 2, 3, 4, 5, 99, 2**40, 5130])
        elif choice == 1:
            value = None
        elif choice == 2:
            value = rng.choice(["VEC3", "MAT4", "SCALAR", "x", "\udcff"])
        elif choice == 3:
            value = [rng.randrange(-1, 6) for _ in range(rng.randint(0, 4))]
        elif choice == 4:
            value = 1e308
        else:
            value = {"children": [rng.randrange(-1, 6)]}
        try:
            parent[path[-1]] = value
        except (TypeError, IndexError):
            pass
    return doc


class _Hang(Exception):
    pass


def _read(path):
    def ring(signum, frame):
        raise _Hang

    old = signal.signal(signal.SIGALRM, ring)
    signal.alarm(SECONDS_PER_READ)
    try:
        return load_model(path)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


READERS = ["obj", "off", "ply", "ply ascii", "stl", "stl ascii", "tgf", "dmat ascii",
           "dmat binary", "rignet", "gltf"]


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    return _seed_files(tmp_path_factory.mktemp("fuzz_seeds"))


@pytest.mark.parametrize("reader", READERS)
def test_reader_fuzz(reader, seeds, tmp_path):
    model, target = seeds[reader]
    _read(model)  # the seed itself reads
    original = target.read_bytes()
    rng = random.Random(f"{reader}-{N}")
    outcomes: Counter = Counter()
    bad = []
    work = tmp_path / "w"
    work.mkdir()
    for src in Path(model).parent.glob(Path(model).stem + "*"):  # the model and its sidecars
        (work / src.name).write_bytes(src.read_bytes())
    wmodel, wtarget = work / Path(model).name, work / Path(target).name
    for k in range(N):
        if reader == "gltf":
            doc = _mutate_json(json.loads(original), rng)
            wtarget.write_text(json.dumps(doc))
        else:
            wtarget.write_bytes(_mutate_bytes(original, rng))
        try:
            m = _read(wmodel)
            outcomes["model"] += 1
            assert np.all(np.isfinite(m.vertices))
            [n.encode("utf-8") for n in m.bone_names]
        except ValueError as e:
            outcomes["malformed (safety net)" if "malformed file (" in str(e)
                     else "ValueError"] += 1
            if "malformed file (" in str(e):
                bad.append(f"case {k}: {e}")
        except _Hang:
            outcomes["hang"] += 1
            bad.append(f"case {k}: no answer in {SECONDS_PER_READ} s")
        except Exception as e:  # noqa: BLE001 - what the test is looking for
            outcomes[type(e).__name__] += 1
            bad.append(f"case {k}: {type(e).__name__}: {e}")
    print(f"\n{reader}: {N} mutated files: {dict(outcomes)}")
    for b in bad[:10]:
        print("   ", b)
    assert set(outcomes) <= {"model", "ValueError"}, bad[:5]


@pytest.mark.parametrize("ext", [".obj", ".off", ".ply", ".stl"])
def test_fast_parsers_match_trimesh(ext, tmp_path):
    """The fast parsers give trimesh's vertices and faces (vertex order kept) on the files the
    writers of osteon and trimesh make; an OBJ with quads, texture indices and negative
    indices is fan-triangulated over the same corners."""
    import trimesh
    from osteon.io.fastmesh import parse_mesh

    V, F = bar(40.0, 4.0, n=10, stations=5)
    path = tmp_path / f"m{ext}"
    write_mesh(path, V, F)
    data = path.read_bytes()
    fast = parse_mesh(data, ext, str(path))
    assert fast is not None
    ref = trimesh.load(io.BytesIO(data), file_type=ext[1:], process=False, maintain_order=True,
                       force="mesh")
    np.testing.assert_array_equal(fast[0], np.asarray(ref.vertices))
    np.testing.assert_array_equal(fast[1], np.asarray(ref.faces))
    if ext == ".obj":
        text = (b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nvt 0 0\n"
                b"f 1/1 2/1 3/1 4/1\nf -5//1 -4//1 -1//1\n")
        v, f = parse_mesh(text, ".obj", "q.obj")
        assert v.shape == (5, 3)
        np.testing.assert_array_equal(f, [[0, 1, 2], [0, 2, 3], [0, 1, 4]])
        with pytest.raises(ValueError, match="q.obj: a face refers to vertex 9, outside 1..5"):
            parse_mesh(text + b"f 1 2 9\n", ".obj", "q.obj")
        with pytest.raises(ValueError, match="line 9: face index 0"):
            parse_mesh(text + b"f 0 1 2\n", ".obj", "q.obj")
