# SPDX-License-Identifier: MIT
"""Gap between the contact surface Γ3 and a rigid obstacle given as an implicit surface.

The obstacle is {φ(x) ≤ 0} for a function φ that is positive on the body's side, e.g. the paper's
2-D obstacle φ(x) = (x1 - 3)²/900 + (x2 + 3)²/9 - 1. The gap at a point x of Γ3 is the distance
g(x) = min {s ≥ 0 : φ(x + s ν) = 0} along the outward normal ν, found for all points at once by
geometric marching (to bracket the first sign change) followed by bisection to machine precision.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from vpcontact.errors import InputError

LevelSet = Callable[[np.ndarray], np.ndarray]


def gap_along_normal(phi: LevelSet, points: np.ndarray, normal: np.ndarray, *,
                     max_distance: float, first_step: float | None = None) -> np.ndarray:
    """Distance from each point to the obstacle {φ ≤ 0} along ``normal``.

    Args:
        phi: vectorised level set, φ(x) for x of shape (3, N), > 0 outside the obstacle.
        points: (N, 3) points on Γ3.
        normal: unit outward normal of Γ3, shape (3,).
        max_distance: rays longer than this count as missing the obstacle.
        first_step: first marching step (default max_distance / 2**20).

    Returns:
        (N,) gaps g ≥ 0.

    Raises:
        InputError: φ is not finite, a point starts inside the obstacle, or a ray misses it.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    normal = np.asarray(normal, dtype=np.float64).reshape(3)
    if points.shape[0] == 0:
        return np.zeros(0)
    if not max_distance > 0:
        raise InputError(f"max_distance must be > 0, got {max_distance}")

    def f(s):
        values = np.asarray(phi((points + s[:, None] * normal).T), dtype=np.float64)
        values = np.broadcast_to(values, s.shape)
        if not np.isfinite(values).all():
            raise InputError("the obstacle level set evaluated to NaN/Inf near the contact surface")
        return values

    n = points.shape[0]
    lo = np.zeros(n)
    f_lo = f(lo)
    inside = f_lo < 0
    if inside.any():
        x = points[np.argmax(inside)]
        raise InputError(f"contact point {x[:points.shape[1]].tolist()} starts inside the obstacle "
                         f"(phi = {f_lo[np.argmax(inside)]:.3g} < 0)")
    hi = np.where(f_lo == 0, 0.0, np.nan)
    step = first_step or max_distance / 2.0 ** 20
    s = np.full(n, step)
    open_ = np.isnan(hi)
    while open_.any():
        f_s = f(np.where(open_, s, 0.0))
        crossed = open_ & (f_s <= 0)
        hi[crossed] = s[crossed]
        lo = np.where(open_ & ~crossed, s, lo)
        open_ &= ~crossed
        if open_.any() and s[open_].min() > max_distance:
            x = points[np.argmax(open_ & (s > max_distance))]
            raise InputError(f"the ray from contact point {x.tolist()} along the normal "
                             f"{normal.tolist()} misses the obstacle within {max_distance:g}")
        s = np.where(open_, 2.0 * s, s)

    # Bisection on [lo, hi] with φ(lo) > 0 ≥ φ(hi): 64 halvings reach machine precision.
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        lo = np.where(f_mid > 0, mid, lo)
        hi = np.where(f_mid > 0, hi, mid)
        if np.all(hi - lo <= 4 * np.finfo(float).eps * np.maximum(hi, 1e-300)):
            break
    return hi
