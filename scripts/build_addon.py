"""Build the osteon Blender add-on packages.

    python scripts/build_addon.py [--wheel dist/osteon-*.whl] [--out dist]

1. the osteon engine wheel (``pip wheel`` of this repository with the running Python,
   unless ``--wheel`` names one): the wheel's Python tag must match Blender's Python
   (3.11 for Blender 4.1-4.5 and Debian's 3.4.1; build with ``python3.10`` for the
   official Blender 3.4-4.0 builds);
2. ``<out>/osteon_blender-<version>-extension.zip``: a Blender 4.2+ extension, the
   manifest listing the wheel bundled in ``wheels/``;
3. ``<out>/osteon_blender-<version>-legacy.zip``: a legacy add-on (``bl_info``) for
   Blender 3.4-4.1 with the engine unpacked in ``osteon_blender/_vendor/`` (the add-on
   puts that folder on ``sys.path`` when ``import osteon`` fails).

NumPy comes with Blender (Debian: ``python3-numpy``); SciPy is optional (the add-on
passes its sparse weights without it).
"""

from __future__ import annotations

import argparse
import glob
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON = os.path.join(ROOT, "blender_addon", "osteon_blender")

# wheel platform tag -> Blender extension platform
PLATFORMS = {
    "linux_x86_64": "linux-x64", "manylinux": "linux-x64", "linux_aarch64": "linux-arm64",
    "win_amd64": "windows-x64", "win_arm64": "windows-arm64",
    "macosx_arm64": "macos-arm64", "macosx_x86_64": "macos-x64",
}


def addon_version() -> str:
    with open(os.path.join(ADDON, "__init__.py"), encoding="utf-8") as fh:
        text = fh.read()
    m = re.search(r'"version":\s*\((\d+),\s*(\d+),\s*(\d+)\)', text)
    if not m:
        raise SystemExit("bl_info version not found")
    return ".".join(m.groups())


def build_wheel(out: str) -> str:
    os.makedirs(out, exist_ok=True)
    cmd = [sys.executable, "-m", "pip", "wheel", ROOT, "--no-deps", "-w", out,
           "-C", f"build-dir={os.path.join(ROOT, 'build', 'wheel-blender-{wheel_tag}')}"]
    if importlib.util.find_spec("scikit_build_core") and importlib.util.find_spec("pybind11"):
        cmd.append("--no-build-isolation")
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)
    tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
    wheels = sorted(glob.glob(os.path.join(out, f"osteon-*-{tag}-*.whl")), key=os.path.getmtime)
    if not wheels:
        raise SystemExit(f"no osteon {tag} wheel in {out}")
    return wheels[-1]


def platform_of(wheel: str) -> str | None:
    plat = os.path.basename(wheel)[:-4].split("-")[-1]
    for key, value in PLATFORMS.items():
        if key in plat:
            return value
    return None


def addon_files():
    for dirpath, dirnames, filenames in os.walk(ADDON):
        dirnames[:] = [d for d in dirnames if d not in ("__pycache__", "_vendor", "wheels")]
        for name in sorted(filenames):
            if name.endswith((".pyc", ".pyo")):
                continue
            full = os.path.join(dirpath, name)
            yield full, os.path.relpath(full, ADDON)


def manifest_with_wheels(wheel_names: list[str], platform: str | None) -> str:
    with open(os.path.join(ADDON, "blender_manifest.toml"), encoding="utf-8") as fh:
        text = fh.read()
    listed = ", ".join(f'"./wheels/{w}"' for w in wheel_names)
    text, n = re.subn(r"(?m)^wheels\s*=\s*\[.*?\]", f"wheels = [{listed}]", text)
    if n != 1:
        raise SystemExit("blender_manifest.toml needs one 'wheels = [...]' line")
    if platform and "platforms" not in text:
        text = text.replace("\n[permissions]", f'\nplatforms = ["{platform}"]\n\n[permissions]', 1)
    return text


def build_extension(wheel: str, out: str, version: str) -> str:
    path = os.path.join(out, f"osteon_blender-{version}-extension.zip")
    name = os.path.basename(wheel)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for full, rel in addon_files():
            if rel == "blender_manifest.toml":
                z.writestr(rel, manifest_with_wheels([name], platform_of(wheel)))
            else:
                z.write(full, rel)
        z.write(wheel, f"wheels/{name}")
    return path


def build_legacy(wheel: str, out: str, version: str) -> str:
    path = os.path.join(out, f"osteon_blender-{version}-legacy.zip")
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z, zipfile.ZipFile(wheel) as w:
        for full, rel in addon_files():
            if rel != "blender_manifest.toml":  # a manifest would make 4.2+ treat it as extension
                z.write(full, f"osteon_blender/{rel}")
        for info in w.infolist():
            if info.filename.startswith("osteon/") and not info.is_dir():
                z.writestr(f"osteon_blender/_vendor/{info.filename}", w.read(info))
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wheel", help="use this osteon wheel instead of building one")
    ap.add_argument("--out", default=os.path.join(ROOT, "dist"), help="output folder")
    a = ap.parse_args(argv)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    wheel = os.path.abspath(a.wheel) if a.wheel else build_wheel(out)
    if not os.path.isfile(wheel):
        raise SystemExit(f"no such wheel: {wheel}")
    if os.path.dirname(wheel) != out:
        shutil.copy2(wheel, out)
    version = addon_version()
    ext = build_extension(wheel, out, version)
    legacy = build_legacy(wheel, out, version)
    for p in (wheel, ext, legacy):
        print(f"{os.path.getsize(p) / 1024:8.0f} KiB  {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
