"""The "Print settings" sub-panel's choices and their mapping onto the wheel's Settings
(``osteon.settings.Settings.print_profile`` and its overrides; docs/printing.md).  No bpy here:
the presets, their sources and the checks are the wheel's (``osteon.profiles``)."""

from osteon import materials, profiles

#: the profile enum: every preset of the wheel, its source as the tooltip
PROFILE_ITEMS = [(key, p.name if key != "solid" else "Solid", p.source)
                 for key, p in profiles.print_profiles().items()]
PATTERN_ITEMS = [(p, p.capitalize(), f"{p} infill (docs/printing.md, 'Infill')")
                 for p in profiles.PATTERNS]

#: property of the sub-panel -> (Settings field, kind that uses it, to the Settings' unit)
FIELDS = {
    "perimeters": ("perimeters", "fdm", int),
    "infill_percent": ("infill", "fdm", lambda v: float(v) / 100.0),  # % in the UI
    "pattern": ("infill_pattern", "fdm", str),
    "line_width_mm": ("line_width_mm", "fdm", float),
    "layer_height_mm": ("layer_height_mm", "fdm", float),
    "top_bottom_layers": ("top_bottom_layers", "fdm", int),
    "shell_mm": ("shell_mm", "resin_hollow", float),
}


def preset_values(key: str) -> dict:
    """The sub-panel's property values of preset ``key`` (what "Change settings" starts from)."""
    p = profiles.get_profile(key)
    return {"perimeters": p.perimeters, "infill_percent": 100.0 * p.infill, "pattern": p.pattern,
            "line_width_mm": p.line_width, "layer_height_mm": p.layer_height,
            "top_bottom_layers": p.top_bottom_layers, "shell_mm": p.shell}


def settings_fields(s) -> dict:
    """``Settings`` keyword arguments of ``scene.osteon.print_settings`` (``s`` the scene's
    ``scene.osteon``): the preset key, plus every override of its kind when "Change settings"
    is on.  Absent sub-panel (an older file): solid."""
    ps = getattr(s, "print_settings", None)
    if ps is None:
        return {}
    out = {"print_profile": str(ps.profile)}
    if getattr(ps, "customize", False):
        kind = profiles.get_profile(ps.profile).kind
        out.update({field: convert(getattr(ps, prop))
                    for prop, (field, k, convert) in FIELDS.items() if k == kind})
    return out


def summary(key: str) -> str:
    """One line on a preset, e.g. "2 perimeters, 15 % gyroid, 4 top/bottom layers"."""
    p = profiles.get_profile(key)
    if p.kind == "fdm":
        return (f"{p.perimeters} perimeters × {p.line_width:g} mm, {100 * p.infill:g} % "
                f"{p.pattern}, {p.top_bottom_layers} top/bottom layers of {p.layer_height:g} mm")
    if p.kind == "resin_hollow":
        return f"hollow, {p.shell:g} mm shell"
    return "solid: every section as cut (SLS, 100 % infill)"


def suggested(material_key: str) -> str | None:
    """The print profile the material's process suggests (``Material.default_profile``)."""
    try:
        return materials.get(material_key).default_profile
    except ValueError:
        return None
