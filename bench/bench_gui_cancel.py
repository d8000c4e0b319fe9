"""Analyze in a real Blender window: the guard's answer time and the time to stop after Esc.

    xvfb-run -a blender --factory-startup --enable-event-simulate \\
        --python bench/bench_gui_cancel.py -- [--repeat 5] [--size-mm 40000]

In the window (not ``-b``) the panel's Analyze runs as a modal job. This script builds the sample
figurine, then, ``--repeat`` times each:

* guard: scales it x1000 with "Scene units" (2.45 km) and clicks Analyze (INVOKE): the time
  until the operator has answered with its dialog, no section cut;
* cancel: prints it ``--size-mm`` tall (~1 section per mm at 2 mm), clicks Analyze (with no
  section limit), waits until
  ``--after`` sections are cut, sends Esc (``Window.event_simulate``) and records the time from
  Esc to the engine's stop (``OsteonJobOperator.last["stop_seconds"]``) and that the scene kept
  no result;

then prints the medians and quits. It imports osteon from ``OSTEON_SITE`` (a site-packages
folder, e.g. this checkout's ``.venv/lib/python3.11/site-packages``) when set, and the add-on
from this checkout, so it needs no install.
"""

from __future__ import annotations

import os
import site
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if os.environ.get("OSTEON_SITE"):
    site.addsitedir(os.environ["OSTEON_SITE"])
    sys.path.insert(0, sys.path.pop())  # ahead of Blender's own site-packages
sys.path.insert(0, str(ROOT / "blender_addon"))

import bpy
from blender_window import view3d


def _args():
    import argparse

    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--size-mm", type=float, default=100000.0)
    ap.add_argument("--after", type=int, default=5000)
    return ap.parse_args(argv)


ARGS = _args()
print("bench_gui_cancel: start", flush=True)


def _invoke(**kw):
    win, area, region, _ui = view3d(make=True)
    with bpy.context.temp_override(window=win, area=area, region=region):
        return bpy.ops.osteon.analyze("INVOKE_DEFAULT", **kw)


def main():
    import osteon_blender
    from osteon_blender import bridge
    from osteon_blender import sample as make_sample_rig
    from osteon_blender.ops._base import OsteonJobOperator

    osteon_blender.register()
    obj, arm = make_sample_rig.build()
    print("bench_gui_cancel: sample built", flush=True)
    s = bpy.context.scene.osteon
    guard_s, stop_s, wall_s, runs = [], [], [], []

    def clear():
        if obj.data.attributes.get(bridge.LAYER) is not None:
            obj.data.attributes.remove(obj.data.attributes[bridge.LAYER])
        s.has_result = False

    def steps():
        # the guard: x1000 in scene units
        s.size_mode, arm.scale = "UNITS", (1000.0, 1000.0, 1000.0)
        bpy.context.view_layer.update()
        for _ in range(ARGS.repeat):
            t0 = time.perf_counter()
            result = _invoke()
            guard_s.append(time.perf_counter() - t0)
            print(f"bench_gui_cancel: guard answered {result} in {guard_s[-1]:.3f} s", flush=True)
            assert result == {"RUNNING_MODAL"} or "CANCELLED" in result, result
            yield 0.3
            win = bpy.context.window_manager.windows[0]
            win.event_simulate(type="ESC", value="PRESS")  # close the dialog
            yield 0.3
        assert not s.has_result
        s.size_mode, arm.scale = "HEIGHT", (1.0, 1.0, 1.0)
        s.print_size_mm = ARGS.size_mm
        bpy.context.view_layer.update()
        for _ in range(ARGS.repeat):
            clear()
            assert _invoke(max_sections=0) == {"RUNNING_MODAL"}  # past the guard
            print(f"bench_gui_cancel: started {OsteonJobOperator.running}", flush=True)
            t_wait = time.perf_counter()
            while (OsteonJobOperator.running is None
                   or OsteonJobOperator.running.sections_done < ARGS.after):
                if time.perf_counter() - t_wait > 30:
                    raise RuntimeError(f"the job did not reach {ARGS.after} sections: "
                                       f"{OsteonJobOperator.running}, {OsteonJobOperator.last}")
                if os.environ.get("OSTEON_DEBUG"):
                    print(f"  {time.perf_counter() - t_wait:.3f} s: {OsteonJobOperator.running}",
                          flush=True)
                yield 0.005
            t_esc = time.perf_counter()
            bpy.context.window_manager.windows[0].event_simulate(type="ESC", value="PRESS")
            while OsteonJobOperator.running is not None:
                yield 0.01
            wall_s.append(time.perf_counter() - t_esc)
            last = dict(OsteonJobOperator.last)
            assert last["outcome"] == "cancelled", last
            assert not s.has_result and obj.data.attributes.get(bridge.LAYER) is None
            stop_s.append(last["stop_seconds"])
            print(f"bench_gui_cancel: cancelled {last}", flush=True)
            runs.append(last)
            yield 0.2
        print(f"guard (x1000, 2.45 km): median {statistics.median(guard_s) * 1e3:.1f} ms "
              f"over {len(guard_s)} clicks: {[round(x * 1e3, 1) for x in guard_s]}")
        print(f"Esc -> engine stopped: median {statistics.median(stop_s) * 1e3:.1f} ms over "
              f"{len(stop_s)} runs: {[round(x * 1e3, 1) for x in stop_s]}; sections done at "
              f"the stop {[r['sections_done'] for r in runs]} of {runs[0]['sections_total']}")
        print(f"Esc sent -> operator ended, seen from the window's timers (includes the frame "
              f"time): median {statistics.median(wall_s) * 1e3:.0f} ms: "
              f"{[round(x * 1e3) for x in wall_s]}")

    gen = steps()

    def tick():
        try:
            return next(gen)
        except StopIteration:
            bpy.ops.wm.quit_blender()
        except Exception:  # noqa: BLE001
            import traceback

            traceback.print_exc()
            os._exit(1)
        return None

    bpy.app.timers.register(tick, first_interval=1.0)


main()
