# SPDX-License-Identifier: MIT
"""Gap between the contact surface Γ3 and a rigid obstacle given as an implicit surface.

The obstacle is {φ(x) ≤ 0} for a function φ that is positive on the body's side, e.g. the paper's
2-D obstacle φ(x) = (x1 - 3)²/900 + (x2 + 3)²/9 - 1. The gap at a point x of Γ3 is the distance
g(x) = min {s ≥ 0 : φ(x + s ν) = 0} along the outward normal ν, found for all points at once by
geometric marching (to bracket the first sign change) followed by bisection to machine precision.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from vpcontact.errors import InputError

LevelSet = Callable[[np.ndarray], np.ndarray]


#: Each marching step goes this factor farther along the ray: an obstacle thinner than about
#: (MARCH_GROWTH − 1) times its distance from the face can fall between two samples and be
#: missed. It was 2 (a thin blade 0.04 thick 0.30 above a block was stepped over, and the block
#: passed through it; a circle's edge seen along a short chord was reported out of reach); 1.1
#: costs about 150 samples per ray that misses (from max_distance / 2²⁰ to max_distance)
#: instead of 20, evaluated on the rays still open only.
MARCH_GROWTH = 1.1


def gap_along_normal(phi: LevelSet, points: np.ndarray, normal: np.ndarray, *,
                     max_distance: float, first_step: float | None = None,
                     signed: bool = False, check_side: bool = True,
                     may_miss: np.ndarray | None = None) -> np.ndarray:
    """Distance from each point to the obstacle {φ ≤ 0} along ``normal``.

    Args:
        phi: vectorised level set, φ(x) for x of shape (3, N), > 0 outside the obstacle.
        points: (N, 3) points on Γ3.
        normal: unit outward normal of Γ3, shape (3,), or one per point, shape (N, 3).
        max_distance: rays longer than this count as missing the obstacle.
        first_step: first marching step (default max_distance / 2**20).
        signed: points inside the obstacle get g < 0, minus their distance to its surface
            backwards along the normal (an obstacle that has moved into the body's reference
            configuration, as an indenter does); otherwise they are an error.
        check_side: refuse an obstacle that is on the body's side of its surface (see
            :func:`_check_side`; off for a moved obstacle, which may have passed through).
        may_miss: (N,) mask of points whose ray may miss: they get the gap ``max_distance``
            (no obstacle within reach along their normal: no contact there, as at the rim of a
            curved face whose normal turns parallel to a plane obstacle). Others raise.

    Returns:
        (N,) gaps (≥ 0 unless ``signed``).

    Raises:
        InputError: φ is not finite, a point starts inside the obstacle (unless ``signed``), or
            a ray misses it.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    normal = np.broadcast_to(np.asarray(normal, dtype=np.float64).reshape(-1, 3), points.shape)
    if points.shape[0] == 0:
        return np.zeros(0)
    if not max_distance > 0:
        raise InputError(f"max_distance must be > 0, got {max_distance}",
                         key="contact.max_distance")

    def f(s, rays=slice(None)):
        """φ at distance s along the rays ``rays`` (a mask or index; default all)."""
        values = np.asarray(phi((points[rays] + s[:, None] * normal[rays]).T), dtype=np.float64)
        values = np.broadcast_to(values, s.shape)
        if not np.isfinite(values).all():
            raise InputError("the obstacle level set evaluated to NaN/Inf near the contact surface",
                             key="contact.obstacle")
        return values

    n = points.shape[0]
    lo = np.zeros(n)
    f_lo = f(lo)
    # A point on the obstacle's surface up to round-off (|φ| ≤ 1e-12 (1 + |x|)) touches it.
    touching = np.abs(f_lo) <= 1e-12 * (1.0 + np.abs(points).max(axis=1))
    f_lo = np.where(touching, 0.0, f_lo)
    inside = f_lo < 0
    if check_side and inside.any():
        _check_side(phi, points[inside], normal[inside], f_lo[inside])
    if signed and inside.any():
        gap = np.empty(n)
        gap[~inside] = gap_along_normal(phi, points[~inside], normal[~inside],
                                        max_distance=max_distance, first_step=first_step,
                                        may_miss=None if may_miss is None else may_miss[~inside])
        gap[inside] = -gap_along_normal(lambda x: -np.asarray(phi(x)), points[inside],
                                        -normal[inside], max_distance=max_distance,
                                        first_step=first_step)
        return gap
    if inside.any():
        i = int(np.argmax(inside))
        x = points[i][:points.shape[1]].tolist()
        raise InputError(f"contact point {x} starts inside the obstacle "
                         f"(phi = {f_lo[i]:.3g} < 0)", key="contact.obstacle")
    hi = np.where(f_lo == 0, 0.0, np.nan)
    lo, hi = _bracket(f, points, normal, lo, hi, max_distance, first_step, may_miss)
    return _bisect(f, lo, hi)


