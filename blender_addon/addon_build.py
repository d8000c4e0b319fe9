"""Build the osteon Blender add-on packages from osteon engine wheels.

    python scripts/build_addon.py [--wheel W ...] [--wheel-dir DIR] [--python PY ...]
                                  [--out dist] [--validate-with BLENDER_OR_BPY_PYTHON]

Which Blender runs which Python (official builds; the engine is a compiled module, so
its wheel must match):

    Blender          Python  package
    3.4 - 4.0        3.10    legacy zip   (bl_info; engine unpacked in osteon_blender/_vendor)
    4.1, Debian 3.4  3.11    legacy zip
    4.2 - 5.0        3.11    extension zip (blender_manifest.toml; wheels/ carries cp311)
    5.1 and later    3.13    extension zip (wheels/ carries cp313)

For each platform among the wheels (linux-x64, linux-arm64, windows-x64, macos-x64,
macos-arm64) it writes

* ``<out>/osteon_blender-<version>-<platform>-extension.zip``: the Blender 4.2+ extension
  with every cp311/cp313 wheel of that platform in ``wheels/``. Its manifest says exactly
  what the zip carries: ``platforms`` is that one platform, ``wheels`` lists the bundled
  wheels, and ``blender_version_min``/``blender_version_max`` span the Blender releases whose
  Python has a wheel in the zip (both wheels: 4.2.0 and no maximum, because Blender itself
  refuses a zip with no wheel for its Python; cp311 only: 4.2.0 to 5.1.0; cp313 only: 5.1.0
  up).
* ``<out>/osteon_blender-<version>-<platform>-legacy.zip``: the legacy add-on for Blender
  3.4-4.1 with the engine of every cp310/cp311 wheel of that platform unpacked side by side in
  ``osteon_blender/_vendor/osteon/`` (``_core.cpython-310-*.so`` and ``_core.cpython-311-*.so``
  coexist; Python loads the one built for it). The add-on puts ``_vendor`` on ``sys.path``
  when ``import osteon`` fails.

Wheels come from ``--wheel``/``--wheel-dir`` (e.g. cibuildwheel's wheelhouse), or are built
here with each ``--python`` interpreter (default: the running one) by ``pip wheel``.
``--validate-with`` runs Blender's own manifest validator on each extension zip: give a
Blender >= 4.2 binary (``blender --command extension validate``) or a Python with the ``bpy``
wheel (the same validator, called through ``bl_pkg``).

Both zips also carry pygel3d (``PYGEL3D``, the curve skeleton behind Make skeleton) for their
platform where PyPI has a wheel: PyGEL3D 0.8.2 publishes py3-none wheels (ctypes + its own
shared library, Python >= 3.11) for linux x86_64 and aarch64 (manylinux_2_28), win_amd64 and
macOS 11+ (universal2, used for macos-x64 and macos-arm64); none for windows-arm64. The
extension lists the wheel in its manifest (Blender installs it), the legacy zip unpacks it
into ``_vendor/`` beside the engine. ``--pygel3d DIR`` takes the wheels from a folder,
``--pygel3d download`` (default) fetches them with ``pip download`` into ``<out>/pygel3d/``
(kept as a cache), ``--pygel3d none`` leaves them out; a platform without a wheel gets a zip
without it, whose Make skeleton says what to do in Blender.

Each zip also carries the user guide, ``docs/blender.md`` (the Preferences' Documentation
button opens it).

NumPy comes with Blender (Debian: ``python3-numpy``); SciPy is optional (the add-on passes
its sparse weights without it).
"""

from __future__ import annotations

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON = os.path.join(ROOT, "blender_addon", "osteon_blender")

