"""Does every text the Osteon sidebar draws fit its button at a given sidebar width?

A stand-in for ``bpy.types.UILayout`` records what the add-on's panels draw (rows, columns,
splits, labels, properties, operators, the result list's rows), then shares the region's
width out the way Blender's layout engine does (a row's items share it equally, a split's
first column gets ``factor``, a labelled enum / string / search field gives its label a third,
as ``ui_item_with_label`` does) and compares each text's width, measured with ``blf`` in the
UI font at the UI scale, with the width of its button minus Blender's text margins.

Used by ``scripts/ui_screenshots.py`` (real window, real region width) and by
``tests/blender/test_ui.py`` (background, the default sidebar width).  Widths in pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy

# Measured on Blender 3.4's sidebar at its default width (229 px, UI scale 1.04 under Xvfb):
# the panels' layout is 173 px wide, a labelled dropdown's label gets a quarter of it.
UNIT = 20.0          # UI_UNIT_X at scale 1, px
TEXT_PAD = 10.0      # text margins inside a button (both sides), px at scale 1
ICON = 18.0          # an icon before a text, px at scale 1
ARROW = 14.0         # the dropdown arrow of a menu button, px at scale 1
CHECKBOX = 20.0      # the box of a checkbox, px at scale 1
PANEL_MARGIN = 54.0  # the tabs, region edges and panel borders, px at scale 1
SUBPANEL_INDENT = 4.0  # extra inset of a sub-panel's layout, px at scale 1
LIST_MARGIN = 26.0   # a UIList's box and its scroll bar / resize handle, px at scale 1
GAP = 2.0            # space between two items of an unaligned row, px at scale 1
LABEL_SHARE = 0.25   # ui_item_with_label: the label's share of a labelled field


def ui_scale() -> float:
    """The UI scale (1 at factory settings; background Blender 3.4 reports 0: the
    preference's own value then)."""
    prefs = bpy.context.preferences
    scale = float(prefs.system.ui_scale)
    return scale if scale > 0 else float(prefs.view.ui_scale)


def text_width(text: str, scale: float) -> float:
    """Width (px) of ``text`` in the UI font (font id 0, 11 pt) at UI scale ``scale``."""
    import blf

    blf.size(0, 11.0 * scale)  # 3.4: dpi defaults to 72 (size = px); 4.x+: size in px
    return float(blf.dimensions(0, text)[0])


@dataclass
class Item:
    kind: str                 # label, prop, operator
    text: str                 # the text Blender draws in the button
    icon: bool = False
    extra: float = 0.0        # px at scale 1 besides the text and icon (arrow, checkbox)
    clip_ok: bool = False     # may be cut: the same text is in its tooltip
    where: str = ""


@dataclass
class Box:
    kind: str                              # row, column, split
    factor: float = 0.0
    children: list = field(default_factory=list)


class FitLayout:
    """Records a panel's draw calls (the subset of UILayout the add-on uses)."""

    def __init__(self, node: Box, where: str):
        self.node, self.where = node, where
        self.scale_y = self.scale_x = 1.0
        self.enabled = self.active = self.alert = True
        self.alignment = "EXPAND"
        self.use_property_split = self.use_property_decorate = False
        self.operator_context = "INVOKE_DEFAULT"

    def _sub(self, kind, factor=0.0):
        b = Box(kind, factor)
        self.node.children.append(b)
        return type(self)(b, self.where)

    def row(self, align=False, heading="", **_kw):
        return self._sub("row")

    def column(self, align=False, heading="", **_kw):
        return self._sub("column")

    def box(self):
        return self._sub("column")

    def split(self, factor=0.0, align=False, **_kw):
        return self._sub("split", factor)

    def grid_flow(self, **_kw):
        return self._sub("column")

    def separator(self, **_kw):
        pass

    def _add(self, item):
        item.where = self.where
        self.node.children.append(item)

    def label(self, text="", icon="NONE", **_kw):
        self._add(Item("label", text, icon not in ("NONE", "")))

    def operator(self, idname, text=None, icon="NONE", emboss=True, **_kw):
        mod, name = idname.split(".")
        op = getattr(getattr(bpy.ops, mod), name)
        if text is None:
            text = op.get_rna_type().name
        # no text may be cut, result rows included: their names come fitted to the column
        # (ui/widgets.fit_text keeps the distinguishing end; the tooltip has the full text)
        self._add(Item("operator", text, icon not in ("NONE", "")))
        return _Props()

    def prop(self, data, name, text=None, icon="NONE", toggle=False, expand=False,
             icon_only=False, slider=False, **_kw):
        rna = data.bl_rna.properties[name]
        label = rna.name if text is None else text
        icon = icon not in ("NONE", "") or icon_only
        if icon_only:
            self._add(Item("prop", "", True))
        elif rna.type in ("FLOAT", "INT"):
            val = getattr(data, name)
            shown = f"{val:.{rna.precision}f}" if rna.type == "FLOAT" else str(val)
            self._add(Item("prop", f"{label}  {shown}" if label else shown, icon))
        elif rna.type == "BOOLEAN":
            if toggle:
                self._add(Item("prop", label, icon))
            else:
                self._add(Item("prop", label, icon, extra=CHECKBOX))
        elif rna.type == "ENUM" and expand:
            row = self.row()
            for it in rna.enum_items:
                row._add(Item("prop", it.name, False))
        elif rna.type == "ENUM":
            cur = getattr(data, name)
            shown = next((it.name for it in rna.enum_items if it.identifier == cur), cur)
            self._labelled(label, shown, icon)
        else:
            self._labelled(label, str(getattr(data, name)), icon)

    def _labelled(self, label, shown, icon):
        if label:
            row = self._sub("split", LABEL_SHARE)
            row._add(Item("label", label, False))
            row._add(Item("prop", shown, icon, extra=ARROW))
        else:
            self._add(Item("prop", shown, icon, extra=ARROW))

    def prop_search(self, data, name, search_data, search_name, text=None, icon="NONE", **_kw):
        label = data.bl_rna.properties[name].name if text is None else text
        self._labelled(label, getattr(data, name), True)

    def template_list(self, list_type, list_id, data, prop, active_data, active_prop,
                      rows=5, **_kw):
        ul = getattr(bpy.types, list_type)
        box = self._sub("list")
        items = getattr(data, prop)
        for i, item in enumerate(items):
            row = type(self)(Box("row"), f"{self.where} / {list_type} row {i}")
            box.node.children.append(row.node)
            ul.draw_item(ul, bpy.context, row, data, item, 0, active_data, active_prop, i)

    def template_ID(self, *a, **k):
        pass

    def context_pointer_set(self, *a, **k):
        pass


class _Props:
    """What ``layout.operator`` returns: any attribute may be set."""

    def __setattr__(self, k, v):
        object.__setattr__(self, k, v)


@dataclass
class Misfit:
    where: str
    text: str
    needed_px: float
    available_px: float

    def __str__(self):
        return (f"{self.where}: '{self.text}' needs {self.needed_px:.0f} px, has "
                f"{self.available_px:.0f} px")


def _measure(node, width: float, scale: float, out: list, all_items: list) -> None:
    if isinstance(node, Item):
        need = text_width(node.text, scale) + (TEXT_PAD + node.extra) * scale
        if node.icon:
            need += ICON * scale
        all_items.append((node, need, width))
        if node.text and need > width + 0.5 and not node.clip_ok:
            out.append(Misfit(node.where, node.text, need, width))
        return
    kids = node.children
    if not kids:
        return
    if node.kind == "column":
        for k in kids:
            _measure(k, width, scale, out, all_items)
    elif node.kind == "list":
        for k in kids:
            _measure(k, width - LIST_MARGIN * scale, scale, out, all_items)
    elif node.kind == "split":
        first = width * node.factor
        rest = (width - first) / max(1, len(kids) - 1)
        for i, k in enumerate(kids):
            _measure(k, first if i == 0 else rest, scale, out, all_items)
    else:  # row: shares in proportion to what each asks (ui_item_fit)
        room = width - GAP * scale * (len(kids) - 1)
        asks = [max(_estimate(k, scale), 1.0) for k in kids]
        total = sum(asks)
        for k, a in zip(kids, asks):
            _measure(k, room * a / total, scale, out, all_items)


def _estimate(node, scale: float) -> float:
    """The width (px) an item or a sub-layout asks for in a row."""
    if isinstance(node, Item):
        need = text_width(node.text, scale) + (TEXT_PAD + node.extra) * scale
        return need + (ICON * scale if node.icon else 0.0)
    if not node.children:
        return 0.0
    sizes = [_estimate(k, scale) for k in node.children]
    return sum(sizes) if node.kind == "row" else max(sizes)


def osteon_panels(classes) -> list:
    """The add-on's sidebar panels, parents before children, in registration order."""
    panels = [c for c in classes if issubclass(c, bpy.types.Panel)]
    return sorted(panels, key=lambda c: 1 if getattr(c, "bl_parent_id", "") else 0)


def check_panels(classes, context, region_width_px: float, scale: float | None = None):
    """(misfits, items): every text of every polled panel at this sidebar width.
    ``items`` lists (Item, needed px, available px) for reports."""
    scale = ui_scale() if scale is None else scale
    out, all_items = [], []
    for cls in osteon_panels(classes):
        poll = getattr(cls, "poll", None)
        if poll is not None and not poll(context):
            continue
        depth = 1 if getattr(cls, "bl_parent_id", "") else 0
        width = region_width_px - (PANEL_MARGIN + depth * SUBPANEL_INDENT) * scale
        root = Box("column")
        lay = FitLayout(root, cls.__name__)
        fake = type("P", (), {"layout": lay, "bl_label": cls.bl_label})()
        header = Box("row")
        if hasattr(cls, "draw_header"):
            hl = FitLayout(header, cls.__name__ + " header")
            cls.draw_header(type("P", (), {"layout": hl})(), context)
        header.children.append(Item("label", cls.bl_label, False, where=cls.__name__ + " title"))
        _measure(header, width - UNIT * scale, scale, out, all_items)
        cls.draw(fake, context)
        _measure(root, width, scale, out, all_items)
    return out, all_items
