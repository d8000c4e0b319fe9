"""Small layout helpers every sidebar panel uses: a labelled dropdown, text wrapped to the
sidebar's width (px at UI scale 1; the default sidebar is 229 px wide)."""

from __future__ import annotations

LABEL_SPLIT = 0.35    # share of a labelled dropdown's row its label gets
DEFAULT_WIDTH = 229   # px, the sidebar's default width at UI scale 1 (no region: headless)
MARGINS = 54          # px at UI scale 1: tabs, panel borders and insets of the sidebar
BOX_INSET = 12        # px at UI scale 1: a box's own borders
SUBPANEL_INDENT = 4   # px at UI scale 1: a sub-panel's layout sits this much further in


def labelled(layout, data, prop: str, label: str, search=None):
    """A dropdown (or a search field: ``search`` = (data, collection name)) with its short
    label in front, the way ``use_property_split`` draws, at a width that keeps both legible."""
    split = layout.split(factor=LABEL_SPLIT, align=True)
    split.label(text=label)
    if search is not None:
        split.prop_search(data, prop, search[0], search[1], text="")
    else:
        split.prop(data, prop, text="")


def text_width_px(context) -> float:
    """Width (px) a label has in this sidebar (the region's, or the default headless)."""
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.type == "UI" else DEFAULT_WIDTH
    return width - MARGINS * _scale(context)


def _scale(context) -> float:
    prefs = context.preferences
    scale = float(prefs.system.ui_scale)
    return scale if scale > 0 else float(prefs.view.ui_scale)


def wrap(text: str, width_px: float, scale: float, icon: bool = False) -> list[str]:
    """``text`` cut at spaces into lines no wider than ``width_px`` in the UI font."""
    import blf

    blf.size(0, 11.0 * scale)
    room = width_px - (12.0 + (20.0 if icon else 0.0)) * scale
    lines, cur = [], ""
    for word in text.split():
        trial = f"{cur} {word}" if cur else word
        if cur and blf.dimensions(0, trial)[0] > room:
            lines.append(cur)
            cur = word
        else:
            cur = trial
    if cur:
        lines.append(cur)
    return lines or [""]


def wrapped_label(layout, context, text: str, icon: str = "NONE", inset: float = 0.0) -> None:
    """``text`` as labels cut to the sidebar's width (``inset`` px at UI scale 1 narrower,
    e.g. inside a box); the first line carries ``icon``."""
    col = layout.column(align=True)
    has_icon = icon not in ("NONE", "")
    room = text_width_px(context) - inset * _scale(context)
    for i, line in enumerate(wrap(text, room, _scale(context), has_icon)):
        col.label(text=line, icon=icon if i == 0 else ("BLANK1" if has_icon else "NONE"))


ELLIPSIS = "…"


def fit_text(text: str, width_px: float, scale: float, keep_end: int = 6) -> str:
    """``text`` as it fits ``width_px`` in the UI font (a button's text margins included):
    itself, or its start, an ellipsis and its last ``keep_end`` characters -- where names of
    one rig differ ("auto_07", "upper_arm.L.001") -- rather than Blender's cut at the end."""
    import blf

    blf.size(0, 11.0 * scale)
    room = width_px - 10.0 * scale

    def width(t: str) -> float:
        return blf.dimensions(0, t)[0]

    if width(text) <= room:
        return text
    tail = text[-keep_end:] if len(text) > keep_end else text
    head = text[: max(0, len(text) - len(tail))]
    while len(head) > 2 and width(head + ELLIPSIS + tail) > room:
        head = head[:-1]                 # the start goes first, down to two characters
    while len(tail) > 3 and width(head + ELLIPSIS + tail) > room:
        tail = tail[1:]                  # then the end, down to its last three
    while head and width(head + ELLIPSIS + tail) > room:
        head = head[:-1]
    return head + ELLIPSIS + tail
