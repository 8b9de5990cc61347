# SPDX-License-Identifier: MIT
"""Data a small-strain contact model cannot mean: warnings, not errors.

A scene can be valid and still not describe what its author meant; the commonest cause is
mixed units. :func:`warnings` returns, as located :class:`~vpcontact.scene.schema.Problem`
values (the command line prints them at ``validate`` and before a ``run``), what the data say
against the model:

* **Yield strain** σ_Y/E above :data:`YIELD_STRAIN_LIMIT`: the law yields only beyond strains a
  small-strain model (ε = sym ∇u) does not describe. E in MPa with σ_Y in Pa (E = 210 000,
  σ_Y = 2.5e8) gives 1 190.
* **Normal compliance out of reach.** The foundation carries a pressure p at the penetration
  δ(p) = (μ p)^(1/α) (σ_ν = −(1/μ)(u_ν − g)_+^α). At a working pressure p_w — the yield stress
  σ_Y with Perzyna's law (contact pressures are of its order wherever the body yields), else
  E·:data:`WORKING_STRAIN` — δ(p_w) larger than :data:`SOFT_FACTOR` times the body's size L
  means the foundation only carries such pressures after the body has sunk into it far beyond
  its own size, outside the small-displacement model: in practice it carries almost nothing.
  (A compliant foundation that carries a small share of the load on purpose — the paper's
  §4.2.2 foundation needs 53 L — is not warned; a compliance in the wrong units is off by
  factors of 10³–10⁶.) δ(p_w) below the
  round-off of the coordinates, ε_mach·L, means no penetration the mesh can represent ever
  carries it: the foundation is rigid to the solver, and its stiffness 1/μ swamps the body's
  (a Signorini condition says that without the ill-conditioning). Both usually come from μ
  read as a friction coefficient or given in other units.
* **Step count** T/k above :data:`MANY_STEPS`: more steps than a quasistatic study usually
  needs (each one a nonlinear solve), often T and k in different time units.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from vpcontact.scene.schema import Problem, Report

__all__ = ["MANY_STEPS", "SOFT_FACTOR", "WORKING_STRAIN", "YIELD_STRAIN_LIMIT", "warnings"]

#: σ_Y/E above this is warned: "a few per cent", the end of the small-strain range.
YIELD_STRAIN_LIMIT = 0.05
#: The strain at which the working pressure E·ε of a law without a yield stress is taken.
WORKING_STRAIN = 1e-3
#: A foundation that needs more than this many body sizes of penetration to carry the working
#: pressure is warned.
SOFT_FACTOR = 1e3
#: T/k above this is warned.
MANY_STEPS = 10_000


def warnings(scene: Any, extent: float | None = None) -> tuple[Problem, ...]:
    """What the data of a resolved scene say against a small-strain model, located at the key
    they concern (file and line, or the ``--set`` override).

    Args:
        scene: a :class:`~vpcontact.scene.Scene`.
        extent: the body's size L (the longest side of its bounding box); default: the built-in
            mesh's, none for a Gmsh mesh (then the compliance is not checked; the command line
            passes the built mesh's).
    """
    report = Report(str(scene.path), scene.locator, tuple(scene.overrides))
    _yield_strain(scene, report)
    size = extent if extent is not None else scene.mesh.extent
    if size is not None:
        for index, contact in enumerate(scene.contacts):
            if contact.type == "normal_compliance":
                _compliance(scene, index, contact, size, report)
    _steps(scene, report)
    return tuple(report.problems)


def _yield_strain(scene: Any, report: Report) -> None:
    law, young = scene.law, scene.material.E
    if law.type != "perzyna":
        return
    sigma_y = float(law.sigma_y.value())
    ratio = sigma_y / young
    if ratio > YIELD_STRAIN_LIMIT:
        report.add("law.sigma_y", (
            f"the yield strain sigma_y/E = {sigma_y:g}/{young:g} = {ratio:.3g} is far beyond "
            f"the few per cent a small-strain model describes (warned above "
            f"{YIELD_STRAIN_LIMIT:g}): are E and sigma_y in the same units? (E in MPa with "
            "sigma_y in Pa gives a million times too much)"))


def working_pressure(scene: Any) -> tuple[float, str]:
    """(p_w, what it is): σ_Y for Perzyna's law, else E·:data:`WORKING_STRAIN`."""
    if scene.law.type == "perzyna":
        return float(scene.law.sigma_y.value()), "the yield stress"
    return scene.material.E * WORKING_STRAIN, f"E × {WORKING_STRAIN:g}"


def _compliance(scene: Any, index: int, contact: Any, size: float, report: Report) -> None:
    pressure, what = working_pressure(scene)
    mu, alpha = contact.mu, contact.alpha
    try:
        depth = (mu * pressure) ** (1.0 / alpha)
    except OverflowError:  # (μ p)^(1/α) beyond double precision
        depth = math.inf
    carried = (f"to carry a pressure of {what} ({pressure:g}) the foundation needs the "
               f"penetration (mu p)^(1/alpha) = {depth:.3g}")
    key = f"{scene.contact_key(index)}.mu"
    if depth > SOFT_FACTOR * size:
        report.add(key, (
            f"mu = {mu:g} is the foundation's compliance (1/stiffness), not a friction "
            f"coefficient: {carried}, {depth / size:.3g} times the body's size {size:g}; "
            "within small displacements it carries almost nothing. Check mu and its units"))
    elif depth < sys.float_info.epsilon * size:
        report.add(key, (
            f"mu = {mu:g} is the foundation's compliance (1/stiffness): {carried}, below the "
            f"round-off of the coordinates ({sys.float_info.epsilon * size:.3g} for the body's "
            f"size {size:g}), so the foundation is rigid to the solver and its stiffness "
            "swamps the body's; use type = \"signorini\" for a rigid foundation, or check mu "
            "and its units"))


def _steps(scene: Any, report: Report) -> None:
    time = scene.time
    steps = math.ceil(time.T / time.k - 1e-9)
    if steps > MANY_STEPS:
        adaptive = (" (with [time] tolerance k is the largest step: the run takes at least "
                    "these)" if time.tolerance is not None else "")
        report.add("time.k", (
            f"T/k = {time.T:g}/{time.k:g} = {steps} steps, more than {MANY_STEPS}{adaptive}: "
            "each step is a nonlinear solve; are T and k in the same time unit?"))
