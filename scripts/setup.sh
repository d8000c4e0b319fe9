#!/usr/bin/env bash
# Installs what osteon needs on a fresh Debian machine (apt: compilers incl. clang/libFuzzer,
# Eigen, GoogleTest, Blender, CalculiX, gmsh, Xvfb) and builds the engine into ./.venv (editable install).
# Idempotent: a second run only rebuilds what changed. Used by scripts/demo.sh, scripts/test.sh
# and .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

APT_PACKAGES=(build-essential cmake ninja-build libeigen3-dev libgtest-dev blender calculix-ccx gmsh
  xvfb python3-venv clang libclang-rt-14-dev prusa-slicer)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] apt-get install ${missing[*]}"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

PYTHON="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  echo "[setup] creating .venv with $($PYTHON --version)"
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q "scikit-build-core>=0.10" "pybind11>=2.12" cmake ninja
# A compiler cache, where the machine has one, makes rebuilds after small C++ edits fast.
if command -v ccache >/dev/null 2>&1; then
  export CMAKE_ARGS="${CMAKE_ARGS:-} -DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
fi
echo "[setup] building osteon (C++ engine + Python package)"
.venv/bin/python -m pip install -q --no-build-isolation -e ".[test]"
.venv/bin/python -c "import osteon; print('[setup] osteon', osteon.__version__, 'ready in .venv')"
