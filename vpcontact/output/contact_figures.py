# SPDX-License-Identifier: MIT
"""Contact figures of a run, from its :class:`~vpcontact.output.fields.ContactHistory` (rank 0):

* :func:`pressure_profiles` (2-D): the contact pressure p = −σ_ν along the contact boundary,
  one curve per output time, coloured by time (``contact_pressure.png``);
* :func:`face_maps` (3-D): a quantity on the contact face at a few times, one map each, on a
  common colour scale (``contact_pressure.png``, and ``contact_history.png`` for u_ν).

The boundary coordinate of a 2-D part, and the map plane of a 3-D face, are the coordinates
along which the part's nodes spread most (x1 for a flat top or bottom face).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vpcontact.output.plots import _pyplot, colorbar, colour_range, save, tidy

#: Curves of a profile figure (times evenly spread over the run, the last included).
PROFILES = 11
#: Maps of a face figure.
MAPS = 4


def _picks(count: int, wanted: int, skip_initial: bool) -> np.ndarray:
    """Indices of ``wanted`` records evenly spread over ``count`` (the last included)."""
    first = 1 if skip_initial and count > 1 else 0
    return np.unique(np.linspace(first, count - 1, wanted).round().astype(int))


def _spread_axes(points: np.ndarray, count: int) -> list[int]:
    """The ``count`` coordinates along which ``points`` spread most, in axis order."""
    spread = np.ptp(points, axis=0)
    return sorted(int(a) for a in np.argsort(spread, kind="stable")[::-1][:count])


def pressure_profiles(path: str | Path, history, part: int, title: str) -> None:
    """p = −σ_ν of the part ``part``'s nodes against the boundary coordinate, one curve per
    output time (at most :data:`PROFILES`), coloured by t (rank 0)."""
    if history.comm.rank != 0 or not history.times:
        return
    sel = np.flatnonzero(history.part == part)
    if not len(sel):
        return
    plt = _pyplot()
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    axis = _spread_axes(history.points[sel], 1)[0]
    order = np.argsort(history.points[sel, axis], kind="stable")
    xs = history.points[sel, axis][order]
    pressure = np.array(history.pressure)[:, sel][:, order]
    times = np.array(history.times)
    norm = Normalize(times[0], times[-1] if times[-1] > times[0] else times[0] + 1.0)
    cmap = plt.get_cmap("viridis")
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for i in _picks(len(times), PROFILES, skip_initial=False):
        ax.plot(xs, pressure[i], "-", marker="o", ms=2, color=cmap(norm(times[i])))
    lo, hi = colour_range(pressure)  # a uniform pressure: a centred axis, not its round-off
    if (lo, hi) != (float(pressure.min()), float(pressure.max())):
        ax.set_ylim(lo, hi)
    ax.set(xlabel=f"x{axis + 1}", ylabel="contact pressure −σ_ν", title=title)
    ax.grid(alpha=0.3)
    tidy(ax)
    colorbar(fig, ScalarMappable(norm=norm, cmap=cmap), ax, "t")
    fig.tight_layout()
    save(fig, path)


def face_maps(path: str | Path, history, part: int, values: list, label: str,
              title: str) -> None:
    """``values`` (one array per record of the history, at every node) of the part ``part``
    on its contact face at :data:`MAPS` times evenly spread over the run, on one colour scale
    (rank 0)."""
    if history.comm.rank != 0 or not history.times:
        return
    sel = np.flatnonzero(history.part == part)
    if len(sel) < 3:
        return
    plt = _pyplot()
    a, b = _spread_axes(history.points[sel], 2)
    x, y = history.points[sel, a], history.points[sel, b]
    data = np.array(values)[:, sel]
    picks = _picks(len(history.times), MAPS, skip_initial=True)
    vmin, vmax = colour_range(data[picks])
    fig, axes = plt.subplots(1, len(picks), figsize=(1.2 + 3.4 * len(picks), 3.8),
                             squeeze=False, sharey=True, constrained_layout=True)
    axes = axes[0]
    triangles = _triangulation(x, y)
    for ax, i in zip(axes, picks):
        if triangles is not None:
            shown = ax.tripcolor(triangles, data[i], cmap="viridis", vmin=vmin, vmax=vmax,
                                 shading="gouraud")
        else:
            shown = ax.scatter(x, y, c=data[i], cmap="viridis", vmin=vmin, vmax=vmax, s=12)
        ax.set_aspect("equal")
        ax.set(xlabel=f"x{a + 1}", title=f"t = {history.times[i]:.4g}")
        tidy(ax)
    axes[0].set_ylabel(f"x{b + 1}")
    fig.suptitle(title)
    colorbar(fig, shown, list(axes), label, shrink=0.8)
    save(fig, path)


def _triangulation(x: np.ndarray, y: np.ndarray):
    """A Delaunay triangulation of the face's nodes (in the map plane) without the triangles
    that bridge a gap of a non-convex face (an edge over 3 times the typical one); None when
    the nodes do not span an area."""
    from matplotlib.tri import Triangulation
    try:
        tri = Triangulation(x, y)
    except (ValueError, RuntimeError):
        return None
    corners = np.stack([x[tri.triangles], y[tri.triangles]], axis=-1)   # (tri, 3, 2)
    edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    if len(edges):
        tri.set_mask(edges > 3.0 * np.median(edges))
    return tri
