#!/usr/bin/env bash
# Prepares both Blenders for the osteon add-on (idempotent; used by blender_tests.sh, demo.sh
# and CI):
#  1. apt: Debian's blender and the system-Python modules it imports (python3-numpy,
#     python3-scipy, python3-pytest): Debian's Blender 3.4.1 runs on the system Python 3.11.
#  2. the engine wheel and the add-on zips in dist/ (scripts/build_addon.py), rebuilt only
#     when engine sources are newer than the wheel.
#  3. Debian's Blender imports the engine from /usr/local/lib/python3.X/dist-packages, which is
#     on its sys.path: `pip install --no-deps --target` of the wheel there.
#  4. the bpy 4.5 wheel in its own venv (.venv-bpy: bpy==4.5.*, pytest, scipy, pygel3d, pygltflib,
#     osteon wheel).
#  5. Blender 5.1+ embeds Python 3.13: a cp313 osteon wheel built with a Python 3.13
#     (OSTEON_PY313, else python3.13 on PATH, else pyenv's 3.13) in a build venv
#     (.venv-py313: scikit-build-core, pybind11, cmake, ninja), and the bpy 5.2 wheel in its own
#     venv (.venv-bpy52: bpy==5.2.*, pytest, scipy, the cp313 osteon wheel).
# Env: OSTEON_PYTHON (builds the wheel; default .venv/bin/python), OSTEON_BPY_VENV,
#      OSTEON_BPY52_VENV, OSTEON_PY313, OSTEON_BLENDER_SITE (where Debian's Blender gets the
#      engine), OSTEON_SKIP_BPY=1 (skips 4 and 5).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
log() { echo "[blender_setup] $*"; }

# 1. Debian packages ---------------------------------------------------------------------
missing=()
for p in blender python3-numpy python3-scipy python3-pytest; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "apt-get install ${missing[*]}"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# 2. engine wheel + add-on zips ----------------------------------------------------------
# A compiler cache, where the machine has one, makes the wheels' rebuilds fast.
if command -v ccache >/dev/null 2>&1; then
  export CMAKE_ARGS="${CMAKE_ARGS:-} -DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
fi
PY="${OSTEON_PYTHON:-$ROOT/.venv/bin/python}"
if [ ! -x "$PY" ]; then
  log "no $PY: run scripts/setup.sh first (or set OSTEON_PYTHON)"; exit 1
fi
TAG="$("$PY" -c 'import sys; print(f"cp{sys.version_info[0]}{sys.version_info[1]}")')"
WHEEL="$(ls -t dist/osteon-*-"$TAG"-*.whl 2>/dev/null | head -1 || true)"
newer_than() {  # newer_than FILE PATHS...: prints the first source file newer than FILE
  local ref="$1"; shift
  find "$@" -type f -newer "$ref" -not -name '*.pyc' -not -path '*/__pycache__/*' \
    2>/dev/null | head -1
}
if [ -z "$WHEEL" ] || [ -n "$(newer_than "$WHEEL" cpp bindings python CMakeLists.txt pyproject.toml)" ]; then
  log "building the osteon wheel and the add-on zips"
  "$PY" scripts/build_addon.py --out dist
  WHEEL="$(ls -t dist/osteon-*-"$TAG"-*.whl | head -1)"
else
  ZIP="$(ls -t dist/osteon_blender-*-legacy.zip 2>/dev/null | head -1 || true)"
  if [ -z "$ZIP" ] || [ -n "$(newer_than "$ZIP" blender_addon "$WHEEL")" ]; then
    log "rebuilding the add-on zips"
    "$PY" scripts/build_addon.py --out dist --wheel "$WHEEL"
  fi
fi
log "engine wheel: $WHEEL"

# 3. Debian's Blender ----------------------------------------------------------------------
BPYVER="$(blender -b --factory-startup --python-expr \
  'import sys; print("PYVER=%d.%d" % sys.version_info[:2])' 2>/dev/null | sed -n 's/^PYVER=//p')"
if [ "cp${BPYVER/./}" != "$TAG" ]; then
  log "Debian's Blender runs Python $BPYVER but the wheel is $TAG: set OSTEON_PYTHON"; exit 1
fi
SITE="${OSTEON_BLENDER_SITE:-/usr/local/lib/python$BPYVER/dist-packages}"
$SUDO mkdir -p "$SITE"
$SUDO "$PY" -m pip install -q --no-deps --upgrade --target "$SITE" "$WHEEL"
# pygel3d (pure-Python wheel + its own shared library) for "Make skeleton" (osteon.auto_skeleton)
blender -b --factory-startup --python-exit-code 1 --python-expr 'import pygel3d' >/dev/null 2>&1 ||
  $SUDO "$PY" -m pip install -q --no-deps --upgrade --target "$SITE" "pygel3d>=0.8"
blender -b --factory-startup --python-exit-code 1 --python-expr \
  'import osteon, numpy; print("[blender_setup] Debian Blender imports", osteon.__file__)' \
  2>&1 | grep 'blender_setup'

