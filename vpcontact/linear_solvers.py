# SPDX-License-Identifier: MIT
"""Which linear solver a step gets: ``[solver] linear = "auto" | "direct" | "iterative"``.

Pure Python (the scene reader validates the key without the finite-element stack); the solvers
themselves are set up by :mod:`vpcontact.solver.linear`.
"""

from __future__ import annotations

#: Choices of ``[solver] linear``.
LINEAR_SOLVERS = ("auto", "direct", "iterative")

#: Unknowns from which ``auto`` picks the iterative solver, by formulation (see the README's
#: "Linear solvers"). Displacements: 10⁵, as before the mixed formulation existed (GAMG works
#: where the tangent is not nearly incompressible). Mixed: MUMPS is faster inside the time loop
#: at every size measured (6.8× at 6 400 unknowns), so ``auto`` switches where its memory would
#: approach this machine's 24 GB (2.7 GB of factors at 143 k unknowns, growing about like
#: n^(4/3)).
ITERATIVE_FROM = {"displacement": 100_000, "mixed": 300_000}


def choose(linear: str, unknowns: int, formulation: str = "displacement") -> str:
    """``"direct"`` or ``"iterative"`` for ``[solver] linear``, the problem's size and its
    formulation (``"displacement"`` or ``"mixed"``)."""
    if linear not in LINEAR_SOLVERS:
        raise ValueError(f"linear solver must be one of {LINEAR_SOLVERS}, got {linear!r}")
    if linear == "auto":
        return "iterative" if unknowns >= ITERATIVE_FROM[formulation] else "direct"
    return linear
