# SPDX-License-Identifier: MIT
"""Figures of a run (matplotlib, Agg): the deformed configuration and the forces; the helpers
every figure shares (colour ranges, colour bars, ticks). The contact figures are in
:mod:`vpcontact.output.contact_figures`.

Axes name the quantity only: a scene has no unit system of its own (its numbers are in whatever
consistent units the user chose), so no unit is printed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vpcontact.model.extent import mesh_extent
from vpcontact.output.fields import boundary_faces, deformed_cells

#: A field whose values spread by at most this fraction of their largest magnitude is drawn as
#: uniform (:func:`colour_range`).
UNIFORM_SPREAD = 1e-9
#: The half-width of a uniform field's colour range, relative to its value.
UNIFORM_HALF_WIDTH = 0.05
#: Major ticks per axis at most (fewer than matplotlib's default, so that labels never overlap).
TICKS = 5


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def colour_range(values) -> tuple[float, float]:
    """(vmin, vmax) of the colour scale of ``values`` (NaN and inf ignored).

    A uniform field — max − min ≤ :data:`UNIFORM_SPREAD` · max|v| — gets a fixed range of
    ±:data:`UNIFORM_HALF_WIDTH` of its value around it (±1 around 0), so that it is drawn in
    one colour, the middle of the map, instead of as its round-off stretched over the whole
    map under an offset colour bar. Any other field gets (min, max).
    """
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if not v.size:
        return -1.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    size = max(abs(lo), abs(hi))
    if hi - lo > UNIFORM_SPREAD * size and size > 0:
        return lo, hi
    centre = 0.5 * (lo + hi)
    half = UNIFORM_HALF_WIDTH * abs(centre) if centre != 0 else 1.0
    return centre - half, centre + half


def colorbar(fig, mappable, ax, label: str, **kwargs):
    """A colour bar with at most :data:`TICKS` ticks and no offset (values as they are)."""
    from matplotlib.ticker import MaxNLocator, ScalarFormatter
    bar = fig.colorbar(mappable, ax=ax, label=label, **kwargs)
    bar.locator = MaxNLocator(TICKS)
    formatter = ScalarFormatter(useOffset=False)
    formatter.set_powerlimits((-3, 4))
    bar.formatter = formatter
    bar.update_ticks()
    return bar


def tidy(ax, three_d: bool = False) -> None:
    """At most :data:`TICKS` major ticks on each axis (4 on a 3-D axes, whose labels crowd),
    numbers without an offset where the axis allows it."""
    from matplotlib.ticker import MaxNLocator
    axes = [ax.xaxis, ax.yaxis] + ([ax.zaxis] if three_d else [])
    for axis in axes:
        axis.set_major_locator(MaxNLocator(4 if three_d else TICKS))
    if three_d:  # (small tick labels, and the axis labels clear of them)
        ax.tick_params(labelsize=7)
        for axis in axes:
            axis.labelpad = 10


def save(fig, path: str | Path) -> None:
    """Write ``fig`` (PNG, 140 dpi) and close it."""
    plt = _pyplot()
    fig.savefig(path, dpi=140)
    plt.close(fig)


def deformed_configuration(path: str | Path, u, von_mises, title: str, scale: float | None = None) -> None:
    """Deformed mesh (x + s·u) coloured by the von Mises norm; 2-D cells or 3-D boundary faces.

    ``scale`` defaults to the factor making the largest displacement 10 % of the body's size.
    Collective: call on every rank; rank 0 draws.
    """
    mesh = u.function_space.mesh
    comm = mesh.comm
    size = mesh_extent(mesh)
    umax = comm.allreduce(float(np.abs(u.x.array).max(initial=0.0)), op=max)
    if scale is None:
        scale = 0.1 * size / umax if umax > 0 else 1.0
    u_scaled = u.copy()
    u_scaled.x.array[:] *= scale
    dim = mesh.topology.dim
    polys, values = (deformed_cells if dim == 2 else boundary_faces)(u_scaled, von_mises)
    if comm.rank != 0:
        return
    plt = _pyplot()
    vmin, vmax = colour_range(values)
    if dim == 2:
        from matplotlib.collections import PolyCollection
        fig, ax = plt.subplots(figsize=(6.4, 5.2))
        coll = PolyCollection(polys, array=values, cmap="viridis", edgecolors="k", linewidths=0.1)
        coll.set_clim(vmin, vmax)
        ax.add_collection(coll)
        ax.autoscale()
        ax.set_aspect("equal")
        ax.set(xlabel="x1", ylabel="x2")
        tidy(ax)
    else:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
        fig = plt.figure(figsize=(8, 5))
        ax = fig.add_subplot(projection="3d")
        coll = Poly3DCollection(polys, array=values, cmap="viridis", edgecolors="k", linewidths=0.05)
        coll.set_clim(vmin, vmax)
        ax.add_collection3d(coll)
        lo, hi = polys.reshape(-1, 3).min(axis=0), polys.reshape(-1, 3).max(axis=0)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
               xlabel="x1", ylabel="x2", zlabel="x3")
        ax.set_box_aspect(hi - lo)
        tidy(ax, three_d=True)
    colorbar(fig, coll, ax, "von Mises norm", shrink=0.8)
    ax.set_title(f"{title}\n(displacements × {scale:.3g})")
    fig.tight_layout()
    save(fig, path)


def contact_evolution(path: str | Path, history, axis: int | None, title: str,
                      line: tuple[int, float] | None = None, obstacle: bool = True,
                      part: int = 0) -> None:
    """u_ν-component of a contact part's nodes (from a
    :class:`~vpcontact.output.fields.ContactHistory`): (a) along it at several times, (b) over
    time. (``vpcontact run`` draws a 3-D contact face as maps instead:
    :func:`vpcontact.output.contact_figures.face_maps`.)

    Args:
        axis: coordinate along which nodes are ordered on the horizontal axis (0 = x1; None:
            the one along which the part's nodes spread most).
        line: ``(coordinate, value)`` selecting nodes on a line in 3-D (e.g. x2 = 0.5).
        part: index of the contact part in the history.
    Rank 0 only (the history is gathered there).
    """
    if history.comm.rank != 0:
        return
    plt = _pyplot()
    pts = history.points
    sel = history.part == part
    if not sel.any():
        return
    if axis is None:
        axis = int(np.argmax(np.ptp(pts[sel], axis=0)))
    if line is not None:
        c, val = line
        nearest = pts[sel][np.argmin(np.abs(pts[sel, c] - val)), c]
        sel &= np.isclose(pts[:, c], nearest)
    order = np.argsort(pts[sel, axis])
    xs = pts[sel, axis][order]
    normal_sign = history.parts[part].nodes.sign
    u = np.array(history.normal_displacement)[:, sel][:, order] * normal_sign   # component value
    times = np.array(history.times)
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(11, 4.2))
    cmap = plt.get_cmap("viridis")
    picks = np.unique(np.linspace(0, len(times) - 1, 11).round().astype(int))
    for i in picks:
        ax_a.plot(xs, u[i], color=cmap(times[i] / times[-1]), label=f"t = {times[i]:.2f}")
    if obstacle:
        ax_a.plot(xs, normal_sign * history.gap[sel][order], "k--", lw=1.2, label="obstacle")
    ax_a.set(xlabel=f"x{axis + 1}", ylabel="normal displacement component",
             title="(a) along the contact boundary")
    # the displacements set the scale: an obstacle far from a few nodes (rims of a curved
    # face) is clipped rather than flattening every curve
    lo, hi = float(u.min(initial=0.0)), float(u.max(initial=0.0))
    span = max(hi - lo, abs(hi), abs(lo), 1e-300)
    if obstacle:  # the obstacle where it is within reach of the scale (not at far rim nodes)
        g = normal_sign * history.gap[sel]
        near = g[(g >= lo - 2 * span) & (g <= hi + 2 * span)]
        lo, hi = min(lo, float(near.min(initial=lo))), max(hi, float(near.max(initial=hi)))
    margin = 0.05 * max(hi - lo, 1e-300)
    ax_a.set_ylim(lo - margin, hi + margin)
    ax_a.legend(fontsize=7, ncol=2)
    for j in np.unique(np.linspace(0, len(xs) - 1, 6).round().astype(int)):
        ax_b.plot(times, u[:, j], label=f"x{axis + 1} = {xs[j]:.2f}")
    ax_b.set(xlabel="t", ylabel="normal displacement component", title="(b) over time")
    ax_b.legend(fontsize=7)
    for ax in (ax_a, ax_b):
        ax.grid(alpha=0.3)
        tidy(ax)
    fig.suptitle(title)
    fig.tight_layout()
    save(fig, path)


def force_history(path: str | Path, forces, title: str) -> None:
    """Reactions and contact forces against time (a); for a driven run, each contact part that
    carries a force against the driving displacement, one panel per part (b, c, …) — none where
    the driver does not move or no part carries a force (rank 0).

    Args:
        forces: a :class:`~vpcontact.output.forces.ForceHistory`.
    """
    if forces.comm.rank != 0 or not forces.times:
        return
    plt = _pyplot()
    panels = _driven_parts(forces)
    fig, axes = plt.subplots(1, 1 + len(panels), figsize=(6 + 4.6 * len(panels), 4.2),
                             squeeze=False)
    axes = axes[0]
    _forces_over_time(axes[0], forces)
    d = np.array(forces.driver, dtype=float)
    parts = np.array(forces.parts)
    for k, (ax, i) in enumerate(zip(axes[1:], panels)):
        ax.plot(d, np.linalg.norm(parts[:, i], axis=1), "o-", ms=3)
        ax.set(xlabel="driving displacement", ylabel="|contact force|",
               title=f"({'bcdefgh'[k]}) '{forces.contact_names[i]}' against the displacement")
    for ax in axes:
        ax.grid(alpha=0.3)
        tidy(ax)
    fig.suptitle(title)
    fig.tight_layout()
    save(fig, path)


def _driven_parts(forces) -> list[int]:
    """The contact parts whose force against the driving displacement means something: the
    driver moves during the run, and the part carries a force (beyond round-off)."""
    if not forces.driver or forces.driver[-1] is None:
        return []
    d = np.array(forces.driver, dtype=float)
    d = d[np.isfinite(d)]
    if not (len(d) and d.max() > d.min()):
        return []
    parts = np.array(forces.parts)
    if parts.size == 0:
        return []
    size = np.linalg.norm(parts, axis=2)                # (times, parts)
    scale = max(float(size.max(initial=0.0)),
                float(np.abs(np.array(forces.reactions)).max(initial=0.0)))
    return [i for i in range(parts.shape[1]) if size[:, i].max() > 1e-9 * scale]


def _forces_over_time(ax, forces) -> None:
    """Panel (a): every reaction and contact-force component that is not round-off."""
    t = np.array(forces.times)
    reactions = np.array(forces.reactions)
    contact = np.array(forces.contact)
    tiny = 1e-9 * max(np.abs(reactions).max(initial=0.0), np.abs(contact).max(initial=0.0))
    curves = [(reactions[:, i, a], "-", f"{name}, {'xyz'[a]}")
              for i, name in enumerate(forces.names) for a in range(forces.dim)]
    curves += [(contact[:, a], "--", f"contact, {'xyz'[a]}") for a in range(forces.dim)]
    if forces.per_part:
        parts = np.array(forces.parts)
        curves += [(parts[:, i, a], ":", f"{name}, {'xyz'[a]}")
                   for i, name in enumerate(forces.contact_names) for a in range(forces.dim)]
    for values, style, label in curves:
        if np.abs(values).max() > tiny:
            ax.plot(t, values, style, label=label)
    ax.set(xlabel="t", ylabel="force", title="(a) reactions and contact force")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
    else:  # nothing touched and nothing was held: say so rather than draw an empty legend
        ax.text(0.5, 0.5, "every force is zero", ha="center", va="center",
                transform=ax.transAxes)
