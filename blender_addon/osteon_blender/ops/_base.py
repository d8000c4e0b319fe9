"""Common operator behaviour: user errors become report() messages, never tracebacks."""

from __future__ import annotations

import traceback

from ..core import OsteonError


class OsteonOperator:
    bl_options = {"REGISTER", "UNDO"}  # noqa: RUF012 (Blender wants a set)

    def run(self, context) -> str:  # returns the INFO message
        raise NotImplementedError

    def progress(self, fraction: float) -> None:
        """Progress in [0, 1] on the window manager's progress bar (no-op in background)."""
        wm = getattr(self, "_wm", None)
        if wm is not None:
            wm.progress_update(fraction)

    def execute(self, context):
        wm = context.window_manager
        try:
            wm.progress_begin(0.0, 1.0)
        except Exception:  # noqa: BLE001 (no progress bar in some background setups)
            wm = None
        self._wm = wm
        try:
            msg = self.run(context)
        except OsteonError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        except Exception as e:  # noqa: BLE001 -- a bug: say so briefly, keep the traceback on the console
            traceback.print_exc()
            self.report({"ERROR"}, f"osteon internal error ({type(e).__name__}): {e}")
            return {"CANCELLED"}
        finally:
            if wm is not None:
                wm.progress_end()
        if msg:
            self.report({"INFO"}, msg)
        return {"FINISHED"}