# Blender release (major, minor) -> the Python its official builds embed.
BLENDER_PYTHON: dict[tuple[int, int], tuple[int, int]] = {
    (3, 4): (3, 10), (3, 5): (3, 10), (3, 6): (3, 10), (4, 0): (3, 10), (4, 1): (3, 11),
    (4, 2): (3, 11), (4, 3): (3, 11), (4, 4): (3, 11), (4, 5): (3, 11), (5, 0): (3, 11),
    (5, 1): (3, 13), (5, 2): (3, 13),
}
EXTENSIONS_FROM = (4, 2)  # the first Blender with extensions (blender_manifest.toml)
EXTENSION_PYTHONS = {py for v, py in BLENDER_PYTHON.items() if v >= EXTENSIONS_FROM}
# Pythons of the legacy add-on: 3.10 (official 3.4-4.0), 3.11 (4.1, Debian's 3.4.1 build)
LEGACY_PYTHONS = {(3, 10), (3, 11)}

# pygel3d (Make skeleton): the pinned release and, per Blender platform, the pip --platform
# tag that selects its wheel on PyPI (None: PyPI has none)
PYGEL3D = "0.8.2"
PYGEL3D_PLATFORMS = {
    "linux-x64": "manylinux_2_28_x86_64", "linux-arm64": "manylinux_2_28_aarch64",
    "windows-x64": "win_amd64", "windows-arm64": None,
    "macos-x64": "macosx_11_0_x86_64", "macos-arm64": "macosx_11_0_arm64",
}
DOCS = ("docs/blender.md",)  # shipped inside the add-on (prefs.py opens it)

# wheel platform tag (its architecture end) -> Blender extension platform
_ARCH = {
    "linux": {"x86_64": "linux-x64", "aarch64": "linux-arm64"},
    "win": {"amd64": "windows-x64", "arm64": "windows-arm64"},
    "macosx": {"x86_64": "macos-x64", "arm64": "macos-arm64"},
}


def addon_version() -> str:
    with open(os.path.join(ADDON, "__init__.py"), encoding="utf-8") as fh:
        text = fh.read()
    m = re.search(r'"version":\s*\((\d+),\s*(\d+),\s*(\d+)\)', text)
    if not m:
        raise SystemExit("bl_info version not found")
    version = ".".join(m.groups())
    manifest_version = _toml_value(_read_manifest(), "version")
    if manifest_version != version:
        raise SystemExit(f"bl_info version {version} != blender_manifest.toml {manifest_version}")
    return version


def wheel_tags(wheel: str) -> tuple[tuple[int, int], str]:
    """``osteon-0.1.0-cp313-cp313-linux_x86_64.whl`` -> ((3, 13), "linux-x64")."""
    parts = os.path.basename(wheel)[:-4].split("-")
    if not wheel.endswith(".whl") or len(parts) not in (5, 6):
        raise SystemExit(f"not a wheel file name: {wheel}")
    m = re.fullmatch(r"cp(\d)(\d+)", parts[-3])
    if not m:
        raise SystemExit(f"{wheel}: expected a CPython tag like cp311, found {parts[-3]}")
    return (int(m.group(1)), int(m.group(2))), platform_of(wheel)


def platform_of(wheel: str) -> str:
    plat = os.path.basename(wheel)[:-4].split("-")[-1].split(".")[0].lower()
    if plat == "win_amd64":
        return "windows-x64"
    for os_key, archs in _ARCH.items():
        if plat.startswith(os_key) or (os_key == "linux" and plat.startswith("manylinux")):
            for arch, name in archs.items():
                if plat.endswith("_" + arch):
                    return name
            if os_key == "macosx" and plat.endswith("_universal2"):
                raise SystemExit(f"{wheel}: universal2 wheels: build one per architecture")
    raise SystemExit(f"{wheel}: unknown platform tag {plat}")


