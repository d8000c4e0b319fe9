#!/usr/bin/env bash
# Runs every test: C++ unit tests (GoogleTest via ctest), the Python suite on the installed
# wheel (engine, readers, CLI, FEM cross-check, robustness, hypothesis), the Blender add-on tests
# in Debian's Blender 3.4, the bpy 4.5 wheel (Python 3.11) and the bpy 5.2 wheel (Python 3.13;
# scripts/blender_tests.sh builds the cp313 engine wheel for it), the sidebar's screenshots in a
# real window under Xvfb (scripts/ui_screenshots.sh, out/screenshots/), a libFuzzer smoke run of the slicer, and the
# C++ tests + Python suite again under AddressSanitizer + UndefinedBehaviorSanitizer.
# Installs what it needs first (scripts/setup.sh). OSTEON_QUICK=1 skips fuzzing and sanitizers.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "== C++ unit tests (GoogleTest)"
launcher=""
if command -v ccache >/dev/null 2>&1; then launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"; fi
cmake -S . -B build/ctest -G Ninja -DOSTEON_BUILD_TESTS=ON -DCMAKE_BUILD_TYPE=Release $launcher >/dev/null
cmake --build build/ctest
ctest --test-dir build/ctest --output-on-failure

echo "== Lint (ruff)"
.venv/bin/ruff check python tests bench blender_addon scripts

echo "== Python tests"
.venv/bin/python -m pytest tests/python -q

echo "== Blender add-on tests (Debian Blender 3.4.1, bpy 4.5, bpy 5.2)"
bash scripts/blender_tests.sh

echo "== Sidebar screenshots and fit check (Debian Blender 3.4.1 in a window under Xvfb)"
bash scripts/ui_screenshots.sh

if [ "${OSTEON_QUICK:-0}" != 1 ]; then
  echo "== Fuzz smoke run (libFuzzer, 20000 inputs)"
  bash scripts/fuzz.sh 20000
  echo "== Sanitizers (ASan + UBSan): GoogleTest and the Python suite"
  bash scripts/sanitize.sh
fi
