#!/usr/bin/env bash
# The README demo: on a fresh Debian machine, build osteon, build the bundled sample rigged
# figurine in Blender, analyse and correct it headless. Leaves in out/:
#   sample_rig.blend            the sample model (made from primitives by osteon_blender/sample.py)
#   sample_stress.png           stress map of the model as modelled (red = at/over allowable)
#   sample_report.json          report of the correction run (before/after, bone scales)
#   sample_corrected.png        stress map after the correction
#   sample_corrected.blend      the corrected model (pose-bone scales + osteon_stress layer)
# Env: OSTEON_SKIP_SETUP=1 to skip installing/building.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT"
if [ "${OSTEON_SKIP_SETUP:-0}" != 1 ]; then
  bash scripts/setup.sh
  OSTEON_SKIP_BPY=1 bash scripts/blender_setup.sh
fi
mkdir -p out
BATCH=blender_addon/osteon_blender/batch.py
blender -b --factory-startup --python-exit-code 1 --python blender_addon/osteon_blender/sample.py -- \
  --out out/sample_rig.blend
blender -b out/sample_rig.blend --python-exit-code 1 --python "$BATCH" -- \
  --report out/sample_analysis.json --png out/sample_stress.png
blender -b out/sample_rig.blend --python-exit-code 1 --python "$BATCH" -- \
  --correct --report out/sample_report.json --png out/sample_corrected.png \
  --save out/sample_corrected.blend
"$ROOT/.venv/bin/python" - <<'PY'
import json
r = json.load(open("out/sample_report.json"))
c = r["correction"]
print(f"max stress {c['max_stress_before_mpa']:.1f} -> {r['max_stress_mpa']:.1f} MPa "
      f"(allowable {r['allowable_stress_mpa']:.1f} MPa), converged: {r['converged']}")
for b in r["weak_bones"]:
    print(f"  {b['bone']:>12}: {b['max_stress_before_mpa']:.1f} -> {b['max_stress_mpa']:.1f} MPa,"
          f" cross-section x{b['scale']:.2f}")
PY
ls -l out/sample_stress.png out/sample_report.json out/sample_corrected.blend