def _bracket(f, points, normal, lo, hi, max_distance, first_step, may_miss):
    """(lo, hi) with φ(lo) > 0 ≥ φ(hi) on every ray whose ``hi`` is NaN, found by marching
    out from ``lo`` in steps growing by :data:`MARCH_GROWTH` (``f(s, rays)``: φ at s along
    the rays); rays that ``may_miss`` and meet nothing within ``max_distance`` get it as both
    ends, others raise."""
    n = points.shape[0]
    step = first_step or max_distance / 2.0 ** 20
    s = np.full(n, step)
    open_ = np.isnan(hi)
    while open_.any():
        f_s = np.ones(n)
        f_s[open_] = f(s[open_], open_)
        crossed = open_ & (f_s <= 0)
        hi[crossed] = s[crossed]
        lo = np.where(open_ & ~crossed, s, lo)
        open_ &= ~crossed
        if open_.any() and s[open_].min() > max_distance:
            beyond = open_ & (s > max_distance)
            if may_miss is not None and np.all(may_miss[beyond]):
                lo = np.where(beyond, max_distance, lo)
                hi = np.where(beyond, max_distance, hi)
                open_ &= ~beyond
                continue
            i = int(np.argmax(beyond & (True if may_miss is None else ~may_miss)))
            raise InputError(f"the ray from contact point {points[i].tolist()} along the normal "
                             f"{normal[i].round(12).tolist()} misses the obstacle within "
                             f"{max_distance:g} (restrict the contact part to where the "
                             "obstacle lies along the normal, or raise contact.max_distance)",
                             key="contact.obstacle")
        s = np.where(open_, MARCH_GROWTH * s, s)
    return lo, hi


def _bisect(f, lo, hi):
    """Bisection on [lo, hi] with φ(lo) > 0 ≥ φ(hi): 64 halvings reach machine precision."""
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        lo = np.where(f_mid > 0, mid, lo)
        hi = np.where(f_mid > 0, hi, mid)
        if np.all(hi - lo <= 4 * np.finfo(float).eps * np.maximum(hi, 1e-300)):
            break
    return hi


def _check_side(phi: LevelSet, points: np.ndarray, normal: np.ndarray, values: np.ndarray) -> None:
    """Raise if φ grows along the body's outward normal at every point inside the obstacle:
    the obstacle is then on the body's side of its surface (a plane whose normal points away
    from the body), whatever a ray would report. An indenter that has moved into the body is
    the other way round: going outwards takes a point deeper into it."""
    probe = 1e-6 * max(float(np.abs(values).max()), 1e-12)
    ahead = np.broadcast_to(np.asarray(phi((points + probe * normal).T), dtype=np.float64),
                            values.shape)
    if np.all(ahead > values):
        raise InputError(f"the obstacle is on the body's side of its surface: at contact point "
                         f"{points[0].tolist()} phi = {values[0]:.3g} < 0 and phi grows along "
                         "the body's outward normal (a plane obstacle's normal must point "
                         "towards the body: reverse it)", key="contact.obstacle")


def shape_level_set(shape: str, params: dict, dim: int) -> LevelSet:
    """Level set φ of a built-in obstacle shape, positive on the body's side.

    * ``plane`` (``point`` p, ``normal`` n towards the body): φ = n̂·(x − p);
    * ``sphere`` (``center`` c, ``radius`` R; a circle in 2-D): φ = |x − c| − R;
    * ``cylinder`` (``center`` c on its axis, ``radius`` R, ``axis`` a in 3-D; a circle in 2-D):
      φ = |(x − c) − ((x − c)·â)â| − R;
    * ``ellipsoid`` (``center`` c, ``semi_axes`` s along x, y, z; an ellipse in 2-D):
      φ = min(s) (|((x − c)/s)| − 1), whose zero set is the ellipsoid exactly.
    """
    def coords(x):
        return np.asarray(x, dtype=np.float64)[:dim]

    if shape == "plane":
        p = np.asarray(params["point"], dtype=np.float64)[:, None]
        n = np.asarray(params["normal"], dtype=np.float64)
        n = (n / np.linalg.norm(n))[:, None]
        return lambda x: np.sum(n * (coords(x) - p), axis=0)
    c = np.asarray(params["center"], dtype=np.float64)[:, None]
    if shape == "sphere" or (shape == "cylinder" and dim < 3):
        radius = float(params["radius"])
        return lambda x: np.linalg.norm(coords(x) - c, axis=0) - radius
    if shape == "cylinder":
        radius = float(params["radius"])
        a = np.asarray(params["axis"], dtype=np.float64)
        a = (a / np.linalg.norm(a))[:, None]

        def cylinder(x):
            r = coords(x) - c
            return np.linalg.norm(r - np.sum(r * a, axis=0) * a, axis=0) - radius
        return cylinder
    if shape == "ellipsoid":
        s = np.asarray(params["semi_axes"], dtype=np.float64)[:, None]
        return lambda x: s.min() * (np.linalg.norm((coords(x) - c) / s, axis=0) - 1.0)
    raise InputError(f"unknown obstacle shape {shape!r}", key="contact.obstacle.shape")


def rotation_matrix(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` (radians, right-handed) about the unit vector along ``axis``
    (Rodrigues' formula), a (3, 3) orthogonal matrix; ``axis`` (0, 0, 1) is the 2-D rotation."""
    a = np.asarray(axis, dtype=np.float64).reshape(3)
    a = a / np.linalg.norm(a)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
