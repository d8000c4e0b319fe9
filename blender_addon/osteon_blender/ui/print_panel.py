"""The sidebar's print-direction block (FDM layers, docs/printing.md)."""

from .. import state


def draw(layout, s):
    col = layout.column(align=True)
    col.prop(s, "layer_strength_ratio")
    col.prop(s, "print_direction")
    if s.print_direction == "AXIS":
        col.prop(s, "print_axis")
    row = col.row(align=True)
    row.operator("osteon.find_orientation", icon="ORIENTATION_GIMBAL")
    row.operator("osteon.apply_orientation", icon="CON_ROTLIKE")
    o = state.of(s.id_data).orientation
    if o is not None and "result" in o:
        col.label(text=f"Best: worst ratio {o['before']:.2f} -> {o['after']:.2f}"
                  + (" (applied)" if o.get("applied") else ""))