def build_wheel(python: str, out: str) -> str:
    """``pip wheel`` of this repository with ``python``; returns the wheel's path."""
    os.makedirs(out, exist_ok=True)
    probe = ("import sys, importlib.util as u; print('cp%d%d' % sys.version_info[:2]); "
             "print(bool(u.find_spec('scikit_build_core') and u.find_spec('pybind11')))")
    tag, have_build_deps = subprocess.run([python, "-c", probe], check=True, capture_output=True,
                                          text=True).stdout.split()
    before = set(glob.glob(os.path.join(out, f"osteon-*-{tag}-*.whl")))
    build_dir = os.path.join(ROOT, "build", "wheel-blender-{wheel_tag}")
    cmd = [python, "-m", "pip", "wheel", ROOT, "--no-deps", "-w", out,
           "--config-settings", f"build-dir={build_dir}"]
    if have_build_deps == "True":
        cmd.append("--no-build-isolation")
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    wheels = sorted(glob.glob(os.path.join(out, f"osteon-*-{tag}-*.whl")), key=os.path.getmtime)
    if not wheels:
        raise SystemExit(f"no osteon {tag} wheel in {out}")
    new = [w for w in wheels if w not in before]
    return (new or wheels)[-1]


def addon_files():
    for dirpath, dirnames, filenames in os.walk(ADDON):
        dirnames[:] = sorted(d for d in dirnames if d not in ("__pycache__", "_vendor", "wheels"))
        for name in sorted(filenames):
            if name.endswith((".pyc", ".pyo")):
                continue
            full = os.path.join(dirpath, name)
            yield full, os.path.relpath(full, ADDON).replace(os.sep, "/")


def doc_files():
    for rel in DOCS:
        yield os.path.join(ROOT, *rel.split("/")), rel


def pygel3d_platform(wheel: str) -> list[str]:
    """The Blender platforms a (py3-none) pygel3d wheel serves; universal2: both macOS ones."""
    out = []
    for tag in os.path.basename(wheel)[:-4].split("-")[-1].lower().split("."):
        if tag.endswith("_universal2") and tag.startswith("macosx"):
            out += ["macos-x64", "macos-arm64"]
        else:
            try:
                out.append(platform_of(f"x-{tag}.whl"))
            except SystemExit:
                continue
    return sorted(set(out))


def pygel3d_wheels(source: str, platforms: set[str], out: str) -> dict[str, str]:
    """Blender platform -> pygel3d wheel, from a folder or ``pip download`` (module doc)."""
    if source == "none":
        return {}
    folder = os.path.join(out, "pygel3d") if source == "download" else os.path.abspath(source)
    found: dict[str, str] = {}

    def scan():
        for w in sorted(glob.glob(os.path.join(folder, "pygel3d-*.whl"))):
            for plat in pygel3d_platform(w):
                found.setdefault(plat, w)

    scan()
    if source == "download":
        for plat in sorted(platforms - set(found)):
            tag = PYGEL3D_PLATFORMS.get(plat)
            if tag is None:
                continue
            cmd = [sys.executable, "-m", "pip", "download", "-q", "--no-deps",
                   "--only-binary=:all:", f"PyGEL3D=={PYGEL3D}", "--platform", tag,
                   "--python-version", "3.11", "-d", folder]
            res = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=300)
            if res.returncode != 0:
                print(f"[build_addon] {plat}: no pygel3d {PYGEL3D} wheel "
                      f"({(res.stderr.strip().splitlines() or ['pip failed'])[-1]})")
            scan()
    for plat in sorted(platforms - set(found)):
        print(f"[build_addon] {plat}: no pygel3d wheel: its zips rig no mesh (Make skeleton "
              "says what to do)")
    return {p: w for p, w in found.items() if p in platforms}


def _read_manifest() -> str:
    with open(os.path.join(ADDON, "blender_manifest.toml"), encoding="utf-8") as fh:
        return fh.read()


def _toml_value(text: str, key: str) -> str | None:
    m = re.search(rf'(?m)^{key}\s*=\s*"([^"]*)"', text)
    return m.group(1) if m else None


def _set_key(text: str, key: str, value: str | None) -> str:
    """Set (or with ``value=None`` remove) a top-level ``key = value`` line of the manifest."""
    line = re.compile(rf"(?m)^{key}\s*=.*\n?")
    if value is None:
        return line.sub("", text)
    if line.search(text):
        return line.sub(lambda _m: f"{key} = {value}\n", text, count=1)
    table = re.search(r"(?m)^\[", text)  # top-level keys go before the first [table]
    at = table.start() if table else len(text)
    return text[:at] + f"{key} = {value}\n\n" + text[at:]


