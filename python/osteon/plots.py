"""Pictures of an analysis: the model coloured by stress, and stress along each bone chain.

Uses matplotlib's Agg backend (no display needed). Orthographic views are drawn with a
``PolyCollection`` sorted back to front, which stays fast for meshes of 10⁵ faces.
Units: mm and MPa.
"""

from __future__ import annotations

import numpy as np

GREY = (0.72, 0.72, 0.72, 1.0)


def _mpl():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return matplotlib, plt


def stress_colors(stress, allowable, culled=None):
    """RGBA per value: blue (0) → red (at the allowable stress and above); grey where culled."""
    matplotlib, _ = _mpl()
    cmap = matplotlib.colormaps["jet"]
    s = np.clip(np.asarray(stress, float) / max(float(allowable), 1e-300), 0.0, 1.0)
    s = np.where(np.isfinite(s), s, 0.0)
    rgba = cmap(s)
    if culled is not None:
        rgba[np.asarray(culled, bool)] = GREY
    return rgba


def _view(ax, vertices, faces, face_rgba, axes, depth_axis, flip_depth, title):
    from matplotlib.collections import PolyCollection

    v2 = vertices[:, axes]
    tri = v2[faces]
    depth = vertices[faces][:, :, depth_axis].mean(1)
    order = np.argsort(depth if not flip_depth else -depth)
    # simple Lambert shading from the viewer's side
    e1 = vertices[faces[:, 1]] - vertices[faces[:, 0]]
    e2 = vertices[faces[:, 2]] - vertices[faces[:, 0]]
    nrm = np.cross(e1, e2)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-300
    shade = 0.55 + 0.45 * np.abs(nrm[:, depth_axis])
    col = face_rgba.copy()
    col[:, :3] *= shade[:, None]
    pc = PolyCollection(tri[order], facecolors=col[order], edgecolors="none", linewidths=0)
    ax.add_collection(pc)
    lo, hi = v2.min(0), v2.max(0)
    pad = 0.03 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    names = "xyz"
    ax.set_xlabel(f"{names[axes[0]]} (mm)")
    ax.set_ylabel(f"{names[axes[1]]} (mm)")
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=7)


def _up_axis(vertices):
    ext = vertices.max(0) - vertices.min(0)
    return int(np.argmax(ext))


def bone_chains(parents):
    """Root-to-leaf chains of bone indices."""
    parents = np.asarray(parents)
    B = len(parents)
    kids = [[] for _ in range(B)]
    for b, p in enumerate(parents):
        if p >= 0:
            kids[p].append(b)
    chains = []
    for leaf in range(B):
        if kids[leaf]:
            continue
        c, k = [], leaf
        while k >= 0:
            c.append(k)
            k = parents[k]
        chains.append(c[::-1])
    return chains


def section_params(analysis, heads, tails):
    """Distance (mm) of each section centre from its bone's head, along the bone."""
    p = getattr(analysis, "section_param", None)
    if p is not None:
        return np.asarray(p, float)
    b = np.asarray(analysis.section_bone)
    u = tails[b] - heads[b]
    u /= np.linalg.norm(u, axis=1, keepdims=True) + 1e-300
    return np.einsum("ij,ij->i", np.asarray(analysis.section_center) - heads[b], u)


