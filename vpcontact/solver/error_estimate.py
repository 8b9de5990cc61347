# SPDX-License-Identifier: MIT
"""Local time-error estimate of a step, from the step's own result and an extrapolation.

A step of order p (implicit Euler p = 1, BDF2 p = 2) from t_n to t_n + k has a local error
L ≈ c_L u^(p+1) k^(p+1)-ish, and the polynomial through the last p + 1 accepted displacements,
extrapolated to t_n + k, errs by E ≈ c_E u^(p+1) (products of the step sizes). Both are
proportional to the same derivative u^(p+1), so the computed difference u_step − u_extrapolated
= L − E gives

    L ≈ L/(L − E) · (u_step − u_extrapolated)       (Milne's device).

The factor L/(L − E) depends on the step sizes only; :func:`milne_factor` evaluates it exactly by
applying the scheme and the extrapolation to u(t) = (t − t_new)^(p+1)/(p+1)! (whose derivative of
order p + 1 is 1). Equal steps: 1/3 for implicit Euler, 2/11 for BDF2. The estimate costs no
solve: the extrapolated state is the Newton predictor's.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def extrapolation_weights(times: Sequence[float], target: float) -> np.ndarray:
    """Lagrange weights w with Σ w_i u(times_i) = P(target), P the interpolant of the nodes."""
    t = np.asarray(times, dtype=float)
    w = np.ones(len(t))
    for i in range(len(t)):
        for j in range(len(t)):
            if j != i:
                w[i] *= (target - t[j]) / (t[i] - t[j])
    return w


def _scheme_result(order: int, steps: Sequence[float], y) -> float:
    """u at t = 0 computed by the scheme from the exact past values y(t) (y'(0) = 0)."""
    k = steps[0]
    if order == 1:  # u_n = u_{n-1} + k u'(t_n)
        return y(-k)
    k1 = steps[1]  # variable-step BDF2 as in vpcontact.solver.bdf2.Bdf2
    omega = k / k1
    a1, a2 = (1 + omega) ** 2 / (1 + 2 * omega), -omega**2 / (1 + 2 * omega)
    return a1 * y(-k) + a2 * y(-k - k1)


def milne_factor(order: int, steps: Sequence[float]) -> float:
    """L/(L − E) for a step of size steps[0] after accepted steps steps[1:] (newest first).

    ``steps`` needs order + 1 entries: the new step and the ``order`` before it.
    """
    if order not in (1, 2) or len(steps) < order + 1:
        raise ValueError(f"order {order} needs {order + 1} step sizes, got {len(steps)}")
    m = order + 1
    steps = [s / steps[0] for s in steps]  # the factor is scale-free: work in units of k

    def y(t):
        return t**m / math.factorial(m)

    local = _scheme_result(order, steps, y)  # minus y(0) = 0
    nodes = past_nodes(steps, order)
    extrapolated = float(extrapolation_weights(nodes, 0.0) @ np.array([y(t) for t in nodes]))
    denominator = local - extrapolated
    return local / denominator if denominator != 0.0 else 1.0


def past_nodes(steps: Sequence[float], order: int) -> np.ndarray:
    """Times of the ``order`` + 1 accepted states relative to the new time (newest first)."""
    return -np.cumsum(steps[: order + 1])
