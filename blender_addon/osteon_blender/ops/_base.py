"""Common operator behaviour: user errors become report() messages, never tracebacks; long
engine runs (Analyze, Correct) show their progress and stop on Esc."""

from __future__ import annotations

import threading
import time
import traceback

import bpy

from .. import core, prefs, service
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


# events a running job lets through: they move the view, never the data
_VIEW_EVENTS = {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "WHEELINMOUSE", "WHEELOUTMOUSE",
                "MOUSEMOVE", "INBETWEEN_MOUSEMOVE", "TRACKPADPAN", "TRACKPADZOOM",
                "MOUSEROTATE", "NDOF_MOTION"}
_POLL_S = 0.05


class OsteonJobOperator(OsteonOperator):
    """An engine job (subclasses: ``steps(job)``, a generator of service steps, and
    ``finished(report)`` -> the INFO message).

    * ``execute`` (scripts, background mode, the redo panel): runs at once, as before; above
      ``max_sections`` sections (< 0: the preference "Section limit"; 0: no limit) it reports
      the guard's message and does nothing.
    * ``invoke`` (a button in the UI): the guard asks first (a dialog: OK runs anyway,
      clicking away cancels); then the engine runs in a worker thread while a modal timer shows
      "n / N sections" in the status bar and the progress cursor; Esc cancels: the engine stops
      between sections and nothing is written to the scene.
    """

    max_sections: bpy.props.IntProperty(
        name="Section limit", default=-1, min=-1,
        description=("Refuse (scripts) or ask (UI) above this many sections; -1: the add-on "
                     "preference, 0: no limit"),
        options={"SKIP_SAVE"},
    )

    #: the Progress of the job under way (None when none runs), for scripts and tests
    running = None
    #: how the last interactive job ended: operator, outcome ("finished", "cancelled",
    #: "error"), sections_done, sections_total, seconds (start to end), stop_seconds (Esc to
    #: the engine's stop, cancelled jobs)
    last: dict = {}  # noqa: RUF012 (replaced, never mutated)

    def steps(self, job):
        raise NotImplementedError

    def finished(self, report: dict) -> str:
        raise NotImplementedError

    def _limit(self, context) -> int:
        return prefs.max_sections(context) if self.max_sections < 0 else self.max_sections

    # ------------------------------------------------------------------ at once
    def run(self, context) -> str:
        report = service.run_steps(self.steps(service.Job(context,
                                                          max_sections=self._limit(context))))
        return self.finished(report)

    def execute(self, context):
        if getattr(self, "_interactive", False):  # OK in the guard's dialog
            self._interactive = False
            return self._start(context, max_sections=0)
        return super().execute(context)

    # ------------------------------------------------------------------ interactive
    def invoke(self, context, _event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return self._start(context, max_sections=self._limit(context))

    def draw(self, _context):
        col = self.layout.column(align=True)
        for line in getattr(self, "_guard_message", "").split(": "):
            col.label(text=line)
        col.label(text="OK runs it anyway (Esc stops it); click outside to cancel")

    def _start(self, context, max_sections: int):
        self._progress = core.import_engine().Progress()
        self._job = service.Job(context, progress=self._progress, max_sections=max_sections)
        self._gen = self.steps(self._job)
        try:
            work = next(self._gen)
        except StopIteration as stop:  # nothing for the engine to do
            return self._done(context, stop.value)
        except service.TooManySections as e:
            self._guard_message = str(e)
            self._interactive = True
            return context.window_manager.invoke_props_dialog(self, width=460)
        except Exception as e:  # noqa: BLE001 -- OsteonError or a bug
            return self._fail(context, e)
        self._t_cancel = None
        self._t_start = time.perf_counter()
        OsteonJobOperator.running = self._progress
        self._launch(work)
        wm = context.window_manager
        self._timer = wm.event_timer_add(_POLL_S, window=context.window)
        try:
            wm.progress_begin(0.0, 1.0)
            self._wm = wm
        except Exception:  # noqa: BLE001
            self._wm = None
        wm.modal_handler_add(self)
        self._show(context)
        return {"RUNNING_MODAL"}

    def _launch(self, work) -> None:
        self._outcome = None

        def body():
            try:
                self._outcome = (True, work())
            except BaseException as e:  # noqa: BLE001 -- handed back to the main thread
                self._outcome = (False, e)
            self._t_end = time.perf_counter()

        self._thread = threading.Thread(target=body, name="osteon-job", daemon=True)
        self._thread.start()

    def _show(self, context) -> None:
        p = self._progress
        if self._t_cancel is not None:
            text = f"Osteon: {self._job.stage} cancelling..."
        else:
            total = p.sections_total
            sections = f"{p.sections_done} / {total} sections" if total else "planning sections"
            runs = f", analysis {p.runs_done + 1}" if self._job.stage == "Correct" else ""
            text = f"Osteon: {self._job.stage}{runs}: {sections} (Esc to cancel)"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        if self._wm is not None:
            self._wm.progress_update(p.fraction)

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS" and self._t_cancel is None:
            self._t_cancel = time.perf_counter()
            self._progress.cancel()  # the engine stops between sections
            self._show(context)
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"} if event.type in _VIEW_EVENTS else {"RUNNING_MODAL"}
        if self._thread.is_alive():
            self._show(context)
            return {"RUNNING_MODAL"}
        self._job.context = context
        ok, value = self._outcome
        try:
            work = self._gen.send(value) if ok else self._gen.throw(value)
        except StopIteration as stop:
            return self._done(context, stop.value)
        except Exception as e:  # noqa: BLE001 -- a cancel, an OsteonError or a bug
            return self._fail(context, e)
        self._launch(work)
        self._show(context)
        return {"RUNNING_MODAL"}

    def _cleanup(self, context, outcome: str = "") -> None:
        if getattr(self, "_t_start", None) is not None:
            p, t_end = self._progress, getattr(self, "_t_end", time.perf_counter())
            OsteonJobOperator.last = {
                "operator": self.bl_idname, "outcome": outcome,
                "sections_done": p.sections_done, "sections_total": p.sections_total,
                "seconds": t_end - self._t_start,
                "stop_seconds": t_end - self._t_cancel if self._t_cancel else None}
            OsteonJobOperator.running = None
            self._t_start = None
        timer = getattr(self, "_timer", None)
        if timer is not None:
            context.window_manager.event_timer_remove(timer)
            self._timer = None
        if getattr(self, "_wm", None) is not None:
            self._wm.progress_end()
            self._wm = None
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def _done(self, context, report):
        self._cleanup(context, "finished")
        msg = self.finished(report)
        if msg:
            self.report({"INFO"}, msg)
        return {"FINISHED"}

    def _fail(self, context, e: BaseException):
        cancelled = isinstance(e, core.import_engine().Cancelled)
        self._cleanup(context, "cancelled" if cancelled else "error")
        if cancelled:
            stop = OsteonJobOperator.last.get("stop_seconds") or 0.0
            self.report({"WARNING"}, f"{self.bl_label} cancelled (the engine stopped "
                                     f"{stop * 1e3:.0f} ms after Esc); the scene is unchanged")
        elif isinstance(e, OsteonError):
            self.report({"ERROR"}, str(e))
        else:
            traceback.print_exception(type(e), e, e.__traceback__)
            self.report({"ERROR"}, f"osteon internal error ({type(e).__name__}): {e}")
        return {"CANCELLED"}