# 4. bpy 4.5 wheel -----------------------------------------------------------------------------
if [ "${OSTEON_SKIP_BPY:-0}" != 1 ]; then
  BPY_VENV="${OSTEON_BPY_VENV:-$ROOT/.venv-bpy}"
  if [ ! -x "$BPY_VENV/bin/python" ]; then
    log "creating $BPY_VENV"
    BASE="$("$PY" -c 'import sys; print(sys._base_executable)')"
    "$BASE" -m venv "$BPY_VENV"
  fi
  "$BPY_VENV/bin/python" -c 'import bpy, pytest, scipy' >/dev/null 2>&1 ||
    "$BPY_VENV/bin/python" -m pip install -q "bpy==4.5.*" pytest scipy
  "$BPY_VENV/bin/python" -m pip install -q --no-deps --force-reinstall "$WHEEL"
  "$BPY_VENV/bin/python" -c 'import pygel3d' >/dev/null 2>&1 ||
    "$BPY_VENV/bin/python" -m pip install -q "pygel3d>=0.8"
  # the wheel's glTF reader: the Fox test compares Blender's glTF import with it
  "$BPY_VENV/bin/python" -c 'import pygltflib' >/dev/null 2>&1 ||
    "$BPY_VENV/bin/python" -m pip install -q "pygltflib>=1.16"
  log "bpy wheel ready in $BPY_VENV"
fi

# 5. Python 3.13: cp313 engine wheel + bpy 5.2 wheel ------------------------------------------
if [ "${OSTEON_SKIP_BPY:-0}" != 1 ]; then
  PY313="${OSTEON_PY313:-}"
  if [ -z "$PY313" ]; then
    # A pyenv shim for python3.13 exists even when 3.13 is not the active version (and then
    # fails), so a candidate counts only if it runs.
    for c in "$(command -v python3.13 || true)" \
      $(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.13*/bin/python 2>/dev/null | sort -rV); do
      if [ -n "$c" ] && "$c" -c 'import sys; assert sys.version_info[:2] == (3, 13)' 2>/dev/null; then
        PY313="$c"; break
      fi
    done
  fi
  if [ -z "$PY313" ] || [ ! -x "$PY313" ]; then
    log "no Python 3.13 found (set OSTEON_PY313; e.g. pyenv install 3.13)"; exit 1
  fi
  BUILD313="$ROOT/.venv-py313"
  if [ ! -x "$BUILD313/bin/python" ]; then
    log "creating the cp313 build venv $BUILD313 with $("$PY313" --version)"
    "$PY313" -m venv "$BUILD313"
  fi
  "$BUILD313/bin/python" -c 'import scikit_build_core, pybind11, cmake, ninja' >/dev/null 2>&1 ||
    "$BUILD313/bin/python" -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12" cmake ninja
  WHEEL313="$(ls -t dist/osteon-*-cp313-*.whl 2>/dev/null | head -1 || true)"
  if [ -z "$WHEEL313" ] || [ -n "$(newer_than "$WHEEL313" cpp bindings python CMakeLists.txt pyproject.toml)" ]; then
    log "building the cp313 osteon wheel"
    "$BUILD313/bin/python" -m pip wheel -q "$ROOT" --no-deps --no-build-isolation -w dist \
      -C "build-dir=$ROOT/build/wheel-blender-{wheel_tag}"
    WHEEL313="$(ls -t dist/osteon-*-cp313-*.whl | head -1)"
  fi
  log "cp313 engine wheel: $WHEEL313"
  BPY52_VENV="${OSTEON_BPY52_VENV:-$ROOT/.venv-bpy52}"
  if [ ! -x "$BPY52_VENV/bin/python" ]; then
    log "creating $BPY52_VENV"
    "$PY313" -m venv "$BPY52_VENV"
  fi
  "$BPY52_VENV/bin/python" -c 'import bpy, pytest, scipy' >/dev/null 2>&1 ||
    "$BPY52_VENV/bin/python" -m pip install -q "bpy==5.2.*" pytest scipy
  "$BPY52_VENV/bin/python" -m pip install -q --no-deps --force-reinstall "$WHEEL313"
  "$BPY52_VENV/bin/python" -c 'import pygel3d' >/dev/null 2>&1 ||
    "$BPY52_VENV/bin/python" -m pip install -q "pygel3d>=0.8"
  "$BPY52_VENV/bin/python" -c 'import pygltflib' >/dev/null 2>&1 ||
    "$BPY52_VENV/bin/python" -m pip install -q "pygltflib>=1.16"
  log "bpy 5.2 wheel ready in $BPY52_VENV"
fi

# 6. the add-on zips from both engine wheels (scripts/build_addon.py): the extension zip carries
#    cp311 (Blender 4.2-5.0) and cp313 (5.1+), the legacy zip cp311 (4.1, Debian's 3.4.1);
#    tests/blender/test_packaging.py checks exactly that. Zipping takes about a second.
if [ -n "${WHEEL313:-}" ]; then
  "$PY" scripts/build_addon.py --out dist --wheel "$WHEEL" --wheel "$WHEEL313"
fi
