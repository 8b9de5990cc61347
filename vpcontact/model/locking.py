# SPDX-License-Identifier: MIT
"""When displacements lock, and which formulation a problem gets by default.

Volumetric locking: P_k displacements cannot represent a (nearly) volume-keeping deformation on
a general mesh without over-constraining it, so the discrete body is too stiff, and stays so
under refinement for P1. Perzyna's flow with a von Mises set keeps the volume: once a region
flows, the consistent tangent keeps the bulk modulus K while its shear stiffness falls towards
μ*/k, and the limit state is a volume-keeping flow. The mixed formulation
(:class:`vpcontact.model.fields.DisplacementPressure`) is free of it.

This module is pure Python: the scene reader uses it without the finite-element stack.
"""

from __future__ import annotations

from vpcontact.errors import InputError

#: The formulations: u alone, or Taylor–Hood displacement and pressure.
FORMULATIONS = ("displacement", "mixed")

#: Poisson's ratio from which an elastic body is treated as nearly incompressible.
NEARLY_INCOMPRESSIBLE_NU = 0.45


def check_formulation(formulation: str) -> str:
    """``formulation`` if it is one of :data:`FORMULATIONS`, else an InputError."""
    if formulation not in FORMULATIONS:
        raise InputError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}",
                         key="discretization.formulation")
    return formulation


def locking_expected(three_d: bool, isochoric: bool, plastic: bool, nu: float) -> bool:
    """P_k displacements lock for a body that can be nearly incompressible (``three_d``: a 3-D
    or plane-strain model) whose flow is isochoric and plastic, or whose elasticity is itself
    nearly incompressible (ν ≥ :data:`NEARLY_INCOMPRESSIBLE_NU`)."""
    return three_d and isochoric and (plastic or nu >= NEARLY_INCOMPRESSIBLE_NU)


def locks(law) -> bool:
    """:func:`locking_expected` for a law object (its elasticity model, ``isochoric`` and
    ``plastic``)."""
    el = getattr(law, "elasticity", None)
    if el is None:
        return False
    return locking_expected(el.model in ("3d", "3d_standard"), getattr(law, "isochoric", False),
                            getattr(law, "plastic", False), el.nu)
