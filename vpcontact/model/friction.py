# SPDX-License-Identifier: MIT
"""Friction on a normal-compliance part: Coulomb's law with the compliance pressure (the model of
Klarbring, Mikelić and Shillor), or Tresca's with a given threshold.

On Γ3 the tangential traction σ_τ opposes the slip of the body over the (fixed) foundation and
is bounded by a threshold s:

    |σ_τ| ≤ s,   σ_τ = −s Δu_τ / |Δu_τ| where the body slips,
    s = 𝔣 p(u_ν) (Coulomb, p = (1/μ)(u_ν − g)_+^α the compliance pressure)
    s = g_T(x) where p > 0 (Tresca: a given threshold, on the part in contact),

incrementally: Δu_τ = (I − n ⊗ n)(u_n − u_{n−1}) is the slip over the step. The step's
equations keep this law's exact value wherever the slip is not tiny, through the regularized
direction

    σ_τ = −s Δu_τ / √(|Δu_τ|² + ε²),     ε = SLIP_LENGTH × the mesh's extent,

which differs from s Δu_τ/|Δu_τ| by a relative ε²/(2|Δu_τ|²) where the body slips (5e-9 for a
slip of 1e4 ε, i.e. 1e-5 of the extent) and, where the body sticks (|σ_τ| < s), lets it creep
by ε (|σ_τ|/s)/√(1 − (σ_τ/s)²) per step (about ε). So the
tangential force of a sliding part is the threshold's integral to solver tolerance, and a
sticking part slips by about ε per step. The residual term and its exact derivative (Newton)
are UFL boundary integrals.

Frictional Signorini (a rigid obstacle) is not available yet: there the normal force is the
variational inequality's multiplier and a Coulomb cone is not a box of SNES VI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import ufl

from vpcontact.errors import InputError

#: ε of the regularized slip direction, relative to the mesh's extent.
SLIP_LENGTH = 1e-9

FRICTION_TYPES = ("coulomb", "tresca")


@dataclass(frozen=True)
class Friction:
    """Coulomb friction (``coefficient`` 𝔣 ≥ 0) or Tresca friction (``threshold``: a number or a
    function of the spatial coordinate returning a UFL expression, ≥ 0)."""

    type: str
    coefficient: Optional[float] = None
    threshold: object = None

    def __post_init__(self):
        if self.type not in FRICTION_TYPES:
            raise InputError(f"friction type must be one of {FRICTION_TYPES}, got {self.type!r}",
                             key="contact.friction.type")
        if self.type == "coulomb" and not (self.coefficient is not None
                                           and math.isfinite(self.coefficient)
                                           and self.coefficient >= 0):
            raise InputError(f"the friction coefficient must be finite and >= 0, got "
                             f"{self.coefficient}", key="contact.friction.coefficient")

    def bound(self, pressure, x):
        """The threshold s (UFL): 𝔣 p, or g_T where p > 0."""
        if self.type == "coulomb":
            return self.coefficient * pressure
        threshold = self.threshold(x) if callable(self.threshold) else self.threshold
        return ufl.conditional(ufl.gt(pressure, 0.0), threshold, 0.0)

    def bound_derivative(self, slope_times_du, x):
        """ds along du (UFL): 𝔣 dp for Coulomb, 0 for Tresca."""
        if self.type == "coulomb":
            return self.coefficient * slope_times_du
        return 0.0


def tangential(w, normal):
    """(I − n ⊗ n) w."""
    return w - ufl.dot(w, normal) * normal


def friction_terms(friction: Friction, u, u_old, du, v, normal, pressure, dpressure, ds,
                   epsilon: float):
    """(residual, Jacobian) of the friction traction on the part (see the module docstring):
    ``pressure`` the compliance pressure p(u) and ``dpressure`` its derivative along du (UFL)."""
    x = ufl.SpatialCoordinate(u.ufl_domain())
    t = tangential(u - u_old, normal)
    dt = tangential(du, normal)
    size = ufl.sqrt(ufl.dot(t, t) + epsilon ** 2)
    s = friction.bound(pressure, x)
    residual = s * ufl.dot(t, v) / size * ds
    direction_change = dt / size - t * ufl.dot(t, dt) / size ** 3
    jacobian = (friction.bound_derivative(dpressure, x) * ufl.dot(t, v) / size
                + s * ufl.dot(direction_change, v)) * ds
    return residual, jacobian
