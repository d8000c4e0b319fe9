"""The sidebar's print-direction block (FDM layers, docs/printing.md)."""

from .. import state
from .widgets import labelled, wrapped_label


def draw(layout, s, context):
    layout.prop(s, "layer_strength_ratio")
    labelled(layout, s, "print_direction", "Layers")
    if s.print_direction == "AXIS":
        labelled(layout, s, "print_axis", "Axis")
    col = layout.column(align=True)
    col.operator("osteon.find_orientation", icon="ORIENTATION_GIMBAL")
    col.operator("osteon.apply_orientation", icon="CON_ROTLIKE")
    col.operator("osteon.export_slicer", icon="EXPORT")  # reinforce instead of reshape (3MF)
    o = state.of(s.id_data).orientation
    if o is not None and "result" in o:
        wrapped_label(layout, context, f"Best: worst ratio {o['before']:.2f} -> "
                      f"{o['after']:.2f}" + (" (applied)" if o.get("applied") else ""))
