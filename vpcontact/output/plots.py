# SPDX-License-Identifier: MIT
"""Figures of the paper's kind: deformed configurations and contact histories (matplotlib, Agg)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vpcontact.model.extent import mesh_extent
from vpcontact.output.fields import ContactHistory, boundary_faces, deformed_cells


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


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
    if dim == 2:
        from matplotlib.collections import PolyCollection
        fig, ax = plt.subplots(figsize=(6.4, 5.2))
        coll = PolyCollection(polys, array=values, cmap="viridis", edgecolors="k", linewidths=0.1)
        ax.add_collection(coll)
        ax.autoscale()
        ax.set_aspect("equal")
        ax.set(xlabel="x1 [m]", ylabel="x2 [m]")
    else:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection
        fig = plt.figure(figsize=(8, 5))
        ax = fig.add_subplot(projection="3d")
        coll = Poly3DCollection(polys, array=values, cmap="viridis", edgecolors="k", linewidths=0.05)
        ax.add_collection3d(coll)
        lo, hi = polys.reshape(-1, 3).min(axis=0), polys.reshape(-1, 3).max(axis=0)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
               xlabel="x1", ylabel="x2", zlabel="x3")
        ax.set_box_aspect(hi - lo)
    fig.colorbar(coll, ax=ax, label="von Mises norm [N/m²]", shrink=0.8)
    ax.set_title(f"{title}\n(displacements × {scale:.3g})")
    fig.tight_layout()
    fig.savefig(path, dpi=140)
    plt.close(fig)


def contact_evolution(path: str | Path, history: ContactHistory, axis: int, title: str,
                      line: tuple[int, float] | None = None, obstacle: bool = True,
                      part: int = 0) -> None:
    """u_ν-component of a contact part's nodes: (a) along it at several times, (b) over time.

    Args:
        axis: coordinate along which nodes are ordered on the horizontal axis (0 = x1).
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
    ax_a.set(xlabel=f"x{axis + 1} [m]", ylabel="normal displacement component [m]",
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
    ax_b.set(xlabel="t [s]", ylabel="normal displacement component [m]", title="(b) over time")
    ax_b.legend(fontsize=7)
    for ax in (ax_a, ax_b):
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=140)
    plt.close(fig)
