#!/usr/bin/env bash
# Runs the add-on tests (tests/blender) in THREE Blenders and fails if any fails:
#   (a) Debian's Blender 3.4.1:  blender -b --python-exit-code 1 --python run_in_blender.py
#   (b) the PyPI bpy 4.5 wheel (Python 3.11):  .venv-bpy/bin/python -m pytest tests/blender
#   (c) the PyPI bpy 5.2 wheel (Python 3.13):  .venv-bpy52/bin/python -m pytest tests/blender
# First wires what they need (scripts/blender_setup.sh). Extra args go to pytest.
# Env: OSTEON_SKIP_SETUP=1 skips the setup step; OSTEON_SKIP_BPY=1 runs (a) only;
#      OSTEON_BPY_VENV, OSTEON_BPY52_VENV name the bpy venvs.
set -uo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
if [ "${OSTEON_SKIP_SETUP:-0}" != 1 ]; then
  bash scripts/blender_setup.sh || { echo "[blender_tests] setup failed"; exit 1; }
fi
export OSTEON_DIST="$ROOT/dist"

echo "[blender_tests] (a) Debian Blender: $(blender --version 2>/dev/null | head -1)"
blender -b --factory-startup --python-exit-code 1 \
  --python tests/blender/run_in_blender.py -- tests/blender -q -ra "$@"
rc_a=$?
echo "[blender_tests] Debian Blender exit code $rc_a"

rc_b=0
if [ "${OSTEON_SKIP_BPY:-0}" != 1 ]; then
  BPY_VENV="${OSTEON_BPY_VENV:-$ROOT/.venv-bpy}"
  echo "[blender_tests] (b) bpy wheel: $("$BPY_VENV/bin/python" -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null)"
  "$BPY_VENV/bin/python" -m pytest tests/blender -q -ra -p no:cacheprovider "$@"
  rc_b=$?
  echo "[blender_tests] bpy wheel exit code $rc_b"
fi

rc_c=0
if [ "${OSTEON_SKIP_BPY:-0}" != 1 ]; then
  BPY52_VENV="${OSTEON_BPY52_VENV:-$ROOT/.venv-bpy52}"
  echo "[blender_tests] (c) bpy wheel: $("$BPY52_VENV/bin/python" -c 'import bpy; print(bpy.app.version_string)' 2>/dev/null)"
  "$BPY52_VENV/bin/python" -m pytest tests/blender -q -ra -p no:cacheprovider "$@"
  rc_c=$?
  echo "[blender_tests] bpy 5.2 wheel exit code $rc_c"
fi
echo "[blender_tests] exit codes: Debian Blender $rc_a, bpy 4.5 $rc_b, bpy 5.2 $rc_c"
if [ "$rc_a" -ne 0 ] || [ "$rc_b" -ne 0 ] || [ "$rc_c" -ne 0 ]; then exit 1; fi
