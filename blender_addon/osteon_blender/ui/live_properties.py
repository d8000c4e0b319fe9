"""scene.osteon_live: the live mode's settings (Live on/off, throttle, Show sections, All
sections)."""

import bpy
from bpy.props import BoolProperty, IntProperty

from .. import overlay, state
from ..core import OsteonError
from ..live import Readout, is_live, start, stop


def _get_enabled(self) -> bool:
    return is_live(self.id_data)


def _set_enabled(self, value: bool) -> None:
    scene = self.id_data
    if not value:
        if is_live(scene):
            stop()
        return
    if is_live(scene):
        return
    ctx = bpy.context
    if ctx.scene != scene:
        return
    try:
        start(ctx)
    except OsteonError as e:
        state.of(scene).live_readout = Readout(status=f"error: {e}")
        print(f"osteon live: {e}")


def _on_show_sections(self, context):
    scene = self.id_data
    overlay.sync(scene)
    sess = state.live_session()
    if self.show_sections and sess is not None and sess.scene_name == scene.name:
        sess.outlined = None            # the timer computes outlines for the latest result


class OsteonLiveSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Live", get=_get_enabled, set=_set_enabled,
        description="Re-analyse the active rigged mesh whenever its pose or shape changes "
                    "(colours and readout follow the edits)")
    throttle_ms: IntProperty(
        name="Throttle (ms)", default=50, min=0, soft_max=1000, max=10000,
        description="Shortest time between two live updates, ms (an update also waits at "
                    "least as long as the previous one took)")
    show_sections: BoolProperty(
        name="Show sections", default=False, update=_on_show_sections,
        description="Draw the outlines of the last analysis's weak sections (magenta), "
                    "doubtful ones (orange) and corner sections (white: a corner raises the "
                    "stress) in the viewport")
    show_all_sections: BoolProperty(
        name="All sections", default=False, update=_on_show_sections,
        description="With Show sections: also draw every other section, thin, coloured by "
                    "stress / allowable (blue 0 to red at the allowable stress, MPa)")


classes = (OsteonLiveSettings,)
