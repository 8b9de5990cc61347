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
#: where the tangent is not nearly incompressible). Mixed: MUMPS is the faster solver of the
#: implicit scheme's Newton iterations at the sizes measured inside the time loop, so ``auto``
#: switches where its memory would approach this machine's 24 GB (2.7 GB of factors at 143 k
#: unknowns, growing about like n^(4/3)). Mixed with a Jacobian fixed within each step (the
#: linearized scheme, Signorini parts only: ``per_step``): the block preconditioner's solves are
#: aimed and probed there, and MUMPS refactorizes whenever the contact set moves; measured in
#: the paper's 3-D test (t = 0.05-0.08 s, k = 0.01) MUMPS is faster at 2 953 unknowns (0.036 s
#: against 0.066 s per step), they tie at 19 690 (0.70 s against 0.71 s), and the iterative
#: solver is 2.5x and 4.7x faster at 44 508 and 143 128 (1.9 s against 4.6 s, 8.2 s against
#: 38.6 s; `bench/results/step_cost_crossover.json`).
ITERATIVE_FROM = {"displacement": 100_000, "mixed": 300_000, "mixed_per_step": 20_000}


def choose(linear: str, unknowns: int, formulation: str = "displacement",
           per_step: bool = False, iterative_possible: bool = True) -> str:
    """``"direct"`` or ``"iterative"`` for ``[solver] linear``, the problem's size and its
    formulation (``"displacement"`` or ``"mixed"``); ``per_step``: the Jacobian is fixed
    within each step (the linearized scheme); ``iterative_possible``: False where only the
    direct solver applies (an obstacle driven by a force), which ``auto`` then picks."""
    if linear not in LINEAR_SOLVERS:
        raise ValueError(f"linear solver must be one of {LINEAR_SOLVERS}, got {linear!r}")
    if linear == "auto":
        key = "mixed_per_step" if formulation == "mixed" and per_step else formulation
        return ("iterative" if iterative_possible and unknowns >= ITERATIVE_FROM[key]
                else "direct")
    return linear
