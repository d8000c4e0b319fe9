#!/usr/bin/env bash
# Builds the engine, its GoogleTest suite and the Python module osteon._core with
# AddressSanitizer + UndefinedBehaviorSanitizer (CMake option OSTEON_SANITIZE=ON, gcc), then runs
# the GoogleTest binaries and the pytest suite against the sanitized module.
#
#   scripts/sanitize.sh                  # everything: ctest + the whole pytest suite
#   scripts/sanitize.sh tests/python/test_robustness.py tests/python/test_fuzz_api.py   # a subset
#
# How the Python side works: the sanitized _core is built with plain CMake into build-asan/ and
# staged next to a copy of python/osteon in build-asan/stage/. A separate venv (.venv-asan, made
# once) sees the packages of .venv through a .pth path line but not .venv's editable hook, so
# `import osteon` picks the staged, sanitized package. CPython itself is not instrumented, so
# libasan (and libstdc++) are LD_PRELOADed and leak detection is off (the interpreter keeps memory until exit).
# UBSan errors abort (-fno-sanitize-recover=undefined); ASan errors abort. Needs: gcc/g++ with
# libasan/libubsan (Debian: build-essential), cmake, ninja, Eigen, GoogleTest, and .venv
# (scripts/setup.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
BUILD="$ROOT/build-asan"
PY="$ROOT/.venv/bin/python"
GEN=(-G Ninja)
command -v ninja >/dev/null || GEN=()

echo "== sanitized build (ASan + UBSan): engine, GoogleTest, osteon._core"
cmake -S . -B "$BUILD" "${GEN[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOSTEON_SANITIZE=ON \
  -DOSTEON_BUILD_TESTS=ON -DOSTEON_BUILD_PYTHON=ON -DPython_EXECUTABLE="$PY" \
  -Dpybind11_DIR="$("$PY" -m pybind11 --cmakedir)" >/dev/null
cmake --build "$BUILD" -j "$(nproc)"

export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
echo "== GoogleTest under ASan + UBSan"
ASAN_OPTIONS="detect_leaks=1:abort_on_error=1" ctest --test-dir "$BUILD" --output-on-failure

echo "== pytest under ASan + UBSan"
STAGE="$BUILD/stage"
rm -rf "$STAGE"
mkdir -p "$STAGE"
cp -r python/osteon "$STAGE/osteon"
find "$STAGE/osteon" -name '_core*.so' -delete
cp "$BUILD"/_core*.so "$STAGE/osteon/"
VENV="$ROOT/.venv-asan"
if [ ! -x "$VENV/bin/python" ]; then
  BASE_PY="$("$PY" -c 'import sys; print(sys._base_executable)')"
  "$BASE_PY" -m venv "$VENV"
fi
SITE_MAIN="$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
SITE_ASAN="$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
echo "$SITE_MAIN" > "$SITE_ASAN/osteon_main_venv.pth"
# libstdc++ must be loaded when ASan starts, or its __cxa_throw interceptor finds no real
# __cxa_throw ("CHECK failed: real___cxa_throw != 0") on the first C++ exception.
LIBASAN="$(${CXX:-g++} -print-file-name=libasan.so)"
LIBSTDCXX="$(${CXX:-g++} -print-file-name=libstdc++.so)"
export LD_PRELOAD="$LIBASAN $LIBSTDCXX"
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:detect_odr_violation=0"
export PYTHONPATH="$STAGE"
"$VENV/bin/python" -c 'import osteon._core as c, sys; print("[sanitize] using", c.__file__)' \
  | grep -q "$STAGE" || { echo "sanitized osteon._core not picked up" >&2; exit 1; }
# The console-script test runs the installed `osteon` of .venv in a child process: it would not
# use the sanitized module, and .venv-asan has no console script.
if [ $# -eq 0 ]; then
  set -- tests/python --deselect tests/python/test_install.py::test_console_script_analyzes_a_model
fi
"$VENV/bin/python" -m pytest -q -p no:cacheprovider "$@"
