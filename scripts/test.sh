#!/usr/bin/env bash
# Runs every test: C++ unit tests (GoogleTest via ctest), the Python suite on the installed
# wheel (engine, readers, CLI, FEM cross-check, robustness), and the Blender add-on tests in
# Debian's Blender 3.4 and the bpy 4.5 wheel. Installs what it needs first (scripts/setup.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "== C++ unit tests (GoogleTest)"
cmake -S . -B build/ctest -G Ninja -DOSTEON_BUILD_TESTS=ON -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/ctest
ctest --test-dir build/ctest --output-on-failure

echo "== Lint (ruff)"
.venv/bin/ruff check python tests bench blender_addon scripts

echo "== Python tests"
.venv/bin/python -m pytest tests/python -q

if [ -f scripts/blender_tests.sh ]; then
  echo "== Blender add-on tests"
  bash scripts/blender_tests.sh
fi
