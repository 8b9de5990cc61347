# SPDX-License-Identifier: MIT
"""Frictionless contact conditions on Γ3 as UFL boundary terms.

Normal compliance (paper eq. (15)) models a deformable foundation,

    σ_ν = -(1/μ) (u_ν - g)_+^α   on Γ3,

and enters the equilibrium equation as the boundary term ∫_Γ3 (1/μ)(u_ν - g)_+^α v_ν da, the
derivative of j(u) = 1/(α+1) ∫_Γ3 (1/μ)(u_ν - g)_+^{α+1} da.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import ufl

from vpcontact.errors import InputError


@dataclass(frozen=True)
class NormalCompliance:
    """Normal compliance on the facets tagged ``tag``.

    Attributes:
        tag: facet tag of Γ3.
        mu: deformability coefficient μ > 0 of the foundation (stiffness 1/μ).
        alpha: exponent α in (0, 1].
        gap: initial gap g ≥ 0 (a number; a UFL expression of x is also accepted).
    """

    tag: int
    mu: float
    alpha: float = 1.0
    gap: object = 0.0

    def __post_init__(self):
        if not (math.isfinite(self.mu) and self.mu > 0):
            raise InputError(f"normal compliance mu must be finite and > 0, got {self.mu}")
        if not 0.0 < self.alpha <= 1.0:
            raise InputError(f"normal compliance exponent alpha must lie in (0, 1], got {self.alpha}")
        if isinstance(self.gap, (int, float)) and not (math.isfinite(self.gap) and self.gap >= 0):
            raise InputError(f"gap g must be finite and >= 0, got {self.gap}")

    def penetration(self, u, normal):
        """(u_ν - g), positive where the body penetrates the foundation."""
        return ufl.dot(u, normal) - self.gap

    def residual(self, u, v, normal, ds):
        """∫_Γ3 (1/μ)(u_ν - g)_+^α v_ν da."""
        pos = ufl.max_value(self.penetration(u, normal), 0.0)
        force = pos if self.alpha == 1.0 else pos ** self.alpha
        return (1.0 / self.mu) * force * ufl.dot(v, normal) * ds(self.tag)

    def jacobian(self, u, du, v, normal, ds):
        """Exact derivative of :meth:`residual` for α = 1 (piecewise linear in u_ν)."""
        if self.alpha != 1.0:
            raise InputError("normal compliance with alpha < 1 is not supported yet (issue 3)")
        return ufl.derivative(self.residual(u, v, normal, ds), u, du)