def blender_range(pythons: set[tuple[int, int]]) -> tuple[str, str | None]:
    """The extension Blenders (4.2+) whose Python has a wheel in ``pythons`` ->
    (blender_version_min, blender_version_max or None); max is exclusive, as in Blender."""
    releases = sorted(v for v in BLENDER_PYTHON if v >= EXTENSIONS_FROM)
    covered = [v for v in releases if BLENDER_PYTHON[v] in pythons]
    if not covered:
        need = sorted({BLENDER_PYTHON[v] for v in releases})
        raise SystemExit("no wheel for a Blender 4.2+ Python: need one of "
                         + ", ".join(f"cp{a}{b}" for a, b in need))
    first, last = releases.index(covered[0]), releases.index(covered[-1])
    if releases[first:last + 1] != covered:
        raise SystemExit("the wheels leave a gap in the Blender releases they cover: "
                         + ", ".join(f"{a}.{b}" for a, b in covered))
    vmin = "{}.{}.0".format(*covered[0])
    vmax = None if last == len(releases) - 1 else "{}.{}.0".format(*releases[last + 1])
    return vmin, vmax


def extension_manifest(wheels: list[str], platform: str, extra_wheels: tuple = ()) -> str:
    pythons = {wheel_tags(w)[0] for w in wheels}
    vmin, vmax = blender_range(pythons)
    text = _read_manifest()
    text = _set_key(text, "blender_version_min", f'"{vmin}"')
    text = _set_key(text, "blender_version_max", f'"{vmax}"' if vmax else None)
    text = _set_key(text, "platforms", f'["{platform}"]')
    listed = ", ".join(f'"./wheels/{os.path.basename(w)}"' for w in [*wheels, *extra_wheels])
    return _set_key(text, "wheels", f"[{listed}]")


def build_extension(wheels: list[str], platform: str, out: str, version: str,
                    extra_wheels: tuple = ()) -> str:
    """The 4.2+ extension zip of one platform, carrying all its cp311/cp313 wheels (and
    ``extra_wheels``: pygel3d's)."""
    path = os.path.join(out, f"osteon_blender-{version}-{platform.replace('-', '_')}-extension.zip")
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for full, rel in [*addon_files(), *doc_files()]:
            if rel == "blender_manifest.toml":
                z.writestr(rel, extension_manifest(wheels, platform, extra_wheels))
            else:
                z.write(full, rel)
        for w in [*wheels, *extra_wheels]:
            z.write(w, f"wheels/{os.path.basename(w)}")
    return path


def build_legacy(wheels: list[str], platform: str, out: str, version: str,
                 extra_wheels: tuple = ()) -> str:
    """The legacy (bl_info) zip of one platform: the engine of each wheel (and the packages
    of ``extra_wheels``: pygel3d) unpacked into osteon_blender/_vendor (the pure-Python files
    are the same in every wheel)."""
    path = os.path.join(out, f"osteon_blender-{version}-{platform.replace('-', '_')}-legacy.zip")
    written: set[str] = set()
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for full, rel in [*addon_files(), *doc_files()]:
            if rel != "blender_manifest.toml":  # a manifest would make 4.2+ treat it as extension
                z.write(full, f"osteon_blender/{rel}")
        for wheel in [*wheels, *extra_wheels]:
            with zipfile.ZipFile(wheel) as w:
                for info in w.infolist():
                    top = info.filename.split("/", 1)[0]
                    if info.is_dir() or top.endswith((".dist-info", ".data")):
                        continue
                    name = f"osteon_blender/_vendor/{info.filename}"
                    if name not in written:
                        z.writestr(name, w.read(info))
                        written.add(name)
    return path