def plot_chains(
    ax, analysis, heads, tails, parents, names, allowable, label_prefix="", style="-", max_legend=12
):
    """Stress along each root→leaf bone chain (x: mm along the chain) with the allowable line."""
    heads, tails = np.asarray(heads, float), np.asarray(tails, float)
    lengths = np.linalg.norm(tails - heads, axis=1)
    bone = np.asarray(analysis.section_bone)
    stress = np.asarray(analysis.stress, float)
    t = section_params(analysis, heads, tails)
    chains = bone_chains(parents)
    for i, ch in enumerate(chains):
        xs, ys, start = [], [], 0.0
        for b in ch:
            sel = np.nonzero(bone == b)[0]
            o = sel[np.argsort(t[sel])]
            xs.append(start + t[o])
            ys.append(stress[o])
            start += lengths[b]
        x, y = np.concatenate(xs), np.concatenate(ys)
        lab = f"{label_prefix}{names[ch[-1]]}" if i < max_legend else None
        ax.plot(x, y, style, lw=1.0, label=lab)
    ax.axhline(allowable, color="k", ls="--", lw=1.0, label=f"allowable {allowable:g} MPa")
    ax.set_xlabel("distance along bone chain from the root (mm)")
    ax.set_ylabel("section stress σ (MPa)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, ncol=2, loc="upper left")


def save_stress_png(
    path,
    vertices,
    faces,
    analysis,
    heads,
    tails,
    parents,
    names,
    allowable,
    title="",
    before=None,
    marks=None,
    dpi=90,
    orientation=None,
    bones=False,
):
    """Write a PNG: two orthographic views coloured by per-vertex stress and the chain plot.

    ``before``: an earlier Analysis drawn dashed in the chain plot (correction);
    ``marks``: (k,3) points (mm) to mark on the views (e.g. FEM-tested sections);
    ``orientation``: an :class:`osteon.orientation.Orientation` drawn as a fourth panel (the
    sphere map of the worst stress ratio by build direction).
    ``bones``: draw the bones (heads → tails) over the views (e.g. an automatic skeleton).
    """
    _, plt = _mpl()
    V = np.asarray(vertices, float)
    Fc = np.asarray(faces)
    vs = np.asarray(analysis.vertex_stress, float)
    vc = getattr(analysis, "vertex_culled", None)
    fs = vs[Fc].mean(1)
    fcull = None if vc is None else np.asarray(vc, bool)[Fc].all(1)
    rgba = stress_colors(fs, allowable, fcull)
    up = _up_axis(V)
    # the two other axes: front view uses the longer of them horizontally
    others = [a for a in range(3) if a != up]
    ext = V.max(0) - V.min(0)
    others.sort(key=lambda a: -ext[a])
    if orientation is None:
        fig = plt.figure(figsize=(13, 4.8), layout="constrained")
        gs = fig.add_gridspec(1, 3, width_ratios=[1, 1, 1.35])
    else:
        fig = plt.figure(figsize=(17.5, 4.8), layout="constrained")
        gs = fig.add_gridspec(1, 4, width_ratios=[1, 1, 1.35, 1.3])
        plot_orientation_map(fig.add_subplot(gs[0, 3]), orientation)
    ax1, ax2, ax3 = (fig.add_subplot(gs[0, i]) for i in range(3))
    # views: look along the shorter horizontal axis, then along the longer one
    _view(ax1, V, Fc, rgba, [others[0], up], others[1], False, "side view")
    _view(ax2, V, Fc, rgba, [others[1], up], others[0], True, "front view")
    if bones:
        h, t = np.asarray(heads, float), np.asarray(tails, float)
        for ax, axes in ((ax1, [others[0], up]), (ax2, [others[1], up])):
            ax.plot(np.stack([h[:, axes[0]], t[:, axes[0]]]), np.stack([h[:, axes[1]],
                    t[:, axes[1]]]), "k-", lw=1.2)
            ax.plot(t[:, axes[0]], t[:, axes[1]], "k.", ms=4)
    if marks is not None and len(marks):
        mk = np.asarray(marks, float).reshape(-1, 3)
        for ax, axes in ((ax1, [others[0], up]), (ax2, [others[1], up])):
            ax.plot(mk[:, axes[0]], mk[:, axes[1]], "k+", ms=9, mew=1.5)
            for i, p in enumerate(mk):
                ax.annotate(
                    str(i + 1),
                    (p[axes[0]], p[axes[1]]),
                    fontsize=7,
                    xytext=(3, 3),
                    textcoords="offset points",
                )
    import matplotlib as mpl

    sm = mpl.cm.ScalarMappable(cmap="jet", norm=mpl.colors.Normalize(0, allowable))
    cb = fig.colorbar(sm, ax=[ax1, ax2], location="bottom", fraction=0.05, shrink=0.6)
    cb.set_label("stress (MPa); grey = safe for sure (culled)", fontsize=8)
    if before is not None:
        plot_chains(
            ax3, before, heads, tails, parents, names, allowable, "before: ", ":", max_legend=0
        )
    plot_chains(ax3, analysis, heads, tails, parents, names, allowable)
    ax3.set_title("stress along each bone chain", fontsize=9)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def save_fem_png(path, report, dpi=110, title=""):
    """Scatter of osteon vs FEM section stress (MPa) for a :class:`osteon.fem.FemReport`."""
    _, plt = _mpl()
    fe = np.array([s.fem_stress_mpa for s in report.sections])
    os_ = np.array([s.osteon_stress_mpa for s in report.sections])
    fig, ax = plt.subplots(figsize=(4.2, 4.0))
    ax.plot(fe, os_, "o", ms=5)
    for i, (a, b) in enumerate(zip(fe, os_, strict=True)):
        ax.annotate(str(i + 1), (a, b), fontsize=7, xytext=(3, 3), textcoords="offset points")
    hi = max(float(np.nanmax(fe)) if len(fe) else 1.0, float(np.nanmax(os_)) if len(os_) else 1.0)
    x = np.linspace(0, 1.1 * hi, 2)
    ax.plot(x, x, "k-", lw=0.8, label="equal")
    ax.fill_between(x, 0.9 * x, 1.1 * x, color="0.85", label="±10 %")
    ax.set_xlabel("FEM worst σ_nn (MPa)")
    ax.set_ylabel("osteon σ = F·d/W (MPa)")
    ax.set_xlim(0, 1.1 * hi)
    ax.set_ylim(0, 1.1 * hi)
    ax.legend(fontsize=7)
    ax.set_title(title or (f"median |err| {100 * report.median_error:.1f} %" if len(fe)
                           else "no section could be checked"), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def save_stress_thumbnail(path, vertices, faces, analysis, allowable, title="", dpi=60):
    """A small PNG for contact sheets (``osteon batch``): the two orthographic views coloured by
    stress as in :func:`save_stress_png`, without axes, colour bar or chain plot (about ten
    times faster to draw). ``path`` may be a file name or a binary file object."""
    _, plt = _mpl()
    V = np.asarray(vertices, float)
    Fc = np.asarray(faces)
    vs = np.asarray(analysis.vertex_stress, float)
    vc = getattr(analysis, "vertex_culled", None)
    fcull = None if vc is None else np.asarray(vc, bool)[Fc].all(1)
    rgba = stress_colors(vs[Fc].mean(1), allowable, fcull)
    up = _up_axis(V)
    others = sorted((a for a in range(3) if a != up), key=lambda a: -float(np.ptp(V[:, a])))
    fig = plt.figure(figsize=(6.0, 3.0))
    ax1 = fig.add_axes((0.01, 0.01, 0.48, 0.86))
    ax2 = fig.add_axes((0.51, 0.01, 0.48, 0.86))
    _view(ax1, V, Fc, rgba, [others[0], up], others[1], False, "side view")
    _view(ax2, V, Fc, rgba, [others[1], up], others[0], True, "front view")
    for ax in (ax1, ax2):
        ax.set_axis_off()
    if title:
        fig.suptitle(title, fontsize=8, y=0.98)
    fig.savefig(path, dpi=dpi, format="png")
    plt.close(fig)


def plot_orientation_map(ax, orientation, *, cmap="viridis_r"):
    """Sphere map of the worst stress ratio over build directions (an
    :class:`osteon.orientation.Orientation`): longitude/latitude of each sampled direction
    coloured by its worst ratio, the best direction (star) and the model's current one (+)."""
    d = np.asarray(orientation.directions, float)
    r = np.asarray(orientation.ratios, float)
    lon = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
    lat = np.degrees(np.arcsin(np.clip(d[:, 2], -1, 1)))
    sc = ax.scatter(lon, lat, c=r, s=4, cmap=cmap, linewidths=0)
    for p, mark, label in ((orientation.direction, "r*", "best"),
                           (orientation.reference_direction, "k+", "current")):
        p = np.asarray(p, float)
        ax.plot(np.degrees(np.arctan2(p[1], p[0])), np.degrees(np.arcsin(np.clip(p[2], -1, 1))),
                mark, ms=10, label=f"{label}: {_ratio_at(orientation, p):.3g}")
    ax.set_xlim(-180, 180)
    ax.set_ylim(-90, 90)
    ax.set_xlabel("build direction longitude (°)")
    ax.set_ylabel("latitude (°)")
    ax.set_title(f"worst stress ratio by build direction (Z/X = "
                 f"{orientation.layer_strength_ratio:g})", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    ax.tick_params(labelsize=7)
    cb = ax.figure.colorbar(sc, ax=ax, fraction=0.05)
    cb.set_label("worst σ / [σ](θ)", fontsize=8)
    return sc


def _ratio_at(orientation, p):
    if np.allclose(p, orientation.direction):
        return orientation.worst_ratio
    return orientation.reference_ratio


def save_orientation_png(path, orientation, title="", dpi=90):
    """Write a PNG with the sphere map of :func:`plot_orientation_map`."""
    _, plt = _mpl()
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    plot_orientation_map(ax, orientation)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
