#!/usr/bin/env bash
# Screenshots of the Osteon sidebar at its default width in Debian's Blender 3.4.1, in a real
# window under Xvfb (software GL), plus the check that every text it draws fits and that the
# summary leads with the verdict (scripts/ui_screenshots.py).  Artifacts: out/screenshots/
# (<step>_window.png, <step>_panel.png, report.json).  Needs xvfb (scripts/setup.sh installs
# it) and the engine importable by Debian's Blender (scripts/blender_setup.sh).
# Usage: bash scripts/ui_screenshots.sh [out dir]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
OUT="${1:-$ROOT/out/screenshots}"
mkdir -p "$OUT"
command -v xvfb-run >/dev/null || { echo "[ui_screenshots] xvfb-run missing (apt-get install xvfb)"; exit 1; }
rc=0
LIBGL_ALWAYS_SOFTWARE=1 timeout 600 xvfb-run -a -s "-screen 0 1600x1000x24" \
  blender --factory-startup --enable-event-simulate \
  --python scripts/ui_screenshots.py -- --out "$OUT" > "$OUT/log.txt" 2>&1 || rc=$?
grep -E "^osteon ui screenshots" "$OUT/log.txt" || true
echo "[ui_screenshots] exit code $rc, screenshots in $OUT"
exit $rc
