# SPDX-License-Identifier: MIT
"""The model a scene runs, in words: the law, its yield set, the 2-D model and the formulation
that were taken, each marked where it came from a default.

``vpcontact show`` writes it at the top of the resolved scene and ``vpcontact run`` prints it as
its first line, e.g. ``law perzyna (yield set von_mises, default), plane strain (default), mixed
P2–P1 (default)``: a default that decides the answer (the yield set, the plane) is never taken
silently.
"""

from __future__ import annotations

from typing import Any

__all__ = ["MU_MEANING", "choices", "formulation"]

#: What the normal-compliance coefficient ``mu`` is, wherever it is shown: contact users read μ
#: as a friction coefficient.
MU_MEANING = "the foundation's compliance (1/stiffness), not a friction coefficient"

_DEFAULT = "default"


def formulation(scene: Any) -> str:
    """``"mixed P2–P1"`` (Taylor–Hood) or ``"displacement P1"``/``"displacement P2"``."""
    if scene.formulation == "mixed":
        return "mixed P2–P1"
    return f"displacement P{scene.degree}"


def choices(scene: Any) -> str:
    """The law (with the yield set of Perzyna's), the plane (2-D) and the formulation of a
    resolved :class:`~vpcontact.scene.Scene`, marked ``default`` where the scene left them to
    their defaults (:attr:`~vpcontact.scene.Scene.defaulted`)."""
    marked = scene.defaulted
    law = scene.law
    notes = [f"yield set {law.yield_set}"] if law.type == "perzyna" else []
    if "law.yield_set" in marked and notes:
        notes[0] += f", {_DEFAULT}"
    if "law.type" in marked:
        notes.append(_DEFAULT)
    parts = [f"law {law.type}" + (f" ({'; '.join(notes)})" if notes else "")]
    if scene.dim == 2:
        parts.append(f"plane {scene.material.plane}"
                     + (f" ({_DEFAULT})" if "material.plane" in marked else ""))
    parts.append(formulation(scene)
                 + (f" ({_DEFAULT})" if "discretization.formulation" in marked else ""))
    return ", ".join(parts)