def validate(zip_path: str, validator: str) -> tuple[bool, str]:
    """Blender's extension validator on ``zip_path``; ``validator`` is a Blender >= 4.2 binary
    or a Python that imports the bpy wheel. Returns (passed, output)."""
    is_python = "python" in os.path.basename(validator).lower()
    if is_python:
        code = ("import sys, bpy\nfrom bl_pkg import bl_extension_cli\n"
                "sys.exit(bl_extension_cli.cli_extension_handler(['validate', sys.argv[1]]))")
        cmd = [validator, "-c", code, zip_path]
    else:
        cmd = [validator, "--factory-startup", "--command", "extension", "validate", zip_path]
    res = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=600)
    return res.returncode == 0, (res.stdout + res.stderr).strip()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 2)[2])
    ap.add_argument("--wheel", action="append", default=[], help="an osteon wheel (repeatable)")
    ap.add_argument("--wheel-dir", action="append", default=[],
                    help="use every osteon-*.whl in this folder (repeatable)")
    ap.add_argument("--python", action="append", default=[],
                    help="build a wheel with this interpreter (repeatable; default: this one "
                         "when no wheel is given)")
    ap.add_argument("--out", default=os.path.join(ROOT, "dist"), help="output folder")
    ap.add_argument("--pygel3d", default="download", metavar="download|DIR|none",
                    help="where the pygel3d wheels come from (default: pip download into "
                         "<out>/pygel3d)")
    ap.add_argument("--validate-with", metavar="BLENDER_OR_PYTHON",
                    help="run Blender's extension validator on each extension zip")
    a = ap.parse_args(argv)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)

    wheels = [os.path.abspath(w) for w in a.wheel]
    for d in a.wheel_dir:
        wheels += sorted(glob.glob(os.path.join(os.path.abspath(d), "osteon-*.whl")))
    pythons = a.python or ([] if wheels else [sys.executable])
    wheels += [build_wheel(py, out) for py in pythons]
    for w in wheels:
        if not os.path.isfile(w):
            raise SystemExit(f"no such wheel: {w}")
    copied = []
    for w in wheels:
        if os.path.dirname(w) != out:
            shutil.copy2(w, out)
        copied.append(os.path.join(out, os.path.basename(w)))
    wheels = copied

    # one wheel per (platform, Python): the newest file wins
    chosen: dict[tuple[str, tuple[int, int]], str] = {}
    for w in sorted(wheels, key=os.path.getmtime):
        py, plat = wheel_tags(w)
        chosen[(plat, py)] = w
    version = addon_version()
    gel = pygel3d_wheels(a.pygel3d, {p for p, _ in chosen}, out)
    made = []
    failed = False
    for plat in sorted({p for p, _ in chosen}):
        mine = [chosen[k] for k in sorted(k for k in chosen if k[0] == plat)]
        ext_wheels = [w for w in mine if wheel_tags(w)[0] in EXTENSION_PYTHONS]
        if ext_wheels:
            extra = (gel[plat],) if plat in gel else ()
            ext = build_extension(ext_wheels, plat, out, version, extra)
            made.append(ext)
            vmin, vmax = blender_range({wheel_tags(w)[0] for w in ext_wheels})
            upto = (f"up to (not incl.) {vmax}" if vmax else
                    "and later (a Blender on another Python finds no wheel and refuses it)")
            print(f"[build_addon] {os.path.basename(ext)}: Blender {vmin} {upto}")
            if a.validate_with:
                ok, text = validate(ext, a.validate_with)
                print(f"[build_addon] Blender validator ({a.validate_with}): "
                      f"{'passed' if ok else 'FAILED'}\n{text}")
                failed |= not ok
        legacy_wheels = [w for w in mine if wheel_tags(w)[0] in LEGACY_PYTHONS]
        if legacy_wheels:
            made.append(build_legacy(legacy_wheels, plat, out, version,
                                     (gel[plat],) if plat in gel else ()))
        else:
            print(f"[build_addon] {plat}: no cp310/cp311 wheel, no legacy zip")
    for p in [*wheels, *made]:
        print(f"{os.path.getsize(p) / 1024:8.0f} KiB  {p}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
